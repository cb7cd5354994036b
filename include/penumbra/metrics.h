// The error metric of DESIGN.md: RMSE8 and penumbra RMSE8 against the reference, over the error
// mask (pixels that hit geometry whose normal faces the light centre).
#pragma once

#include <cstdint>

#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/light.h"

namespace penumbra {

struct ErrorStats {
  double rmse8 = 0.0;          //!< sqrt(mean((V - Vref)^2)) * 255 over the mask
  double penumbraRmse8 = 0.0;  //!< the same over mask pixels where V or Vref is in (0.01, 0.99)
  double maxAbsError = 0.0;    //!< max |V - Vref| over the mask, in [0, 1]
  size_t maskPixels = 0;
  size_t penumbraPixels = 0;
  //! Mask pixels the reference puts in the umbra (Vref < 0.05) that the technique lights (V > 0.5):
  //! light leaking through an occluder, which RMSE8 averages away.
  size_t umbraLeaks = 0;
  //! Mask pixels (not on the image border) whose V differs from the median of its 3x3 neighbourhood by
  //! more than 0.25 where the reference's differs by less than 0.05: isolated specks, spikes and lines
  //! the reference does not have, which RMSE8 also averages away.
  size_t speckle = 0;
};

// 1 where the pixel hits geometry whose shading normal faces the light's centre sample.
Image<uint8_t> errorMask(const GBuffer& gbuffer, const Light& light);

// Thresholds of ErrorStats::umbraLeaks and ErrorStats::speckle, in V.
inline constexpr float kUmbraReference = 0.05f;  //!< reference V below this: umbra
inline constexpr float kUmbraLeakLit = 0.5f;     //!< technique V above this there: a leak
inline constexpr float kSpeckleJump = 0.25f;     //!< |V - median3x3(V)| above this: a speck ...
inline constexpr float kSpeckleCalm = 0.05f;     //!< ... where the reference's is below this

ErrorStats compareVisibility(const Image<float>& v, const Image<float>& reference, const Image<uint8_t>& mask);

}  // namespace penumbra
