// The stages the few-ray techniques share (raytraced-soft, hybrid): shadow rays of 8 x 8 pixel tiles
// traced as 16-ray packets (8 x 2 pixels, one sample each), the tiles classified and the penumbra
// tiles marked, and V resolved from the ray sums and filtered along each pixel's penumbra width
// (penumbra_filter.h).
//
// Samples: one set of spp points correlated multi-jittered over [0,1)^2 (CmjSampler, as the
// reference's), shifted per pixel by a random offset modulo 1 (a Cranley-Patterson rotation: each
// pixel's set stays stratified and unbiased) and made into rays 16 lanes at a time by
// rt::buildShadowRays (one sample of 16 pixels a packet). The offset
// is a hash of (seed, pixel index), so a pixel's rays do not depend on the thread or the order that
// traces them and V is bit-identical for a seed at any thread count; the shared set costs two adds
// per sample where a CMJ pattern per pixel costs three hashed permutations.
//
// Penumbra width (similar triangles): a blocker at distance t along a ray to a light point at
// distance t_l blurs the shadow over D t / (t_l - t) on the receiver, D = 2 Light::extent() (for a
// directional light D t, D the solar disk's diameter at unit distance). A pixel's width ratio
// t / (t_l - t) (directional: t) is the mean over its blocked rays; a pixel none of whose rays was
// blocked takes a caller's estimate (hybrid: its blocker search) or else the mean over the 3 x 3
// tiles around it. In pixels: divided by the pixel's footprint at its view depth.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "penumbra/camera.h"
#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/light.h"
#include "penumbra/options.h"
#include "penumbra/sampling.h"
#include "penumbra/scene.h"
#include "penumbra/techniques/raytraced.h"
#include "penumbra_filter.h"
#include "rt/ray_scene.h"

namespace penumbra::raytraced {

using penumbra::PenumbraFilterOptions;  // include/penumbra/techniques/raytraced.h
using penumbra::TemporalOptions;

inline constexpr int kTile = 8;  //!< pixels per tile side

enum class TileClass : uint8_t { Empty, Lit, Umbra, Mixed };

// A pixel's sums over the rays traced for it (or, for a pixel the caller decides, one stand-in ray).
struct RaySums {
  float weight = 0.0f;   //!< sum of the light-profile weights
  float visible = 0.0f;  //!< sum of the weights of unblocked rays
  float ratio = 0.0f;    //!< sum over blocked rays of t / (t_l - t) (directional: t)
  uint8_t blocked = 0;   //!< blocked rays
};

// A tile's pixels: x in [x0, x1), y in [y0, y1) (the image's last tiles are cut at its edge).
struct TileBounds {
  int x0, y0, x1, y1;
};

// One frame's per-pixel sums and per-tile classes.
struct FewRayFrame {
  int width = 0, height = 0, tilesX = 0, tilesY = 0;
  std::vector<RaySums> sums;      //!< per pixel, row-major
  std::vector<TileClass> tiles;   //!< per tile, row-major
  std::vector<uint8_t> penumbra;  //!< per tile: 1 where its pixels trace every sample and are filtered
  // resolveVisibility's images: kept with the frame so that a technique run frame after frame reuses
  // their pages (a fresh page costs a fault, about 16 us on the machines measured: 4 MB at 1024^2
  // is some 1000 faults per image).
  Image<float> noisy, radius, reach, scratch;

  void reset(int w, int h);
  // reset, with every per-pixel buffer made at w x h and its pages touched (ShadowTechnique::reserve).
  void reserve(int w, int h);
  RaySums& at(int x, int y) { return sums[static_cast<size_t>(y) * width + x]; }
  const RaySums& at(int x, int y) const { return sums[static_cast<size_t>(y) * width + x]; }
  int tileOf(int x, int y) const { return (y / kTile) * tilesX + x / kTile; }
  TileBounds bounds(int tile) const {
    const int x0 = (tile % tilesX) * kTile, y0 = (tile / tilesX) * kTile;
    return {x0, y0, std::min(x0 + kTile, width), std::min(y0 + kTile, height)};
  }
  void clearTile(int tile);  //!< zeroes the sums of the tile's pixels
};

// Traces samples [first, last) of every pixel of a tile that sees geometry, adding them to its sums.
class TileRayTracer {
 public:
  TileRayTracer(const RayScene& scene, const Light& light, float epsilon, int samplesPerPixel, uint64_t seed);
  // Returns the rays traced.
  int64_t traceTile(const GBuffer& gbuffer, int tile, uint32_t first, uint32_t last, FewRayFrame& frame) const;
  // Classifies a tile from one probe ray (sample 0) in each 2 x 2 quad, 16 per tile in one packet, and
  // gives every pixel of a uniform tile the probes' answer as a stand-in ray (few_ray.cpp). Returns
  // the rays traced.
  int64_t probeTile(const GBuffer& gbuffer, int tile, FewRayFrame& frame) const;

