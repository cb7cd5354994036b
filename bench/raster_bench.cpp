// Benchmarks of the software rasterizer (src/raster): the camera G-buffer at 1024x1024 for a
// ~100k-triangle scene (three finely tessellated spheres and two tori on a ground plane, built with
// primitives.h) and for the `crowded` built-in scene, and a 1024x1024 light map of each. Wall-clock
// milliseconds per call, all threads oneTBB gives the process, each rendered into the same G-buffer or
// map frame after frame (the first frame's allocation apart: BM_GBuffer_Tessellated100k_FirstFrame).
// Target: the 100k-triangle G-buffer in under 50 ms on 2 cores.
#include <benchmark/benchmark.h>

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "penumbra/primitives.h"
#include "penumbra/raster.h"
#include "penumbra/scene_io.h"
#include "penumbra/timer.h"

namespace penumbra {
namespace {

Object placed(int32_t id, Mesh mesh, const Vec3& at) {
  Object o;
  o.name = "object " + std::to_string(id);
  o.id = id;
  transformMesh(mesh, glm::translate(Mat4(1.0f), at));
  o.mesh = std::move(mesh);
  return o;
}

// Three spheres and two tori on a ground plane, their segment counts scaled by `k` (triangles grow as
// k^2: about 101k at k = 1, 258k at 1.6, 1M at 3.15), the shape the same.
Scene tessellated(float k) {
  auto n = [k](int segments) { return static_cast<int>(std::lround(static_cast<float>(segments) * k)); };
  Scene s;
  s.name = "tessellated";
  s.objects.push_back(placed(0, makePlane(12.0f, 12.0f), Vec3(0.0f)));
  s.objects.push_back(placed(1, makeSphere(1.0f, n(160), n(80)), Vec3(-2.2f, 1.0f, 0.0f)));
  s.objects.push_back(placed(2, makeSphere(1.0f, n(160), n(80)), Vec3(0.0f, 1.0f, -1.5f)));
  s.objects.push_back(placed(3, makeSphere(1.0f, n(160), n(80)), Vec3(2.2f, 1.0f, 0.0f)));
  s.objects.push_back(placed(4, makeTorus(0.8f, 0.3f, n(96), n(64)), Vec3(-1.0f, 0.3f, 2.0f)));
  s.objects.push_back(placed(5, makeTorus(0.8f, 0.3f, n(96), n(64)), Vec3(1.2f, 0.3f, 2.0f)));
  s.camera.position = Vec3(0.0f, 4.0f, 8.0f);
  s.camera.lookAt = Vec3(0.0f, 0.5f, 0.0f);
  s.camera.fovYDegrees = 40.0f;
  s.lights.push_back(Light::sphere(Vec3(2.0f, 8.0f, 3.0f), 0.5f));
  return s;
}

const Scene& tessellated100k() {
  static const Scene scene = tessellated(1.0f);
  return scene;
}

const Scene& crowded() {
  static const Scene scene = loadScene("crowded");
  return scene;
}

// Frame to frame: one G-buffer rendered into again and again, as a renderer does, after one untimed
// frame. The first frame, into a fresh G-buffer, also pays its 48 MB of new pages (FirstFrame).
void gbufferBench(benchmark::State& state, const Scene& scene) {
  const int size = static_cast<int>(state.range(0));
  GBuffer g = renderGBuffer(scene, size, size);
  for (auto _ : state) {
    renderGBuffer(scene, size, size, g);
    benchmark::DoNotOptimize(g.objectId.data());
  }
  state.counters["triangles"] = static_cast<double>(scene.triangleCount());
}

void gbufferFirstFrameBench(benchmark::State& state, const Scene& scene) {
  const int size = static_cast<int>(state.range(0));
  for (auto _ : state) {
    GBuffer g = renderGBuffer(scene, size, size);
    benchmark::DoNotOptimize(g.objectId.data());
  }
  state.counters["triangles"] = static_cast<double>(scene.triangleCount());
}

void lightMapBench(benchmark::State& state, const Scene& scene) {
  const int size = static_cast<int>(state.range(0));
  const Light light =
      scene.lights.empty()
          ? Light::sphere(scene.bounds().center() + Vec3(0.0f, 2.0f * scene.bounds().radius(), 0.0f), 0.5f)
          : scene.lights.front();
  LightMap m = renderLightMap(scene, light, size);
  for (auto _ : state) {
    renderLightMap(scene, light, size, m);
    benchmark::DoNotOptimize(m.lsDepth.data());
  }
  state.counters["triangles"] = static_cast<double>(scene.triangleCount());
}

void BM_GBuffer_Tessellated100k(benchmark::State& state) { gbufferBench(state, tessellated100k()); }
void BM_GBuffer_Crowded(benchmark::State& state) { gbufferBench(state, crowded()); }
void BM_GBuffer_Tessellated100k_FirstFrame(benchmark::State& state) {
  gbufferFirstFrameBench(state, tessellated100k());
}
void BM_LightMap_Tessellated100k(benchmark::State& state) { lightMapBench(state, tessellated100k()); }
void BM_LightMap_Crowded(benchmark::State& state) { lightMapBench(state, crowded()); }

// The G-buffer against triangle count (issue target: 1M triangles at most 3x the 258k time): the same
// scene at about 258k and 1M triangles, frame to frame at 1024^2, timed interleaved in one run.
void gbufferScaling(benchmark::State& state) {
  const Scene small = tessellated(1.6f), large = tessellated(3.15f);
  GBuffer gSmall = renderGBuffer(small, 1024, 1024), gLarge = renderGBuffer(large, 1024, 1024);
  double smallMs = 0.0, largeMs = 0.0;
  for (auto _ : state) {
    Timer a;
    renderGBuffer(small, 1024, 1024, gSmall);
    smallMs += a.elapsedMs();
    Timer b;
    renderGBuffer(large, 1024, 1024, gLarge);
    largeMs += b.elapsedMs();
    benchmark::DoNotOptimize(gLarge.objectId.data());
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["small_triangles"] = static_cast<double>(small.triangleCount());
  state.counters["large_triangles"] = static_cast<double>(large.triangleCount());
  state.counters["small_ms"] = smallMs / n;
  state.counters["large_ms"] = largeMs / n;
  state.counters["large_over_small"] = smallMs > 0.0 ? largeMs / smallMs : 0.0;
}
BENCHMARK(gbufferScaling)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(10);

BENCHMARK(BM_GBuffer_Tessellated100k)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GBuffer_Crowded)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GBuffer_Tessellated100k_FirstFrame)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LightMap_Tessellated100k)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LightMap_Crowded)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace penumbra
