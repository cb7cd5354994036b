// Hostile geometry: every registered technique (the registry is iterated, so a newly registered one
// is covered without touching this file) survives inputs that break naive soft-shadow code — zero-area
// and sliver triangles, duplicated vertices and triangles, non-manifold edges, open meshes, non-finite
// vertices built in code, a light inside an object, a light touching a receiver, a camera looking
// away from everything, a 1x1 image and 10^6 tiny triangles — with V finite and in [0, 1], V = 1
// where the pixel sees nothing, and no crash. Where a closed form exists (a light sealed in a box, a
// camera that sees nothing) the output is checked against it. Image sizes over the limit of
// include/penumbra/scene.h (16384 x 16384) are refused before anything is allocated.
//
// The accepted refusal: a technique that does not support a light shape throws an Error naming the
// shape (it then runs with another shape: every technique must accept at least one). No technique
// refuses a mesh for its topology (open, non-manifold, inconsistently wound, repeated triangles):
// ssv and wedges, whose papers assume closed 2-manifolds, take any mesh as a closed oriented
// surface (mesh_topology.h), and they shadow a soup of a box's repeated triangles exactly as the box.
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "penumbra/error.h"
#include "penumbra/metrics.h"
#include "penumbra/primitives.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "rt/ray_scene.h"
#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

using testing::makeObject;

Mesh translated(Mesh mesh, const Vec3& offset) {
  transformMesh(mesh, glm::translate(Mat4(1.0f), offset));
  return mesh;
}

// Lights of every shape around `center` (extent about `size`), facing down: each technique runs with
// every one of them it supports.
std::vector<Light> lightsAround(const Vec3& center, float size) {
  return {Light::sphere(center, size),
          Light::disk(center, Vec3(0.0f, -1.0f, 0.0f), size),
          Light::rect(center, Vec3(size, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 0.6f * size)),
          Light::polygon(
              {center + Vec3(-size, 0.0f, 0.0f), center + Vec3(0.0f, 0.0f, size), center + Vec3(size, 0.0f, 0.0f)}),
          Light::segment(center - Vec3(size, 0.0f, 0.0f), center + Vec3(size, 0.0f, 0.0f)),
          Light::directional(center, radians(4.0f))};
}

ParamSet cheapParams(const TechniqueInfo& info) {
  ParamSet given;
  if (info.hasParam("spp")) given.set("spp", int64_t{4}, "test");
  if (info.hasParam("samples")) given.set("samples", int64_t{4}, "test");
  if (info.hasParam("map_size")) given.set("map_size", int64_t{64}, "test");
  return given;
}

void expectValidVisibility(const std::string& what, const GBuffer& gbuffer, const Image<float>& v) {
  ASSERT_EQ(v.width(), gbuffer.width()) << what;
  ASSERT_EQ(v.height(), gbuffer.height()) << what;
  size_t bad = 0;
  for (float x : v) bad += !(std::isfinite(x) && x >= 0.0f && x <= 1.0f);
  EXPECT_EQ(bad, 0u) << what << ": V must be finite and in [0, 1]";
  size_t litMisses = 0, misses = 0;
  for (int y = 0; y < v.height(); ++y)
    for (int x = 0; x < v.width(); ++x)
      if (!gbuffer.hit(x, y)) {
        ++misses;
        litMisses += v(x, y) == 1.0f;
      }
  EXPECT_EQ(litMisses, misses) << what << ": a pixel that sees nothing must have V = 1";
}

// What one technique did with one light.
struct TechniqueRun {
  std::string technique;
  Light light;
  bool ran = false;
  std::string refusal;  //!< the Error message when it refused
  Image<float> v;
};

