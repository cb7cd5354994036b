// Signed error maps and scan-line choice for comparison reports (src/eval/report_figures.h).
// The colour map interpolates ColorBrewer's RdBu in sRGB, as the page's legend (an SVG gradient of
// the same stops) does, so a colour in a map reads the same on the legend.
#include "eval/report_figures.h"

#include <algorithm>
#include <cmath>

#include "penumbra/error.h"
#include "penumbra/metrics.h"

namespace penumbra {

namespace {

// Exact inverse of the sRGB encoding image_io applies, so that a byte of the colour map survives
// writePng's linear -> sRGB -> byte round trip.
float srgbDecode(uint8_t byte) {
  const float c = static_cast<float>(byte) / 255.0f;
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

const std::vector<std::pair<double, Srgb8>>& divergingStops() {
  static const std::vector<std::pair<double, Srgb8>> stops = {
      {-1.0, {0x05, 0x30, 0x61}}, {-0.8, {0x21, 0x66, 0xac}}, {-0.6, {0x43, 0x93, 0xc3}}, {-0.4, {0x92, 0xc5, 0xde}},
      {-0.2, {0xd1, 0xe5, 0xf0}}, {0.0, {0xf7, 0xf7, 0xf7}},  {0.2, {0xfd, 0xdb, 0xc7}},  {0.4, {0xf4, 0xa5, 0x82}},
      {0.6, {0xd6, 0x60, 0x4d}},  {0.8, {0xb2, 0x18, 0x2b}},  {1.0, {0x67, 0x00, 0x1f}}};
  return stops;
}

Srgb8 unmeasuredColor() { return {0x59, 0x59, 0x59}; }

Srgb8 divergingColor(double t) {
  if (std::isnan(t)) return unmeasuredColor();
  const auto& stops = divergingStops();
  t = std::clamp(t, -1.0, 1.0);  // display saturation only: the legend states the range
  size_t i = 1;
  while (i + 1 < stops.size() && stops[i].first < t) ++i;
  const auto& [t0, c0] = stops[i - 1];
  const auto& [t1, c1] = stops[i];
  const double w = (t - t0) / (t1 - t0);
  Srgb8 out;
  for (int c = 0; c < 3; ++c) out[c] = static_cast<uint8_t>(std::lround((1.0 - w) * c0[c] + w * c1[c]));
  return out;
}

Image<Vec3> signedErrorMap(const Image<float>& v, const Image<float>& reference, const Image<uint8_t>& mask,
                           double range) {
  if (!(range > 0.0) || !std::isfinite(range))
    fail("signed error map: range = {} must be a positive number of V units (e.g. 0.5)", range);
  if (v.width() != reference.width() || v.height() != reference.height() || v.width() != mask.width() ||
      v.height() != mask.height())
    fail("signed error map: visibility {}x{}, reference {}x{} and mask {}x{} must have the same size", v.width(),
         v.height(), reference.width(), reference.height(), mask.width(), mask.height());
  // 8-bit colours in a lookup table: a pixel is one table read, not a search over the stops.
  constexpr int kSteps = 1024;
  std::vector<Vec3> table(kSteps + 1);
  for (int i = 0; i <= kSteps; ++i) {
    const Srgb8 c = divergingColor(-1.0 + 2.0 * i / kSteps);
    table[static_cast<size_t>(i)] = Vec3(srgbDecode(c[0]), srgbDecode(c[1]), srgbDecode(c[2]));
  }
  const Srgb8 g = unmeasuredColor();
  const Vec3 grey(srgbDecode(g[0]), srgbDecode(g[1]), srgbDecode(g[2]));
  Image<Vec3> out(v.width(), v.height());
  const double scale = 0.5 * kSteps / range;
  for (size_t i = 0; i < v.size(); ++i) {
    if (!mask[i]) {
      out[i] = grey;
      continue;
    }
    const double d = static_cast<double>(v[i]) - static_cast<double>(reference[i]);
    const double k = std::clamp(std::round(d * scale + 0.5 * kSteps), 0.0, static_cast<double>(kSteps));
    out[i] = table[static_cast<size_t>(k)];
  }
  return out;
}

int mostPenumbraRow(const Image<float>& reference, const Image<uint8_t>& mask) {
  if (reference.width() != mask.width() || reference.height() != mask.height())
    fail("scan-line choice: reference {}x{} and mask {}x{} must have the same size", reference.width(),
         reference.height(), mask.width(), mask.height());
  int best = reference.height() / 2;
  int bestCount = 0;
  for (int y = 0; y < reference.height(); ++y) {
    int count = 0;
    const float* v = reference.row(y);
    const uint8_t* m = mask.row(y);
    for (int x = 0; x < reference.width(); ++x) count += m[x] && inPenumbra(v[x]);
    if (count > bestCount) {
      best = y;
      bestCount = count;
    }
  }
  return best;
}

}  // namespace penumbra