 private:
  int64_t tracePixels(const GBuffer& gbuffer, const int* xs, const int* ys, int count, uint32_t first, uint32_t last,
                      FewRayFrame& frame) const;

  const RayScene& scene_;
  const Light& light_;
  float epsilon_;
  std::vector<Vec2> points_;  //!< the shared sample set in [0,1)^2
  uint64_t seed_;
};

// A tile's class from its pixels' sums: Lit when none of their rays was blocked, Umbra when all were.
TileClass classifyTile(const GBuffer& gbuffer, const FewRayFrame& frame, int tile);

// Marks frame.penumbra: the tiles that are mixed, or touch (8-neighbourhood) a mixed tile or one of
// the other uniform class; every tile with geometry when `skipUniform` is off. Returns their count.
int markPenumbraTiles(FewRayFrame& frame, bool skipUniform);

// Every sample [0, spp) of every pixel of the penumbra tiles, their sums cleared first (replacing the
// probes' or the map's stand-ins), in parallel over tiles. Returns the rays traced.
int64_t tracePenumbraTiles(const GBuffer& gbuffer, const TileRayTracer& tracer, uint32_t spp, FewRayFrame& frame);

// V from the sums (1 where the pixel sees nothing), filtered in the penumbra tiles (min_radius scaled
// by sqrt(2 / samplesPerPixel), the rays' noise against that of 2 rays). `fallbackRatio`
// (may be null; <= 0: none) is a pixel's width ratio where none of its own rays was blocked.
void resolveVisibility(const GBuffer& gbuffer, FewRayFrame& frame, const Light& light, int samplesPerPixel,
                       const PenumbraFilterOptions& filter, float tanHalfFovY, const Image<float>* fallbackRatio,
                       Image<float>& v);

class TemporalHistory {
 public:
  // Blends `v` (this frame's V) with the history in place and keeps the result as the next history.
  void accumulate(const GBuffer& gbuffer, const Camera& camera, const TemporalOptions& options, Image<float>& v);
  // Frames accumulated so far: the index of the frame about to be rendered.
  uint64_t frames() const { return frames_; }

 private:
  Image<float> v_;
  Image<float> blended_;  //!< the blend's output, kept so that each frame reuses its pages
  Image<Vec3> positions_;
  Image<int32_t> objectIds_;
  Camera camera_;
  uint64_t frames_ = 0;
};

// What raytraced-soft and hybrid keep between calls: the last prepare's ray scene, light and camera,
// the frame's storage, the temporal history, and the last visibility pass's statistics.
struct FewRayState {
  RaySceneCache raysCache;         //!< built when the geometry changed, else kept
  const RayScene* rays = nullptr;  //!< raysCache's scene, after prepare
  std::optional<Light> light;      //!< the light the rays aim at
  float epsilon = 0.0f;            //!< shadowRayEpsilon of the scene
  float tanHalfFovY = 0.0f;        //!< the camera's, for pixel footprints
  Camera camera;                   //!< this frame's, for the temporal history
  FewRayFrame frame;               //!< kept across frames: its storage is reused
  TemporalHistory history;         //!< the frames before, when temporal is on
  double rayCount = 0.0;
  double penumbraTileFraction = 0.0;
  // Milliseconds of the visibility pass's stages (stats, not finer passes: the report's visibility
  // column is the pass's own time, which finer passes would leave empty).
  double stageMs[3] = {0.0, 0.0, 0.0};

  // A new ray scene for `scene`, and its camera; `light` is what the rays aim at.
  void prepare(const Scene& scene, const Light& light);
  // The sample patterns' seed of the frame about to be rendered: new each frame when temporal is on.
  uint64_t frameSeed(const TemporalOptions& temporal, uint64_t seed) const;
  // rays, penumbra_tile_fraction and the stage times, the first stage named `firstStage`.
  std::vector<std::pair<std::string, double>> stats(const std::string& firstStage) const;
};

}  // namespace penumbra::raytraced
