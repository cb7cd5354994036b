// Tests of src/io/image_io.cpp: EXR round trip bit-exact; PNGs decodable by an independent
// decoder (stb_image) with the sRGB curve of IEC 61966-2-1 at known values; errors name the path.
#include "penumbra/image_io.h"

#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <unistd.h>

#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include "penumbra/error.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

class ImageIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("penumbra_image_io_" + std::to_string(getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

void expectErrorNaming(const std::function<void()>& f, const std::string& text) {
  try {
    f();
    FAIL() << "expected an Error naming " << text;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

TEST_F(ImageIoTest, ExrRoundTripIsExact) {
  Image<float> v(7, 3);
  for (size_t i = 0; i < v.size(); ++i) v[i] = std::sin(0.37f * static_cast<float>(i)) * 0.5f + 0.5f;
  v(0, 0) = 0.0f;
  v(1, 0) = 1.0f;
  v(2, 0) = 0.123456789f;
  v(3, 0) = std::numeric_limits<float>::denorm_min();
  v(4, 0) = 1.0e30f;
  const std::string file = path("v.exr");
  writeExr(file, v);
  const Image<float> back = readExr(file);
  ASSERT_EQ(back.width(), 7);
  ASSERT_EQ(back.height(), 3);
  for (size_t i = 0; i < v.size(); ++i) EXPECT_EQ(back[i], v[i]) << "pixel " << i;
}

TEST_F(ImageIoTest, PngIsSrgbEncoded) {
  // Linear -> sRGB 8-bit, from the IEC 61966-2-1 curve: 0.5 -> 0.7354 (188), 0.18 -> 0.4614 (118),
  // 0.001 on the linear toe -> 0.01292 (3), 0.0031308 at the knee -> 0.04045 (10); out of range clamps.
  Image<Vec3> rgb(4, 2);
  rgb(0, 0) = Vec3(0.0f, 0.5f, 1.0f);
  rgb(1, 0) = Vec3(0.18f, 0.001f, 0.0031308f);
  rgb(2, 0) = Vec3(2.0f, -1.0f, 0.5f);
  rgb(3, 1) = Vec3(1.0f, 0.0f, 0.0f);
  const std::string file = path("rgb.png");
  writePng(file, rgb);
  int w = 0, h = 0, channels = 0;
  unsigned char* data = stbi_load(file.c_str(), &w, &h, &channels, 3);
  ASSERT_NE(data, nullptr) << stbi_failure_reason();
  EXPECT_EQ(w, 4);
  EXPECT_EQ(h, 2);
  EXPECT_EQ(channels, 3);
  auto px = [&](int x, int y, int c) { return static_cast<int>(data[3 * (y * w + x) + c]); };
  EXPECT_EQ(px(0, 0, 0), 0);
  EXPECT_EQ(px(0, 0, 1), 188);
  EXPECT_EQ(px(0, 0, 2), 255);
  EXPECT_EQ(px(1, 0, 0), 118);
  EXPECT_EQ(px(1, 0, 1), 3);
  EXPECT_EQ(px(1, 0, 2), 10);
  EXPECT_EQ(px(2, 0, 0), 255);
  EXPECT_EQ(px(2, 0, 1), 0);
  EXPECT_EQ(px(3, 1, 0), 255);  // row order: (3, 1) is the last pixel of the second row
  EXPECT_EQ(px(3, 1, 1), 0);
  EXPECT_EQ(px(0, 1, 0), 0);
  stbi_image_free(data);
}

TEST_F(ImageIoTest, GrayPngIsLinear) {
  Image<float> v(3, 1);
  v[0] = 0.0f;
  v[1] = 0.25f;  // 63.75 -> 64
  v[2] = 1.0f;
  const std::string file = path("v.png");
  writePngGray(file, v);
  int w = 0, h = 0, channels = 0;
  unsigned char* data = stbi_load(file.c_str(), &w, &h, &channels, 1);
  ASSERT_NE(data, nullptr) << stbi_failure_reason();
  EXPECT_EQ(channels, 1);
  EXPECT_EQ(data[0], 0);
  EXPECT_EQ(data[1], 64);
  EXPECT_EQ(data[2], 255);
  stbi_image_free(data);
}

TEST_F(ImageIoTest, UnwritablePathsNameThePath) {
  const std::string missingDir = path("no/such/dir/out");
  expectErrorNaming([&] { writePng(missingDir + ".png", Image<Vec3>(2, 2)); }, missingDir + ".png");
  expectErrorNaming([&] { writePngGray(missingDir + "_v.png", Image<float>(2, 2)); }, missingDir + "_v.png");
  expectErrorNaming([&] { writeExr(missingDir + ".exr", Image<float>(2, 2)); }, missingDir + ".exr");
  expectErrorNaming([&] { writePng(path("empty.png"), Image<Vec3>()); }, "empty.png");
}

TEST_F(ImageIoTest, ReadingBadExrNamesThePath) {
  const std::string missing = path("missing.exr");
  expectErrorNaming([&] { readExr(missing); }, missing);
  const std::string notExr = path("not.exr");
  writePngGray(notExr, Image<float>(2, 2, 0.5f));  // a PNG under an .exr name
  expectErrorNaming([&] { readExr(notExr); }, notExr);
}

}  // namespace
}  // namespace penumbra
