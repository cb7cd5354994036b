// Temporal error of a sequence of frames (include/penumbra/motion.h): how much a technique's V changes
// from one frame to the next beyond what the reference's V does. A still-frame error (RMSE8) cannot
// see a shadow that shimmers as the light moves; these can.
//
// For consecutive frames k and k + 1, per pixel, e = |(V[k+1] - V[k]) - (Vref[k+1] - Vref[k])|, over
// the pixels in both frames' error masks where any of V[k], V[k+1], Vref[k], Vref[k+1] is in the
// penumbra interval (0.01, 0.99) of the still-frame metric:
//  - flicker: the mean of e, times 255 (the units of RMSE8);
//  - pop rate: the share of those pixels with e > kPopJump;
//  - reversed pops: the share of pops (at frames k, k + 1) that pop back the other way at the next
//    pair (k + 1, k + 2), at the same pixel: shimmer, a change undone a frame later.
// The reference's own noise floor is the same measure between two reference sequences of different
// seeds (both sides then carry noise, so it is about twice one side's).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "penumbra/image.h"

namespace penumbra {

inline constexpr float kPopJump = 0.1f;  //!< e above this (in V): a pop

struct TemporalStats {
  double flicker = 0.0;       //!< mean e * 255 over the counted pixels of every consecutive pair
  double popRate = 0.0;       //!< share of counted pixels with e > kPopJump, in [0, 1]
  double reversedPops = 0.0;  //!< share of pops undone at the next pair, in [0, 1] (0 with no pops)
  size_t pixels = 0;          //!< counted (pixel, pair) samples
  size_t pops = 0;            //!< of those, pops
  size_t framePairs = 0;      //!< consecutive pairs: frames - 1
};

// v[k], reference[k] and masks[k] are frame k's technique V, reference V and error mask (all frames
// the same size). Throws Error when the sequences' lengths or the images' sizes differ, or when there
// are fewer than 2 frames.
TemporalStats temporalError(const std::vector<Image<float>>& v, const std::vector<Image<float>>& reference,
                            const std::vector<Image<uint8_t>>& masks);

}  // namespace penumbra
