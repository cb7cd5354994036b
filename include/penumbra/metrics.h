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
};

// 1 where the pixel hits geometry whose shading normal faces the light's centre sample.
Image<uint8_t> errorMask(const GBuffer& gbuffer, const Light& light);

ErrorStats compareVisibility(const Image<float>& v, const Image<float>& reference, const Image<uint8_t>& mask);

}  // namespace penumbra
