// penumbra/engine.h: the engine's arrays into a scene and a G-buffer. A G-buffer handed over as arrays
// and back is penumbra's own, field for field, and a technique gives the same V on it; bad buffers and
// meshes are refused with messages naming what is wrong.
#include "penumbra/engine.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "penumbra/error.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

// The objects of a scene as the engine's meshes (arrays owned by `storage`).
std::vector<EngineMesh> meshesOf(const Scene& scene, std::vector<std::vector<float>>& positions,
                                 std::vector<std::vector<uint32_t>>& indices) {
  std::vector<EngineMesh> meshes;
  positions.clear();
  indices.clear();
  for (const Object& o : scene.objects) {
    std::vector<float>& p = positions.emplace_back();
    for (const Vec3& v : o.mesh.positions) p.insert(p.end(), {v.x, v.y, v.z});
    std::vector<uint32_t>& t = indices.emplace_back();
    for (const glm::uvec3& tri : o.mesh.triangles) t.insert(t.end(), {tri.x, tri.y, tri.z});
  }
  for (size_t k = 0; k < scene.objects.size(); ++k) meshes.push_back({scene.objects[k].id, positions[k], indices[k]});
  return meshes;
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Engine, ArraysAndBackAreTheGBufferAndTheVOfPenumbrasOwn) {
  const Scene original = loadScene("torus");
  std::vector<std::vector<float>> positions;
  std::vector<std::vector<uint32_t>> indices;
  const std::vector<EngineMesh> meshes = meshesOf(original, positions, indices);
  const Scene scene = makeScene(meshes, original.camera, original.lights[0]);
  ASSERT_EQ(scene.objects.size(), original.objects.size());
  EXPECT_EQ(scene.triangleCount(), original.triangleCount());

  const GBuffer own = renderGBuffer(original, 97, 61);  // any size, odd on purpose
  std::vector<float> p, n;
  for (const Vec3& v : own.wsPosition) p.insert(p.end(), {v.x, v.y, v.z});
  for (const Vec3& v : own.wsNormal) n.insert(n.end(), {2.0f * v.x, 2.0f * v.y, 2.0f * v.z});  // not unit
  std::vector<float> gn;
  for (const Vec3& v : own.wsGeometricNormal) gn.insert(gn.end(), {v.x, v.y, v.z});
  EngineGBuffer buffers;
  buffers.wsGeometricNormal = gn;
  buffers.width = own.width();
  buffers.height = own.height();
  buffers.wsPosition = p;
  buffers.wsNormal = n;
  buffers.objectId = std::span<const int32_t>(own.objectId.data(), own.objectId.size());
  const GBuffer g = makeGBuffer(buffers, original.camera, meshes);
  size_t hits = 0;
  for (int y = 0; y < own.height(); ++y)
    for (int x = 0; x < own.width(); ++x) {
      ASSERT_EQ(g.objectId(x, y), own.objectId(x, y));
      if (!own.hit(x, y)) continue;
      ++hits;
      EXPECT_EQ(g.wsPosition(x, y), own.wsPosition(x, y));
      EXPECT_LT(glm::length(g.wsNormal(x, y) - own.wsNormal(x, y)), 1e-6f);
      EXPECT_NEAR(g.csDepth(x, y), own.csDepth(x, y), 1e-4f * own.csDepth(x, y));
    }
  EXPECT_GT(hits, 1000u);

  // The techniques read positions, normals and ids: the same V (normals renormalized may move by an
  // ulp, which may move a pixel's V by as little).
  for (const char* name : {"hard", "pcss", "brabec"}) {
    auto a = createTechnique(name), b = createTechnique(name);
    Image<float> va, vb;
    a->prepare(original, original.lights[0]);
    a->visibility(own, va);
    b->prepare(scene, scene.lights[0]);
    b->visibility(g, vb);
    size_t differ = 0;
    for (size_t i = 0; i < va.size(); ++i) differ += std::abs(va[i] - vb[i]) > 0.1f;
    EXPECT_EQ(differ, 0u) << name;
  }
}

