// The registry and the harness around it: every registered technique has a valid schema and says how
// it treats the light shapes, and every one survives the inputs the foundation promises not to crash
// on (an empty scene, degenerate triangles, a camera inside an object, every light shape, concave
// polygons included) with a finite V in [0, 1], or refuses a light with an Error naming its shape.
#include "penumbra/registry.h"

#include <cmath>
#include <set>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "core/scene_caches.h"
#include "penumbra/error.h"
#include "penumbra/metrics.h"
#include "penumbra/primitives.h"
#include "penumbra/raster.h"
#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

using testing::makeObject;

// A ground plane and a box above it, lit from above by `light`, seen from above.
Scene groundAndBox(const Light& light) {
  Scene scene;
  scene.objects.push_back(makeObject(0, makePlane(8.0f, 8.0f)));
  Mesh box = makeBox(Vec3(1.0f));
  transformMesh(box, glm::translate(Mat4(1.0f), Vec3(0.0f, 1.5f, 0.0f)));
  scene.objects.push_back(makeObject(1, std::move(box)));
  scene.lights.push_back(light);
  scene.camera.position = Vec3(0.0f, 7.0f, 6.0f);
  scene.camera.lookAt = Vec3(0.0f);
  return scene;
}

std::vector<Light> everyLightShape() {
  return {
      Light::sphere(Vec3(0.5f, 5.0f, 0.0f), 0.5f), Light::disk(Vec3(0.5f, 5.0f, 0.0f), Vec3(0.0f, -1.0f, 0.0f), 0.5f),
      Light::rect(Vec3(0.5f, 5.0f, 0.0f), Vec3(0.5f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 0.3f)),
      Light::segment(Vec3(-0.5f, 5.0f, 0.0f), Vec3(1.0f, 5.0f, 0.0f)),
      Light::polygon({Vec3(0.0f, 5.0f, 0.0f), Vec3(0.5f, 5.0f, 0.8f), Vec3(1.0f, 5.0f, 0.0f)}),
      Light::directional(Vec3(0.1f, 1.0f, 0.0f), radians(5.0f), LightProfile::LimbDarkened),
      // A concave polygon: an L (its centroid on the emitter) and a U (its centroid off it).
      Light::polygon({Vec3(0.0f, 5.0f, 0.0f), Vec3(1.0f, 5.0f, 0.0f), Vec3(1.0f, 5.0f, 0.4f), Vec3(0.4f, 5.0f, 0.4f),
                      Vec3(0.4f, 5.0f, 1.0f), Vec3(0.0f, 5.0f, 1.0f)}),
      Light::polygon({Vec3(0.0f, 5.0f, 0.0f), Vec3(1.2f, 5.0f, 0.0f), Vec3(1.2f, 5.0f, 1.0f), Vec3(0.9f, 5.0f, 1.0f),
                      Vec3(0.9f, 5.0f, 0.2f), Vec3(0.3f, 5.0f, 0.2f), Vec3(0.3f, 5.0f, 1.0f), Vec3(0.0f, 5.0f, 1.0f)})};
}

// Runs a technique with cheap settings; returns V. Techniques that reject a light shape must say
// so with an Error that names the shape they were given; that is the only accepted failure.
bool runCheap(const TechniqueInfo& info, const Scene& scene, const GBuffer& gbuffer, Image<float>& v) {
  ParamSet given;
  if (info.hasParam("spp")) given.set("spp", int64_t{4}, "test");
  if (info.hasParam("samples")) given.set("samples", int64_t{4}, "test");
  if (info.hasParam("map_size")) given.set("map_size", int64_t{64}, "test");
  auto technique = info.create(resolveParams(info.name, info.params, given));
  try {
    technique->prepare(scene, scene.lights.at(0));
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(toString(scene.lights[0].shape())), std::string::npos)
        << info.name << " rejected a light without naming its shape: " << e.what();
    return false;
  }
  technique->visibility(gbuffer, v);
  return true;
}

void expectValidVisibility(const std::string& what, const GBuffer& gbuffer, const Image<float>& v) {
  ASSERT_EQ(v.width(), gbuffer.width()) << what;
  ASSERT_EQ(v.height(), gbuffer.height()) << what;
  size_t bad = 0;
  for (float x : v) bad += !(std::isfinite(x) && x >= 0.0f && x <= 1.0f);
  EXPECT_EQ(bad, 0u) << what << ": V must be finite and in [0, 1]";
  for (int y = 0; y < v.height(); ++y)
    for (int x = 0; x < v.width(); ++x)
      if (!gbuffer.hit(x, y)) {
        ASSERT_EQ(v(x, y), 1.0f) << what << ": a pixel that sees nothing is lit";
      }
}

