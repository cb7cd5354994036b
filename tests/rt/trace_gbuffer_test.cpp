// Tests of traceGBuffer (src/rt/trace_gbuffer.cpp) against closed forms: a camera looking straight
// at a plane (every depth equals the distance, positions on the plane where the pixel's ray meets it),
// normals flipped to the camera for back faces, shading normals interpolated from vertex normals,
// misses, and independence from the thread count.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <cstring>

#include "penumbra/error.h"
#include "rt/ray_scene.h"
#include "rt/rt_test_scenes.h"

namespace penumbra {
namespace {

using testing::makeObject;
using testing::makeScene;
using testing::quadMesh;

Scene planeFacing(const Vec3& u, const Vec3& v) {
  Scene s = makeScene({makeObject(5, quadMesh(Vec3(0.0f), u, v), "plane")});
  s.camera.position = Vec3(0.0f, 0.0f, 5.0f);
  s.camera.lookAt = Vec3(0.0f);
  s.camera.up = Vec3(0, 1, 0);
  s.camera.fovYDegrees = 60.0f;
  return s;
}

TEST(TraceGBuffer, PlaneInFrontOfTheCamera) {
  // The plane z = 0 fills the view (half-size 10 against a half-view of 5 tan 30 = 2.9).
  const Scene scene = planeFacing(Vec3(10, 0, 0), Vec3(0, 10, 0));
  const RayScene rays(scene);
  const int w = 16, h = 12;
  const GBuffer g = traceGBuffer(scene, rays, w, h);
  ASSERT_EQ(g.width(), w);
  ASSERT_EQ(g.height(), h);
  const float tanHalf = std::tan(radians(30.0f));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      ASSERT_TRUE(g.hit(x, y));
      EXPECT_EQ(g.objectId(x, y), 5);
      EXPECT_NEAR(g.csDepth(x, y), 5.0f, 1e-5f);  // view depth, not ray length
      // Where the pixel centre's ray meets z = 0: x right, y up, 5 units away.
      const float ndcX = 2.0f * (x + 0.5f) / w - 1.0f, ndcY = 1.0f - 2.0f * (y + 0.5f) / h;
      const Vec3 expected(5.0f * ndcX * tanHalf * w / h, 5.0f * ndcY * tanHalf, 0.0f);
      EXPECT_NEAR(glm::length(g.wsPosition(x, y) - expected), 0.0f, 1e-5f);
      EXPECT_NEAR(g.wsNormal(x, y).z, 1.0f, 1e-6f);
      EXPECT_NEAR(g.wsGeometricNormal(x, y).z, 1.0f, 1e-6f);
      // Triangle 0 lies below the diagonal y = x of the quad (pixels on it may report either).
      if (std::abs(expected.x - expected.y) > 1e-4f) {
        EXPECT_EQ(g.triangleId(x, y), expected.x > expected.y ? 0 : 1);
      }
    }
}

TEST(TraceGBuffer, BackFacesTurnTheirNormalsToTheCamera) {
  // Wound to face -z (away from the camera at z = 5).
  const Scene scene = planeFacing(Vec3(0, 10, 0), Vec3(10, 0, 0));
  ASSERT_NEAR(scene.objects[0].mesh.faceNormal(0).z, -1.0f, 1e-6f);
  const RayScene rays(scene);
  const GBuffer g = traceGBuffer(scene, rays, 4, 4);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      EXPECT_NEAR(g.wsGeometricNormal(x, y).z, 1.0f, 1e-6f);
      EXPECT_NEAR(g.wsNormal(x, y).z, 1.0f, 1e-6f);
    }
}

