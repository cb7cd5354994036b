// Numerical health of every registered technique (the registry is iterated, so a newly registered
// one is covered without touching this file): its V is bit-identical between two runs with the same
// parameters (seed included) and thread count — on one instance run twice and on a fresh instance —
// and within 1/255 (one step of an 8-bit image) between 1 and 2 worker threads. The thread count is
// set with tbb::global_control (which also bounds any pool Embree's BVH builds use) around a
// tbb::task_arena of that many threads.
//
// Storage reserved before the first frame (ShadowTechnique::reserve) changes no V.
//
// Over a sequence (include/penumbra/motion.h), one instance carried from frame to frame, as compare
// and bench run it, gives each frame the V a fresh instance gives (stable light maps included).
//
// Each technique runs on the first built-in scene whose light it supports (torus: sphere, linear:
// segment, concave: polygon, triangle: directional), at 128 x 128 with its defaults except the
// cost knobs (16 spp, 8 light samples, 256-texel maps), so every pass of the technique runs.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "penumbra/error.h"
#include "penumbra/motion.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

constexpr int kImageSize = 128;

struct TestScene {
  Scene scene;
  GBuffer gbuffer;
};

const std::vector<TestScene>& testScenes() {
  static const std::vector<TestScene> scenes = [] {  // test-only cache, built once per process
    std::vector<TestScene> out;
    for (const char* name : {"torus", "linear", "concave", "triangle"}) {
      TestScene s;
      s.scene = loadScene(name);
      s.gbuffer = renderGBuffer(s.scene, kImageSize, kImageSize);
      out.push_back(std::move(s));
    }
    return out;
  }();
  return scenes;
}

std::unique_ptr<ShadowTechnique> create(const TechniqueInfo& info, bool stableMap = false) {
  ParamSet given;
  if (stableMap && info.hasParam("map_fit")) given.setFromKeyValue("map_fit=stable", "test");
  if (info.hasParam("spp")) given.set("spp", int64_t{16}, "test");
  if (info.hasParam("samples")) given.set("samples", int64_t{8}, "test");
  if (info.hasParam("map_size")) given.set("map_size", int64_t{256}, "test");
  if (info.hasParam("seed")) given.set("seed", int64_t{7}, "test");
  return info.create(resolveParams(info.name, info.params, given));
}

// prepare + visibility on `threads` worker threads.
Image<float> runWithThreads(ShadowTechnique& technique, const TestScene& s, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  tbb::task_arena arena(threads);
  Image<float> v;
  arena.execute([&] {
    technique.prepare(s.scene, s.scene.lights.at(0));
    technique.visibility(s.gbuffer, v);
  });
  return v;
}

// The first test scene whose light the technique accepts; nullptr if it refuses them all.
const TestScene* acceptedScene(const TechniqueInfo& info) {
  for (const TestScene& s : testScenes()) {
    try {
      create(info)->prepare(s.scene, s.scene.lights.at(0));
      return &s;
    } catch (const Error& e) {
      const std::string message = e.what();
      if (message.find(toString(s.scene.lights[0].shape())) == std::string::npos) {
        ADD_FAILURE() << info.name << " on " << s.scene.name
                      << " failed with an Error that is not a light-shape refusal: " << message;
        return nullptr;
      }
    }
  }
  ADD_FAILURE() << info.name << " accepts none of the lights of torus, linear, concave and triangle";
  return nullptr;
}

size_t differingPixels(const Image<float>& a, const Image<float>& b, size_t& first) {
  size_t count = 0;
  first = a.size();
  for (size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(float)) != 0) {
      if (count++ == 0) first = i;
    }
  return count;
}

