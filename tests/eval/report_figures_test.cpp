// Tests of src/eval/report_figures.cpp: the diverging colour map is white at 0, ColorBrewer's RdBu
// end colours at -1/+1 (blue below the reference, red above), saturates beyond, and darkens
// monotonically away from 0 on each side; a signed error map written as PNG reads back as exactly
// the colour map's bytes; the scan-line choice counts reference penumbra pixels inside the mask.
#include "eval/report_figures.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#include <stb/stb_image.h>

#include "penumbra/error.h"
#include "penumbra/image_io.h"

namespace penumbra {
namespace {

double luminance(const Srgb8& c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

TEST(ReportFigures, DivergingMapEndsAndCentre) {
  EXPECT_EQ(divergingColor(0.0), (Srgb8{0xf7, 0xf7, 0xf7}));
  EXPECT_EQ(divergingColor(-1.0), (Srgb8{0x05, 0x30, 0x61}));  // RdBu's darkest blue
  EXPECT_EQ(divergingColor(1.0), (Srgb8{0x67, 0x00, 0x1f}));   // RdBu's darkest red
  // Beyond the range the map saturates at its ends (the legend says so).
  EXPECT_EQ(divergingColor(-3.0), divergingColor(-1.0));
  EXPECT_EQ(divergingColor(7.0), divergingColor(1.0));
  EXPECT_EQ(divergingColor(std::numeric_limits<double>::quiet_NaN()), unmeasuredColor());
  // Negative errors are blue, positive red.
  const Srgb8 below = divergingColor(-0.5), above = divergingColor(0.5);
  EXPECT_GT(below[2], below[0]);
  EXPECT_GT(above[0], above[2]);
}

TEST(ReportFigures, DivergingMapDarkensAwayFromZero) {
  double previousNeg = luminance(divergingColor(0.0)), previousPos = previousNeg;
  for (int i = 1; i <= 100; ++i) {
    const double t = i / 100.0;
    const double neg = luminance(divergingColor(-t)), pos = luminance(divergingColor(t));
    EXPECT_LE(neg, previousNeg + 1e-9) << t;
    EXPECT_LE(pos, previousPos + 1e-9) << t;
    previousNeg = neg;
    previousPos = pos;
  }
  // The grey of unmeasured pixels is not a colour of the map: no error reads as "not measured".
  for (int i = -100; i <= 100; ++i) EXPECT_NE(divergingColor(i / 100.0), unmeasuredColor()) << i;
}

TEST(ReportFigures, SignedErrorMapPngHoldsTheColourMapBytes) {
  Image<float> reference(5, 1, 0.5f), v(5, 1, 0.5f);
  Image<uint8_t> mask(5, 1, 1);
  const double range = 0.25;
  v(1, 0) = 0.5f + 0.25f;   // +range: the red end
  v(2, 0) = 0.5f - 0.125f;  // -range/2
  v(3, 0) = 1.0f;           // +2 range: saturated red
  mask(4, 0) = 0;           // not measured
  const auto path =
      std::filesystem::temp_directory_path() / ("penumbra_error_map_" + std::to_string(getpid()) + ".png");
  writePng(path.string(), signedErrorMap(v, reference, mask, range));
  int w = 0, h = 0, channels = 0;
  unsigned char* bytes = stbi_load(path.string().c_str(), &w, &h, &channels, 3);
  std::filesystem::remove(path);
  ASSERT_NE(bytes, nullptr);
  ASSERT_EQ(w, 5);
  ASSERT_EQ(h, 1);
  const Srgb8 expected[] = {divergingColor(0.0), divergingColor(1.0), divergingColor(-0.5), divergingColor(1.0),
                            unmeasuredColor()};
  for (int x = 0; x < 5; ++x)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(bytes[3 * x + c], expected[x][c]) << "pixel " << x << " channel " << c;
  stbi_image_free(bytes);
}

TEST(ReportFigures, SignedErrorMapRejectsBadInput) {
  Image<float> a(4, 4, 0.0f), b(4, 3, 0.0f);
  Image<uint8_t> mask(4, 4, 1);
  for (double range : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()}) {
    try {
      signedErrorMap(a, a, mask, range);
      FAIL() << range;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("range"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(signedErrorMap(a, b, mask, 0.5), Error);
}

TEST(ReportFigures, MostPenumbraRowCountsMaskedPenumbraPixels) {
  Image<float> reference(8, 6, 1.0f);
  Image<uint8_t> mask(8, 6, 1);
  for (int x = 0; x < 3; ++x) reference(x, 1) = 0.5f;  // 3 penumbra pixels in row 1
  for (int x = 0; x < 5; ++x) reference(x, 4) = 0.3f;  // 5 in row 4, but two of them unmasked
  mask(0, 4) = mask(1, 4) = 0;
  for (int x = 0; x < 8; ++x) reference(x, 5) = 0.0f;  // umbra: not penumbra
  EXPECT_EQ(mostPenumbraRow(reference, mask), 1);      // 3 vs 3: the topmost row wins the tie
  mask(1, 4) = 1;
  EXPECT_EQ(mostPenumbraRow(reference, mask), 4);  // 4 vs 3
  // No penumbra anywhere: the middle row.
  EXPECT_EQ(mostPenumbraRow(Image<float>(8, 6, 1.0f), mask), 3);
  EXPECT_THROW(mostPenumbraRow(Image<float>(8, 5, 1.0f), mask), Error);
}

}  // namespace
}  // namespace penumbra
