// The roofline row of the shadow-map passes: a kernel that streams exactly the bytes a visibility pass
// must move at 1024^2 on `crowded` — per pixel the world position, the geometric normal and the object
// id read (28 bytes) and V written (4), and the 1024^2 depth map read once (4 MB) — with no other work,
// and each shadow-map technique's visibility pass as a multiple of it, timed interleaved in one run
// (counters `<technique>_over_roofline`; issue target: hard <= 4x). The kernel is a lower bound of a
// pass's time on this machine: the memory traffic alone, in parallel over rows as the passes run.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "bench_common.h"
#include "penumbra/timer.h"

namespace penumbra {
namespace {

// Reads every byte a shadow pass reads and writes V: each pixel's V depends on its position, normal and
// id and on the map texel of the same index (the map is the image's size here, so all of it is read once).
void streamShadowBytes(const GBuffer& g, const LightMap& map, Image<float>& v) {
  const int width = g.width(), height = g.height();
  v.resizeForOverwrite(width, height);
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      const Vec3* __restrict p = g.wsPosition.row(y);
      const Vec3* __restrict n = g.wsGeometricNormal.row(y);
      const int32_t* __restrict id = g.objectId.row(y);
      const float* __restrict depth = map.lsDepth.row(y);
      float* __restrict out = v.row(y);
      for (int x = 0; x < width; ++x) {
        const float s = p[x].x + p[x].y + p[x].z + n[x].x + n[x].y + n[x].z;
        out[x] = id[x] >= 0 && s < depth[x] ? 1.0f : 0.0f;
      }
    }
  });
}

void shadowRoofline(benchmark::State& state) {
  const bench::BenchScene& s = bench::builtinScene("crowded", 1024);
  const LightMap map = renderLightMap(s.scene, s.scene.lights.at(0), 1024);
  if (map.size != s.gbuffer.width() || map.size != s.gbuffer.height()) {
    state.SkipWithError("the roofline kernel reads the map texel of each pixel's index: sizes must match");
    return;
  }
  const std::vector<std::string> names = {"hard", "pcf", "pcss", "brabec", "plm", "smoothies", "kirsch"};
  std::vector<std::unique_ptr<ShadowTechnique>> techniques;
  for (const std::string& name : names) {
    techniques.push_back(bench::makeTechnique(name, {"map_size=1024"}));
    techniques.back()->prepare(s.scene, s.scene.lights.at(0));
  }
  Image<float> v;
  streamShadowBytes(s.gbuffer, map, v);  // the first touch of every page, before any timing
  for (auto& t : techniques) t->visibility(s.gbuffer, v);
  double rooflineMs = 0.0;
  std::vector<double> ms(names.size(), 0.0);
  for (auto _ : state) {
    Timer timer;
    streamShadowBytes(s.gbuffer, map, v);
    benchmark::DoNotOptimize(v.data());
    rooflineMs += timer.elapsedMs();
    for (size_t i = 0; i < techniques.size(); ++i) {
      Timer t;
      techniques[i]->visibility(s.gbuffer, v);
      benchmark::DoNotOptimize(v.data());
      ms[i] += t.elapsedMs();
    }
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["roofline_ms"] = rooflineMs / n;
  for (size_t i = 0; i < names.size(); ++i) {
    state.counters[names[i] + "_ms"] = ms[i] / n;
    state.counters[names[i] + "_over_roofline"] = rooflineMs > 0.0 ? ms[i] / rooflineMs : 0.0;
  }
  state.counters["bytes_MB"] = (32.0 * s.gbuffer.width() * s.gbuffer.height() + 4.0 * map.lsDepth.size()) / 1e6;
}
BENCHMARK(shadowRoofline)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(20);

}  // namespace
}  // namespace penumbra
