// The error metric of DESIGN.md ("Definitions"): RMSE8 = sqrt(mean((V - Vref)^2)) * 255 over the error
// mask, the unit of the Lawlor 2006 comparison table (papers/lawlor-2006..., Fig. 10). Sums are
// accumulated in double so the metric does not depend on image size through float round-off.
#include "penumbra/metrics.h"

#include <cmath>

#include "penumbra/error.h"

namespace penumbra {

namespace {

// Bounds of the open interval that counts a value as "in the penumbra" (DESIGN.md).
constexpr float kPenumbraLow = 0.01f;
constexpr float kPenumbraHigh = 0.99f;

bool inPenumbra(float v) { return v > kPenumbraLow && v < kPenumbraHigh; }

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
  double sumSq = 0.0, penumbraSumSq = 0.0, maxAbs = 0.0;
  size_t maskCount = 0, penumbraCount = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    if (!mask[i]) continue;
    const double d = static_cast<double>(v[i]) - static_cast<double>(reference[i]);
    sumSq += d * d;
    maxAbs = std::max(maxAbs, std::abs(d));
    ++maskCount;
    if (inPenumbra(v[i]) || inPenumbra(reference[i])) {
      penumbraSumSq += d * d;
      ++penumbraCount;
    }
  }
  ErrorStats stats;
  stats.maskPixels = maskCount;
  stats.penumbraPixels = penumbraCount;
  stats.maxAbsError = maxAbs;
  // An empty set has no error to report; 0 (with its count of 0) says so without a NaN in reports.
  stats.rmse8 = maskCount ? std::sqrt(sumSq / static_cast<double>(maskCount)) * 255.0 : 0.0;
  stats.penumbraRmse8 = penumbraCount ? std::sqrt(penumbraSumSq / static_cast<double>(penumbraCount)) * 255.0 : 0.0;
  return stats;
}

}  // namespace penumbra
