// The software rasterizer's products: the camera G-buffer and light-space depth + object-id maps.
// The rasterizer itself (src/raster/rasterizer.h) is internal; these are what techniques consume.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/light.h"
#include "penumbra/math.h"
#include "penumbra/scene.h"

namespace penumbra {

// Rasterizes the camera view of `scene` into a width x height G-buffer (pixel centres sampled).
GBuffer renderGBuffer(const Scene& scene, int width, int height);
// The same into `out`, whose images keep their storage where it is large enough: a G-buffer rendered
// every frame then costs a pass over its memory, not fresh pages.
void renderGBuffer(const Scene& scene, int width, int height, GBuffer& out);
// `g` made the empty width x height G-buffer of GBuffer(width, height), its six images filled
// concurrently (their pages touched): storage for renderGBuffer made before the frames that use it.
void resetGBuffer(GBuffer& g, int width, int height);

// Which surfaces a light map keeps per texel: the nearest surface's depth alone (LightMap::objectId
// left empty, for the techniques that compare depths only), the nearest with its object id (the
// shadow map), or also the deepest (LightMap::lsFarDepth, rasterized in the same pass; the ribbon
// techniques' far layer), with the nearest's id or, for a technique that never reads ids, without.
enum class LightMapLayers { NearestDepth, Nearest, NearestAndFarthest, NearestDepthAndFarthest };

// How a light map is fitted to the scene bounds each time it is rendered (src/raster/light_map.cpp).
enum class LightMapFit {
  // Refitted to the scene every frame from the light's centre sample: the finest texels, but the
  // texel grid turns, shifts and rescales as the light moves, so edges shimmer over a sequence.
  Tight,
  // As engines stabilize their cascades: the axis quantized to fixed directions (sphere and segment
  // lights; a planar light keeps its normal, a directional light its direction), the extent quantized
  // to steps of 2^(1/16), and the map's origin snapped to a world-fixed lattice of whole texels.
  // Under light motion within a lattice cell the map does not change at all. Texels are coarser than
  // Tight's by up to an extent step plus what the quantized axis's tilt costs, and the map looks
  // from up to a texel (at the scene's centre) away from the light's centre sample.
  Stable,
  // Stable, looking along a world axis (+-x, +-y, +-z) as a cube map's face does, where one lies
  // within 30 degrees of Stable's axis with the scene well in front of the light (else Stable's): the
  // window is centred on the scene a whole number of texels off the axis, and the lattice steps a
  // whole texel at the depth of the scene's far face. The floor under a light above the scene then
  // lies in the map's plane and keeps its texels while the map steps; only what stands above it moves
  // against the grid, as its shadow does. A planar light whose normal is a world axis keeps it.
  Aligned,
};

// The scene seen from the light's centre sample: a size x size map of light-space depth and object
// id. Local lights use a perspective projection, directional lights an orthographic one; either is
// fitted to the scene bounds so every object lands in the map.
struct LightMap {
  int size = 0;
  bool orthographic = false;
  Vec3 wsOrigin{0.0f};  //!< light-space origin: the centre sample, snapped when Stable (directional: behind the scene)
  Frame lsFrame;        //!< light-space axes in world space; +z along the light's axis
  // Projection of light-space (x, y) to map coordinates, one of:
  //  perspective: s = size/2 * (1 + (x / (z tanHalfFov) - o_x)), t = size/2 * (1 - (y / (z tanHalfFov) - o_y))
  //  orthographic: s = size/2 * (1 + x / halfWidth),    t = size/2 * (1 - y / halfWidth)
  // with o = windowOffset: the window is centred on the axis (o = 0) but in an Aligned map, whose
  // window is centred on the scene, a whole number of texels off the axis.
  float tanHalfFov = 1.0f;          //!< perspective
  float halfWidth = 1.0f;           //!< orthographic, world units
  Vec2 windowOffset{0.0f};          //!< perspective: the window's centre over tanHalfFov (x / z, y / z)
  float zNear = 0.0f, zFar = 1.0f;  //!< light-space depth range that holds the scene
  Image<float> lsDepth;             //!< light-space depth z (distance along +z); kInfinity where empty
  Image<int32_t> objectId;          //!< kNoObject where empty; empty (0 x 0) with LightMapLayers::NearestDepth
  // LightMapLayers::NearestAndFarthest only (else empty): the light-space depth of the deepest
  // surface along the texel's ray; kInfinity where empty. Only in the tiles farTiles names.
  Image<float> lsFarDepth;
  // Which kFarLayerTile x kFarLayerTile tiles (row-major, ceil(size / kFarLayerTile) to a row) hold
  // lsFarDepth: nonzero where they do; empty where every tile does. Elsewhere lsFarDepth holds
  // whatever its storage held (rasterizeLightMap says why).
  std::vector<uint8_t> farTiles;

