// The error metric (docs/architecture.md, "Vocabulary"): RMSE8 and penumbra RMSE8 against the
// reference, over the error mask (pixels that hit geometry whose normal faces the light centre).
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

// The open interval of V that counts a pixel as "in the penumbra" (docs/architecture.md, "Vocabulary").
inline constexpr float kPenumbraLow = 0.01f;
inline constexpr float kPenumbraHigh = 0.99f;
inline bool inPenumbra(float v) { return v > kPenumbraLow && v < kPenumbraHigh; }

// Thresholds of ErrorStats::umbraLeaks and ErrorStats::speckle, in V.
inline constexpr float kUmbraReference = 0.05f;  //!< reference V below this: umbra
inline constexpr float kUmbraLeakLit = 0.5f;     //!< technique V above this there: a leak
inline constexpr float kSpeckleJump = 0.25f;     //!< |V - median3x3(V)| above this: a speck ...
inline constexpr float kSpeckleCalm = 0.05f;     //!< ... where the reference's is below this

ErrorStats compareVisibility(const Image<float>& v, const Image<float>& reference, const Image<uint8_t>& mask);

// The half-penumbra truths of Lawlor 2006, Sec. 4 (Fig. 11: "Smoothies and Kirsch and Döllner are
// compared with the outer and inner penumbra respectively"; Fig. 10: "they only compute one half of
// the penumbra"). Sec. 2 (Fig. 2, Fig. 3) splits the light at the point the hard shadow is cast from:
// across a straight edge, V = 1/2 + 1/2 d/a in the outer penumbra ("more than half of the light source
// is visible"; d/a the visible fraction of the half the occluder covers first) and V = 1/2 - 1/2 d/a in
// the inner one (d/a the hidden fraction of the other half). A technique that keeps the hard shadow
// dark and fades from 0 at its edge outwards (smoothies) draws the visibility of the first half,
//     V_outer = max(0, 2 V - 1)   (0 in the inner penumbra and umbra, d/a in the outer penumbra),
// and one that keeps everything outside the hard shadow lit and fades from 1 at its edge inwards
// (kirsch) draws the visibility of the second half,
//     V_inner = min(1, 2 V)       (1 in the outer penumbra and outside, 1 - d/a in the inner penumbra).
// The two halves average to the full truth, (V_outer + V_inner) / 2 = V, at every V. Applied per pixel
// to the reference, they are exact for a straight edge under a light symmetric about its centre (disk,
// sphere, rect, directional); elsewhere they are the same per-pixel split of the truth's V.
enum class PenumbraHalf { Outer, Inner };
float halfPenumbraVisibility(float v, PenumbraHalf half);
Image<float> halfPenumbraTruth(const Image<float>& reference, PenumbraHalf half);

}  // namespace penumbra