// Runs every registered technique with every light of `lights` on the scene `makeScene(light)`
// (whose geometry and camera must not depend on the light: one G-buffer serves all). Checks that
// each output is valid, that refusals name the light's shape, and that every technique ran with at
// least one light. Returns every run.
std::vector<TechniqueRun> runEveryTechnique(const std::function<Scene(const Light&)>& makeScene,
                                            const std::vector<Light>& lights, const GBuffer& gbuffer,
                                            const std::string& what, bool everyLight = true) {
  std::vector<TechniqueRun> runs;
  for (const TechniqueInfo& info : techniqueRegistry()) {
    bool anyRan = false;
    for (const Light& light : lights) {
      const Scene scene = makeScene(light);
      TechniqueRun run{info.name, light, false, {}, {}};
      auto technique = info.create(resolveParams(info.name, info.params, cheapParams(info)));
      const std::string label = info.name + " with a " + std::string(toString(light.shape())) + " light " + what;
      try {
        technique->prepare(scene, light);
        technique->visibility(gbuffer, run.v);
        run.ran = true;
      } catch (const Error& e) {
        run.refusal = e.what();
        EXPECT_NE(run.refusal.find(toString(light.shape())), std::string::npos)
            << label << ": refused with an Error that is not about the light shape: " << run.refusal;
      }
      if (run.ran) {
        expectValidVisibility(label, gbuffer, run.v);
        anyRan = true;
      }
      runs.push_back(std::move(run));
      if (anyRan && !everyLight) break;
    }
    EXPECT_TRUE(anyRan) << info.name << " " << what << ": accepted none of the light shapes";
  }
  return runs;
}

const TechniqueRun* findRun(const std::vector<TechniqueRun>& runs, const std::string& technique, LightShape shape) {
  for (const TechniqueRun& r : runs)
    if (r.technique == technique && r.light.shape() == shape && r.ran) return &r;
  return nullptr;
}

// A ground plane, seen from above and in front, with `occluder` as object 1.
Scene groundWith(Mesh occluder, const Light& light) {
  Scene scene;
  scene.objects.push_back(makeObject(0, makePlane(8.0f, 8.0f)));
  scene.objects.push_back(makeObject(1, std::move(occluder)));
  scene.lights.push_back(light);
  scene.camera.position = Vec3(0.0f, 6.0f, 5.0f);
  scene.camera.lookAt = Vec3(0.0f, 0.5f, 0.0f);
  return scene;
}

const Vec3 kLightCenter(0.4f, 5.0f, 0.2f);

// Runs every technique on ground + occluder with every light shape above it.
std::vector<TechniqueRun> runOnGround(const Mesh& occluder, const std::string& what) {
  const std::vector<Light> lights = lightsAround(kLightCenter, 0.5f);
  const auto make = [&](const Light& light) { return groundWith(occluder, light); };
  const GBuffer gbuffer = renderGBuffer(make(lights[0]), 40, 32);
  return runEveryTechnique(make, lights, gbuffer, what);
}

TEST(HostileGeometry, ZeroAreaAndSliverTriangles) {
  Mesh m;
  // Slivers: 2 units long, 1e-5 wide (about 1e-4 of a pixel here), some standing on edge towards the light.
  for (int i = 0; i < 8; ++i) {
    const float x = -1.0f + 0.25f * static_cast<float>(i);
    const auto n = static_cast<uint32_t>(m.positions.size());
    m.positions.push_back(Vec3(x, 1.0f, -1.0f));
    m.positions.push_back(Vec3(x + 1e-5f, 1.0f, 1.0f));
    m.positions.push_back(Vec3(x, 1.0f + (i % 2 ? 0.0f : 1e-5f), 1.0f));
    m.triangles.push_back({n, n + 1, n + 2});
  }
  // Zero area: a point three times, two equal corners, collinear corners, and a needle along the light's axis.
  const auto n = static_cast<uint32_t>(m.positions.size());
  m.positions.push_back(Vec3(0.3f, 1.2f, 0.1f));
  m.positions.push_back(Vec3(0.3f, 1.2f, 0.1f));
  m.positions.push_back(Vec3(0.5f, 1.4f, 0.3f));
  m.positions.push_back(Vec3(0.7f, 1.6f, 0.5f));
  m.positions.push_back(Vec3(0.4f, 3.0f, 0.2f));
  m.positions.push_back(Vec3(0.4f, 0.5f, 0.2f));
  m.triangles.push_back({n, n, n});
  m.triangles.push_back({n, n + 1, n + 2});
  m.triangles.push_back({n, n + 2, n + 3});
  m.triangles.push_back({n + 4, n + 5, n + 4});
  // A real occluder among them, so the techniques have a shadow to draw.
  const Mesh box = translated(makeBox(Vec3(0.6f)), Vec3(-0.8f, 1.2f, 0.0f));
  const auto b = static_cast<uint32_t>(m.positions.size());
  m.positions.insert(m.positions.end(), box.positions.begin(), box.positions.end());
  for (const glm::uvec3& t : box.triangles) m.triangles.push_back(t + glm::uvec3(b));
  runOnGround(m, "with zero-area and sliver triangles");
}