  Vec3 lsFromWs(const Vec3& wsP) const { return lsFrame.toLocal(wsP - wsOrigin); }
  // Map coordinates (s, t) of a world point (texel centres at integer + 0.5, t down) and its
  // light-space depth z.
  Vec3 project(const Vec3& wsP) const { return projectLightSpace(lsFromWs(wsP)); }
  // The same for a point already in light space (lsFromWs): callers that need both skip the
  // second transform.
  Vec3 projectLightSpace(const Vec3& lsP) const {
    const float half = 0.5f * static_cast<float>(size);
    const float scale = orthographic ? 1.0f / halfWidth : 1.0f / (lsP.z * tanHalfFov);
    return Vec3(half * (1.0f + (lsP.x * scale - windowOffset.x)), half * (1.0f - (lsP.y * scale - windowOffset.y)),
                lsP.z);
  }
  // World point at map coordinates (s, t) and light-space depth z (the inverse of project).
  Vec3 unproject(float s, float t, float z) const;
  // Size of one texel in world units at light-space depth z.
  float texelWorldSize(float z) const {
    return 2.0f * (orthographic ? halfWidth : z * tanHalfFov) / static_cast<float>(size);
  }
};

// The light map's axes for `light` over a scene with these bounds: Light::lightFrame, with its axis
// quantized to fixed directions when the fit is Stable and the light has no axis of its own.
Frame lightMapFrame(const Light& light, const Bounds3& sceneBounds, LightMapFit fit);

LightMap renderLightMap(const Scene& scene, const Light& light, int size, LightMapFit fit = LightMapFit::Tight);
// The same into `out`, whose images keep their storage where it is large enough: a map rendered
// every frame then costs a pass over its memory, not fresh pages.
void renderLightMap(const Scene& scene, const Light& light, int size, LightMap& out,
                    LightMapFit fit = LightMapFit::Tight, LightMapLayers layers = LightMapLayers::Nearest);
// renderLightMap in two steps, for a caller that needs the map's projection to decide where it wants
// the far layer (the ribbon techniques: only where a ribbon can reach, most often a small part of the
// map; the far layer elsewhere would double the depth test's work for nothing).
// fitLightMap sets every field of `out` but its images, as renderLightMap would (the images keep their
// storage); rasterizeLightMap then draws `scene` (the one the map was fitted to) into them, the far
// layer only in the kFarLayerTile tiles whose flag in `farTiles` is nonzero (as LightMap::farTiles;
// empty: everywhere). Together they give renderLightMap's map to the bit in every tile that has a
// layer.
inline constexpr int kFarLayerTile = 64;
void fitLightMap(const Scene& scene, const Light& light, int size, LightMap& out, LightMapFit fit = LightMapFit::Tight);
void rasterizeLightMap(const Scene& scene, LightMap& map, LightMapLayers layers = LightMapLayers::Nearest,
                       std::span<const uint8_t> farTiles = {});
// The storage of a size x size map of these layers made in `out` and its pages touched, for
// ShadowTechnique::reserve: a later renderLightMap into it of that size allocates nothing.
void reserveLightMap(LightMap& out, int size, LightMapLayers layers = LightMapLayers::Nearest);

}  // namespace penumbra
