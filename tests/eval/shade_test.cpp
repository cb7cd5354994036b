// Tests of src/eval/shade.cpp: radiance = albedo * (ambient + E * V), exposure-normalized, against
// values computed by hand for a directional light (E = intensity * cos theta, exact).
#include "penumbra/shade.h"

#include <cmath>

#include <gtest/gtest.h>

#include "penumbra/error.h"

namespace penumbra {
namespace {

constexpr float kTol = 1e-5f;

void expectVec(const Vec3& expected, const Vec3& actual) {
  EXPECT_NEAR(expected.x, actual.x, kTol);
  EXPECT_NEAR(expected.y, actual.y, kTol);
  EXPECT_NEAR(expected.z, actual.z, kTol);
}

Scene oneObjectScene(float intensity) {
  Scene scene;
  scene.name = "test";
  Object object;
  object.id = 7;
  object.albedo = Vec3(0.5f, 0.25f, 1.0f);
  scene.objects.push_back(object);
  Light sun = Light::directional(Vec3(0.0f, 1.0f, 0.0f), radians(1.0f));
  sun.setIntensity(intensity);
  scene.lights.push_back(sun);
  scene.ambient = 0.1f;
  return scene;
}

TEST(Shade, HandComputedRadiance) {
  const Scene scene = oneObjectScene(2.0f);
  GBuffer g(4, 1);
  const float c60 = std::cos(radians(60.0f));
  for (int x = 0; x < 3; ++x) g.objectId(x, 0) = 7;
  g.wsNormal(0, 0) = Vec3(0.0f, 1.0f, 0.0f);                     // E = 2, V = 1
  g.wsNormal(1, 0) = Vec3(0.0f, 1.0f, 0.0f);                     // E = 2, V = 0
  g.wsNormal(2, 0) = Vec3(std::sin(radians(60.0f)), c60, 0.0f);  // E = 1, V = 1
  Image<float> v(4, 1, 1.0f);
  v(1, 0) = 0.0f;
  ShadeOptions options;
  options.exposureQuantile = 1.0;
  options.background = Vec3(0.1f, 0.2f, 0.3f);
  const Image<Vec3> rgb = shade(scene, scene.lights[0], g, v, options);
  // Peak E = 2, so ambient = 0.1 * 2 = 0.2; the brightest unshadowed radiance (max channel, albedo
  // 1) is 0.2 + 2 = 2.2, which exposure maps to 1.
  const Vec3 albedo(0.5f, 0.25f, 1.0f);
  expectVec(albedo * (0.2f + 2.0f) / 2.2f, rgb(0, 0));
  expectVec(albedo * 0.2f / 2.2f, rgb(1, 0));
  expectVec(albedo * (0.2f + 1.0f) / 2.2f, rgb(2, 0));
  expectVec(options.background, rgb(3, 0));
}

TEST(Shade, ExposureQuantileIgnoresAFewHotPixels) {
  // 100 receivers at E = 1 and one hot pixel at E = 2: with the 0.99 quantile the receivers are
  // exposed to exactly their albedo (not clipped, not darkened by the hot pixel), which clips.
  const Scene scene = oneObjectScene(2.0f);
  GBuffer g(101, 1);
  for (int x = 0; x < 101; ++x) {
    g.objectId(x, 0) = 7;
    g.wsNormal(x, 0) = Vec3(std::sin(radians(60.0f)), std::cos(radians(60.0f)), 0.0f);
  }
  g.wsNormal(50, 0) = Vec3(0.0f, 1.0f, 0.0f);
  const Image<float> v(101, 1, 1.0f);
  const Image<Vec3> rgb = shade(scene, scene.lights[0], g, v);
  // Peak E = 1 -> ambient 0.1, white = 1 * (0.1 + 1).
  expectVec(Vec3(0.5f, 0.25f, 1.0f), rgb(0, 0));
  EXPECT_NEAR(rgb(50, 0).z, (0.1f + 2.0f) / 1.1f, kTol);
}

TEST(Shade, LinearInVisibility) {
  const Scene scene = oneObjectScene(1.0f);
  GBuffer g(3, 1);
  for (int x = 0; x < 3; ++x) {
    g.objectId(x, 0) = 7;
    g.wsNormal(x, 0) = Vec3(0.0f, 1.0f, 0.0f);
  }
  Image<float> v(3, 1);
  v[0] = 0.0f;
  v[1] = 0.5f;
  v[2] = 1.0f;
  const Image<Vec3> rgb = shade(scene, scene.lights[0], g, v);
  expectVec(0.5f * (rgb[0] + rgb[2]), rgb[1]);
}

TEST(Shade, NothingHitGivesBackground) {
  const Scene scene = oneObjectScene(1.0f);
  const GBuffer g(3, 2);
  const Image<Vec3> rgb = shade(scene, scene.lights[0], g, Image<float>(3, 2, 1.0f));
  for (const Vec3& c : rgb) expectVec(ShadeOptions{}.background, c);
}

TEST(Shade, BadInputIsAnError) {
  const Scene scene = oneObjectScene(1.0f);
  GBuffer g(2, 1);
  g.objectId(0, 0) = 3;  // not in the scene
  EXPECT_THROW(shade(scene, scene.lights[0], g, Image<float>(2, 1, 1.0f)), Error);
  g.objectId(0, 0) = 7;
  EXPECT_THROW(shade(scene, scene.lights[0], g, Image<float>(1, 1, 1.0f)), Error);
  ShadeOptions options;
  options.exposureQuantile = 0.0;
  EXPECT_THROW(shade(scene, scene.lights[0], g, Image<float>(2, 1, 1.0f), options), Error);
}

}  // namespace
}  // namespace penumbra