TEST(Determinism, SameSeedAndThreadCountGiveBitIdenticalOutput) {
  for (const TechniqueInfo& info : techniqueRegistry()) {
    const TestScene* s = acceptedScene(info);
    if (s == nullptr) continue;
    auto technique = create(info);
    const Image<float> first = runWithThreads(*technique, *s, 2);
    // The same instance prepared next for another scene (its last object gone), then for this one
    // again: whatever a technique keeps between prepares must not leak into the next (each gives
    // what a fresh instance gives).
    TestScene fewer = *s;
    fewer.scene.objects.pop_back();
    const Image<float> afterOther = runWithThreads(*technique, fewer, 2);
    const Image<float> freshOther = runWithThreads(*create(info), fewer, 2);
    const Image<float> again = runWithThreads(*technique, *s, 2);
    auto fresh = create(info);
    const Image<float> other = runWithThreads(*fresh, *s, 2);
    ASSERT_EQ(first.size(), static_cast<size_t>(kImageSize * kImageSize)) << info.name;
    ASSERT_EQ(again.size(), first.size()) << info.name;
    ASSERT_EQ(other.size(), first.size()) << info.name;
    size_t at = 0;
    EXPECT_EQ(differingPixels(first, again, at), 0u)
        << info.name << " on " << s->scene.name
        << ": a run of one instance prepared for another scene before differs, first at pixel " << at << " ("
        << (at < first.size() ? first[at] : 0.0f) << " vs " << (at < first.size() ? again[at] : 0.0f) << ")";
    EXPECT_EQ(differingPixels(afterOther, freshOther, at), 0u)
        << info.name << " on " << s->scene.name
        << " less its last object, after a run on the whole scene: differs from a fresh "
        << "instance, first at pixel " << at;
    EXPECT_EQ(differingPixels(first, other, at), 0u)
        << info.name << " on " << s->scene.name << ": a fresh instance differs, first at pixel " << at << " ("
        << (at < first.size() ? first[at] : 0.0f) << " vs " << (at < first.size() ? other[at] : 0.0f) << ")";
  }
}

TEST(Determinism, OneInstanceAcrossTheFramesOfASequenceGivesEachFrameAFreshInstancesV) {
  for (const TechniqueInfo& info : techniqueRegistry()) {
    const TestScene* s = acceptedScene(info);
    if (s == nullptr) continue;
    const Light& light = s->scene.lights.at(0);
    const Vec3 key = light.isDirectional() ? light.direction() : light.center();  // motion.h: a key per shape
    Motion motion;
    motion.path = {key, key + Vec3(0.3f, 0.0f, 0.1f)};
    motion.frames = 3;
    motion.validate(s->scene, "test motion");
    auto carried = create(info, true);
    for (int frame = 0; frame < motion.frames; ++frame) {
      const TestScene at{sceneAtFrame(s->scene, motion, frame), s->gbuffer};  // the camera stays
      const Image<float> v = runWithThreads(*carried, at, 2);
      const Image<float> fresh = runWithThreads(*create(info, true), at, 2);
      size_t first = 0;
      EXPECT_EQ(differingPixels(v, fresh, first), 0u)
          << info.name << " on " << s->scene.name << ", frame " << frame
          << ": the instance carried from the previous frames differs from a fresh one, first at pixel " << first;
    }
  }
}

// ShadowTechnique::reserve makes storage only: an instance whose frames' storage was made before its
// first frame, for the G-buffer's size or for another one (which the frame then remakes), gives the V
// of one without; a size below 1 x 1 is refused.
TEST(Determinism, StorageReservedBeforeTheFirstFrameChangesNoV) {
  for (const TechniqueInfo& info : techniqueRegistry()) {
    const TestScene* s = acceptedScene(info);
    if (s == nullptr) continue;
    const Image<float> plain = runWithThreads(*create(info), *s, 2);
    for (const auto& [width, height] : {std::pair{kImageSize, kImageSize}, std::pair{40, 24}}) {
      auto reserved = create(info);
      reserved->reserve(width, height);
      const Image<float> v = runWithThreads(*reserved, *s, 2);
      size_t first = 0;
      EXPECT_EQ(differingPixels(plain, v, first), 0u)
          << info.name << " on " << s->scene.name << ", storage reserved for " << width << " x " << height
          << ": differs from an instance without, first at pixel " << first;
    }
    EXPECT_THROW(create(info)->reserve(0, kImageSize), Error) << info.name;
  }
}

TEST(Determinism, OneAndTwoThreadsAgreeWithinOneStepOf255) {
  for (const TechniqueInfo& info : techniqueRegistry()) {
    const TestScene* s = acceptedScene(info);
    if (s == nullptr) continue;
    auto one = create(info);
    auto two = create(info);
    const Image<float> v1 = runWithThreads(*one, *s, 1);
    const Image<float> v2 = runWithThreads(*two, *s, 2);
    ASSERT_EQ(v1.size(), v2.size()) << info.name;
    float worst = 0.0f;
    size_t worstAt = 0;
    for (size_t i = 0; i < v1.size(); ++i) {
      const float d = std::abs(v1[i] - v2[i]);
      if (!(d <= worst)) {  // also catches a NaN
        worst = std::isnan(d) ? kInfinity : d;
        worstAt = i;
      }
    }
    // The bound is the design's (one 8-bit step); every technique registered when this test was
    // written passed it (the worst difference per technique was not recorded).
    EXPECT_LE(worst, 1.0f / 255.0f) << info.name << " on " << s->scene.name << ": 1 vs 2 threads differ by " << worst
                                    << " at pixel " << worstAt;
  }
}

}  // namespace
}  // namespace penumbra
