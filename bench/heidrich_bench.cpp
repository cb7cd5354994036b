// Benchmarks of `heidrich` (Heidrich, Brabec, Seidel 2000, soft shadow maps for linear lights) on the
// `linear` built-in scene at 1024x1024 with 1024x1024 maps, wall-clock ms, next to `hard` in the same
// run (ratios within one run only: the machines are shared and noisy):
//  - heidrichOverHard/k: prepare (k + 1 shadow maps, edge detection, skins, 2k visibility maps) and
//    visibility of both techniques, interleaved in every iteration; counters are the mean ms of each
//    pass and the ratios prepare_over_hard, visibility_over_hard, total_over_hard.
//  - heidrichCameraMove/k: the slides' "static walk-through": maps prepared once, then every frame
//    sees a moved camera (two G-buffers alternating) and runs the visibility pass only, for heidrich
//    and for hard, interleaved; counter visibility_over_hard (the target: <= 2).
#include "bench_common.h"

#include <memory>
#include <string>
#include <vector>

#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "penumbra/timer.h"

namespace penumbra {
namespace {

// The scene's camera (gbuffer) and the camera moved sideways and up (movedGbuffer).
struct LinearBenchScene : bench::BenchScene {
  GBuffer movedGbuffer;
};

const LinearBenchScene& linear1024() {
  static const LinearBenchScene s = [] {
    LinearBenchScene b;
    b.scene = loadScene("linear");
    b.gbuffer = renderGBuffer(b.scene, 1024, 1024);
    Scene moved = b.scene;
    moved.camera.position += Vec3(1.5f, 1.0f, -0.5f);
    b.movedGbuffer = renderGBuffer(moved, 1024, 1024);
    return b;
  }();
  return s;
}

std::unique_ptr<ShadowTechnique> make(const std::string& name, const std::vector<std::string>& keyValues) {
  ParamSet p;
  p.setFromKeyValue("map_size=1024", "bench");
  for (const std::string& kv : keyValues) p.setFromKeyValue(kv, "bench");
  return createTechnique(name, p);
}

void heidrichOverHard(benchmark::State& state) {
  auto hard = make("hard", {});
  auto heidrich = make("heidrich", {"subdivisions=" + std::to_string(state.range(0))});
  bench::timeAgainstBaseline(state, linear1024(), "hard", *hard, "heidrich", *heidrich);
}
BENCHMARK(heidrichOverHard)->Arg(1)->Arg(2)->Arg(4)->Unit(benchmark::kMillisecond)->UseRealTime();

void heidrichCameraMove(benchmark::State& state) {
  const LinearBenchScene& s = linear1024();
  const Light& light = s.scene.lights.at(0);
  auto hard = make("hard", {});
  auto heidrich = make("heidrich", {"subdivisions=" + std::to_string(state.range(0))});
  hard->prepare(s.scene, light);
  heidrich->prepare(s.scene, light);
  Image<float> v;
  double hardMs = 0.0, heidrichMs = 0.0;
  bool moved = false;
  for (auto _ : state) {
    const GBuffer& g = moved ? s.movedGbuffer : s.gbuffer;
    moved = !moved;
    for (ShadowTechnique* t : {hard.get(), heidrich.get()}) {
      Timer timer;
      t->visibility(g, v);
      benchmark::DoNotOptimize(v.data());
      (t == hard.get() ? hardMs : heidrichMs) += timer.elapsedMs();
    }
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["hard_visibility_ms"] = hardMs / n;
  state.counters["heidrich_visibility_ms"] = heidrichMs / n;
  state.counters["visibility_over_hard"] = heidrichMs / hardMs;
}
BENCHMARK(heidrichCameraMove)->Arg(1)->Arg(2)->Arg(4)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace penumbra
