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
#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
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
  static constexpr LightMapLayers kLayers = LightMapLayers::NearestDepth;  // compares depths only

  void reserveImpl(int width, int height) override {
    reserveShadowMap(options_.lightMap, map_, kLayers);
    state_.frame.reserve(width, height);
  }

  void prepareImpl(const Scene& scene, const Light& light) override {
    createShadowMap(scene, light, options_.lightMap, map_, kLayers);
    // The rays and the clamp look from the map's origin too (shadow_map.h): under map_fit=stable a light
    // moving within one lattice cell then changes nothing, as for every light-map technique.
    const Light atOrigin = lightAtMapOrigin(light, map_);
    setHorizonClamp(options_.lightMap.horizon, atOrigin);
    state_.prepare(scene, atOrigin);
    zMin_ = minMapDepth(map_);
    lightSize_ = light.extent();
    searchScale_ = map_.orthographic ? lightSize_ : lightSize_ / zMin_;
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override;

  // A quad's classified pixel: its search, written as a stand-in ray into `sums` (few_ray.h's tile
  // classes read them): lit, umbra (carrying the search's width ratio), or uncertain. `filterLit` is the
  // filter's lit fraction where the search found some blockers but not all. Returns the search's width
  // ratio, 0 when it found no blocker.
  float standIn(const ShadowReceiver& r, const BlockerSearch& found, float filterLit, raytraced::RaySums& sums) const {
    sums = raytraced::RaySums{1.0f, 1.0f, 0.0f, 0};  // lit
    if (found.blockers == 0) return 0.0f;
    const float ratio = ratioOf(r, found);
    bool umbra = found.blockers == static_cast<int>(blockerDisk_.size());
    if (!umbra) {
      if (filterLit == 1.0f) return ratio;  // lit: the stand-in set above
      umbra = filterLit == 0.0f;
    }
    sums = raytraced::RaySums{1.0f, umbra ? 0.0f : 0.5f, ratio, 1};
    return ratio;
  }
  // PCSS's width ratio (z_r - z_b) / z_b (orthographic: z_r - z_b), at least 0.
  float ratioOf(const ShadowReceiver& r, const BlockerSearch& found) const {
    const float zr = r.lsDepth, zb = found.meanDepth;
    return std::max(0.0f, map_.orthographic ? zr - zb : (zr - zb) / zb);
  }

  // The quads' searches of one row of pixels (the first pixel of each quad on this row that sees
  // geometry and has no pixel of its quad above it chosen): the blocker searches of the listed pixels
  // in one call, then, where a search found some blockers but not all, the same taps over PCSS's
  // penumbra estimate, the disk of radius R (z_r - z_b) / z_b: where all its taps agree they decide
  // (the search region, at the nearest depth in the map, is wider than the penumbra).
  struct RowScratch {
    ReceiverRow receivers;
    std::vector<int32_t> pixels, filtered;
    std::vector<float> radius;
    std::vector<Vec2> rotation;
    std::vector<BlockerSearch> found;
    std::vector<float> lit;
  };
  void searchRow(const GBuffer& gbuffer, int y, RowScratch& w) const {
    const auto n = static_cast<size_t>(gbuffer.width());
    w.radius.resize(n);
    w.rotation.resize(n);
    w.found.resize(n);
    w.lit.resize(n);
    makeReceiverRow(map_, gbuffer.wsPosition.row(y), gbuffer.wsGeometricNormal.row(y), gbuffer.width(), options_.bias,
                    w.receivers);
    // The pixels whose receiver is out of the map, or nearer than every blocker, need no search: lit.
    size_t kept = 0;
    for (const int32_t x : w.pixels) {
      const auto i = static_cast<size_t>(x);
      w.found[i] = BlockerSearch{};
      w.lit[i] = 1.0f;
      if (!searchesForBlockers(w.receivers, i, zMin_)) continue;
      w.radius[i] = std::min(searchRadiusTexels(w.receivers, i, searchScale_, zMin_), static_cast<float>(map_.size));
      w.rotation[i] = rotations_(x, y);
      w.pixels[kept++] = x;
    }
    w.pixels.resize(kept);
    const DepthTexels texels = depthTexels(map_);
    searchBlockersRow(texels, w.receivers, w.pixels, w.radius.data(), w.rotation.data(), blockerDisk_, w.found.data());
    w.filtered.clear();
    for (const int32_t x : w.pixels) {
      const auto i = static_cast<size_t>(x);
      const BlockerSearch& found = w.found[i];
      if (found.blockers == 0 || found.blockers == static_cast<int>(blockerDisk_.size())) continue;
      const ShadowReceiver r = w.receivers[x];
      w.radius[i] = std::min(lightSize_ * ratioOf(r, found) / r.texelWorld, static_cast<float>(map_.size));
      w.filtered.push_back(x);
    }
    pcfDiskNearestRow(texels, w.receivers, w.filtered, w.radius.data(), w.rotation.data(), blockerDisk_, w.lit.data());
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
  // probes), given to the quad's pixels; and the tiles' classes. A row of tiles at a time, each pair of
  // rows searched a row of pixels per call (searchRow).
  const int width = gbuffer.width(), height = gbuffer.height();
  const int tilesX = state_.frame.tilesX;
  tbb::enumerable_thread_specific<std::array<RowScratch, 2>> scratch;
  tbb::parallel_for(tbb::blocked_range<int>(0, state_.frame.tilesY), [&](const tbb::blocked_range<int>& tileRows) {
    std::array<RowScratch, 2>& w = scratch.local();
    for (int tileRow = tileRows.begin(); tileRow < tileRows.end(); ++tileRow) {
      const int y0 = tileRow * raytraced::kTile, y1 = std::min(y0 + raytraced::kTile, height);
      for (int qy = y0; qy < y1; qy += 2) {
        // Each quad's chosen pixel: its first pixel that sees geometry, in row order.
        const int rows = std::min(qy + 2, y1) - qy;
        w[0].pixels.clear();
        w[1].pixels.clear();
        for (int qx = 0; qx < width; qx += 2) {
          const int xEnd = std::min(qx + 2, width);
          bool chosen = false;
          for (int row = 0; row < rows && !chosen; ++row)
            for (int x = qx; x < xEnd && !chosen; ++x)
              if (gbuffer.hit(x, qy + row)) {
                w[static_cast<size_t>(row)].pixels.push_back(x);
                chosen = true;
              }
        }
        for (int row = 0; row < rows; ++row)
          if (!w[static_cast<size_t>(row)].pixels.empty()) searchRow(gbuffer, qy + row, w[static_cast<size_t>(row)]);
        // The quads' stand-ins, given to their pixels that see geometry.
        for (int qx = 0; qx < width; qx += 2) {
          const int xEnd = std::min(qx + 2, width);
          RaySums sums;
          float ratio = -1.0f;
          for (int row = 0; row < rows; ++row)
            for (int x = qx; x < xEnd; ++x) {
              const int y = qy + row;
              if (!gbuffer.hit(x, y)) continue;
              if (ratio < 0.0f) {  // the quad's chosen pixel, searched on its row
                const RowScratch& r = w[static_cast<size_t>(row)];
                const auto i = static_cast<size_t>(x);
                ratio = standIn(r.receivers[x], r.found[i], r.lit[i], sums);
              }
              state_.frame.at(x, y) = sums;
              searchRatio_(x, y) = ratio;
            }
        }
      }
      for (int tx = 0; tx < tilesX; ++tx) {
        const int tile = tileRow * tilesX + tx;
        state_.frame.tiles[static_cast<size_t>(tile)] = classifyTile(gbuffer, state_.frame, tile);
      }
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
