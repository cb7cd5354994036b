// Shared shadow-map stages (Filament-style free functions) used by the shadow-map techniques
// (`hard`, `pcf`, `pcss`, `multisample`) and by `brabec`:
//  - createShadowMap: the light-space depth + object-id map seen from one point of the light
//    (renderLightMap), with the technique's map size validated;
//  - makeReceiver + the depth compare: a camera pixel's surface point in map coordinates, with a
//    receiver-plane depth (Isidoro 2006, "Shadow mapping: GPU-based tips and techniques", GDC) and a
//    slope-scaled bias (Williams 1978's shadow map plus the usual polygon-offset style bias);
//  - the PCF box kernel (Reeves, Salesin, Cook 1987, "Rendering antialiased shadows with depth
//    maps", SIGGRAPH), exact for the nearest-texel compare function;
//  - the PCSS blocker search (Fernando 2005, "Percentage-closer soft shadows", SIGGRAPH sketch):
//    mean depth of the blockers in a disk of texels, and PCF over a disk (bilinear or nearest-texel
//    taps), vectorized in chunks of taps, 16 to a vector where the CPU has AVX-512F (shadow_map.cpp;
//    every path gives the same V).
//
// Conventions (docs/architecture.md, "Spaces"; include/penumbra/raster.h): map coordinates (s, t) in texels,
// texel (i, j) covers [i, i+1) x [j, j+1) and its depth was rasterized at its centre (i+0.5, j+0.5);
// light-space depth z is the distance along the light's axis, in world units.
//
// Depth compare. A texel holds a blocker for a receiver when its depth is smaller than the depth the
// receiver's tangent plane has *at that texel's centre*, minus a bias. Evaluating the receiver's
// plane at the texel centre (rather than comparing against the receiver's own depth) removes the
// depth error of a tilted receiver that grows with the texel offset, so the same compare serves a
// 1-texel lookup and a 40-texel PCSS kernel. The bias that is left covers curvature, faceting and
// float rounding:
//     bias = bias_constant * texelWorldSize(z) + bias_slope * |grad z|,
// with |grad z| the receiver plane's depth change per texel (world units), i.e. texelWorldSize(z)
// times tan(angle between the surface normal and the ray to the light) in a perspective map.
// Approximations: the plane is extrapolated linearly in (s, t) (exact for an orthographic map, first
// order for a perspective one); its slope is limited to kMaxDepthSlope texel sizes per texel (about
// 84 degrees from facing the light) so a receiver seen edge-on from the light does not extrapolate to
// absurd depths. Receivers outside the map (behind a local light, or outside its frustum) are lit:
// the map records no occluder for them.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/horizon.h"
#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/light.h"
#include "penumbra/math.h"
#include "penumbra/options.h"
#include "penumbra/raster.h"
#include "penumbra/sampling.h"
#include "penumbra/scene.h"
#include "penumbra/techniques/shadow_map.h"