// Every registered technique runs on the scene with valid V. A technique that refuses the scene's
// light shape (naming it) runs on the same scene under the first shape of everyLightShape() it
// accepts; it must accept one.
void expectEveryTechniqueValid(const Scene& scene, const GBuffer& gbuffer, const std::string& what) {
  for (const TechniqueInfo& info : techniqueRegistry()) {
    Image<float> v;
    bool ran = runCheap(info, scene, gbuffer, v);
    for (const Light& light : everyLightShape()) {
      if (ran) break;
      Scene other = scene;
      other.lights = {light};
      ran = runCheap(info, other, gbuffer, v);
    }
    ASSERT_TRUE(ran) << info.name << " accepts none of the light shapes";
    expectValidVisibility(info.name + " " + what, gbuffer, v);
  }
}

TEST(Registry, NamesAreUniqueAndSchemasResolveToTheirDefaults) {
  std::set<std::string> names;
  for (const TechniqueInfo& info : techniqueRegistry()) {
    EXPECT_TRUE(names.insert(info.name).second) << "duplicate technique " << info.name;
    EXPECT_FALSE(info.summary.empty()) << info.name;
    EXPECT_FALSE(info.source.empty()) << info.name;
    std::set<std::string> params;
    for (const ParamSpec& p : info.params) {
      EXPECT_TRUE(params.insert(p.name).second) << info.name << "." << p.name << " listed twice";
      EXPECT_FALSE(p.help.empty()) << info.name << "." << p.name << " has no help";
    }
    // Every default lies in its own range, so a technique built with no parameters is valid.
    EXPECT_NO_THROW(resolveParams(info.name, info.params, ParamSet{})) << info.name;
    EXPECT_NE(createTechnique(info.name), nullptr);
    EXPECT_EQ(createTechnique(info.name)->name(), info.name);
  }
  for (const char* required : {"reference", "none", "raytraced-hard"}) EXPECT_TRUE(names.count(required)) << required;
}

TEST(Registry, UnknownTechniqueListsTheKnownOnes) {
  try {
    createTechnique("refrence");
    FAIL() << "an unknown name must throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("refrence"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("reference"), std::string::npos);
  }
}

TEST(Registry, EveryTechniqueHandlesEveryLightShape) {
  for (const Light& light : everyLightShape()) {
    const Scene scene = groundAndBox(light);
    const GBuffer gbuffer = renderGBuffer(scene, 48, 40);
    for (const TechniqueInfo& info : techniqueRegistry()) {
      Image<float> v;
      if (runCheap(info, scene, gbuffer, v)) {
        expectValidVisibility(info.name + " with a " + std::string(toString(light.shape())) + " light", gbuffer, v);
      }
    }
  }
}

// TechniqueInfo::tracesRays says which techniques use the scene's shared Embree scene (compare and
// bench build it before timing them, and only when one of them runs): a technique not flagged never
// builds it, and a flagged one does under some light.
TEST(Registry, TracesRaysSaysWhichTechniquesBuildTheSharedRayScene) {
  std::set<std::string> built;
  for (const Light& light : everyLightShape()) {
    for (const TechniqueInfo& info : techniqueRegistry()) {
      Scene scene = groundAndBox(light);
      scene.caches = makeSceneCaches();
      const GBuffer gbuffer = renderGBuffer(scene, 48, 40);
      Image<float> v;
      if (!runCheap(info, scene, gbuffer, v)) continue;
      if (scene.caches->rayScene) built.insert(info.name);
      EXPECT_TRUE(info.tracesRays || !scene.caches->rayScene)
          << info.name << " built the shared Embree scene under a " << toString(light.shape())
          << " light but does not say it traces rays";
    }
  }
  for (const TechniqueInfo& info : techniqueRegistry())
    if (info.tracesRays) {
      EXPECT_TRUE(built.count(info.name)) << info.name << " says it traces rays but never did";
    }
}

TEST(Registry, EveryTechniqueSaysHowItTreatsAConcavePolygonLight) {
  // The line `penumbra techniques` shows; EveryTechniqueHandlesEveryLightShape checks that the
  // technique does run on L- and U-shaped lights, or refuses them naming the shape.
  for (const TechniqueInfo& info : techniqueRegistry()) {
    EXPECT_FALSE(info.lights.empty()) << info.name << " has no line in registry.cpp's lightHandling";
    EXPECT_NE(info.lights.find("polygon"), std::string::npos) << info.name << ": " << info.lights;
  }
}

// Every technique estimates its cost (the CLI's up-front check): finite, and following the
// parameters that set it — a light map's memory grows with its texel count, rays with the pixels.
TEST(Registry, EveryTechniqueEstimatesItsCost) {
  for (const TechniqueInfo& info : techniqueRegistry()) {
    ASSERT_TRUE(info.estimate) << info.name << " has no resource estimate in registry.cpp";
    const Params defaults = resolveParams(info.name, info.params, {});
    const ResourceEstimate e = info.estimate(defaults, 64, 32);
    EXPECT_TRUE(std::isfinite(e.bytes) && e.bytes >= 0.0 && std::isfinite(e.rays) && e.rays >= 0.0 &&
                std::isfinite(e.texels) && e.texels >= 0.0)
        << info.name;
    if (info.hasParam("map_size")) {
      // The map's part alone (an image of no pixels: hybrid adds buffers per pixel).
      ParamSet doubled;
      doubled.set("map_size", int64_t{2048}, "test");
      const ResourceEstimate small = info.estimate(defaults, 0, 0);
      const ResourceEstimate big = info.estimate(resolveParams(info.name, info.params, doubled), 0, 0);
      EXPECT_NEAR(big.bytes, 4.0 * small.bytes, 1e-6 * small.bytes)
          << info.name << ": a map of 2048^2 holds 4x the texels of 1024^2";
      EXPECT_NE(big.drivers.find("map_size=2048"), std::string::npos) << info.name << ": " << big.drivers;
    }
    if (e.rays > 0.0) {
      EXPECT_GE(info.estimate(defaults, 128, 32).rays, 2.0 * e.rays - 1e-9) << info.name;
    }
  }
  const TechniqueInfo& reference = findTechnique("reference");
  EXPECT_EQ(reference.estimate(resolveParams("reference", reference.params, {}), 64, 32).rays, 64.0 * 32.0 * 256.0);
}

