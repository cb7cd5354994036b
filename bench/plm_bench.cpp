// Benchmarks of `plm` (Lawlor 2006, "Interpolation-friendly soft shadow maps"): the prepare pass
// (light map, silhouette edges, ribbons, the lower limit's rays) and the visibility pass (one
// bilinear fetch of four channels and Equation 2 per pixel) on the `crowded` built-in scene at
// 1024x1024 with a 256^2 and a 1024^2 map, against `hard` at the same map size. The target:
// plm visibility <= 1.5x hard visibility (the paper: "a single bilinear fetch and nine instructions
// per pixel"). Ratios are taken within one run: plmOverHard alternates the two techniques in every
// iteration and reports visibility_over_hard and prepare_over_hard as counters.
//
// lawlorTable runs the whole Fig. 10 sweep of Lawlor 2006 (src/experiments/lawlor_table.h) once on
// `triangle` at 512x512 against a 4096-spp truth and reports every row's RMSE8 per map size as
// counters; with PENUMBRA_LAWLOR_OUT=<dir> set it also writes the table (JSON, Markdown) and Fig. 11's
// images there. It takes about a minute on 2 cores: run it alone (--benchmark_filter=lawlorTable).
#include "bench_common.h"

#include <cstdlib>
#include <memory>
#include <string>

#include "experiments/lawlor_table.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "penumbra/timer.h"

namespace penumbra {
namespace {

void plmOverHard(benchmark::State& state) {
  const std::string map = "map_size=" + std::to_string(state.range(0));
  auto hard = bench::makeTechnique("hard", {map});
  auto plm = bench::makeTechnique("plm", {map});
  bench::timeAgainstBaseline(state, bench::builtinScene("crowded", 1024), "hard", *hard, "plm", *plm);
}
BENCHMARK(plmOverHard)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

// smoothies and kirsch share plm's ribbon stages; issue 22's target for all three: prepare <= 2x hard's.
void ribbonOverHard(benchmark::State& state, const std::string& name) {
  auto hard = bench::makeTechnique("hard", {"map_size=1024"});
  auto ribbon = bench::makeTechnique(name, {"map_size=1024"});
  bench::timeAgainstBaseline(state, bench::builtinScene("crowded", 1024), "hard", *hard, name, *ribbon);
}
BENCHMARK_CAPTURE(ribbonOverHard, smoothies, std::string("smoothies"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(ribbonOverHard, kirsch, std::string("kirsch"))->Unit(benchmark::kMillisecond)->UseRealTime();

void lawlorTable(benchmark::State& state) {
  const Scene scene = loadScene("triangle");
  for (auto _ : state) {
    const LawlorTable table = runLawlorTable(scene);
    for (const LawlorRow& row : table.rows)
      for (size_t i = 0; i < table.options.mapSizes.size(); ++i)
        state.counters[row.spec.technique +
                       (!row.spec.half                          ? ""
                        : *row.spec.half == PenumbraHalf::Outer ? "_outer"
                                                                : "_inner") +
                       "_" + std::to_string(table.options.mapSizes[i])] = row.rmse8[i];
    if (const char* out = std::getenv("PENUMBRA_LAWLOR_OUT")) writeLawlorTable(table, out);
  }
}
BENCHMARK(lawlorTable)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
}  // namespace penumbra
