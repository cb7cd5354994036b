// Benchmarks of the few-ray techniques (src/techniques/raytraced/).
//
// raytracedSoftOverBrabec, hybridOverPcss: the frame-time targets at 1024x1024 on `torus` and
// `crowded`: raytraced-soft within 2x brabec's frame (at RMSE8 at most brabec's), hybrid within
// pcss's (at RMSE8 at most pcss's); the RMSE8s are in docs/results.md. Interleaved, one untimed frame
// first (bench_common.h); total_over_<baseline> is the ratio.
//
// rayThroughput: shadow rays per second of a technique's ray stages against Embree's own
// rtcOccluded16 and rtcIntersect16 on the very same rays: one pass of the technique is traced with a
// PacketLog attached to its ray scene (rt/ray_scene.h), which keeps every packet as the technique
// handed it to Embree, and the clock then times the technique's passes (log detached) and Embree
// alone replaying the logged packets in parallel (a fresh copy each time, as Embree writes the hits),
// interleaved. The technique's time is that of its stages that trace: the reference's whole pass;
// raytraced-soft's probe and rays stages (they also classify the tiles); hybrid's rays stage (its
// shadow-map classification traces nothing). Counters: technique_rays_per_s; raw_occluded16 and
// raw_intersect16 rays_per_s on the logged packets; technique_over_raw_same_query (against the query the
// technique makes: occlusion for the reference, closest hits for the few-ray techniques, which need the
// blocker's distance) and technique_over_raw_occluded (the target: at least 0.8; a closest-hit
// query costs more than an occlusion query on the same rays, which this ratio charges to the
// technique). The replay's scene is built with RayScene's flags (robust, high quality). On `crowded` at
// 512x512, at the spp named.
#include "bench_common.h"

#include <algorithm>
#include <cstring>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "rt/ray_scene.h"

