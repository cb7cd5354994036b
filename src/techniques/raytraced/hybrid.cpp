// `hybrid`: a shadow map decides where rays are needed, as engines pair shadow maps with ray tracing
// (AMD FidelityFX Hybrid Shadows; UE5's shadow-map ray marching is a relative): the map answers lit
// and umbra, and rays and the filter run only where it cannot.
//
//  1. The light map from the light's centre (shadow_map.h) and, for one pixel of each 2 x 2 quad,
//     PCSS's blocker search (Fernando 2005; pcss.cpp): `blocker_samples` taps of a Vogel disk,
//     rotated per pixel, over the region through which the receiver sees the light at the nearest
//     depth in the map. No tap blocked: lit; every tap blocked: umbra; otherwise the same taps over
//     PCSS's penumbra estimate, the disk of radius R (z_r - z_b) / z_b (z_b the blockers' mean
//     depth), decide: all lit, lit; all blocked, umbra; otherwise uncertain. The quad's other pixels
//     take its class.
//  2. Tiles of 8 x 8 pixels from those classes, and the penumbra tiles marked as raytraced-soft marks
//     them (few_ray.h): mixed tiles and their neighbours, and tiles between a lit and an umbra one.
//  3. In the penumbra tiles only, `spp` shadow rays per pixel (few_ray.h), and the filter of
//     penumbra_filter.h along each pixel's penumbra width: from its blocked rays' hit distances, or,
//     where none of its rays was blocked, from the blocker search's mean depth z_b (the width ratio
//     (z_r - z_b) / z_b, orthographic: z_r - z_b).
//  4. Every other pixel takes the map's answer, 0 or 1.
//
// Approximations: the search's taps are a sample of the region, so a pixel whose taps all miss (or all
// hit) the blockers is called lit (umbra) although a few texels of the region say otherwise; marking
// the neighbours of every mixed tile catches most of them. The search takes the light as a disk of
// radius Light::extent() (PCSS's default); the rays sample its true shape, from the map's origin
// (lightAtMapOrigin: the light's centre under the default tight fit). Map size, fit and depth bias as
// every light-map technique's (shadow_map.h).
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "../shadow_map/shadow_map.h"
#include "core/image_fill.h"
#include "few_ray.h"
#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/techniques/raytraced.h"
#include "rt/ray_scene.h"

namespace penumbra {
namespace {

class HybridTechnique final : public ShadowTechnique {
 public:
  explicit HybridTechnique(const HybridOptions& options)
      : options_(options), blockerDisk_(vogelDisk(options.blockerSamples)) {}
  std::string_view name() const override { return "hybrid"; }

  std::vector<std::pair<std::string, double>> stats() const override { return state_.stats("classify"); }

