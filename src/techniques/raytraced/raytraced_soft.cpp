// `raytraced-soft`: what engines ship for area-light shadows today — a few shadow rays per pixel and
// a denoiser — on the same G-buffer as the papers' techniques.
//
//  1. Probes: in each 8 x 8 tile, one ray from one pixel of each 2 x 2 quad (16 rays, one packet)
//     toward a point of the light, traced for its closest hit, so a blocked ray also gives the
//     blocker's distance. The tile is wholly lit, wholly in umbra, or mixed.
//  2. A tile that is mixed, or touches (8-neighbourhood) a mixed tile or one of the other uniform
//     class, is a penumbra tile: each of its pixels traces spp rays (few_ray.h: 16-ray packets of
//     8 x 2 pixels), and only they are filtered. The other tiles take their probes' 0 or 1
//     (`skip_uniform_tiles`; off: every tile is a penumbra tile).
//  3. Each penumbra pixel's penumbra width from its rays' hit distances (few_ray.h: similar
//     triangles, as PCSS's estimate but from the hits themselves), in pixels.
//  4. The filter of penumbra_filter.h, radius `filter_scale` times that width (at most max_radius).
//
// Approximations: the light is a disk of radius Light::extent() for the width estimate only (the
// rays sample its true shape); a segment's shadow is filtered isotropically, so across the segment
// it is blurred as much as along it; a tile classified uniform from its 16 probes keeps 0 or 1
// (a pixel of true V 0.95 in a tile all of whose probes were lit, and whose neighbours' were too,
// stays 1). Spatial only: nothing is carried from one frame to the next. Parameters and units:
// RaytracedSoftOptions below and PenumbraFilterOptions (penumbra_filter.h).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "few_ray.h"
#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/techniques/raytraced.h"
#include "rt/ray_scene.h"

namespace penumbra {
namespace {

class RaytracedSoftTechnique final : public ShadowTechnique {
 public:
  explicit RaytracedSoftTechnique(const RaytracedSoftOptions& options) : options_(options) {}
  std::string_view name() const override { return "raytraced-soft"; }

  std::vector<std::pair<std::string, double>> stats() const override { return state_.stats("probe"); }

 private:
  void reserveImpl(int width, int height) override { state_.frame.reserve(width, height); }
  void prepareImpl(const Scene& scene, const Light& light) override { state_.prepare(scene, light); }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override;

  RaytracedSoftOptions options_;
  raytraced::FewRayState state_;
};

void RaytracedSoftTechnique::visibilityImpl(const GBuffer& gbuffer, Image<float>& v) {
  if (!state_.rays || !state_.light)
    fail("raytraced-soft: visibility() called before prepare(); call prepare(scene, light) first");
  using namespace raytraced;
  Timer stageTimer;
  state_.frame.reset(gbuffer.width(), gbuffer.height());
  const TileRayTracer tracer(*state_.rays, *state_.light, state_.epsilon, options_.samplesPerPixel,
                             state_.frameSeed(options_.temporal, options_.seed));
  const int tiles = static_cast<int>(state_.frame.tiles.size());
  std::atomic<int64_t> rays{0};

  // 1. Probes and tile classes (each tile's pixels are traced and read by one thread).
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles), [&](const tbb::blocked_range<int>& range) {
    int64_t local = 0;
    for (int tile = range.begin(); tile < range.end(); ++tile) {
      local += tracer.probeTile(gbuffer, tile, state_.frame);
    }
    rays += local;
  });
  state_.stageMs[0] = stageTimer.elapsedMs();
  stageTimer.reset();

  // 2. Every sample of every pixel of the penumbra tiles.
  const int penumbraTiles = markPenumbraTiles(state_.frame, options_.skipUniformTiles);
  rays += tracePenumbraTiles(gbuffer, tracer, static_cast<uint32_t>(options_.samplesPerPixel), state_.frame);
  state_.stageMs[1] = stageTimer.elapsedMs();
  stageTimer.reset();

  // 3, 4. V, filtered along the penumbra width.
  resolveVisibility(gbuffer, state_.frame, *state_.light, options_.samplesPerPixel, options_.filter, state_.tanHalfFovY,
                    nullptr, v);
  if (options_.temporal.enabled) state_.history.accumulate(gbuffer, state_.camera, options_.temporal, v);
  state_.stageMs[2] = stageTimer.elapsedMs();
  state_.rayCount = static_cast<double>(rays.load());
  state_.penumbraTileFraction = tiles > 0 ? static_cast<double>(penumbraTiles) / tiles : 0.0;
}

}  // namespace

std::unique_ptr<ShadowTechnique> makeTechnique(const RaytracedSoftOptions& o) {
  validateOptions("raytraced-soft", o);
  return std::make_unique<RaytracedSoftTechnique>(o);
}

TechniqueInfo raytracedSoftTechniqueInfo() {
  TechniqueInfo info;
  info.name = "raytraced-soft";
  info.summary = "a few shadow rays per pixel in penumbra tiles, filtered along the penumbra width their hits give";
  info.source = "engine practice (axis-aligned filtering, Mehta et al. 2012; SIGMA; FidelityFX shadow denoiser)";
  info.tracesRays = true;
  info.setOptions<RaytracedSoftOptions>([](const RaytracedSoftOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
