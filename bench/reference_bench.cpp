// Speed of the `reference` technique on the built-in `crowded` scene (~17k triangles, sphere light):
// shadow (occlusion) rays per second of visibility(), reported as the counter "rays/s", and the BVH
// build of prepare(). The camera G-buffer is ray cast once outside the timed loop. Target on 2 cores:
// >= 20 M rays/s (single precision, 16-ray coherent packets).
#include <benchmark/benchmark.h>

#include "penumbra/reference.h"
#include "penumbra/scene_io.h"
#include "rt/ray_scene.h"

namespace penumbra {
namespace {

struct CrowdedFixture {
  Scene scene = loadScene("crowded");
  GBuffer gbuffer;
  explicit CrowdedFixture(int size) {
    const RayScene rays(scene);
    gbuffer = traceGBuffer(scene, rays, size, size);
  }
};

void BM_ReferenceVisibility(benchmark::State& state) {
  const CrowdedFixture fixture(static_cast<int>(state.range(0)));
  ReferenceTechnique reference(ReferenceOptions{static_cast<uint32_t>(state.range(1)), 1});
  reference.prepare(fixture.scene, fixture.scene.lights.at(0));
  Image<float> v;
  double rays = 0.0;
  for (auto _ : state) {
    reference.visibility(fixture.gbuffer, v);
    benchmark::DoNotOptimize(v.data());
    for (const auto& [name, value] : reference.stats())
      if (name == "rays") rays += value;
  }
  state.counters["rays/s"] = benchmark::Counter(rays, benchmark::Counter::kIsRate);
}
// image size, spp. Wall-clock time: the pass runs on every core.
BENCHMARK(BM_ReferenceVisibility)->Args({256, 64})->Args({128, 256})->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ReferencePrepare(benchmark::State& state) {
  const Scene scene = loadScene("crowded");
  ReferenceTechnique reference(ReferenceOptions{});
  for (auto _ : state) reference.prepare(scene, scene.lights.at(0));
  state.counters["triangles"] = static_cast<double>(scene.triangleCount());
}
BENCHMARK(BM_ReferencePrepare)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace penumbra

BENCHMARK_MAIN();