namespace penumbra {

// Receiver-plane slope limit, in texel sizes of depth per texel (tan 84 degrees ~ 9.5).
inline constexpr float kMaxDepthSlope = 10.0f;

// The light-space depth + object-id map of `light` seen from its centre sample (renderLightMap).
// Throws Error if the size is outside [kMinShadowMapSize, kMaxShadowMapSize].
LightMap createShadowMap(const Scene& scene, const Light& light, const LightMapOptions& options);
// The same into `out`, reusing its storage (renderLightMap); `out` is untouched when the size is refused.
void createShadowMap(const Scene& scene, const Light& light, const LightMapOptions& options, LightMap& out,
                     LightMapLayers layers = LightMapLayers::Nearest);
// createShadowMap's first step alone (fitLightMap: the projection, no images), for a technique that
// chooses where it wants the far layer from it before rasterizeLightMap; the same check of the size.
void fitShadowMap(const Scene& scene, const Light& light, const LightMapOptions& options, LightMap& out);
// The storage createShadowMap fills at the options' map size made in `out` (reserveLightMap), for a
// technique's reserveImpl.
void reserveShadowMap(const LightMapOptions& options, LightMap& out, LightMapLayers layers = LightMapLayers::Nearest);

// The light as `map` sees it: moved so that its centre sample is the map's origin. A stable fit
// (LightMapFit::Stable) snaps that origin to a world lattice, so whatever a technique takes from the
// light besides the map (silhouettes, the side a receiver faces, rays to the light) must look from the
// same point: from the light's own centre it would change within a lattice cell, where the map holds
// still, and no longer match the map. A tight fit's origin is the centre itself, and a directional
// light has no position: `light` is returned unchanged for both.
Light lightAtMapOrigin(const Light& light, const LightMap& map);

// Smallest finite depth in the map (the nearest possible blocker); kInfinity for an empty map.
float minMapDepth(const LightMap& map);

// One camera pixel's surface point as seen by a shadow map.
struct ShadowReceiver {
  float s = 0.0f, t = 0.0f;  //!< map coordinates, texels
  float lsDepth = 0.0f;      //!< light-space depth z, world units
  float dzds = 0.0f;         //!< receiver plane's depth change per texel along s, world units
  float dzdt = 0.0f;         //!< ... along t
  float bias = 0.0f;         //!< world units
  float texelWorld = 0.0f;   //!< texelWorldSize(lsDepth), world units
  bool inMap = false;        //!< false: behind a local light or outside the map's frustum (lit)
};

namespace detail {
// num / den limited to [-kMaxDepthSlope, kMaxDepthSlope], also when den is 0.
inline float limitedRatio(float num, float den) {
  // 0 / 0 (a surface seen edge-on from the light, whose normal has no component along this map axis
  // either): its depth does not change along the axis (the quotient, NaN, would make every compare
  // with the receiver's plane false).
  if (std::abs(num) <= kMaxDepthSlope * std::abs(den)) return den != 0.0f ? num / den : 0.0f;
  const float sign = (num < 0.0f) != (den < 0.0f) ? -1.0f : 1.0f;
  return sign * kMaxDepthSlope;
}
}  // namespace detail

// The receiver at map position stz = (s, t, depth) of light-space point lsP with light-space normal lsN:
// the map bounds test, the receiver plane's slopes and the bias. makeReceiver's second half, for
// callers that already hold the light-space point (heidrich's maps share one frame). Inline: it runs
// once per pixel and map, and a caller with two maps (heidrich) overlaps their two chains of divides.
inline ShadowReceiver receiverAt(const LightMap& map, const Vec3& stz, const Vec3& lsP, const Vec3& lsN,
                                 const DepthBias& bias) {
  ShadowReceiver r;
  r.s = stz.x;
  r.t = stz.y;
  r.lsDepth = stz.z;
  const float size = static_cast<float>(map.size);
  if (!(r.s >= 0.0f && r.s < size && r.t >= 0.0f && r.t < size) || !std::isfinite(r.lsDepth)) return r;
  r.inMap = true;
  r.texelWorld = map.texelWorldSize(r.lsDepth);
  // The receiver plane N.X = N.P met by the ray through map position (s, t). Perspective: the ray
  // is X = z (a, b, 1), a growing with s and b falling with t by texelWorld / z per texel, so
  // dz/ds = -Nx texelWorld / (N.d) and dz/dt = +Ny texelWorld / (N.d) with N.d = N.P / z.
  // Orthographic: X = (x, y, z), the same with N.d = Nz. Both in texel sizes per texel here.
  const float nDotD = map.orthographic ? lsN.z : glm::dot(lsN, lsP) / lsP.z;
  const float gs = detail::limitedRatio(-lsN.x, nDotD);
  const float gt = detail::limitedRatio(lsN.y, nDotD);
  r.dzds = gs * r.texelWorld;
  r.dzdt = gt * r.texelWorld;
  r.bias = r.texelWorld * (bias.constantTexels + bias.slope * std::sqrt(gs * gs + gt * gt));
  return r;
}

// A camera pixel's surface point as the map sees it. Inline: every shadow-map technique calls it once
// per pixel, and in the caller's loop the compiler overlaps its divides with the caller's work.
inline ShadowReceiver makeReceiver(const LightMap& map, const Vec3& wsPosition, const Vec3& wsGeometricNormal,
                                   const DepthBias& bias) {
  const Vec3 lsP = map.lsFromWs(wsPosition);
  if (!map.orthographic && !(lsP.z > 0.0f)) return {};  // behind a local light: not in its map
  return receiverAt(map, map.projectLightSpace(lsP), lsP, map.lsFrame.toLocal(wsGeometricNormal), bias);
}

// The receivers of a row of pixels, as structure of arrays: makeReceiverRow sets them up in one loop the
// compiler vectorizes (no calls, no branches; the same float operations as makeReceiver, so each field
// is makeReceiver's to the bit), where makeReceiver, called pixel by pixel, cannot be. Pixels that see
// nothing get receivers too; callers skip them.
struct ReceiverRow {
  std::vector<float> s, t, lsDepth, dzds, dzdt, bias, texelWorld;
  std::vector<int32_t> inMap;  //!< 0 or 1 (32 bits, as the floats: one vector width in the loop)
  // The nearest texel's blocker threshold (blockerThreshold at (floor s, floor t)) and that texel's
  // index in the map (y * size + x), for hardShadow's compare; 0 outside the map.
  std::vector<float> nearestThreshold;
  std::vector<int32_t> nearestTexel;

