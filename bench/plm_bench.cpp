// Benchmarks of `plm` (Lawlor 2006, "Interpolation-friendly soft shadow maps"): the prepare pass
// (light map, silhouette edges, ribbons, the lower limit's rays) and the visibility pass (one
// bilinear fetch of four channels and Equation 2 per pixel) on the `crowded` built-in scene at
// 1024x1024 with a 256^2 and a 1024^2 map, against `hard` at the same map size. The target:
// plm visibility <= 1.5x hard visibility (the paper: "a single bilinear fetch and nine instructions
// per pixel"). Ratios are taken within one run: plmOverHard alternates the two techniques in every
// iteration and reports the ratio of their visibility and prepare times as counters.
//
// lawlorTable runs the whole Fig. 10 sweep of Lawlor 2006 (include/penumbra/lawlor_table.h) once on
// `triangle` at 512x512 against a 4096-spp truth and reports every row's RMSE8 per map size as
// counters; with PENUMBRA_LAWLOR_OUT=<dir> set it also writes the table (JSON, Markdown) and Fig. 11's
// images there. It takes about a minute on 2 cores: run it alone (--benchmark_filter=lawlorTable).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <memory>
#include <string>

#include "penumbra/lawlor_table.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "penumbra/timer.h"

namespace penumbra {
namespace {

struct CrowdedScene {
  Scene scene;
  GBuffer gbuffer;
};

const CrowdedScene& crowded() {
  static const CrowdedScene s = [] {
    CrowdedScene c;
    c.scene = loadScene("crowded");
    c.gbuffer = renderGBuffer(c.scene, 1024, 1024);
    return c;
  }();
  return s;
}

std::unique_ptr<ShadowTechnique> make(const std::string& name, int64_t mapSize) {
  ParamSet p;
  p.set("map_size", mapSize, "bench");
  return createTechnique(name, p);
}

void plmOverHard(benchmark::State& state) {
  const CrowdedScene& s = crowded();
  const Light& light = s.scene.lights.at(0);
  auto hard = make("hard", state.range(0));
  auto plm = make("plm", state.range(0));
  Image<float> v;
  double hardPrepare = 0.0, hardVisibility = 0.0, plmPrepare = 0.0, plmVisibility = 0.0;
  for (auto _ : state) {
    for (ShadowTechnique* t : {hard.get(), plm.get()}) {
      t->prepare(s.scene, light);
      t->visibility(s.gbuffer, v);
      benchmark::DoNotOptimize(v.data());
      const PassTimings timings = t->timings();
      (t == hard.get() ? hardPrepare : plmPrepare) += timings.get("prepare");
      (t == hard.get() ? hardVisibility : plmVisibility) += timings.get("visibility");
    }
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["hard_prepare_ms"] = hardPrepare / n;
  state.counters["hard_visibility_ms"] = hardVisibility / n;
  state.counters["plm_prepare_ms"] = plmPrepare / n;
  state.counters["plm_visibility_ms"] = plmVisibility / n;
  state.counters["plm_over_hard_visibility"] = hardVisibility > 0.0 ? plmVisibility / hardVisibility : 0.0;
  state.counters["plm_over_hard_prepare"] = hardPrepare > 0.0 ? plmPrepare / hardPrepare : 0.0;
}
BENCHMARK(plmOverHard)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

void lawlorTable(benchmark::State& state) {
  const Scene scene = loadScene("triangle");
  for (auto _ : state) {
    const LawlorTable table = runLawlorTable(scene);
    for (const LawlorRow& row : table.rows)
      for (size_t i = 0; i < table.options.mapSizes.size(); ++i)
        state.counters[row.spec.technique + "_" + std::to_string(table.options.mapSizes[i])] = row.rmse8[i];
    if (const char* out = std::getenv("PENUMBRA_LAWLOR_OUT")) writeLawlorTable(table, out);
  }
}
BENCHMARK(lawlorTable)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
}  // namespace penumbra
