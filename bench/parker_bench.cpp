// Benchmarks of `parker` (Parker, Shirley and Smits 1998) against `raytraced-hard`, the hard
// ray-traced shadow the paper compares with ("The ray tracer was approximately 20% slower after the
// change"), at 1024x1024 on `spheres` (analytic spheres: parker tests the true spheres, raytraced-
// hard traces their tessellations) and `torus` (a triangle mesh: parker's outer objects are its
// silhouette edges). The targets are parker <= 1.3x raytraced-hard on spheres and <= 2x on meshes.
// Both techniques run in every iteration, interleaved, so that they see the same machine load; the
// counters are the mean milliseconds of each pass and the ratios parker / raytraced-hard of each
// pass and of their total (visibility_over_raytraced_hard is the per-frame ray work).
// Measured (2-core development machine, medians of 3 repetitions): visibility 1.16x on spheres and
// 1.47x on torus, prepare + visibility 1.10x and 1.48x. Both build their rays the same way (one
// direction to the light per pixel, rt::storeRay); before raytraced-hard did, the ratios read
// 1.05x and 1.31x, a fifth of parker's apparent lead being raytraced-hard's slower set-up.
#include "bench_common.h"

namespace penumbra {
namespace {

void parkerOverRaytracedHard(benchmark::State& state, const std::string& sceneName) {
  const bench::BenchScene& s = bench::builtinScene(sceneName, 1024);
  auto hard = bench::makeTechnique("raytraced-hard");
  auto parker = bench::makeTechnique("parker");
  bench::timeAgainstBaseline(state, s, "raytraced_hard", *hard, "parker", *parker);
}

BENCHMARK_CAPTURE(parkerOverRaytracedHard, spheres1024, std::string("spheres"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(parkerOverRaytracedHard, torus1024, std::string("torus"))->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace penumbra
