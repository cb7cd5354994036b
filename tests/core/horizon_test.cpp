// Tests of core/horizon.h: the light above a receiver's horizon, in closed form per light shape,
// against the light's own samples (Light::sample over a stratified grid), and the clamp of V by it,
// on its own and behind a light-map technique (`horizon`) against the reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "core/horizon.h"

#include "penumbra/metrics.h"
#include "penumbra/primitives.h"
#include "penumbra/raster.h"
#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

// The share of the light's sample weight on the side of the plane through p that ng points to, from
// n x n stratified samples.
double sampledShare(const Light& light, const Vec3& p, const Vec3& ng, int n) {
  const Vec3 normal = ng;
  double above = 0.0, total = 0.0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const LightSample s = light.sample(p, Vec2((static_cast<float>(i) + 0.5f) / static_cast<float>(n),
                                                 (static_cast<float>(j) + 0.5f) / static_cast<float>(n)));
      total += s.weight;
      above += glm::dot(s.wsDirection, normal) > 0.0f ? s.weight : 0.0;
    }
  return above / total;
}

TEST(Horizon, ClosedFormsMatchTheLightsOwnSamples) {
  const struct {
    const char* name;
    Light light;
  } lights[] = {
      {"sphere", Light::sphere(Vec3(0.3f, 3.0f, -0.2f), 0.6f)},
      {"disk", Light::disk(Vec3(-0.4f, 3.0f, 0.5f), glm::normalize(Vec3(0.2f, -1.0f, 0.1f)), 0.7f)},
      {"rect", Light::rect(Vec3(0.5f, 3.0f, 0.2f), Vec3(0.8f, 0.0f, 0.1f), Vec3(-0.0625f, 0.2f, 0.5f))},
      {"L polygon", Light::polygon({Vec3(-1.0f, 3.0f, -1.0f), Vec3(1.0f, 3.0f, -1.0f), Vec3(1.0f, 3.0f, 0.0f),
                                    Vec3(0.0f, 3.0f, 0.0f), Vec3(0.0f, 3.0f, 1.0f), Vec3(-1.0f, 3.0f, 1.0f)})},
      {"segment", Light::segment(Vec3(-0.9f, 3.0f, 0.3f), Vec3(0.8f, 3.2f, -0.4f))},
      {"directional", Light::directional(glm::normalize(Vec3(0.3f, 1.0f, 0.2f)), 0.35f)},
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  for (const auto& [name, light] : lights) {
    double worst = 0.0;
    int straddled = 0;
    for (int k = 0; k < 300; ++k) {
      const Vec3 p(1.5f * unit(rng), 1.2f + 1.2f * unit(rng), 1.5f * unit(rng));
      const Vec3 ng(unit(rng), unit(rng), unit(rng));
      if (glm::length(ng) < 0.1f) continue;
      if (light.shape() == LightShape::Sphere && glm::length(p - light.center()) <= light.radius()) continue;
      const double closed = lightAboveHorizon(light, p, ng);
      const double sampled = sampledShare(light, p, ng, 64);
      worst = std::max(worst, std::abs(closed - sampled));
      straddled += sampled > 0.05 && sampled < 0.95 ? 1 : 0;
      EXPECT_GE(closed, 0.0) << name;
      EXPECT_LE(closed, 1.0) << name;
    }
    std::printf("[ measured ] %s: largest |closed form - 64^2 samples| %.4f over 300 planes, %d of them cutting it\n",
                name, worst, straddled);
    // 64 x 64 stratified samples resolve a straight cut to about a sample row's share, 1/64.
    EXPECT_LT(worst, 0.02) << name;
    EXPECT_GT(straddled, 20) << name << ": the planes must cut the light";
  }
}

TEST(Horizon, PlanesThroughALightGiveTheSharesOnTheirNormalsSide) {
  // A downward disk of radius 0.5 over the origin and a vertical plane x = -0.01, normal +x: the disk
  // beyond the chord at 0.02 radii from its centre, 1 - (acos t - t sqrt(1 - t^2)) / pi.
  const Light disk = Light::disk(Vec3(0.0f, 3.0f, 0.0f), Vec3(0.0f, -1.0f, 0.0f), 0.5f);
  const float t = 0.02f;
  EXPECT_NEAR(lightAboveHorizon(disk, Vec3(-0.01f, 0.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f)),
              1.0f - (std::acos(t) - t * std::sqrt(1.0f - t * t)) / kPi, 1e-5f);
  // A 1 x 1 rect over the origin and vertical planes: through its edge x = 0.5 all of it on the -x side
  // and none on the +x side; through x = 0.25 a quarter on the +x side, three quarters on the -x side;
  // through its centre, half.
  const Light rect = Light::rect(Vec3(0.0f, 3.0f, 0.0f), Vec3(0.5f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 0.5f));
  EXPECT_NEAR(lightAboveHorizon(rect, Vec3(0.5f, 0.0f, 0.0f), Vec3(-1.0f, 0.0f, 0.0f)), 1.0f, 1e-6f);
  EXPECT_NEAR(lightAboveHorizon(rect, Vec3(0.5f, 0.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f)), 0.0f, 1e-6f);
  EXPECT_NEAR(lightAboveHorizon(rect, Vec3(0.25f, 0.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f)), 0.25f, 1e-5f);
  EXPECT_NEAR(lightAboveHorizon(rect, Vec3(0.25f, 0.0f, 0.0f), Vec3(-2.0f, 0.0f, 0.0f)), 0.75f, 1e-5f);
  EXPECT_NEAR(lightAboveHorizon(rect, Vec3(0.0f), Vec3(1.0f, 0.0f, 0.0f)), 0.5f, 1e-5f);
  // Facing the light squarely: all of it; turned away from it: none.
  EXPECT_EQ(lightAboveHorizon(rect, Vec3(0.0f), Vec3(0.0f, 1.0f, 0.0f)), 1.0f);
  EXPECT_EQ(lightAboveHorizon(rect, Vec3(0.0f), Vec3(0.0f, -1.0f, 0.0f)), 0.0f);
  // A segment from x = -1 to 1 and the plane x = 0.5: a quarter of it beyond, three quarters before.
  const Light segment = Light::segment(Vec3(-1.0f, 3.0f, 0.0f), Vec3(1.0f, 3.0f, 0.0f));
  EXPECT_NEAR(lightAboveHorizon(segment, Vec3(0.5f, 0.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f)), 0.25f, 1e-6f);
  EXPECT_NEAR(lightAboveHorizon(segment, Vec3(0.5f, 0.0f, 0.0f), Vec3(-1.0f, 0.0f, 0.0f)), 0.75f, 1e-6f);
}

// A sphere on the ground under a large rect light: on the sphere near its terminator the plane of a
// receiver cuts through the light, and a map seen from the light's centre lights what the sphere's own
// surface half shades.
Scene sphereScene() {
  Scene scene;
  Object ground;
  ground.id = 0;
  ground.name = "ground";
  ground.mesh = makePlane(12.0f, 12.0f);
  Object ball;
  ball.id = 1;
  ball.name = "ball";
  ball.mesh = makeSphere(0.8f, 64, 32);
  transformMesh(ball.mesh, glm::translate(Mat4(1.0f), Vec3(0.0f, 0.8f, 0.0f)));
  scene.objects = {ground, ball};
  scene.lights = {Light::rect(Vec3(0.4f, 3.0f, 0.3f), Vec3(0.9f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 0.9f))};
  scene.camera.position = Vec3(0.0f, 1.6f, 3.6f);
  scene.camera.lookAt = Vec3(0.0f, 0.6f, 0.0f);
  return scene;
}

TEST(Horizon, TheClampLowersTheErrorOfLightMapTechniquesNearATerminatorAndNeverRaisesV) {
  const Scene scene = sphereScene();
  const GBuffer g = renderGBuffer(scene, 96, 96);
  const Image<uint8_t> mask = errorMask(g, scene.lights[0]);
  const Image<float> truth = testing::runTechnique("reference", scene, g, {"spp=256"});
  const Light& light = scene.lights[0];
  for (const char* name : {"hard", "pcss", "plm"}) {
    const Image<float> off = testing::runTechnique(name, scene, g, {"horizon=off"});
    const double before = compareVisibility(off, truth, mask).rmse8;
    for (const char* mode : {"facing", "plane"}) {
      const Image<float> on = testing::runTechnique(name, scene, g, {std::string("horizon=") + mode});
      int lowered = 0;
      for (int y = 0; y < g.height(); ++y)
        for (int x = 0; x < g.width(); ++x) {
          const float a = off(x, y), b = on(x, y);
          ASSERT_LE(b, a) << name << " " << mode;  // the clamp only lowers V
          lowered += b < a ? 1 : 0;
          if (std::string(mode) == "facing" && b < a) {
            // only to 0, and only on a face turned from the light's centre
            EXPECT_EQ(b, 0.0f) << name;
            EXPECT_LT(glm::dot(g.wsGeometricNormal(x, y), light.center() - g.wsPosition(x, y)), 0.0f) << name;
          }
        }
      const double after = compareVisibility(on, truth, mask).rmse8;
      std::printf(
          "[ measured ] sphere under a large rect light, %s: RMSE8 %.2f -> %.2f with horizon=%s, %d pixels "
          "lowered\n",
          name, before, after, mode, lowered);
      EXPECT_GT(lowered, 50) << name << " " << mode;
      EXPECT_LT(after, before) << name << " " << mode;
    }
  }
}

}  // namespace
}  // namespace penumbra
