// Tests of `raytraced-soft` (src/techniques/raytraced/raytraced_soft.cpp) and its filter
// (penumbra_filter.h), against the reference:
//  - the filtered V approaches the reference as the ray count grows, and the filter lowers the error
//    of the same rays unfiltered;
//  - no shadow crosses an object boundary or a depth discontinuity (a plate floating over a floor,
//    as two objects and as one): the plate's V is 1 exactly, and the filter's output on either side
//    of the plate's outline does not change when the input on the other side does;
//  - V is bit-identical for a seed at 1, 2 and 4 threads;
//  - every light shape runs and beats the hard shadow of its centre;
//  - temporal accumulation converges on a still frame and flickers less under a moving light.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "penumbra/metrics.h"
#include "penumbra/motion.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "penumbra/temporal_metrics.h"
#include "rt/rt_test_scenes.h"
#include "techniques/raytraced/penumbra_filter.h"

namespace penumbra {
namespace {

using testing::makeObject;
using testing::makeScene;
using testing::quadMesh;

constexpr int kSize = 128;

Image<float> run(const std::string& technique, const Scene& scene, const Light& light, const GBuffer& g,
                 const std::vector<std::string>& params = {}) {
  ParamSet given;
  for (const std::string& p : params) given.setFromKeyValue(p, "test");
  auto t = createTechnique(technique, given);
  t->prepare(scene, light);
  Image<float> v;
  t->visibility(g, v);
  return v;
}

struct Rendered {
  Scene scene;
  GBuffer gbuffer;
  Image<float> reference;
  Image<uint8_t> mask;
};

// A built-in scene at 128 x 128 with its reference at 1024 spp (test-only cache, once per process).
const Rendered& rendered(const std::string& name) {
  static std::vector<std::pair<std::string, Rendered>> cache;
  for (const auto& [n, r] : cache)
    if (n == name) return r;
  Rendered r;
  r.scene = loadScene(name);
  r.gbuffer = renderGBuffer(r.scene, kSize, kSize);
  r.reference = run("reference", r.scene, r.scene.lights.at(0), r.gbuffer, {"spp=1024"});
  r.mask = errorMask(r.gbuffer, r.scene.lights.at(0));
  cache.emplace_back(name, std::move(r));
  return cache.back().second;
}

double rmse8(const Rendered& r, const Image<float>& v) { return compareVisibility(v, r.reference, r.mask).rmse8; }

TEST(RaytracedSoft, ApproachesTheReferenceAsTheRayCountGrows) {
  for (const char* name : {"torus", "crowded"}) {
    const Rendered& r = rendered(name);
    double previous = 1e9;
    for (int spp : {1, 4, 16}) {
      const std::string sppParam = "spp=" + std::to_string(spp);
      const double filtered = rmse8(r, run("raytraced-soft", r.scene, r.scene.lights[0], r.gbuffer, {sppParam}));
      const double unfiltered =
          rmse8(r, run("raytraced-soft", r.scene, r.scene.lights[0], r.gbuffer, {sppParam, "filter_scale=0"}));
      std::printf("%s spp %d: RMSE8 filtered %.2f, unfiltered %.2f\n", name, spp, filtered, unfiltered);
      EXPECT_LT(filtered, previous) << name << " spp " << spp;
      EXPECT_LT(filtered, unfiltered) << name << " spp " << spp << ": the filter must lower the error of its rays";
      previous = filtered;
    }
  }
}

// A plate at height 1 over a floor at height 0 under a rect light, seen obliquely: the plate's image
// borders the floor's shadow on screen. `oneObject`: both are one object, so only the plane-distance
// weight stands between them.
Scene plateScene(bool oneObject) {
  Mesh plate = quadMesh(Vec3(0, 0, 1), Vec3(0.6f, 0, 0), Vec3(0, 0.6f, 0));
  Mesh floor = quadMesh(Vec3(0.0f), Vec3(4, 0, 0), Vec3(0, 4, 0));
  Scene s;
  if (oneObject) {
    Mesh both = floor;
    const auto base = static_cast<unsigned>(both.positions.size());
    for (const Vec3& p : plate.positions) both.positions.push_back(p);
    for (const glm::uvec3& t : plate.triangles) both.triangles.push_back(t + glm::uvec3(base));
    s = makeScene({makeObject(1, both, "floor and plate")});
  } else {
    s = makeScene({makeObject(1, floor, "floor"), makeObject(2, plate, "plate")});
  }
  s.camera.position = Vec3(0.0f, -3.5f, 3.0f);
  s.camera.lookAt = Vec3(0.0f, 0.3f, 0.3f);
  s.camera.up = Vec3(0, 0, 1);
  s.camera.fovYDegrees = 50.0f;
  s.lights.push_back(Light::rect(Vec3(0.3f, 0.4f, 3.0f), Vec3(0.5f, 0, 0), Vec3(0, 0.5f, 0)));
  return s;
}

TEST(RaytracedSoft, NoShadowCrossesAnObjectBoundaryOrADepthDiscontinuity) {
  for (bool oneObject : {false, true}) {
    const Scene scene = plateScene(oneObject);
    const GBuffer g = renderGBuffer(scene, kSize, kSize);
    const Light& light = scene.lights[0];
    auto onPlate = [&](int x, int y) { return g.hit(x, y) && g.wsPosition(x, y).z > 0.5f; };

    // End to end: nothing stands between the plate and the light, so every ray is lit and the
    // plate's V must be 1 exactly, although its image borders the floor's shadow.
    const Image<float> v = run("raytraced-soft", scene, light, g);
    const Image<float> ref = run("reference", scene, light, g, {"spp=1024"});
    int platePixels = 0, shadowNearPlate = 0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        if (onPlate(x, y)) {
          ++platePixels;
          EXPECT_EQ(v(x, y), 1.0f) << "plate pixel (" << x << ", " << y << "), one object: " << oneObject;
          continue;
        }
        bool nearPlate = false;
        for (int dy = -3; dy <= 3; ++dy)
          for (int dx = -3; dx <= 3; ++dx)
            nearPlate = nearPlate ||
                        (x + dx >= 0 && y + dy >= 0 && x + dx < kSize && y + dy < kSize && onPlate(x + dx, y + dy));
        shadowNearPlate += nearPlate && g.hit(x, y) && ref(x, y) < 0.5f;
      }
    EXPECT_GT(platePixels, 200);
    EXPECT_GT(shadowNearPlate, 20) << "the floor's shadow must border the plate's image for the test to mean anything";

    // The filter alone, with a radius of 20 pixels everywhere: changing the input on one side of the
    // plate's outline must leave every output on the other side bit-identical.
    Image<float> noisy(kSize, kSize, 1.0f), radius(kSize, kSize, 20.0f), reach(kSize, kSize, kInfinity);
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) noisy(x, y) = static_cast<float>((x * 7 + y * 13) % 11) / 10.0f;
    raytraced::PenumbraFilterInput input;
    input.noisy = &noisy;
    input.radius = &radius;
    input.reach = &reach;
    input.tanHalfFovY = std::tan(0.5f * radians(scene.camera.fovYDegrees));
    Image<float> scratch, base;
    raytraced::filterPenumbrae(g, input, raytraced::PenumbraFilterOptions{}, scratch, base);
    for (bool changePlate : {true, false}) {
      Image<float> changed = noisy;
      for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x)
          if (g.hit(x, y) && onPlate(x, y) == changePlate) changed(x, y) = 1.0f - changed(x, y);
      input.noisy = &changed;
      Image<float> out;
      raytraced::filterPenumbrae(g, input, raytraced::PenumbraFilterOptions{}, scratch, out);
      int compared = 0, differing = 0;
      for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
          if (!g.hit(x, y) || onPlate(x, y) == changePlate) continue;
          ++compared;
          differing += std::memcmp(&out(x, y), &base(x, y), sizeof(float)) != 0;
        }
      EXPECT_GT(compared, 200);
      EXPECT_EQ(differing, 0) << (changePlate ? "the plate's input reached the floor"
                                              : "the floor's input reached the plate")
                              << ", one object: " << oneObject;
    }
  }
}