namespace penumbra {
namespace {

void raytracedSoftOverBrabec(benchmark::State& state, const std::string& sceneName) {
  const bench::BenchScene& s = bench::builtinScene(sceneName, 1024);
  auto brabec = bench::makeTechnique("brabec");
  auto soft = bench::makeTechnique("raytraced-soft");
  bench::timeAgainstBaseline(state, s, "brabec", *brabec, "raytraced_soft", *soft);
}
BENCHMARK_CAPTURE(raytracedSoftOverBrabec, torus1024, std::string("torus"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(raytracedSoftOverBrabec, crowded1024, std::string("crowded"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void hybridOverPcss(benchmark::State& state, const std::string& sceneName) {
  const bench::BenchScene& s = bench::builtinScene(sceneName, 1024);
  auto pcss = bench::makeTechnique("pcss");
  auto hybrid = bench::makeTechnique("hybrid");
  bench::timeAgainstBaseline(state, s, "pcss", *pcss, "hybrid", *hybrid);
}
BENCHMARK_CAPTURE(hybridOverPcss, torus1024, std::string("torus"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(hybridOverPcss, crowded1024, std::string("crowded"))->Unit(benchmark::kMillisecond)->UseRealTime();

// The scene as RayScene builds it, for Embree's own calls.
struct EmbreeScene {
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene scene = rtcNewScene(device);
  explicit EmbreeScene(const Scene& s) {
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    for (const Object& object : s.objects) {
      if (object.mesh.triangles.empty()) continue;
      RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                   3 * sizeof(float), object.mesh.positions.size()));
      auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
          geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), object.mesh.triangles.size()));
      for (size_t i = 0; i < object.mesh.positions.size(); ++i)
        for (int k = 0; k < 3; ++k) vertices[3 * i + k] = object.mesh.positions[i][k];
      for (size_t i = 0; i < object.mesh.triangles.size(); ++i)
        for (int k = 0; k < 3; ++k) indices[3 * i + k] = object.mesh.triangles[i][k];
      rtcCommitGeometry(geom);
      rtcAttachGeometry(scene, geom);
      rtcReleaseGeometry(geom);
    }
    rtcCommitScene(scene);
  }
  ~EmbreeScene() {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;
};

// A logged packet as Embree's own types, with its valid mask.
struct Packet {
  RTCRayHit16 rays;  // the ray half for rtcOccluded16, both halves for rtcIntersect16
  alignas(64) int valid[16];
};

std::vector<Packet> toEmbree(const std::vector<LoggedPacket>& logged) {
  std::vector<Packet> packets(logged.size());
  for (size_t i = 0; i < logged.size(); ++i) {
    static_assert(sizeof(RayPacket16) == sizeof(RTCRay16));
    std::memcpy(&packets[i].rays.ray, &logged[i].rays, sizeof(RTCRay16));
    for (int lane = 0; lane < 16; ++lane) {
      packets[i].valid[lane] = lane < logged[i].count ? -1 : 0;
      packets[i].rays.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
      packets[i].rays.hit.instID[0][lane] = RTC_INVALID_GEOMETRY_ID;
    }
  }
  return packets;
}

// Seconds to trace every packet (a fresh copy: Embree writes tfar and the hits), on every core.
double traceRaw(const EmbreeScene& embree, const std::vector<Packet>& source, bool intersect) {
  std::vector<Packet> packets = source;
  Timer timer;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, packets.size()), [&](const tbb::blocked_range<size_t>& range) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (size_t i = range.begin(); i < range.end(); ++i) {
      if (intersect)
        rtcIntersect16(packets[i].valid, embree.scene, &context, &packets[i].rays);
      else
        rtcOccluded16(packets[i].valid, embree.scene, &context, &packets[i].rays.ray);
    }
  });
  return timer.elapsedMs() / 1000.0;
}

void rayThroughput(benchmark::State& state, const std::string& technique, int spp) {
  const bench::BenchScene& s = bench::builtinScene("crowded", 512);
  auto t = bench::makeTechnique(technique, {"spp=" + std::to_string(spp)});
  const EmbreeScene embree(s.scene);
  Image<float> v;
  t->prepare(s.scene, s.scene.lights.at(0));
  t->visibility(s.gbuffer, v);  // untimed: storage in place
  // The ray scene the technique traces: the scene's shared one (RaySceneCache).
  RaySceneCache cache;
  const RayScene& rays = cache.get(s.scene);
  PacketLog log;
  rays.attachLog(&log);
  t->visibility(s.gbuffer, v);
  rays.attachLog(nullptr);
  const std::vector<LoggedPacket> logged = log.packets();
  if (logged.empty()) {
    state.SkipWithError("the technique traced no packets");
    return;
  }
  const bool closestHit = logged.front().closestHit;
  size_t loggedRays = 0;
  for (const LoggedPacket& p : logged) loggedRays += static_cast<size_t>(p.count);
  const std::vector<Packet> packets = toEmbree(logged);

  // Stages that trace, by the technique's stats (bench header); the reference's is its whole pass.
  const std::vector<std::string> tracing = technique == "raytraced-soft"
                                               ? std::vector<std::string>{"probe_ms", "rays_ms"}
                                           : technique == "hybrid" ? std::vector<std::string>{"rays_ms"}
                                                                   : std::vector<std::string>{};
  double techniqueSeconds = 0.0, techniqueRays = 0.0, occludedSeconds = 0.0, intersectSeconds = 0.0;
  for (auto _ : state) {
    Timer timer;
    t->visibility(s.gbuffer, v);
    const double passSeconds = timer.elapsedMs() / 1000.0;
    benchmark::DoNotOptimize(v.data());
    double stageMs = 0.0;
    for (const auto& [name, value] : t->stats()) {
      if (name == "rays") techniqueRays += value;
      if (std::find(tracing.begin(), tracing.end(), name) != tracing.end()) stageMs += value;
    }
    techniqueSeconds += tracing.empty() ? passSeconds : stageMs / 1000.0;
    occludedSeconds += traceRaw(embree, packets, false);
    intersectSeconds += traceRaw(embree, packets, true);
  }
  const double n = static_cast<double>(state.iterations());
  const double techniqueRate = techniqueRays / techniqueSeconds;
  const double occludedRate = static_cast<double>(loggedRays) * n / occludedSeconds;
  const double intersectRate = static_cast<double>(loggedRays) * n / intersectSeconds;
  state.counters["technique_rays_per_s"] = techniqueRate;
  state.counters["raw_occluded16_rays_per_s"] = occludedRate;
  state.counters["raw_intersect16_rays_per_s"] = intersectRate;
  state.counters["rays_per_packet"] = static_cast<double>(loggedRays) / static_cast<double>(logged.size());
  state.counters["technique_over_raw_same_query"] = techniqueRate / (closestHit ? intersectRate : occludedRate);
  state.counters["technique_over_raw_occluded"] = techniqueRate / occludedRate;
}
BENCHMARK_CAPTURE(rayThroughput, reference1spp, std::string("reference"), 1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(rayThroughput, reference4spp, std::string("reference"), 4)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(rayThroughput, raytracedSoft2spp, std::string("raytraced-soft"), 2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(rayThroughput, hybrid2spp, std::string("hybrid"), 2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace penumbra