TEST(HostileGeometry, DuplicatedVerticesAndTriangles) {
  // A box as a triangle soup (every triangle with its own three vertices), each triangle twice,
  // once more with the opposite winding, and one vertex position repeated a hundred times.
  const Mesh box = translated(makeBox(Vec3(1.0f)), Vec3(0.0f, 1.5f, 0.0f));
  Mesh soup;
  for (const glm::uvec3& t : box.triangles) {
    for (int copy = 0; copy < 2; ++copy) {
      const auto n = static_cast<uint32_t>(soup.positions.size());
      for (int k = 0; k < 3; ++k) soup.positions.push_back(box.positions[t[k]]);
      soup.triangles.push_back({n, n + 1, n + 2});
    }
    const auto n = static_cast<uint32_t>(soup.positions.size());
    for (int k = 0; k < 3; ++k) soup.positions.push_back(box.positions[t[k]]);
    soup.triangles.push_back({n, n + 2, n + 1});
  }
  for (int i = 0; i < 100; ++i) soup.positions.push_back(box.positions[0]);
  const std::vector<TechniqueRun> runs = runOnGround(soup, "with duplicated vertices and triangles");
  // The soup covers exactly the box's surface, so the exact hard shadow is the box's.
  const std::vector<Light> lights = lightsAround(kLightCenter, 0.5f);
  const Scene solid = groundWith(box, lights[0]);
  const GBuffer gbuffer = renderGBuffer(solid, 40, 32);
  auto hard = createTechnique("raytraced-hard");
  hard->prepare(solid, lights[0]);
  Image<float> truth;
  hard->visibility(gbuffer, truth);
  const TechniqueRun* soupHard = findRun(runs, "raytraced-hard", LightShape::Sphere);
  ASSERT_NE(soupHard, nullptr);
  size_t differ = 0, shadowed = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    differ += truth[i] != soupHard->v[i];
    shadowed += truth[i] == 0.0f;
  }
  EXPECT_GT(shadowed, 20u) << "the box casts a shadow into the image";
  EXPECT_EQ(differ, 0u) << "a triangle soup of a box shadows exactly like the box";
  // ssv and wedges weld the soup and drop its repeated triangles (mesh_topology.h): to them it is
  // the box, a closed solid, bit for bit.
  for (const char* name : {"ssv", "wedges"}) {
    const TechniqueRun* soupRun = findRun(runs, name, LightShape::Rect);
    ASSERT_NE(soupRun, nullptr) << name;
    const Image<float> boxV = testing::runTechnique(name, groundWith(box, soupRun->light), gbuffer);
    size_t soft = 0;
    for (const float x : boxV) soft += x > 0.0f && x < 1.0f;
    EXPECT_GT(soft, 5u) << name << ": the box casts a soft shadow into the image";
    EXPECT_TRUE(std::equal(boxV.begin(), boxV.end(), soupRun->v.begin())) << name << ": the soup shadows as the box";
  }
}

TEST(HostileGeometry, NonManifoldEdgesAndOpenMeshes) {
  // Four triangles sharing one edge (a "book" of pages), a box with its top face missing, and a
  // lone triangle: edges with four faces, with one face, and a mesh with no inside at all.
  Mesh m;
  const Vec3 e0(-0.5f, 1.0f, 0.0f), e1(0.5f, 1.0f, 0.0f);
  m.positions = {e0, e1};
  for (int page = 0; page < 4; ++page) {
    const float a = radians(20.0f + 45.0f * static_cast<float>(page));
    m.positions.push_back(Vec3(0.0f, 1.0f + 0.6f * std::sin(a), 0.6f * std::cos(a)));
    m.triangles.push_back({0u, 1u, static_cast<uint32_t>(m.positions.size() - 1)});
  }
  const Mesh box = translated(makeBox(Vec3(0.8f)), Vec3(-1.5f, 1.0f, 0.5f));
  const auto b = static_cast<uint32_t>(m.positions.size());
  m.positions.insert(m.positions.end(), box.positions.begin(), box.positions.end());
  for (const glm::uvec3& t : box.triangles) {
    bool top = true;
    for (int k = 0; k < 3; ++k) top = top && box.positions[t[k]].y > 1.3f;
    if (!top) m.triangles.push_back(t + glm::uvec3(b));
  }
  EXPECT_EQ(m.triangles.size(), 4u + 10u);
  const auto t = static_cast<uint32_t>(m.positions.size());
  m.positions.push_back(Vec3(1.0f, 1.5f, -0.5f));
  m.positions.push_back(Vec3(1.8f, 1.5f, -0.5f));
  m.positions.push_back(Vec3(1.4f, 1.5f, -1.2f));
  m.triangles.push_back({t, t + 1, t + 2});
  runOnGround(m, "with non-manifold edges and open meshes");
}

