// Prepare against triangle count, for every single-sample technique, on a real mesh: the built-in
// `wuson` scene (assimp-testmodels' Wuson, fitted onto its ground plane) with every triangle of
// every object split into 4 (edge midpoints, shared between neighbours, so the mesh stays connected
// and its shape is unchanged) 0 to 3 times: 1x, 4x, 16x and 64x the triangles (3.7k to 239k), and for
// the ray-traced techniques 1 and 4 times (15k and 956k). The shape being the
// same, the silhouette edges grow as the square root of the triangles (each silhouette edge is
// split in two per level) while the welding, edge matching and rasterization grow with the
// triangles themselves.
//
// Each iteration makes the technique afresh and times six prepares under light 0 (rect; heidrich
// under light 4, a segment, the only shape it takes): the first, which builds every cache a
// technique keeps while the geometry is unchanged (plm's, smoothies' and kirsch's edge adjacency,
// plm's and parker's BVH), and five more, steady-state frames as `penumbra bench` quotes them.
// Counters: triangles; first_ms, the mean of the first, and prepare_ms, of the steady ones' medians;
// first_us_per_triangle and prepare_us_per_triangle, the same per triangle: flat across the sizes
// when prepare grows linearly with the triangle count, falling where a part of it does not depend on
// the triangles (the passes over the 1024^2 map of the shadow-map techniques), rising where it grows
// faster. Compare within one run only (the machines are shared and noisy).
#include "bench_common.h"

#include <algorithm>
#include <array>
#include <map>
#include <utility>