  ShadowReceiver operator[](int x) const {
    const auto i = static_cast<size_t>(x);
    ShadowReceiver r;
    r.s = s[i];
    r.t = t[i];
    r.lsDepth = lsDepth[i];
    r.dzds = dzds[i];
    r.dzdt = dzdt[i];
    r.bias = bias[i];
    r.texelWorld = texelWorld[i];
    r.inMap = inMap[i] != 0;
    return r;
  }
};
// The receivers of `count` pixels with these world positions and geometric normals (a G-buffer row).
void makeReceiverRow(const LightMap& map, const Vec3* wsPositions, const Vec3* wsGeometricNormals, int count,
                     const DepthBias& bias, ReceiverRow& out);
// The same for a perspective `map` whose axes are those of `frame` and whose origin lies at lsOffset in
// frame's light space (heidrich's maps, one per sample point of the light): each pixel is taken into
// frame's light space and moved by -lsOffset, as heidrich::receiverInMap does, to the bit.
void makeReceiverRowInFrame(const LightMap& frame, const Vec3& lsOffset, const LightMap& map, const Vec3* wsPositions,
                            const Vec3* wsGeometricNormals, int count, const DepthBias& bias, ReceiverRow& out);

// The depth below which texel (i, j) holds a blocker for the receiver.
inline float blockerThreshold(const ShadowReceiver& r, int i, int j) {
  return r.lsDepth + r.dzds * (static_cast<float>(i) + 0.5f - r.s) + r.dzdt * (static_cast<float>(j) + 0.5f - r.t) -
         r.bias;
}

// 1 if texel (i, j) lets the light through to the receiver, 0 if it holds a blocker. Texels outside
// the map hold nothing.
inline float litAtTexel(const LightMap& map, const ShadowReceiver& r, int i, int j) {
  if (i < 0 || j < 0 || i >= map.size || j >= map.size) return 1.0f;
  return map.lsDepth(i, j) < blockerThreshold(r, i, j) ? 0.0f : 1.0f;
}

// Williams' hard shadow: the compare at the texel holding (s, t). V in {0, 1}.
inline float hardShadow(const LightMap& map, const ShadowReceiver& r) {
  if (!r.inMap) return 1.0f;
  return litAtTexel(map, r, static_cast<int>(std::floor(r.s)), static_cast<int>(std::floor(r.t)));
}

// PCF: the mean of the nearest-texel compare function over the square of side `widthTexels`
// centred at (s, t). Computed exactly: the square covers whole texels with weight 1 and partial
// texels at its border with the covered fraction (separable weights 1-f, 1, ..., 1, f), so V varies
// continuously with (s, t) — a box of width 1 is the familiar 2x2 bilinear PCF.
float pcfBox(const LightMap& map, const ShadowReceiver& r, float s, float t, float widthTexels);

// A disk of n sample offsets in the unit disk, evenly spread (Vogel's sunflower spiral:
// radius sqrt((i + 0.5) / n), angle i times the golden angle). Deterministic.
std::vector<Vec2> vogelDisk(int n);

// Rotation (cos, sin) of a per-pixel disk pattern, from a hash of the pixel: trades the banding of
// one fixed pattern for fine noise. Deterministic.
Vec2 pixelRotation(int x, int y);

// Per-pixel rotations from a 16x16 tile repeated over the image (the interleaved-gradient trick):
// the tile holds each of the kCount angles 2 pi k / kCount once, placed by pixelRotation's hash of the
// tile cell (the cells sorted by hash take k = 0, 1, ...), so a pixel costs a table read instead of a
// hash. Noise that repeats every 16 pixels reads as noise; every 16x16 block holds every angle.
class PixelRotations {
 public:
  static constexpr int kTileBits = 4;
  static constexpr int kTile = 1 << kTileBits;
  static constexpr int kCount = kTile * kTile;
  PixelRotations();
  Vec2 operator()(int x, int y) const {
    return table_[static_cast<size_t>(((y & (kTile - 1)) << kTileBits) | (x & (kTile - 1)))];
  }