TEST(RaytracedSoft, BitIdenticalForASeedAtAnyThreadCountAlsoInTheHybrid) {
  for (const char* technique : {"raytraced-soft", "hybrid"}) {
    const Rendered& r = rendered("torus");
    Image<float> first;
    for (int threads : {1, 2, 4}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
      tbb::task_arena arena(threads);
      Image<float> v;
      arena.execute([&] { v = run(technique, r.scene, r.scene.lights[0], r.gbuffer, {"seed=3"}); });
      if (first.empty()) {
        first = v;
        continue;
      }
      ASSERT_EQ(v.size(), first.size());
      EXPECT_EQ(std::memcmp(v.data(), first.data(), v.size() * sizeof(float)), 0)
          << technique << ", " << threads << " threads";
    }
    const Image<float> otherSeed = run(technique, r.scene, r.scene.lights[0], r.gbuffer, {"seed=4"});
    EXPECT_NE(std::memcmp(otherSeed.data(), first.data(), first.size() * sizeof(float)), 0)
        << technique << ": the seed must select the samples";
  }
}

TEST(RaytracedSoft, EveryLightShapeBeatsTheHardShadowOfItsCentreAlsoInTheHybrid) {
  // sphere (torus), segment (linear), concave polygon (concave), directional (triangle), and a disk
  // and a rect over the plate of the test above.
  struct Case {
    std::string label;
    Scene scene;
  };
  std::vector<Case> cases;
  for (const char* name : {"torus", "linear", "concave", "triangle"}) cases.push_back({name, loadScene(name)});
  Scene disk = plateScene(false);
  disk.lights = {Light::disk(Vec3(0.3f, 0.4f, 3.0f), Vec3(0, 0, -1), 0.6f)};
  cases.push_back({"plate under a disk", disk});
  cases.push_back({"plate under a rect", plateScene(false)});
  for (const Case& c : cases) {
    const GBuffer g = renderGBuffer(c.scene, kSize, kSize);
    const Light& light = c.scene.lights.at(0);
    const Image<float> ref = run("reference", c.scene, light, g, {"spp=1024"});
    const Image<uint8_t> mask = errorMask(g, light);
    const double hard = compareVisibility(run("raytraced-hard", c.scene, light, g), ref, mask).rmse8;
    const double pcss = compareVisibility(run("pcss", c.scene, light, g), ref, mask).rmse8;
    for (const char* technique : {"raytraced-soft", "hybrid"}) {
      const Image<float> v = run(technique, c.scene, light, g);
      for (float value : v)
        ASSERT_TRUE(value >= 0.0f && value <= 1.0f) << technique << ", " << c.label << ": V " << value;
      const double soft = compareVisibility(v, ref, mask).rmse8;
      std::printf("%s (%s): RMSE8 %s %.2f, raytraced-hard %.2f, pcss %.2f\n", c.label.c_str(),
                  std::string(toString(light.shape())).c_str(), technique, soft, hard, pcss);
      EXPECT_LT(soft, hard) << technique << ", " << c.label;
    }
  }
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

// Temporal accumulation (few_ray.h), one instance carried across frames as compare runs a sequence:
// on a still frame the error falls as frames accumulate; under a moving light it flickers less than
// each frame alone, with a per-frame error not worse; a sequence is deterministic.
TEST(RaytracedSoft, TemporalAccumulationConvergesWhenStillAndFlickersLessUnderAMovingLight) {
  const Rendered& r = rendered("torus");
  const Light& light = r.scene.lights[0];
  for (const char* technique : {"raytraced-soft", "hybrid"}) {
    ParamSet temporal;
    temporal.setFromKeyValue("temporal=true", "test");
    auto t = createTechnique(technique, temporal);
    Image<float> v;
    std::vector<double> errors;
    for (int frame = 0; frame < 8; ++frame) {
      t->prepare(r.scene, light);
      t->visibility(r.gbuffer, v);
      errors.push_back(rmse8(r, v));
    }
    std::printf("%s, still, temporal: RMSE8 frame 1 %.2f, frame 4 %.2f, frame 8 %.2f\n", technique, errors[0],
                errors[3], errors[7]);
    EXPECT_LT(errors[7], 0.8 * errors[0]) << technique;
    EXPECT_LT(errors[7], errors[3]) << technique;
  }

  // The light moves 0.2 units over 6 frames (docs/results.md's torus path).
  Motion motion;
  motion.path = {Vec3(-1.0f, 6.0f, -1.5f), Vec3(-0.8f, 6.0f, -1.5f)};
  motion.frames = 6;
  motion.validate(r.scene, "test");
  std::vector<Image<float>> truth;
  std::vector<Image<uint8_t>> masks;
  for (int frame = 0; frame < motion.frames; ++frame) {
    const Scene s = sceneAtFrame(r.scene, motion, frame);
    truth.push_back(run("reference", s, s.lights[0], r.gbuffer, {"spp=1024"}));
    masks.push_back(errorMask(r.gbuffer, s.lights[0]));
  }
  for (const char* technique : {"raytraced-soft", "hybrid"}) {
    auto sequence = [&](bool temporal) {
      ParamSet given;
      given.setFromKeyValue(temporal ? "temporal=true" : "temporal=false", "test");
      auto t = createTechnique(technique, given);
      std::vector<Image<float>> frames;
      double meanError = 0.0;
      for (int frame = 0; frame < motion.frames; ++frame) {
        const Scene s = sceneAtFrame(r.scene, motion, frame);
        Image<float> v;
        t->prepare(s, s.lights[0]);
        t->visibility(r.gbuffer, v);
        meanError += compareVisibility(v, truth[static_cast<size_t>(frame)], masks[static_cast<size_t>(frame)]).rmse8;
        frames.push_back(std::move(v));
      }
      return std::pair{temporalError(frames, truth, masks).flicker, meanError / motion.frames};
    };
    const auto [flickerOff, errorOff] = sequence(false);
    const auto [flickerOn, errorOn] = sequence(true);
    std::printf("%s, moving light: flicker %.2f -> %.2f, mean RMSE8 %.2f -> %.2f with temporal\n", technique,
                flickerOff, flickerOn, errorOff, errorOn);
    EXPECT_LT(flickerOn, flickerOff) << technique;
    EXPECT_LT(errorOn, errorOff) << technique;

    // Deterministic: the same sequence again gives the same last frame, bit for bit.
    ParamSet given;
    given.setFromKeyValue("temporal=true", "test");
    Image<float> a, b;
    for (Image<float>* out : {&a, &b}) {
      auto t = createTechnique(technique, given);
      for (int frame = 0; frame < motion.frames; ++frame) {
        const Scene s = sceneAtFrame(r.scene, motion, frame);
        t->prepare(s, s.lights[0]);
        t->visibility(r.gbuffer, *out);
      }
    }
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << technique;
  }
}

}  // namespace
}  // namespace penumbra
