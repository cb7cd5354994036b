// Benchmarks of `brabec` (Brabec & Seidel 2002) on the `crowded` built-in scene, wall-clock ms:
//  - 1024x1024 image, 1024x1024 light map: prepare (light map + tile summary) and visibility with the
//    Sec. 4.3 interpolation on and off, next to `hard` (one map lookup per pixel) in the same run.
//    The targets: brabec with interpolation <= 4x hard, and >= 5x faster than its exhaustive search.
//    The exhaustive search is the paper's Sec. 4.2 search at every pixel: every texel of the radius'
//    box examined (interpolate=false, accelerate=false). Two more rows separate the two speed-ups:
//    the interpolation alone over that same search (accelerate=false on both sides), and the tile
//    summary + local radius alone (accelerate=true, interpolate=false: still every pixel searched,
//    but tiles that cannot hold a qualifying texel skipped; it never changes V).
//    `speedups` times these passes interleaved in each iteration, so the ratios it reports as
//    counters come from one run under the same load: interpolated_over_hard; plain_over_interpolated
//    (the default against the exhaustive search); plain_over_plain_interpolated (the interpolation's
//    own speed-up); exhaustive_over_interpolated (the interpolation's gain over the tile-culled
//    search); paper_criteria_over_hard (interpolate_kinks=false).
//  - 512x512 image, 256x256 light map (the paper's setup, 10-15 fps on a 1.7 GHz Pentium 4 with the
//    maps rendered on a GeForce3): prepare + visibility per frame, reported as the counter `fps`.
// Counter `search_fraction`: searched pixels over pixels that see geometry. Compare ratios taken in
// one run only: the machines are shared and noisy.
#include <benchmark/benchmark.h>

#include <iterator>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "penumbra/timer.h"