 private:
  std::vector<Vec2> table_;
};

// The depths the disk kernels below read: texel (i, j) at depth[j * stride + i], j and i in
// [0, size) (a LightMap's, or a copy laid out otherwise).
struct DepthTexels {
  const float* depth = nullptr;
  size_t stride = 0;  //!< floats from one row to the next, >= size
  int size = 0;       //!< texels per side
};
inline DepthTexels depthTexels(const LightMap& map) {
  return DepthTexels{map.lsDepth.data(), static_cast<size_t>(map.size), map.size};
}

struct BlockerSearch {
  int blockers = 0;        //!< samples that found a blocker
  float meanDepth = 0.0f;  //!< mean light-space depth of those blockers (0 when none)
};

// The blocker search's radius in texels before any cut, scale (z - zMin) / texelWorld: the search
// disk's world radius at a receiver of depth z over the texel size there (scale = R / zMin for a
// perspective map, R for an orthographic one); a receiver searches when it lies in the map and behind
// the map's nearest depth zMin (nothing can block in front of it). Shared by pcss (listSearchingPixels)
// and hybrid's quad search.
inline float searchRadiusTexels(const ReceiverRow& receivers, size_t x, float scale, float zMin) {
  return scale * (receivers.lsDepth[x] - zMin) / receivers.texelWorld[x];
}
inline bool searchesForBlockers(const ReceiverRow& receivers, size_t x, float zMin) {
  return receivers.inMap[x] != 0 && receivers.lsDepth[x] > zMin;
}

// PCSS's first step over a row of receivers: which pixels search for blockers and how far. A pixel
// searches when it sees geometry (ids[x] != kNoObject), lies in the map and lies behind the map's
// nearest depth zMin (nothing can block in front of it); it is listed in `pixels`, in order. Every
// pixel gets radius[x] = min(scale (z - zMin) / texelWorld, maxRadius) texels (the search disk's
// world radius at the receiver over the texel size there; scale = R / zMin for a perspective map, R
// for an orthographic one), clamped[x] = whether the cut applied, and out[x] = 1 (V of the pixels that
// do not search, replaced where they do). Every array has room for `width` pixels. One pass of 16
// pixels to a vector where the CPU has AVX-512F; the same results on every path.
struct SearchingPixels {
  int count = 0;        //!< pixels listed
  int64_t hits = 0;     //!< pixels that see geometry
  int64_t clamped = 0;  //!< listed pixels whose radius was cut
};
SearchingPixels listSearchingPixels(const int32_t* ids, const ReceiverRow& receivers, int width, float scale,
                                    float zMin, float maxRadius, int32_t* pixels, float* radius, uint8_t* clamped,
                                    float* out);

// PCSS blocker search: the texels under the disk `pattern` (unit-disk offsets) rotated by
// `rotation` and scaled to `radiusTexels` around (r.s, r.t).
BlockerSearch searchBlockers(const DepthTexels& map, const ShadowReceiver& r, float radiusTexels,
                             std::span<const Vec2> pattern, const Vec2& rotation);

// searchBlockers at each listed pixel x of a row of receivers (makeReceiverRow), with radius
// radiusTexels[x] and rotation rotations[x], into out[x]: the same results, with the work that does not
// depend on the pixel done once per row.
void searchBlockersRow(const DepthTexels& map, const ReceiverRow& receivers, std::span<const int32_t> pixels,
                       const float* radiusTexels, const Vec2* rotations, std::span<const Vec2> pattern,
                       BlockerSearch* out);

// pcfDisk and pcfDiskNearest at each listed pixel x of a row of receivers, into out[x]: the same values.
void pcfDiskRow(const DepthTexels& map, const ReceiverRow& receivers, std::span<const int32_t> pixels,
                const float* radiusTexels, const Vec2* rotations, std::span<const Vec2> pattern, float* out);
void pcfDiskNearestRow(const DepthTexels& map, const ReceiverRow& receivers, std::span<const int32_t> pixels,
                       const float* radiusTexels, const Vec2* rotations, std::span<const Vec2> pattern, float* out);

// PCF over a disk: the mean of 1-texel box compares (pcfBox width 1) at the pattern's offsets.
float pcfDisk(const DepthTexels& map, const ShadowReceiver& r, float radiusTexels, std::span<const Vec2> pattern,
              const Vec2& rotation);

// PCF over a disk with one compare per tap, at the texel holding (s, t) + offset (the taps of
// searchBlockers): a quarter of pcfDisk's reads, for disks whose taps lie over a texel apart, where
// the 1-texel box of pcfDisk smooths little. V is a multiple of 1 / pattern.size().
float pcfDiskNearest(const DepthTexels& map, const ShadowReceiver& r, float radiusTexels, std::span<const Vec2> pattern,
                     const Vec2& rotation);

inline BlockerSearch searchBlockers(const LightMap& map, const ShadowReceiver& r, float radiusTexels,
                                    std::span<const Vec2> pattern, const Vec2& rotation) {
  return searchBlockers(depthTexels(map), r, radiusTexels, pattern, rotation);
}
inline float pcfDisk(const LightMap& map, const ShadowReceiver& r, float radiusTexels, std::span<const Vec2> pattern,
                     const Vec2& rotation) {
  return pcfDisk(depthTexels(map), r, radiusTexels, pattern, rotation);
}
inline float pcfDiskNearest(const LightMap& map, const ShadowReceiver& r, float radiusTexels,
                            std::span<const Vec2> pattern, const Vec2& rotation) {
  return pcfDiskNearest(depthTexels(map), r, radiusTexels, pattern, rotation);
}

// Runs f(y, receivers) for every row y of the G-buffer with the row's receivers in `map`
// (makeReceiverRow), in parallel over rows: the loop of forEachReceiver, for passes that read the
// row's arrays themselves (hard's nearest-texel compare) or count per row.
template <class F>
void forEachReceiverRow(const GBuffer& gbuffer, const LightMap& map, const DepthBias& bias, F&& f) {
  tbb::parallel_for(tbb::blocked_range<int>(0, gbuffer.height()), [&](const tbb::blocked_range<int>& rows) {
    ReceiverRow receivers;  // per task: a few per frame
    for (int y = rows.begin(); y < rows.end(); ++y) {
      makeReceiverRow(map, gbuffer.wsPosition.row(y), gbuffer.wsGeometricNormal.row(y), gbuffer.width(), bias,
                      receivers);
      f(y, static_cast<const ReceiverRow&>(receivers));
    }
  });
}

// Runs f(x, y, receiver) -> V for every pixel of the G-buffer that sees geometry, with its receiver in
// `map` set up a row at a time (makeReceiverRow), in parallel over rows; V = 1 where the pixel sees
// nothing; then clamps the row by the receivers' own surfaces as `horizon` says
// (ShadowTechnique::horizonForRows).
// Deterministic: every pixel is computed on its own.
template <class F>
void forEachReceiver(const GBuffer& gbuffer, const LightMap& map, const DepthBias& bias, Image<float>& v, F&& f,
                     const HorizonBound& horizon = {}) {
  // Every pixel written below, in parallel: no serial fill first (and a fresh image's pages are first
  // touched by both cores).
  v.resizeForOverwrite(gbuffer.width(), gbuffer.height());
  forEachReceiverRow(gbuffer, map, bias, [&](int y, const ReceiverRow& receivers) {
    float* out = v.row(y);
    const int32_t* ids = gbuffer.objectId.row(y);
    for (int x = 0; x < gbuffer.width(); ++x) out[x] = ids[x] != kNoObject ? f(x, y, receivers[x]) : 1.0f;
    clampRowToHorizon(gbuffer, horizon, y, out);
  });
}

// Runs f(x, y) -> V for every pixel of the G-buffer that sees geometry, in parallel over rows;
// V = 1 where the pixel sees nothing. Deterministic: every pixel is computed on its own.
template <class F>
void forEachReceiverPixel(const GBuffer& gbuffer, Image<float>& v, F&& f) {
  v.resizeForOverwrite(gbuffer.width(), gbuffer.height());  // every pixel written below
  tbb::parallel_for(tbb::blocked_range<int>(0, gbuffer.height()), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      float* out = v.row(y);
      for (int x = 0; x < gbuffer.width(); ++x) out[x] = gbuffer.hit(x, y) ? f(x, y) : 1.0f;
    }
  });
}

}  // namespace penumbra