TEST(TraceGBuffer, ShadingNormalsInterpolateVertexNormals) {
  Scene scene = planeFacing(Vec3(10, 0, 0), Vec3(0, 10, 0));
  Mesh& m = scene.objects[0].mesh;
  // Normals leaning along x with the vertex's x: a "curved" plane whose shading normal varies.
  m.normals = {glm::normalize(Vec3(-1, 0, 2)), glm::normalize(Vec3(1, 0, 2)), glm::normalize(Vec3(1, 0, 2)),
               glm::normalize(Vec3(-1, 0, 2))};
  const RayScene rays(scene);
  const GBuffer g = traceGBuffer(scene, rays, 9, 9);
  for (int y = 0; y < 9; ++y)
    for (int x = 0; x < 9; ++x) {
      // Linear interpolation along x of the two normals (the position's x on the quad is in [-10, 10]).
      const float s = (g.wsPosition(x, y).x + 10.0f) / 20.0f;
      const Vec3 expected = glm::normalize((1.0f - s) * m.normals[0] + s * m.normals[1]);
      EXPECT_NEAR(glm::length(g.wsNormal(x, y) - expected), 0.0f, 1e-5f) << x << "," << y;
      EXPECT_NEAR(g.wsGeometricNormal(x, y).z, 1.0f, 1e-6f);
    }
  // The left half leans left, the right half right.
  EXPECT_LT(g.wsNormal(0, 4).x, 0.0f);
  EXPECT_GT(g.wsNormal(8, 4).x, 0.0f);
}

TEST(TraceGBuffer, MissesAndDepthOfATiltedPlane) {
  // A small square plane tilted about x, seen from above: pixels off it miss, pixels on it report the
  // view depth = distance along the viewing axis of the interpolated position.
  Scene scene = planeFacing(Vec3(1, 0, 0), glm::normalize(Vec3(0, 1, 1)));
  const RayScene rays(scene);
  const GBuffer g = traceGBuffer(scene, rays, 32, 32);
  int hits = 0, misses = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      if (!g.hit(x, y)) {
        ++misses;
        EXPECT_EQ(g.triangleId(x, y), -1);
        EXPECT_EQ(g.csDepth(x, y), kInfinity);
        continue;
      }
      ++hits;
      EXPECT_NEAR(g.csDepth(x, y), 5.0f - g.wsPosition(x, y).z, 1e-5f);
      // On the plane: perpendicular to its normal.
      EXPECT_NEAR(glm::dot(g.wsPosition(x, y), glm::normalize(Vec3(0, -1, 1))), 0.0f, 1e-5f);
    }
  EXPECT_GT(hits, 20);
  EXPECT_GT(misses, 20);
}

TEST(TraceGBuffer, EmptySceneMissesEverywhere) {
  Scene scene = planeFacing(Vec3(1, 0, 0), Vec3(0, 1, 0));
  scene.objects.clear();
  const RayScene rays(scene);
  const GBuffer g = traceGBuffer(scene, rays, 8, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) EXPECT_FALSE(g.hit(x, y));
}

TEST(TraceGBuffer, SameResultOnOneAndTwoThreads) {
  const Scene scene = planeFacing(Vec3(1, 0, 0), glm::normalize(Vec3(0, 1, 1)));
  const RayScene rays(scene);
  GBuffer a, b;
  tbb::task_arena(1).execute([&] { a = traceGBuffer(scene, rays, 24, 16); });
  tbb::task_arena(2).execute([&] { b = traceGBuffer(scene, rays, 24, 16); });
  EXPECT_EQ(std::memcmp(a.wsPosition.data(), b.wsPosition.data(), a.wsPosition.size() * sizeof(Vec3)), 0);
  EXPECT_EQ(std::memcmp(a.csDepth.data(), b.csDepth.data(), a.csDepth.size() * sizeof(float)), 0);
}

TEST(TraceGBuffer, RejectsABadSizeAndMismatchedNormals) {
  Scene scene = planeFacing(Vec3(1, 0, 0), Vec3(0, 1, 0));
  const RayScene rays(scene);
  EXPECT_THROW(traceGBuffer(scene, rays, 0, 4), Error);
  scene.objects[0].mesh.normals = {Vec3(0, 0, 1)};  // one normal for four vertices
  try {
    traceGBuffer(scene, rays, 4, 4);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'plane' has 1 vertex normals for 4 vertices"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace penumbra
