// The error metric (docs/architecture.md, "Vocabulary"): RMSE8 = sqrt(mean((V - Vref)^2)) * 255 over the
// error mask, the unit of the Lawlor 2006 comparison table (Fig. 10). Sums are
// accumulated in double so the metric does not depend on image size through float round-off.
#include "penumbra/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "penumbra/error.h"

namespace penumbra {

namespace {

// |V(x, y) - median of V over the 3x3 block around it|; (x, y) not on the border.
float distanceToMedian3x3(const Image<float>& v, int x, int y) {
  std::array<float, 9> block;
  int n = 0;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) block[n++] = v(x + dx, y + dy);
  std::nth_element(block.begin(), block.begin() + 4, block.end());
  return std::abs(v(x, y) - block[4]);
}

size_t countSpeckle(const Image<float>& v, const Image<float>& reference, const Image<uint8_t>& mask) {
  size_t count = 0;
  for (int y = 1; y + 1 < v.height(); ++y)
    for (int x = 1; x + 1 < v.width(); ++x) {
      if (!mask(x, y)) continue;
      if (distanceToMedian3x3(v, x, y) > kSpeckleJump && distanceToMedian3x3(reference, x, y) < kSpeckleCalm) ++count;
    }
  return count;
}

}  // namespace

Image<uint8_t> errorMask(const GBuffer& gbuffer, const Light& light) {
  Image<uint8_t> mask(gbuffer.width(), gbuffer.height(), 0);
  for (int y = 0; y < gbuffer.height(); ++y) {
    for (int x = 0; x < gbuffer.width(); ++x) {
      if (!gbuffer.hit(x, y)) continue;
      const Vec3& wsP = gbuffer.wsPosition(x, y);
      // A pixel facing away from the light centre is in its own (attached) shadow: every technique
      // agrees there by shading, so it would only dilute the error of the cast shadows.
      mask(x, y) = glm::dot(gbuffer.wsNormal(x, y), light.directionToCenter(wsP)) > 0.0f ? 1 : 0;
    }
  }
  return mask;
}

ErrorStats compareVisibility(const Image<float>& v, const Image<float>& reference, const Image<uint8_t>& mask) {
  if (v.width() != reference.width() || v.height() != reference.height() || v.width() != mask.width() ||
      v.height() != mask.height())
    fail("compareVisibility: visibility {}x{}, reference {}x{} and mask {}x{} must have the same size", v.width(),
         v.height(), reference.width(), reference.height(), mask.width(), mask.height());
  ErrorStats stats;
  double sumSq = 0.0, penumbraSumSq = 0.0, maxAbs = 0.0;
  size_t maskCount = 0, penumbraCount = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    if (!mask[i]) continue;
    const double d = static_cast<double>(v[i]) - static_cast<double>(reference[i]);
    sumSq += d * d;
    maxAbs = std::max(maxAbs, std::abs(d));
    ++maskCount;
    if (reference[i] < kUmbraReference && v[i] > kUmbraLeakLit) ++stats.umbraLeaks;
    if (inPenumbra(v[i]) || inPenumbra(reference[i])) {
      penumbraSumSq += d * d;
      ++penumbraCount;
    }
  }
  stats.speckle = countSpeckle(v, reference, mask);
  stats.maskPixels = maskCount;
  stats.penumbraPixels = penumbraCount;
  stats.maxAbsError = maxAbs;
  // An empty set has no error to report; 0 (with its count of 0) says so without a NaN in reports.
  stats.rmse8 = maskCount ? std::sqrt(sumSq / static_cast<double>(maskCount)) * 255.0 : 0.0;
  stats.penumbraRmse8 = penumbraCount ? std::sqrt(penumbraSumSq / static_cast<double>(penumbraCount)) * 255.0 : 0.0;
  return stats;
}

float halfPenumbraVisibility(float v, PenumbraHalf half) {
  // Outer: the light's first half is hidden while V <= 1/2, and its visible fraction is 2V - 1 beyond.
  // Inner: the second half is whole while V >= 1/2, and its visible fraction is 2V below (metrics.h).
  return half == PenumbraHalf::Outer ? std::max(0.0f, 2.0f * v - 1.0f) : std::min(1.0f, 2.0f * v);
}

Image<float> halfPenumbraTruth(const Image<float>& reference, PenumbraHalf half) {
  Image<float> out(reference.width(), reference.height());
  for (size_t i = 0; i < reference.size(); ++i) out[i] = halfPenumbraVisibility(reference[i], half);
  return out;
}

}  // namespace penumbra
