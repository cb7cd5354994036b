// Temporal metrics (include/penumbra/temporal_metrics.h) on sequences built here, where flicker, pop
// rate and reversed pops are known by hand.
#include <vector>

#include <gtest/gtest.h>

#include "penumbra/error.h"
#include "penumbra/temporal_metrics.h"

namespace penumbra {
namespace {

Image<float> filled(int w, int h, float value) {
  Image<float> image(w, h);
  for (float& v : image) v = value;
  return image;
}

Image<uint8_t> allMask(int w, int h) {
  Image<uint8_t> mask(w, h);
  for (uint8_t& m : mask) m = 1;
  return mask;
}

TEST(TemporalError, ATechniqueThatFollowsTheTruthHasNoFlicker) {
  // The truth darkens by 0.05 a frame; the technique is off by a constant 0.2 but changes alike.
  std::vector<Image<float>> truth, v;
  for (int k = 0; k < 4; ++k) {
    truth.push_back(filled(4, 3, 0.8f - 0.05f * k));
    v.push_back(filled(4, 3, 0.6f - 0.05f * k));
  }
  const TemporalStats s = temporalError(v, truth, std::vector<Image<uint8_t>>(4, allMask(4, 3)));
  EXPECT_NEAR(s.flicker, 0.0, 1e-4);
  EXPECT_EQ(s.pops, 0u);
  EXPECT_EQ(s.pixels, 3u * 12u);
  EXPECT_EQ(s.framePairs, 3u);
}

TEST(TemporalError, ShimmerIsCountedAsPopsThatReverse) {
  // A still truth at 0.5; one pixel of the technique alternates 0.5, 0.8, 0.5, 0.8 (a shimmer), another
  // steps once 0.5 -> 0.8 and stays; the rest follow the truth.
  const int w = 5, h = 2;
  std::vector<Image<float>> truth(4, filled(w, h, 0.5f)), v(4, filled(w, h, 0.5f));
  for (int k = 0; k < 4; ++k) v[k](0, 0) = (k % 2) ? 0.8f : 0.5f;
  for (int k = 1; k < 4; ++k) v[k](1, 0) = 0.8f;
  const TemporalStats s = temporalError(v, truth, std::vector<Image<uint8_t>>(4, allMask(w, h)));
  // e: pixel (0,0) 0.3 at every pair, pixel (1,0) 0.3 at the first pair; 30 samples in all.
  EXPECT_EQ(s.pixels, 30u);
  EXPECT_EQ(s.pops, 4u);
  EXPECT_NEAR(s.popRate, 4.0 / 30.0, 1e-12);
  EXPECT_NEAR(s.flicker, 4.0 * 0.3 * 255.0 / 30.0, 1e-3);
  // Pops with a next pair: (0,0) at pairs 0 and 1, (1,0) at pair 0; undone next: (0,0) both times.
  EXPECT_NEAR(s.reversedPops, 2.0 / 3.0, 1e-12);
}

TEST(TemporalError, OnlyPenumbraPixelsInBothMasksCount) {
  const int w = 3, h = 1;
  std::vector<Image<float>> truth = {filled(w, h, 1.0f), filled(w, h, 1.0f)};
  std::vector<Image<float>> v = {filled(w, h, 1.0f), filled(w, h, 1.0f)};
  v[1](0, 0) = 0.0f;  // lit -> black where the truth stays lit
  v[1](1, 0) = 0.5f;  // lit -> penumbra
  std::vector<Image<uint8_t>> masks = {allMask(w, h), allMask(w, h)};
  masks[1](2, 0) = 0;  // out of the second frame's mask
  v[1](2, 0) = 0.5f;
  const TemporalStats s = temporalError(v, truth, masks);
  // (0,0): every value is 0 or 1, none in the penumbra interval, so it is not counted (as in the
  // still-frame penumbra RMSE8); (1,0) counts; (2,0) is masked out.
  EXPECT_EQ(s.pixels, 1u);
  EXPECT_EQ(s.pops, 1u);
  EXPECT_NEAR(s.flicker, 0.5 * 255.0, 1e-3);
}

TEST(TemporalError, MismatchedSequencesAreRefused) {
  std::vector<Image<float>> two(2, filled(2, 2, 0.5f)), three(3, filled(2, 2, 0.5f));
  std::vector<Image<uint8_t>> masks2(2, allMask(2, 2));
  EXPECT_THROW(temporalError(two, three, masks2), Error);
  EXPECT_THROW(temporalError({filled(2, 2, 0.5f)}, {filled(2, 2, 0.5f)}, {allMask(2, 2)}), Error);
  std::vector<Image<float>> odd = {filled(2, 2, 0.5f), filled(3, 2, 0.5f)};
  EXPECT_THROW(temporalError(odd, two, masks2), Error);
}

}  // namespace
}  // namespace penumbra