TEST(HostileGeometry, NonFiniteVerticesBuiltInCode) {
  // Scene files and mesh files reject non-finite vertices at load (tests/io/malformed_files_test.cpp);
  // a scene built in code can still hold them. Each technique either refuses with an Error or
  // ignores the broken triangles; V stays valid either way.
  Mesh m = translated(makeBox(Vec3(1.0f)), Vec3(0.0f, 1.5f, 0.0f));
  const auto n = static_cast<uint32_t>(m.positions.size());
  m.positions.push_back(Vec3(std::nanf(""), 1.0f, 0.0f));
  m.positions.push_back(Vec3(kInfinity, 1.0f, 0.0f));
  m.positions.push_back(Vec3(0.0f, -kInfinity, 1.0f));
  m.triangles.push_back({n, n + 1, n + 2});
  m.triangles.push_back({0u, 1u, n});
  const std::vector<Light> lights = lightsAround(kLightCenter, 0.5f);
  GBuffer gbuffer;
  try {
    gbuffer = renderGBuffer(groundWith(m, lights[0]), 40, 32);
  } catch (const Error& e) {
    SUCCEED() << "the rasterizer refuses non-finite vertices: " << e.what();
    return;
  }
  for (const TechniqueInfo& info : techniqueRegistry()) {
    for (const Light& light : lights) {
      const Scene scene = groundWith(m, light);
      auto technique = info.create(resolveParams(info.name, info.params, cheapParams(info)));
      Image<float> v;
      try {
        technique->prepare(scene, light);
        technique->visibility(gbuffer, v);
      } catch (const Error&) {
        continue;  // refusing a broken scene is fine; crashing or writing NaN is not
      }
      expectValidVisibility(
          info.name + " with a " + std::string(toString(light.shape())) + " light and non-finite vertices", gbuffer, v);
    }
  }
}

TEST(HostileGeometry, LightInsideAClosedObject) {
  // The light sits inside a closed box that hangs over the ground: nothing outside the box can see
  // any of it, so the truth is V = 0 on every surface that faces the light.
  const Vec3 center(0.0f, 2.0f, 0.0f);
  const Mesh box = translated(makeBox(Vec3(1.6f)), center);
  const std::vector<Light> lights = lightsAround(center, 0.3f);
  const std::vector<Light> local(lights.begin(), lights.end() - 1);  // a directional light cannot be inside
  const auto make = [&](const Light& light) { return groundWith(box, light); };
  const GBuffer gbuffer = renderGBuffer(make(local[0]), 40, 32);
  const std::vector<TechniqueRun> runs = runEveryTechnique(make, local, gbuffer, "inside a closed box");
  const Image<uint8_t> mask = errorMask(gbuffer, local[0]);
  size_t masked = 0;
  for (uint8_t m : mask) masked += m;
  EXPECT_GT(masked, 200u) << "the ground around the box faces the light";
  for (const char* name : {"reference", "raytraced-hard"}) {
    const TechniqueRun* run = findRun(runs, name, LightShape::Sphere);
    ASSERT_NE(run, nullptr) << name;
    size_t lit = 0;
    for (size_t i = 0; i < mask.size(); ++i) lit += mask[i] && run->v[i] != 0.0f;
    EXPECT_EQ(lit, 0u) << name << ": a light sealed in a box lights nothing outside it";
  }
}

