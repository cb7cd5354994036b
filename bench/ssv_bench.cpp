// Benchmarks of the silhouette techniques `ssv` (Rouf 2007) and `wedges` against `raytraced-hard`,
// at 1024x1024, on `concave` (a 28-triangle U slab under a square light) and on a torus of 12,288
// triangles (96 x 64 segments) under the same square light: the prepare pass (ssv: facet
// classification, double silhouette, rings and edge shadows; wedges: silhouette from the centre;
// raytraced-hard: the BVH) and the visibility pass (per pixel), in milliseconds of wall-clock time.
// wedges' prepare also builds the BVH of its hard-shadow rays (silhouettes cut at a receiver's
// depth, wedges.cpp). Counters: facets, silhouette edges (penumbra + umbra for ssv; the thesis
// assumes about f^0.8 of them, Section 3.4.1) and rings.
// Each iteration times the technique and raytraced-hard interleaved and reports the ratio of
// their totals (`over_raytraced_hard`): compare ratios from one run only, the machines are shared.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "penumbra/primitives.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "penumbra/timer.h"

namespace penumbra {
namespace {

struct BenchScene {
  Scene scene;
  GBuffer gbuffer;
};

const BenchScene& benchScene(const std::string& name) {
  static const BenchScene concave = [] {
    BenchScene b;
    b.scene = loadScene("concave");
    b.gbuffer = renderGBuffer(b.scene, 1024, 1024);
    return b;
  }();
  static const BenchScene torus = [] {
    BenchScene b;
    b.scene = loadScene("concave");
    Object& o = b.scene.objects.at(1);
    o.name = "torus";
    o.mesh = makeTorus(0.8f, 0.25f, 96, 64);
    transformMesh(o.mesh, glm::rotate(glm::translate(Mat4(1.0f), Vec3(0.0f, 1.4f, 0.0f)), radians(25.0f),
                                      Vec3(1.0f, 0.0f, 0.0f)));
    b.gbuffer = renderGBuffer(b.scene, 1024, 1024);
    return b;
  }();
  return name == "torus" ? torus : concave;
}

void passes(benchmark::State& state, const std::string& technique, const std::string& sceneName) {
  const BenchScene& s = benchScene(sceneName);
  auto t = createTechnique(technique);
  auto hard = createTechnique("raytraced-hard");
  Image<float> v;
  double prepareMs = 0.0, visibilityMs = 0.0, hardMs = 0.0;
  for (auto _ : state) {
    Timer a;
    t->prepare(s.scene, s.scene.lights.at(0));
    prepareMs += a.elapsedMs();
    Timer b;
    t->visibility(s.gbuffer, v);
    visibilityMs += b.elapsedMs();
    benchmark::DoNotOptimize(v.data());
    Timer c;
    hard->prepare(s.scene, s.scene.lights.at(0));
    hard->visibility(s.gbuffer, v);
    hardMs += c.elapsedMs();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["prepare_ms"] = prepareMs / n;
  state.counters["visibility_ms"] = visibilityMs / n;
  state.counters["raytraced_hard_ms"] = hardMs / n;
  state.counters["over_raytraced_hard"] = (prepareMs + visibilityMs) / hardMs;
  for (const auto& [key, value] : t->stats()) state.counters[key] = value;
}

BENCHMARK_CAPTURE(passes, ssv_concave, "ssv", "concave")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(passes, wedges_concave, "wedges", "concave")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(passes, ssv_torus12k, "ssv", "torus")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(passes, wedges_torus12k, "wedges", "torus")->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace penumbra
