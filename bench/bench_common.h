// Shared pieces of the technique benchmarks: built-in scenes with their camera G-buffer (cached per
// process), technique creation from "key=value" strings, and the interleaved comparison every
// "X over baseline" benchmark uses. Both techniques run in every iteration, one after the other, so
// they see the same machine load; ratios are only meaningful within one run (the machines are shared
// and noisy).
#pragma once

#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "penumbra/timer.h"

namespace penumbra::bench {

struct BenchScene {
  Scene scene;
  GBuffer gbuffer;
};

// Built-in scene `name` with its G-buffer at size x size; filled on first use, on the main thread.
inline const BenchScene& builtinScene(const std::string& name, int size) {
  static std::map<std::pair<std::string, int>, BenchScene> cache;  // benchmark-only cache
  const auto key = std::make_pair(name, size);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  BenchScene b;
  b.scene = loadScene(name);
  b.gbuffer = renderGBuffer(b.scene, size, size);
  return cache.emplace(key, std::move(b)).first->second;
}

inline std::unique_ptr<ShadowTechnique> makeTechnique(const std::string& name,
                                                      const std::vector<std::string>& keyValues = {}) {
  ParamSet p;
  for (const std::string& kv : keyValues) p.setFromKeyValue(kv, "bench");
  return createTechnique(name, p);
}

// Times prepare and visibility of `baseline` and `technique` on `s`, interleaved, and reports the
// mean ms of each pass (<label>_prepare_ms, <label>_visibility_ms) and the ratios technique /
// baseline (prepare_over_<baseline>, visibility_over_<baseline>, total_over_<baseline>). Both run one
// untimed frame first: the timed ones are the frame-to-frame cost, with the techniques' storage in
// place, not the first frame's page faults (a few iterations would otherwise carry them).
inline void timeAgainstBaseline(benchmark::State& state, const BenchScene& s, const std::string& baselineLabel,
                                ShadowTechnique& baseline, const std::string& label, ShadowTechnique& technique) {
  const Light& light = s.scene.lights.at(0);
  Image<float> v;
  for (ShadowTechnique* t : {&baseline, &technique}) {
    t->prepare(s.scene, light);
    t->visibility(s.gbuffer, v);
  }
  double ms[2][2] = {};  // [baseline, technique][prepare, visibility]
  for (auto _ : state) {
    int index = 0;
    for (ShadowTechnique* t : {&baseline, &technique}) {
      Timer timer;
      t->prepare(s.scene, light);
      ms[index][0] += timer.elapsedMs();
      timer.reset();
      t->visibility(s.gbuffer, v);
      benchmark::DoNotOptimize(v.data());
      ms[index][1] += timer.elapsedMs();
      ++index;
    }
  }
  const double n = static_cast<double>(state.iterations());
  state.counters[baselineLabel + "_prepare_ms"] = ms[0][0] / n;
  state.counters[baselineLabel + "_visibility_ms"] = ms[0][1] / n;
  state.counters[label + "_prepare_ms"] = ms[1][0] / n;
  state.counters[label + "_visibility_ms"] = ms[1][1] / n;
  state.counters["prepare_over_" + baselineLabel] = ms[1][0] / ms[0][0];
  state.counters["visibility_over_" + baselineLabel] = ms[1][1] / ms[0][1];
  state.counters["total_over_" + baselineLabel] = (ms[1][0] + ms[1][1]) / (ms[0][0] + ms[0][1]);
}

}  // namespace penumbra::bench