TEST(HostileGeometry, LightTouchingAReceiver) {
  // A sphere light resting on the ground, a rect and a polygon light standing on it, a segment
  // light with one end on it: receiver points at distance zero from the emitter, where the
  // silhouette-disk and solid-angle formulas divide by zero. A box beside them casts a shadow.
  const Mesh box = translated(makeBox(Vec3(0.6f)), Vec3(-1.0f, 0.3f, 0.0f));
  const std::vector<Light> lights = {
      Light::sphere(Vec3(0.0f, 0.5f, 0.0f), 0.5f),
      Light::rect(Vec3(0.0f, 0.5f, 0.0f), Vec3(0.5f, 0.0f, 0.0f), Vec3(0.0f, 0.5f, 0.0f)),
      Light::polygon({Vec3(-0.5f, 0.0f, 0.0f), Vec3(0.5f, 0.0f, 0.0f), Vec3(0.0f, 1.0f, 0.0f)}),
      Light::disk(Vec3(0.0f, 0.5f, 0.0f), Vec3(0.0f, 0.0f, 1.0f), 0.5f),
      Light::segment(Vec3(0.0f, 0.0f, 0.0f), Vec3(0.3f, 1.0f, 0.0f))};
  const auto make = [&](const Light& light) { return groundWith(box, light); };
  const GBuffer gbuffer = renderGBuffer(make(lights[0]), 40, 32);
  const std::vector<TechniqueRun> runs = runEveryTechnique(make, lights, gbuffer, "touching the ground");
  // The reference still draws the box's shadow on the ground.
  const TechniqueRun* reference = findRun(runs, "reference", LightShape::Sphere);
  ASSERT_NE(reference, nullptr);
  size_t shadowed = 0;
  for (float x : reference->v) shadowed += x < 0.5f;
  EXPECT_GT(shadowed, 5u) << "the box shadows the ground";
}

TEST(HostileGeometry, CameraLookingAwayFromEverything) {
  const std::vector<Light> lights = lightsAround(kLightCenter, 0.5f);
  const auto make = [&](const Light& light) {
    Scene scene = groundWith(translated(makeBox(Vec3(1.0f)), Vec3(0.0f, 1.5f, 0.0f)), light);
    scene.camera.position = Vec3(0.0f, 2.0f, 6.0f);
    scene.camera.lookAt = Vec3(0.0f, 4.0f, 20.0f);  // up and away from the scene
    return scene;
  };
  const GBuffer gbuffer = renderGBuffer(make(lights[0]), 24, 16);
  size_t hits = 0;
  for (int32_t id : gbuffer.objectId) hits += id != kNoObject;
  ASSERT_EQ(hits, 0u) << "the camera must see nothing";
  runEveryTechnique(make, lights, gbuffer, "with a camera that sees nothing");  // checks V = 1 everywhere
}

TEST(HostileGeometry, OneByOneImage) {
  const Mesh box = translated(makeBox(Vec3(1.0f)), Vec3(0.4f, 1.5f, 0.2f));
  const std::vector<Light> lights = lightsAround(kLightCenter, 0.5f);
  const auto make = [&](const Light& light) {
    Scene scene = groundWith(box, light);
    scene.camera.position = Vec3(0.4f, 6.0f, 0.3f);  // straight down through the box's shadow
    scene.camera.lookAt = Vec3(0.4f, 0.0f, 0.2f);
    scene.camera.up = Vec3(0.0f, 0.0f, -1.0f);
    return scene;
  };
  const GBuffer gbuffer = renderGBuffer(make(lights[0]), 1, 1);
  ASSERT_TRUE(gbuffer.hit(0, 0));
  const std::vector<TechniqueRun> runs = runEveryTechnique(make, lights, gbuffer, "on a 1x1 image");
  const TechniqueRun* hard = findRun(runs, "raytraced-hard", LightShape::Sphere);
  ASSERT_NE(hard, nullptr);
  EXPECT_EQ(hard->v[0], 1.0f) << "the one pixel sees the box's top, which the light sees";
}