TEST(Registry, EmptySceneIsFullyLitForEveryTechnique) {
  Scene scene;
  scene.lights.push_back(Light::sphere(Vec3(0.0f, 5.0f, 0.0f), 0.5f));
  const GBuffer gbuffer = renderGBuffer(scene, 16, 16);
  expectEveryTechniqueValid(scene, gbuffer, "on an empty scene");
}

TEST(Registry, DegenerateTrianglesDoNotBreakAnyTechnique) {
  Scene scene = groundAndBox(Light::sphere(Vec3(0.5f, 5.0f, 0.0f), 0.5f));
  Mesh& box = scene.objects[1].mesh;
  const auto n = static_cast<uint32_t>(box.positions.size());
  box.positions.push_back(Vec3(0.2f, 1.2f, 0.1f));  // a repeated point
  box.positions.push_back(Vec3(0.2f, 1.2f, 0.1f));
  box.positions.push_back(Vec3(0.4f, 1.4f, 0.3f));  // collinear with the two below
  box.positions.push_back(Vec3(0.6f, 1.6f, 0.5f));
  if (!box.normals.empty()) box.normals.resize(box.positions.size(), Vec3(0.0f, 1.0f, 0.0f));
  box.triangles.push_back({n, n + 1, n + 2});  // zero area: two equal corners
  box.triangles.push_back({n, n + 2, n + 3});  // zero area: collinear corners
  box.triangles.push_back({0u, 0u, 0u});       // one vertex three times
  const GBuffer gbuffer = renderGBuffer(scene, 48, 40);
  expectEveryTechniqueValid(scene, gbuffer, "with degenerate triangles");
}

TEST(Registry, CameraInsideAnObject) {
  Scene scene = groundAndBox(Light::sphere(Vec3(0.5f, 5.0f, 0.0f), 0.5f));
  scene.camera.position = Vec3(0.0f, 1.5f, 0.0f);  // the centre of the box
  scene.camera.lookAt = Vec3(0.3f, 1.0f, 0.2f);    // down at the floor
  const GBuffer gbuffer = renderGBuffer(scene, 32, 32);
  size_t hits = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) hits += gbuffer.hit(x, y);
  EXPECT_EQ(hits, 32u * 32u) << "from inside a closed box every pixel sees its inner walls";
  expectEveryTechniqueValid(scene, gbuffer, "with the camera inside a box");
  // Inside the closed box, every wall facing the light (the floor, in the error mask) lies under
  // the roof: the reference and the exact hard shadow put it in full umbra. (Walls facing away from
  // the light are outside the mask, and shading multiplies their V by an irradiance of 0.)
  const Image<uint8_t> mask = errorMask(gbuffer, scene.lights[0]);
  size_t masked = 0;
  for (uint8_t m : mask) masked += m;
  EXPECT_GT(masked, 50u) << "the camera looks down at the box's floor";
  for (const char* name : {"reference", "raytraced-hard"}) {
    Image<float> v;
    ASSERT_TRUE(runCheap(findTechnique(name), scene, gbuffer, v));
    for (size_t i = 0; i < v.size(); ++i)
      if (mask[i]) {
        ASSERT_EQ(v[i], 0.0f) << name << " at pixel " << i;
      }
  }
}

TEST(Registry, ZeroAreaLightsAreRefused) {
  EXPECT_THROW(Light::sphere(Vec3(0.0f), 0.0f), Error);
  EXPECT_THROW(Light::disk(Vec3(0.0f), Vec3(0.0f, 1.0f, 0.0f), 0.0f), Error);
  EXPECT_THROW(Light::rect(Vec3(0.0f), Vec3(1.0f, 0.0f, 0.0f), Vec3(0.0f)), Error);
  EXPECT_THROW(Light::segment(Vec3(1.0f), Vec3(1.0f)), Error);
  EXPECT_THROW(Light::polygon({Vec3(0.0f), Vec3(1.0f, 0.0f, 0.0f), Vec3(2.0f, 0.0f, 0.0f)}), Error);
  EXPECT_THROW(Light::directional(Vec3(0.0f, 1.0f, 0.0f), 0.0f), Error);
}

}  // namespace
}  // namespace penumbra
