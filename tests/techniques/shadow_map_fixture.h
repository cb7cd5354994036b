// Shared test data for the shadow-map technique tests (hard, pcf, pcss, multisample, brabec): a
// built-in scene at 512x512 with its rasterized G-buffer, error mask, a reference and the exact hard
// shadow (raytraced-hard), computed once per test process and cached. The paper's setup: the
// techniques run with a 256x256 light map (map_size=256).
// Reference samples: 64 spp (about 1 s per scene on 2 cores, paid once per test executable: ctest
// runs each area's tests in one process, so this cache is shared by all of them). Measured on `torus`, the 64-spp
// reference differs from a 256-spp one by RMSE8 1.3 (penumbra RMSE8 3.8): against the techniques' penumbra errors of 17
// and more it adds under 0.5 in quadrature, far below the margins of the thresholds.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "penumbra/gbuffer.h"
#include "penumbra/metrics.h"
#include "penumbra/primitives.h"
#include "penumbra/raster.h"
#include "penumbra/reference.h"
#include "penumbra/registry.h"
#include "penumbra/scene.h"
#include "penumbra/scene_io.h"

namespace penumbra::testing {

inline constexpr int kShadowTestImageSize = 512;
inline constexpr uint32_t kShadowTestReferenceSpp = 64;

struct ShadowTestScene {
  Scene scene;
  GBuffer gbuffer;
  Image<uint8_t> mask;     //!< errorMask: pixels facing the light
  Image<float> reference;  //!< V of the reference, kShadowTestReferenceSpp
  Image<float> hardTruth;  //!< V of raytraced-hard (the exact hard shadow)
  const Light& light() const { return scene.lights.at(0); }
};

// The cached test data of built-in scene `name` (first light).
inline const ShadowTestScene& shadowTestScene(const std::string& name) {
  static std::map<std::string, std::unique_ptr<ShadowTestScene>> cache;  // test-only cache
  auto it = cache.find(name);
  if (it != cache.end()) return *it->second;
  auto s = std::make_unique<ShadowTestScene>();
  s->scene = loadScene(name);
  s->gbuffer = renderGBuffer(s->scene, kShadowTestImageSize, kShadowTestImageSize);
  s->mask = errorMask(s->gbuffer, s->light());
  ReferenceTechnique reference(ReferenceOptions{kShadowTestReferenceSpp, 1});
  reference.prepare(s->scene, s->light());
  reference.visibility(s->gbuffer, s->reference);
  auto hard = createTechnique("raytraced-hard");
  hard->prepare(s->scene, s->light());
  hard->visibility(s->gbuffer, s->hardTruth);
  return *cache.emplace(name, std::move(s)).first->second;
}

// Runs technique `name` with "key=value" parameters on `gbuffer`, lit by the scene's first light.
inline Image<float> runTechnique(const std::string& name, const Scene& scene, const GBuffer& gbuffer,
                                 const std::vector<std::string>& keyValues = {}) {
  ParamSet given;
  for (const std::string& kv : keyValues) given.setFromKeyValue(kv, "test");
  auto technique = createTechnique(name, given);
  technique->prepare(scene, scene.lights.at(0));
  Image<float> v;
  technique->visibility(gbuffer, v);
  return v;
}

// Runs technique `name` with "key=value" parameters on the test scene's G-buffer.
inline Image<float> runTechnique(const std::string& name, const ShadowTestScene& s,
                                 const std::vector<std::string>& keyValues = {}) {
  return runTechnique(name, s.scene, s.gbuffer, keyValues);
}

// An object with id `id`, named after it, made of `mesh`.
inline Object makeObject(int32_t id, Mesh mesh) {
  Object o;
  o.name = "object" + std::to_string(id);
  o.id = id;
  o.mesh = std::move(mesh);
  return o;
}

// The straight-edge setup of Lawlor 2006's exactness claim: an 8 x 8 ground at y = 0 and, `height`
// above it, a horizontal rectangle covering x < edgeX (|z| < 3), under a directional disk light of
// `angleDegrees` straight down.
inline Scene straightEdgeScene(float edgeX, float height, float angleDegrees,
                               LightProfile profile = LightProfile::Uniform) {
  Scene scene;
  Object ground;
  ground.name = "ground";
  ground.id = 0;
  ground.mesh = makePlane(8.0f, 8.0f);
  Object occluder;
  occluder.name = "occluder";
  occluder.id = 1;
  occluder.mesh.positions = {Vec3(-3.0f, height, -3.0f), Vec3(edgeX, height, -3.0f), Vec3(edgeX, height, 3.0f),
                             Vec3(-3.0f, height, 3.0f)};
  occluder.mesh.triangles = {{0u, 2u, 1u}, {0u, 3u, 2u}};  // wound to face +y, the light
  scene.objects = {ground, occluder};
  scene.lights.push_back(Light::directional(Vec3(0.0f, 1.0f, 0.0f), radians(angleDegrees), profile));
  return scene;
}

// A G-buffer of n points evenly spaced from a to b on an upward-facing receiver (object id 0): a
// scan line across a shadow edge on the ground, independent of the camera.
inline GBuffer groundLineGBuffer(const Vec3& a, const Vec3& b, int n) {
  GBuffer g(n, 1);
  for (int i = 0; i < n; ++i) {
    g.wsPosition(i, 0) = a + (b - a) * (static_cast<float>(i) / static_cast<float>(n - 1));
    g.wsNormal(i, 0) = g.wsGeometricNormal(i, 0) = Vec3(0.0f, 1.0f, 0.0f);
    g.objectId(i, 0) = 0;
    g.triangleId(i, 0) = 0;
    g.csDepth(i, 0) = 1.0f;
  }
  return g;
}

inline ErrorStats errorAgainstReference(const Image<float>& v, const ShadowTestScene& s) {
  return compareVisibility(v, s.reference, s.mask);
}

}  // namespace penumbra::testing