namespace penumbra {
namespace {

// Every triangle split into 4 at its edges' midpoints; midpoints shared by the two triangles of an
// edge (keyed by the edge's vertex pair), shading normals interpolated where the mesh has them.
Mesh subdivide(const Mesh& mesh) {
  Mesh out;
  out.positions = mesh.positions;
  out.normals = mesh.normals;
  const bool hasNormals = mesh.normals.size() == mesh.positions.size();
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
  const auto midpoint = [&](uint32_t a, uint32_t b) {
    const auto key = std::minmax(a, b);
    auto it = midpoints.find(key);
    if (it != midpoints.end()) return it->second;
    const auto index = static_cast<uint32_t>(out.positions.size());
    out.positions.push_back(0.5f * (mesh.positions[a] + mesh.positions[b]));
    if (hasNormals) {
      const Vec3 n = mesh.normals[a] + mesh.normals[b];
      out.normals.push_back(glm::dot(n, n) > 0.0f ? glm::normalize(n) : mesh.normals[a]);
    }
    midpoints.emplace(key, index);
    return index;
  };
  out.triangles.reserve(4 * mesh.triangles.size());
  for (const glm::uvec3& t : mesh.triangles) {
    const uint32_t ab = midpoint(t.x, t.y), bc = midpoint(t.y, t.z), ca = midpoint(t.z, t.x);
    out.triangles.emplace_back(t.x, ab, ca);
    out.triangles.emplace_back(ab, t.y, bc);
    out.triangles.emplace_back(ca, bc, t.z);
    out.triangles.emplace_back(ab, bc, ca);
  }
  if (!hasNormals) out.normals.clear();
  return out;
}

// `wuson` with its triangles times `factor` (a power of 4); built once per factor.
Scene& refinedWuson(int factor) {
  static std::map<int, Scene> cache;  // benchmark-only cache
  auto it = cache.find(factor);
  if (it != cache.end()) return it->second;
  Scene scene = loadScene("wuson");
  for (int f = 1; f < factor; f *= 4)
    for (Object& object : scene.objects) object.mesh = subdivide(object.mesh);
  return cache.emplace(factor, std::move(scene)).first->second;
}

// declared: the scene's geometry declared (Scene::declareGeometry, as the command line and the Python
// module declare theirs), so that a steady prepare proves nothing; else undeclared, and each use of the
// shared caches hashes every mesh.
constexpr int kSteadyFrames = 5;

void prepareScaling(benchmark::State& state, const std::string& technique, bool declared) {
  Scene& scene = refinedWuson(static_cast<int>(state.range(0)));
  const Light& light = scene.lights.at(technique == "heidrich" ? 4 : 0);
  size_t triangles = 0;
  for (const Object& o : scene.objects) triangles += o.mesh.triangles.size();
  double firstMs = 0.0, steadyMs = 0.0;
  for (auto _ : state) {
    // A fresh technique on a scene with fresh caches (Scene::caches, where the Embree scene is shared
    // between techniques): its first prepare builds every cache; the second is a steady-state frame.
    scene.caches = makeSceneCaches();
    scene.geometryRevision = 0;
    if (declared) scene.declareGeometry();
    auto t = bench::makeTechnique(technique);
    Timer timer;
    t->prepare(scene, light);
    firstMs += timer.elapsedMs();
    // Steady frames: their median, as `penumbra bench` reports, so that the one right after the
    // first frame's build, whose memory that build evicted from the CPU's caches (a microsecond
    // where nothing is rebuilt), does not stand for them all.
    std::array<double, kSteadyFrames> steady{};
    for (double& ms : steady) {
      timer.reset();
      t->prepare(scene, light);
      ms = timer.elapsedMs();
    }
    std::nth_element(steady.begin(), steady.begin() + kSteadyFrames / 2, steady.end());
    steadyMs += steady[kSteadyFrames / 2];
  }
  const double n = static_cast<double>(state.iterations()), perTriangle = 1000.0 / static_cast<double>(triangles);
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["first_ms"] = firstMs / n;
  state.counters["first_us_per_triangle"] = firstMs / n * perTriangle;
  state.counters["prepare_ms"] = steadyMs / n;
  state.counters["prepare_us_per_triangle"] = steadyMs / n * perTriangle;
}

#define PENUMBRA_PREPARE_SCALING(name)                               \
  BENCHMARK_CAPTURE(prepareScaling, name, std::string(#name), false) \
      ->Arg(1)                                                       \
      ->Arg(4)                                                       \
      ->Arg(16)                                                      \
      ->Arg(64)                                                      \
      ->Unit(benchmark::kMillisecond)                                \
      ->UseRealTime()

PENUMBRA_PREPARE_SCALING(hard);
PENUMBRA_PREPARE_SCALING(pcss);
PENUMBRA_PREPARE_SCALING(brabec);
PENUMBRA_PREPARE_SCALING(plm);
PENUMBRA_PREPARE_SCALING(smoothies);
PENUMBRA_PREPARE_SCALING(kirsch);
PENUMBRA_PREPARE_SCALING(heidrich);
PENUMBRA_PREPARE_SCALING(parker);

// The ray-traced techniques keep their Embree scene while the geometry is the same: a steady prepare
// builds no BVH, so at 1M triangles (256x) it should cost about what it costs at 16k (4x): with the
// geometry declared it does; undeclared, the hash that proves it unchanged grows with the triangles.
#define PENUMBRA_PREPARE_SCALING_RAYS(label, technique)                             \
  BENCHMARK_CAPTURE(prepareScaling, label, std::string(technique), false)           \
      ->Arg(4)                                                                      \
      ->Arg(256)                                                                    \
      ->Unit(benchmark::kMillisecond)                                               \
      ->UseRealTime();                                                              \
  BENCHMARK_CAPTURE(prepareScaling, label##_declared, std::string(technique), true) \
      ->Arg(4)                                                                      \
      ->Arg(256)                                                                    \
      ->Unit(benchmark::kMillisecond)                                               \
      ->UseRealTime()

// The names as strings: a name with '-' passed as macro tokens would be stringized with spaces.
PENUMBRA_PREPARE_SCALING_RAYS(raytraced_hard, "raytraced-hard");
PENUMBRA_PREPARE_SCALING_RAYS(raytraced_soft, "raytraced-soft");
PENUMBRA_PREPARE_SCALING_RAYS(hybrid, "hybrid");
PENUMBRA_PREPARE_SCALING_RAYS(reference, "reference");

#undef PENUMBRA_PREPARE_SCALING_RAYS
#undef PENUMBRA_PREPARE_SCALING

}  // namespace
}  // namespace penumbra
