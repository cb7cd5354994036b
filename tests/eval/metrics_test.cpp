// Tests of src/eval/metrics.cpp against hand-computed values of docs/architecture.md's formulas:
// RMSE8 = sqrt(mean((V - Vref)^2)) * 255 over the mask; penumbra RMSE8 over mask pixels where V or
// Vref lies in the open interval (0.01, 0.99).
#include "penumbra/metrics.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "penumbra/error.h"

namespace penumbra {
namespace {

TEST(ErrorMask, HitPixelsFacingTheLightCentreOnly) {
  GBuffer g(4, 1);
  const Light light = Light::sphere(Vec3(0.0f, 10.0f, 0.0f), 1.0f);
  // Pixel 0: floor facing up, towards the light. Pixel 1: facing down, away from it.
  // Pixel 2: a wall whose normal is perpendicular to the direction to the light (dot = 0: not facing).
  // Pixel 3: miss.
  g.objectId(0, 0) = 0;
  g.wsPosition(0, 0) = Vec3(0.0f);
  g.wsNormal(0, 0) = Vec3(0.0f, 1.0f, 0.0f);
  g.objectId(1, 0) = 0;
  g.wsPosition(1, 0) = Vec3(0.0f);
  g.wsNormal(1, 0) = Vec3(0.0f, -1.0f, 0.0f);
  g.objectId(2, 0) = 1;
  g.wsPosition(2, 0) = Vec3(0.0f);
  g.wsNormal(2, 0) = Vec3(1.0f, 0.0f, 0.0f);
  g.wsNormal(3, 0) = Vec3(0.0f, 1.0f, 0.0f);  // a miss never counts, whatever its stale normal
  const Image<uint8_t> mask = errorMask(g, light);
  EXPECT_EQ(mask(0, 0), 1);
  EXPECT_EQ(mask(1, 0), 0);
  EXPECT_EQ(mask(2, 0), 0);
  EXPECT_EQ(mask(3, 0), 0);
}

TEST(ErrorMask, DirectionalLightUsesItsDirection) {
  GBuffer g(2, 1);
  const Light sun = Light::directional(Vec3(1.0f, 1.0f, 0.0f), radians(0.5f));
  g.objectId(0, 0) = 0;
  g.wsNormal(0, 0) = Vec3(1.0f, 0.0f, 0.0f);  // dot = 0.707 > 0
  g.objectId(1, 0) = 0;
  g.wsNormal(1, 0) = Vec3(-1.0f, 0.0f, 0.0f);  // dot < 0
  const Image<uint8_t> mask = errorMask(g, sun);
  EXPECT_EQ(mask(0, 0), 1);
  EXPECT_EQ(mask(1, 0), 0);
}

TEST(CompareVisibility, HandComputedRmse8) {
  Image<float> v(3, 2), ref(3, 2);
  Image<uint8_t> mask(3, 2, 1);
  // (v, ref): (1,1) (0.5,0.25) (0,0) (0.75,1) (0,0.5) and a masked-out pixel with a huge error.
  const float vs[6] = {1.0f, 0.5f, 0.0f, 0.75f, 0.0f, 0.0f};
  const float rs[6] = {1.0f, 0.25f, 0.0f, 1.0f, 0.5f, 1.0f};
  for (int i = 0; i < 6; ++i) {
    v[i] = vs[i];
    ref[i] = rs[i];
  }
  mask[5] = 0;
  const ErrorStats s = compareVisibility(v, ref, mask);
  // Squared errors over the 5 masked pixels: 0, 1/16, 0, 1/16, 1/4 -> mean 3/40.
  EXPECT_EQ(s.maskPixels, 5u);
  EXPECT_NEAR(s.rmse8, std::sqrt(3.0 / 40.0) * 255.0, 1e-9);
  // Penumbra pixels: (0.5, 0.25), (0.75, 1), (0, 0.5): squared errors 1/16, 1/16, 1/4 -> mean 1/8.
  EXPECT_EQ(s.penumbraPixels, 3u);
  EXPECT_NEAR(s.penumbraRmse8, std::sqrt(1.0 / 8.0) * 255.0, 1e-9);
  EXPECT_DOUBLE_EQ(s.maxAbsError, 0.5);
}

TEST(CompareVisibility, UmbraLeaksCountLitPixelsTheReferencePutsInTheUmbra) {
  Image<float> v(5, 1), ref(5, 1);
  Image<uint8_t> mask(5, 1, 1);
  // (v, ref): a leak (0.6, 0.0); at the thresholds, which do not count (0.5, 0.0) and (0.9, 0.05); a
  // leak outside the mask; and a dark pixel in the umbra.
  const float vs[5] = {0.6f, 0.5f, 0.9f, 1.0f, 0.0f};
  const float rs[5] = {0.0f, 0.0f, 0.05f, 0.01f, 0.0f};
  for (int i = 0; i < 5; ++i) {
    v[i] = vs[i];
    ref[i] = rs[i];
  }
  mask[3] = 0;
  EXPECT_EQ(compareVisibility(v, ref, mask).umbraLeaks, 1u);
}

TEST(CompareVisibility, SpeckleCountsIsolatedJumpsTheReferenceDoesNotHave) {
  // A lit 7x7 image: the reference has a smooth ramp, the technique the same ramp with one dark speck,
  // one bright speck in a dark block and a one-pixel line across the image. A straight hard edge (half
  // the block dark) is no speckle: the median of a pixel on either side of it is its own side.
  Image<float> ref(7, 7, 1.0f), v(7, 7, 1.0f);
  Image<uint8_t> mask(7, 7, 1);
  for (int y = 0; y < 7; ++y)
    for (int x = 0; x < 7; ++x) ref(x, y) = v(x, y) = 0.5f + 0.01f * static_cast<float>(x);
  v(2, 2) = 0.0f;  // a dark speck in the ramp
  EXPECT_EQ(compareVisibility(v, ref, mask).speckle, 1u);
  for (int x = 0; x < 7; ++x) v(x, 4) = 1.0f;  // a line: each of its 5 inner pixels is 3 of 9 in its block
  EXPECT_EQ(compareVisibility(v, ref, mask).speckle, 1u + 5u);
  // Where the reference jumps too (its own edge), a jump of the technique is not speckle.
  ref(2, 2) = 0.0f;
  EXPECT_EQ(compareVisibility(v, ref, mask).speckle, 5u);
  // A hard edge, in both images: none.
  Image<float> edge(7, 7, 1.0f);
  for (int y = 0; y < 7; ++y)
    for (int x = 0; x < 3; ++x) edge(x, y) = 0.0f;
  EXPECT_EQ(compareVisibility(edge, Image<float>(7, 7, 1.0f), mask).speckle, 0u);
  // Border pixels have no full block and are not counted; masked-out pixels neither.
  Image<float> border(7, 7, 1.0f);
  border(0, 3) = 0.0f;
  border(3, 3) = 0.0f;
  EXPECT_EQ(compareVisibility(border, Image<float>(7, 7, 1.0f), mask).speckle, 1u);
  mask(3, 3) = 0;
  EXPECT_EQ(compareVisibility(border, Image<float>(7, 7, 1.0f), mask).speckle, 0u);
}

TEST(CompareVisibility, PenumbraIntervalIsOpen) {
  // 0.01 and 0.99 themselves are not penumbra values; just inside them are.
  Image<float> v(4, 1), ref(4, 1);
  Image<uint8_t> mask(4, 1, 1);
  v[0] = 0.01f;
  ref[0] = 0.0f;
  v[1] = 0.99f;
  ref[1] = 1.0f;
  v[2] = 0.011f;
  ref[2] = 0.0f;
  v[3] = 1.0f;
  ref[3] = 0.989f;
  const ErrorStats s = compareVisibility(v, ref, mask);
  EXPECT_EQ(s.penumbraPixels, 2u);
  const double e2 = 0.011f, e3 = 1.0f - 0.989f;
  EXPECT_NEAR(s.penumbraRmse8, std::sqrt((e2 * e2 + e3 * e3) / 2.0) * 255.0, 1e-6);
}

TEST(CompareVisibility, IdenticalImagesHaveZeroError) {
  Image<float> v(5, 5, 0.3f);
  Image<uint8_t> mask(5, 5, 1);
  const ErrorStats s = compareVisibility(v, v, mask);
  EXPECT_EQ(s.rmse8, 0.0);
  EXPECT_EQ(s.penumbraRmse8, 0.0);
  EXPECT_EQ(s.maxAbsError, 0.0);
  EXPECT_EQ(s.penumbraPixels, 25u);
}

TEST(CompareVisibility, EmptyMaskReportsZeroPixelsAndNoNan) {
  Image<float> v(2, 2, 0.0f), ref(2, 2, 1.0f);
  Image<uint8_t> mask(2, 2, 0);
  const ErrorStats s = compareVisibility(v, ref, mask);
  EXPECT_EQ(s.maskPixels, 0u);
  EXPECT_EQ(s.rmse8, 0.0);
  EXPECT_EQ(s.penumbraRmse8, 0.0);
}

TEST(CompareVisibility, SizeMismatchIsAnError) {
  Image<float> v(2, 2), ref(3, 2);
  Image<uint8_t> mask(2, 2, 1);
  EXPECT_THROW(compareVisibility(v, ref, mask), Error);
}

// Lawlor 2006, Sec. 2: a straight occluder edge under a distant light symmetric about its centre.
// Seen from a receiver at edge offset u (in light radii, u < 0 inside the hard shadow of the centre
// sample), the occluder hides the part of the light with x > u. The outer half-penumbra truth is the
// visible fraction of the half x > 0 (covered first as the receiver moves into the shadow), the inner
// one that of the half x < 0; both are counted here over a fine grid on the light, independently of
// halfPenumbraTruth's formula, which only sees the full V.
double diskVisibleFraction(double u) {  // closed form: the area of the unit disk with x < u, over pi
  u = std::clamp(u, -1.0, 1.0);
  return (u * std::sqrt(1.0 - u * u) + std::asin(u) + std::numbers::pi / 2.0) / std::numbers::pi;
}

TEST(HalfPenumbraTruth, StraightEdgeUnderADistantDiskLight) {
  constexpr int kOffsets = 41, kGrid = 801;
  Image<float> v(kOffsets, 1);
  for (int i = 0; i < kOffsets; ++i) v(i, 0) = static_cast<float>(diskVisibleFraction(-1.2 + 2.4 * i / (kOffsets - 1)));
  const Image<float> outer = halfPenumbraTruth(v, PenumbraHalf::Outer);
  const Image<float> inner = halfPenumbraTruth(v, PenumbraHalf::Inner);
  for (int i = 0; i < kOffsets; ++i) {
    const double u = -1.2 + 2.4 * i / (kOffsets - 1);
    size_t right = 0, rightVisible = 0, left = 0, leftVisible = 0;
    for (int a = 0; a < kGrid; ++a)
      for (int b = 0; b < kGrid; ++b) {
        const double x = -1.0 + 2.0 * (a + 0.5) / kGrid, y = -1.0 + 2.0 * (b + 0.5) / kGrid;
        if (x * x + y * y > 1.0) continue;
        (x > 0.0 ? right : left) += 1;
        if (x < u) (x > 0.0 ? rightVisible : leftVisible) += 1;
      }
    SCOPED_TRACE(u);
    // Grid error: one column of the half disk, 1/(kGrid/2) of its width, at most ~0.004 of its area.
    EXPECT_NEAR(outer(i, 0), static_cast<double>(rightVisible) / right, 4e-3);
    EXPECT_NEAR(inner(i, 0), static_cast<double>(leftVisible) / left, 4e-3);
    // The halves average to the full truth.
    EXPECT_NEAR(0.5 * (outer(i, 0) + inner(i, 0)), v(i, 0), 1e-6);
  }
}

TEST(HalfPenumbraTruth, StraightEdgeUnderADistantRectLight) {
  // A square light [-1, 1]^2 with the edge parallel to a side: V = (u + 1) / 2 across the penumbra,
  // the outer half's visible fraction is clamp(u, 0, 1) and the inner half's clamp(u + 1, 0, 1).
  for (double u = -1.5; u <= 1.5; u += 0.125) {
    const float v = static_cast<float>(std::clamp((u + 1.0) / 2.0, 0.0, 1.0));
    SCOPED_TRACE(u);
    EXPECT_FLOAT_EQ(halfPenumbraVisibility(v, PenumbraHalf::Outer), static_cast<float>(std::clamp(u, 0.0, 1.0)));
    EXPECT_FLOAT_EQ(halfPenumbraVisibility(v, PenumbraHalf::Inner), static_cast<float>(std::clamp(u + 1.0, 0.0, 1.0)));
  }
}

}  // namespace
}  // namespace penumbra