TEST(HostileGeometry, OversizedImagesAreRefusedBeforeAllocation) {
  const Scene scene = groundWith(makeBox(Vec3(1.0f)), Light::sphere(kLightCenter, 0.5f));
  // 16384 x 16384 is within the per-side limit but over the pixel limit: a G-buffer of about 13 GB.
  for (const auto& [w, h] : {std::pair{16384, 16384}, std::pair{16385, 1}, std::pair{0, 1}, std::pair{9000, 8000}}) {
    try {
      renderGBuffer(scene, w, h);
      ADD_FAILURE() << w << " x " << h << " must be refused";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("renderGBuffer"), std::string::npos) << message;
      EXPECT_NE(message.find(std::to_string(w) + " x " + std::to_string(h)), std::string::npos) << message;
      EXPECT_TRUE(message.find(std::to_string(kMaxImagePixels)) != std::string::npos ||
                  message.find(std::to_string(kMaxImageSide)) != std::string::npos)
          << "the message must state the limit: " << message;
    }
  }
  const RayScene rays(scene);
  EXPECT_THROW(traceGBuffer(scene, rays, 16384, 16384), Error);
  // The largest image per side is fine when its pixel count is (a 16384-wide strip).
  EXPECT_EQ(renderGBuffer(scene, 16384, 1).width(), 16384);
  // Scene files are checked at load, naming the file and the field.
  const std::string text = R"({"camera": {"position": [0, 5, 5], "look_at": [0, 0, 0]}, "lights": [], "objects": [],
                             "image": {"width": 16384, "height": 16384}})";
  try {
    parseScene(text, "big.json");
    ADD_FAILURE() << "a 16384 x 16384 scene image must be refused";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("big.json: image"), std::string::npos) << message;
    EXPECT_NE(message.find(std::to_string(kMaxImagePixels)), std::string::npos) << message;
  }
}

TEST(HostileGeometry, AMillionTinyTriangles) {
  // 10^6 separate triangles, each about a fifth of a pixel, in a 1000 x 1000 grid over a 2 x 2
  // square at height 1.5: half of every grid cell is covered, a screen that blocks about half of the light.
#if defined(__SANITIZE_ADDRESS__)
  // The sanitizer build checks memory safety, not scale: 10^4 triangles run the same code paths.
  constexpr int kGrid = 100;
#else
  constexpr int kGrid = 1000;
#endif
  Mesh m;
  m.positions.reserve(3 * kGrid * kGrid);
  m.triangles.reserve(kGrid * kGrid);
  const float cell = 2.0f / kGrid;
  for (int j = 0; j < kGrid; ++j)
    for (int i = 0; i < kGrid; ++i) {
      const float x = -1.0f + cell * static_cast<float>(i), z = -1.0f + cell * static_cast<float>(j);
      const auto n = static_cast<uint32_t>(m.positions.size());
      m.positions.push_back(Vec3(x, 1.5f, z));
      m.positions.push_back(Vec3(x, 1.5f, z + cell));
      m.positions.push_back(Vec3(x + cell, 1.5f, z));
      m.triangles.push_back({n, n + 1, n + 2});
    }
  ASSERT_EQ(m.triangleCount(), static_cast<size_t>(kGrid) * kGrid);
  const std::vector<Light> lights = lightsAround(kLightCenter, 0.5f);
  Scene base = groundWith(std::move(m), lights[0]);
  const GBuffer gbuffer = renderGBuffer(base, 48, 40);
  const auto make = [&](const Light& light) {
    Scene scene = base;  // a copy per run: 36 MB, small next to the techniques' own work
    scene.lights[0] = light;
    return scene;
  };
  // One light per technique (the first it accepts). Measured on 2 cores: about 50 s in all, most of
  // it in the silhouette passes of plm, smoothies and kirsch (5-6 s each: every edge is open) and
  // parker's light buffer (12 s, coarsened to stay within its entry limit: 8 GB without); ssv and
  // wedges take 8-13 s each (the screen is a two-sided sheet of 10^6 separate pieces: 10^6
  // silhouette rings, tens of thousands of them in each penumbra pixel's light).
  const std::vector<TechniqueRun> runs = runEveryTechnique(make, lights, gbuffer, "with 10^6 tiny triangles", false);
  // Under the screen, the reference sees about half of the light through it.
  const TechniqueRun* reference = findRun(runs, "reference", LightShape::Sphere);
  ASSERT_NE(reference, nullptr);
  double sum = 0.0;
  size_t under = 0;
  for (int y = 0; y < gbuffer.height(); ++y)
    for (int x = 0; x < gbuffer.width(); ++x) {
      const Vec3 p = gbuffer.wsPosition(x, y);
      // Ground seen through the screen's gaps, where every ray to the light crosses the screen.
      if (gbuffer.objectId(x, y) == 0 && std::abs(p.x) < 0.9f && std::abs(p.z) < 0.9f) {
        sum += reference->v(x, y);
        ++under;
      }
    }
  ASSERT_GT(under, 20u);
  EXPECT_NEAR(sum / static_cast<double>(under), 0.5, 0.2) << "the screen blocks half of the light";
}

}  // namespace
}  // namespace penumbra
