// Tests of `raytraced-hard` (src/techniques/raytraced/raytraced_hard.cpp): V is the exact hard shadow of a
// point light at the light's centre sample, checked against the segment p -> centre crossing a
// rectangle occluder computed by hand, for a local and a directional light.
#include <gtest/gtest.h>

#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "rt/rt_test_scenes.h"

namespace penumbra {
namespace {

using testing::makeObject;
using testing::makeScene;
using testing::pointsGBuffer;
using testing::quadMesh;

// Occluder: [-0.5, 0.5] x [-0.3, 0.3] at z = 2; receiver at z = 0.
Scene occluderScene() {
  return makeScene({makeObject(1, quadMesh(Vec3(0, 0, 2), Vec3(0.5f, 0, 0), Vec3(0, 0.3f, 0)), "occluder"),
                    makeObject(2, quadMesh(Vec3(0.0f), Vec3(20, 0, 0), Vec3(0, 20, 0)), "receiver")});
}

std::vector<float> hardVisibility(const Light& light, const std::vector<Vec3>& points) {
  auto t = createTechnique("raytraced-hard");
  EXPECT_EQ(t->name(), "raytraced-hard");
  t->prepare(occluderScene(), light);
  Image<float> v;
  t->visibility(pointsGBuffer(points, Vec3(0, 0, 1), 2), v);
  std::vector<float> out;
  for (int x = 0; x < v.width(); ++x) out.push_back(v(x, 0));
  return out;
}

TEST(RaytracedHard, LocalLightCentreSegment) {
  // A large rect light centred at (0.4, 0.1, 4): the ray from p crosses z = 2 at (p + c) / 2.
  const Light light = Light::rect(Vec3(0.4f, 0.1f, 4.0f), Vec3(1.5f, 0, 0), Vec3(0, 1.5f, 0));
  std::vector<Vec3> points;
  std::vector<float> expected;
  for (int i = 0; i < 40; ++i) {
    const Vec3 p(-2.0f + 0.1f * i + 0.013f, 0.37f * std::sin(0.7f * i), 0.0f);
    const Vec2 crossing = 0.5f * (Vec2(p.x, p.y) + Vec2(0.4f, 0.1f));
    // Skip points whose crossing is within 1e-3 of the occluder's edge (float ties).
    const float dx = std::abs(crossing.x) - 0.5f, dy = std::abs(crossing.y) - 0.3f;
    if (std::abs(dx) < 1e-3f || std::abs(dy) < 1e-3f) continue;
    points.push_back(p);
    expected.push_back(dx < 0.0f && dy < 0.0f ? 0.0f : 1.0f);
  }
  const auto v = hardVisibility(light, points);
  int shadowed = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(v[i], expected[i]) << "point (" << points[i].x << ", " << points[i].y << ")";
    shadowed += expected[i] == 0.0f;
  }
  EXPECT_GT(shadowed, 3);
  EXPECT_LT(shadowed, static_cast<int>(points.size()) - 3);
}

TEST(RaytracedHard, DirectionalLightCentreDirection) {
  // Sun along (1, 0, 2) / |.| with a 30 degree disk: only its centre direction matters.
  const Light light = Light::directional(Vec3(1, 0, 2), radians(30.0f));
  // The ray from p crosses z = 2 at p.x + 1.
  const std::vector<Vec3> points = {Vec3(-1.0f, 0, 0),  Vec3(-1.45f, 0.2f, 0), Vec3(-0.55f, -0.25f, 0),
                                    Vec3(-1.55f, 0, 0), Vec3(-0.45f, 0, 0),    Vec3(-1.0f, 0.35f, 0)};
  const std::vector<float> expected = {0, 0, 0, 1, 1, 1};
  EXPECT_EQ(hardVisibility(light, points), expected);
}

TEST(RaytracedHard, MissedPixelsAreLitAndTimingsAreReported) {
  auto t = createTechnique("raytraced-hard");
  t->prepare(occluderScene(), Light::sphere(Vec3(0, 0, 4), 0.5f));
  GBuffer g = pointsGBuffer({Vec3(0.0f), Vec3(0.0f)}, Vec3(0, 0, 1), 2);
  g.objectId(1, 0) = kNoObject;
  Image<float> v;
  t->visibility(g, v);
  EXPECT_EQ(v(0, 0), 0.0f);
  EXPECT_EQ(v(1, 0), 1.0f);
  const PassTimings timings = t->timings();
  ASSERT_EQ(timings.passes.size(), 2u);
  EXPECT_EQ(timings.passes[0].first, "prepare");
  EXPECT_EQ(timings.passes[1].first, "visibility");
  EXPECT_TRUE(findTechnique("raytraced-hard").params.empty());
}

TEST(RaytracedHard, VisibilityBeforePrepareIsAnError) {
  auto t = createTechnique("raytraced-hard");
  Image<float> v;
  EXPECT_THROW(t->visibility(GBuffer(2, 2), v), Error);
}

}  // namespace
}  // namespace penumbra