TEST(Engine, NormalsTurnTowardsTheCamera) {
  const Scene original = loadScene("torus");
  std::vector<std::vector<float>> positions;
  std::vector<std::vector<uint32_t>> indices;
  const std::vector<EngineMesh> meshes = meshesOf(original, positions, indices);
  const GBuffer own = renderGBuffer(original, 32, 32);
  std::vector<float> p, n;
  for (const Vec3& v : own.wsPosition) p.insert(p.end(), {v.x, v.y, v.z});
  for (const Vec3& v : own.wsNormal) n.insert(n.end(), {-v.x, -v.y, -v.z});  // facing away
  EngineGBuffer buffers{32, 32, p, n, std::span<const int32_t>(own.objectId.data(), own.objectId.size()), {}, {}};
  const GBuffer g = makeGBuffer(buffers, original.camera, meshes);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x)
      if (own.hit(x, y)) {
        EXPECT_LT(glm::length(g.wsNormal(x, y) - own.wsNormal(x, y)), 1e-6f);
      }
}

TEST(Engine, BadMeshesAndBuffersAreRefusedByName) {
  const std::vector<float> tri = {0, 0, 0, 1, 0, 0, 0, 0, 1};
  const std::vector<uint32_t> ok = {0, 1, 2}, bad = {0, 1, 5};
  Camera camera;
  const Light light = Light::sphere(Vec3(0, 4, 0), 0.5f);
  EXPECT_NE(messageOf([&] {
              makeScene({{0, tri, bad}}, camera, light);
            }).find("engine mesh 0 (id 0): triangle 0 indexes vertex 5: expected indices below its 3 vertices"),
            std::string::npos);
  EXPECT_NE(messageOf([&] {
              makeScene({{0, tri, ok}, {0, tri, ok}}, camera, light);
            }).find("engine mesh 1: id 0"),
            std::string::npos);
  EXPECT_NE(messageOf([&] {
              makeScene({{-3, tri, ok}}, camera, light);
            }).find("id -3 is not valid"),
            std::string::npos);
  const std::vector<float> nan = {0, 0, 0, std::numeric_limits<float>::quiet_NaN(), 0, 0, 0, 0, 1};
  EXPECT_NE(messageOf([&] {
              makeScene({{0, nan, ok}}, camera, light);
            }).find("vertex 1 is not finite"),
            std::string::npos);

  const std::vector<EngineMesh> meshes = {{0, tri, ok}};
  std::vector<float> p = {0.2f, 0.0f, 0.2f}, n = {0.0f, 1.0f, 0.0f};
  std::vector<int32_t> id = {0};
  EngineGBuffer b{1, 1, p, n, id, {}, {}};
  EXPECT_NO_THROW(makeGBuffer(b, camera, meshes));
  id[0] = 7;
  EXPECT_NE(messageOf([&] {
              makeGBuffer(b, camera, meshes);
            }).find("objectId at pixel (0, 0) is 7: expected kNoObject (-1) or the id of one of the 1 meshes"),
            std::string::npos);
  id[0] = 0;
  n = {0.0f, 0.0f, 0.0f};
  EXPECT_NE(messageOf([&] { makeGBuffer(b, camera, meshes); }).find("wsNormal at pixel (0, 0)"), std::string::npos);
  n = {0.0f, 1.0f, 0.0f};
  p[1] = std::numeric_limits<float>::infinity();
  EXPECT_NE(messageOf([&] { makeGBuffer(b, camera, meshes); }).find("wsPosition at pixel (0, 0) is not finite"),
            std::string::npos);
  p[1] = 0.0f;
  const std::vector<float> behind = {-1.0f};
  b.csDepth = behind;
  EXPECT_NE(messageOf([&] { makeGBuffer(b, camera, meshes); }).find("csDepth at pixel (0, 0) is -1"),
            std::string::npos);
  b.csDepth = {};
  b.wsNormal = {};
  EXPECT_NE(messageOf([&] { makeGBuffer(b, camera, meshes); }).find("wsNormal is missing"), std::string::npos);
  const std::vector<float> shortNormals = {0.0f, 1.0f};
  b.wsNormal = shortNormals;
  EXPECT_NE(messageOf([&] { makeGBuffer(b, camera, meshes); }).find("wsNormal holds 2 values: expected 3"),
            std::string::npos);
  b.wsNormal = n;
  b.width = 0;
  EXPECT_NE(messageOf([&] { makeGBuffer(b, camera, meshes); }).find("engine G-buffer"), std::string::npos);
}

}  // namespace
}  // namespace penumbra