 private:
  void prepareImpl(const Scene& scene, const Light& light) override {
    createShadowMap(scene, light, options_.lightMap, map_);
    // The rays look from the map's origin too (shadow_map.h): under map_fit=stable a light moving
    // within one lattice cell then changes nothing, as for every light-map technique.
    state_.prepare(scene, lightAtMapOrigin(light, map_));
    zMin_ = minMapDepth(map_);
    lightSize_ = light.extent();
    searchScale_ = map_.orthographic ? lightSize_ : lightSize_ / zMin_;
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override;

  // The blocker search's class of one pixel, written as a stand-in ray into `sums` (few_ray.h's tile
  // classes read them): lit, umbra (carrying the search's width ratio), or uncertain. Returns the
  // search's width ratio, 0 when it found no blocker.
  float classify(const GBuffer& gbuffer, int x, int y, raytraced::RaySums& sums) const {
    sums = raytraced::RaySums{1.0f, 1.0f, 0.0f, 0};  // lit
    const ShadowReceiver r =
        makeReceiver(map_, gbuffer.wsPosition(x, y), gbuffer.wsGeometricNormal(x, y), options_.bias);
    if (!r.inMap || !(r.lsDepth > zMin_)) return 0.0f;
    const float zr = r.lsDepth;
    const float radius = std::min(searchScale_ * (zr - zMin_) / r.texelWorld, static_cast<float>(map_.size));
    const BlockerSearch found = searchBlockers(map_, r, radius, blockerDisk_, rotations_(x, y));
    if (found.blockers == 0) return 0.0f;
    const float zb = found.meanDepth;
    const float ratio = std::max(0.0f, map_.orthographic ? zr - zb : (zr - zb) / zb);
    bool umbra = found.blockers == static_cast<int>(blockerDisk_.size());
    if (!umbra) {
      // The search region (at the nearest depth in the map) is wider than the penumbra: PCSS's
      // estimate of it, the disk of radius R (z_r - z_b) / z_b, decides where all its taps agree.
      const float filterRadius = std::min(lightSize_ * ratio / r.texelWorld, static_cast<float>(map_.size));
      const float lit = pcfDiskNearest(map_, r, filterRadius, blockerDisk_, rotations_(x, y));
      if (lit == 1.0f) return ratio;  // lit: the stand-in set above
      umbra = lit == 0.0f;
    }
    sums = raytraced::RaySums{1.0f, umbra ? 0.0f : 0.5f, ratio, 1};
    return ratio;
  }

  HybridOptions options_;
  std::vector<Vec2> blockerDisk_;
  PixelRotations rotations_;
  LightMap map_;
  float zMin_ = 0.0f;
  float lightSize_ = 0.0f;    //!< the light's radius (directional: tan of half its angle)
  float searchScale_ = 0.0f;  //!< light size (orthographic) or light size / zMin_ (perspective)
  raytraced::FewRayState state_;
  Image<float> searchRatio_;
};

void HybridTechnique::visibilityImpl(const GBuffer& gbuffer, Image<float>& v) {
  if (map_.size == 0 || !state_.rays || !state_.light)
    fail("hybrid: visibility() called before prepare(); call prepare(scene, light) first");
  using namespace raytraced;
  Timer stageTimer;
  state_.frame.reset(gbuffer.width(), gbuffer.height());
  resetInParallel(searchRatio_, gbuffer.width(), gbuffer.height(), 0.0f);
  const int tiles = static_cast<int>(state_.frame.tiles.size());

  // 1. The map's class of each 2 x 2 quad, from a search at its first pixel that sees geometry (a
  // quarter of the searches; a tile is uniform only if its 16 quads agree, as raytraced-soft's 16
  // probes), given to the quad's pixels; and the tiles' classes.
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles), [&](const tbb::blocked_range<int>& range) {
    for (int tile = range.begin(); tile < range.end(); ++tile) {
      const auto [x0, y0, x1, y1] = state_.frame.bounds(tile);
      for (int qy = y0; qy < y1; qy += 2)
        for (int qx = x0; qx < x1; qx += 2) {
          RaySums sums;
          float ratio = -1.0f;
          for (int y = qy; y < std::min(qy + 2, y1); ++y)
            for (int x = qx; x < std::min(qx + 2, x1); ++x) {
              if (!gbuffer.hit(x, y)) continue;
              if (ratio < 0.0f) ratio = classify(gbuffer, x, y, sums);
              state_.frame.at(x, y) = sums;
              searchRatio_(x, y) = ratio;
            }
        }
      state_.frame.tiles[static_cast<size_t>(tile)] = classifyTile(gbuffer, state_.frame, tile);
    }
  });
  state_.stageMs[0] = stageTimer.elapsedMs();
  stageTimer.reset();

  // 2, 3. Rays in the penumbra tiles, replacing the stand-ins.
  const int penumbraTiles = markPenumbraTiles(state_.frame, true);
  const TileRayTracer tracer(*state_.rays, *state_.light, state_.epsilon, options_.samplesPerPixel,
                             state_.frameSeed(options_.temporal, options_.seed));
  const int64_t rays =
      tracePenumbraTiles(gbuffer, tracer, static_cast<uint32_t>(options_.samplesPerPixel), state_.frame);
  state_.stageMs[1] = stageTimer.elapsedMs();
  stageTimer.reset();

  // 3, 4. V: filtered rays in the penumbra tiles, the map's 0 or 1 elsewhere.
  resolveVisibility(gbuffer, state_.frame, *state_.light, options_.samplesPerPixel, options_.filter, state_.tanHalfFovY,
                    &searchRatio_, v);
  if (options_.temporal.enabled) state_.history.accumulate(gbuffer, state_.camera, options_.temporal, v);
  state_.stageMs[2] = stageTimer.elapsedMs();
  state_.rayCount = static_cast<double>(rays);
  state_.penumbraTileFraction = tiles > 0 ? static_cast<double>(penumbraTiles) / tiles : 0.0;
}

}  // namespace

std::unique_ptr<ShadowTechnique> makeTechnique(const HybridOptions& o) {
  validateOptions("hybrid", o);
  return std::make_unique<HybridTechnique>(o);
}

TechniqueInfo hybridTechniqueInfo() {
  TechniqueInfo info;
  info.name = "hybrid";
  info.summary = "a shadow map's blocker search answers lit and umbra; rays and the penumbra filter run elsewhere";
  info.source = "engine practice (FidelityFX Hybrid Shadows; PCSS's blocker search, Fernando 2005)";
  info.tracesRays = true;
  info.setOptions<HybridOptions>([](const HybridOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