namespace penumbra {
namespace {

struct BrabecBenchScene {
  Scene scene;
  GBuffer gbuffer;
};

const BrabecBenchScene& crowdedAt(int size) {
  static std::map<int, BrabecBenchScene> cache;  // bench-only cache, filled on the main thread
  auto it = cache.find(size);
  if (it != cache.end()) return it->second;
  BrabecBenchScene b;
  b.scene = loadScene("crowded");
  b.gbuffer = renderGBuffer(b.scene, size, size);
  return cache.emplace(size, std::move(b)).first->second;
}

std::unique_ptr<ShadowTechnique> make(const std::string& name, const std::vector<std::string>& keyValues) {
  ParamSet p;
  for (const std::string& kv : keyValues) p.setFromKeyValue(kv, "bench");
  return createTechnique(name, p);
}

double statOf(const ShadowTechnique& t, const std::string& key) {
  for (const auto& [k, v] : t.stats())
    if (k == key) return v;
  return 0.0;
}

void brabecPrepare(benchmark::State& state, int imageSize, int mapSize) {
  const BrabecBenchScene& s = crowdedAt(imageSize);
  auto t = make("brabec", {"map_size=" + std::to_string(mapSize)});
  for (auto _ : state) t->prepare(s.scene, s.scene.lights.at(0));
}

// The exhaustive search without the tile summary and the local radius: the plain Sec. 4.2 search.
void brabecPlainExhaustive(benchmark::State& state, int imageSize, int mapSize) {
  const BrabecBenchScene& s = crowdedAt(imageSize);
  auto t = make("brabec", {"map_size=" + std::to_string(mapSize), "interpolate=false", "accelerate=false"});
  t->prepare(s.scene, s.scene.lights.at(0));
  Image<float> v;
  for (auto _ : state) {
    t->visibility(s.gbuffer, v);
    benchmark::DoNotOptimize(v.data());
  }
}

void brabecVisibility(benchmark::State& state, const std::string& name, int imageSize, int mapSize, bool interpolate) {
  const BrabecBenchScene& s = crowdedAt(imageSize);
  std::vector<std::string> kv = {"map_size=" + std::to_string(mapSize)};
  if (name == "brabec") kv.push_back(interpolate ? "interpolate=true" : "interpolate=false");
  auto t = make(name, kv);
  t->prepare(s.scene, s.scene.lights.at(0));
  Image<float> v;
  for (auto _ : state) {
    t->visibility(s.gbuffer, v);
    benchmark::DoNotOptimize(v.data());
  }
  if (name == "brabec") state.counters["search_fraction"] = statOf(*t, "search_fraction");
}

// One whole frame of the paper's setup: light map, tiles and visibility.
void brabecFrame(benchmark::State& state, int imageSize, int mapSize) {
  const BrabecBenchScene& s = crowdedAt(imageSize);
  auto t = make("brabec", {"map_size=" + std::to_string(mapSize)});
  Image<float> v;
  double ms = 0.0;
  int64_t frames = 0;
  for (auto _ : state) {
    Timer timer;
    t->prepare(s.scene, s.scene.lights.at(0));
    t->visibility(s.gbuffer, v);
    benchmark::DoNotOptimize(v.data());
    ms += timer.elapsedMs();
    ++frames;
  }
  state.counters["fps"] = frames > 0 ? 1000.0 * static_cast<double>(frames) / ms : 0.0;
}

// The ratios of the targets, the passes interleaved (see the file comment).
void brabecSpeedups(benchmark::State& state, int imageSize, int mapSize) {
  const BrabecBenchScene& s = crowdedAt(imageSize);
  const std::string map = "map_size=" + std::to_string(mapSize);
  std::unique_ptr<ShadowTechnique> passes[] = {make("hard", {map}),
                                               make("brabec", {map}),
                                               make("brabec", {map, "interpolate=false"}),
                                               make("brabec", {map, "interpolate=false", "accelerate=false"}),
                                               make("brabec", {map, "interpolate_kinks=false"}),
                                               make("brabec", {map, "accelerate=false"})};
  for (auto& t : passes) t->prepare(s.scene, s.scene.lights.at(0));
  constexpr int kPasses = static_cast<int>(std::size(passes));
  double ms[kPasses] = {};
  Image<float> v;
  for (auto _ : state)
    for (int i = 0; i < kPasses; ++i) {
      Timer timer;
      passes[i]->visibility(s.gbuffer, v);
      benchmark::DoNotOptimize(v.data());
      ms[i] += timer.elapsedMs();
    }
  state.counters["interpolated_over_hard"] = ms[1] / ms[0];
  state.counters["exhaustive_over_interpolated"] = ms[2] / ms[1];
  state.counters["plain_over_interpolated"] = ms[3] / ms[1];
  state.counters["paper_criteria_over_hard"] = ms[4] / ms[0];
  // The interpolation's own speed-up with the paper's search (no tiles on either side).
  state.counters["plain_over_plain_interpolated"] = ms[3] / ms[5];
  state.counters["search_fraction"] = statOf(*passes[1], "search_fraction");
}

BENCHMARK_CAPTURE(brabecSpeedups, crowded1024_map1024, 1024, 1024)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(4);
BENCHMARK_CAPTURE(brabecPrepare, crowded1024_map1024, 1024, 1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(brabecVisibility, hard_crowded1024_map1024, std::string("hard"), 1024, 1024, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(brabecVisibility, interpolated_crowded1024_map1024, std::string("brabec"), 1024, 1024, true)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(brabecVisibility, exhaustive_crowded1024_map1024, std::string("brabec"), 1024, 1024, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(brabecPlainExhaustive, crowded1024_map1024, 1024, 1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(brabecPrepare, crowded512_map256, 512, 256)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(brabecVisibility, interpolated_crowded512_map256, std::string("brabec"), 512, 256, true)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(brabecVisibility, exhaustive_crowded512_map256, std::string("brabec"), 512, 256, false)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(brabecFrame, crowded512_map256, 512, 256)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace penumbra
