// renderLightMap and LightMap's projections (include/penumbra/raster.h): the scene seen from the
// light's centre sample, as the depth map of Brabec & Seidel 2002 (Sec. 3) and of the shadow-map
// family. Light space (docs/architecture.md, "Spaces"): origin at the centre sample, +z along the
// light's axis (Light::lightFrame) towards the scene, and lsDepth is the light-space z itself (linear, world
// units), not an NDC value.
//
// Fitting (so that every object lands in the map with as fine texels as possible):
//  - local lights: a square perspective frustum around +z whose half-angle holds all 8 corners of
//    the scene bounds, with a 0.1% margin. When a corner lies behind the light's plane (the light is
//    inside or beside the bounds), or the corners would need more, the field of view is clamped to
//    kMaxFovDegrees (150 degrees): geometry beyond 75 degrees off the axis is then missing from the
//    map. zNear sits just in front of the nearest corner, or at 1e-6 of the farthest corner's depth
//    when a corner is behind the light; geometry nearer than zNear is clipped. The depth key is the
//    reversed, infinite-far -zNear / z (see rasterizer.h).
//  - directional lights: an orthographic square centred on the bounds' centre, holding the corners'
//    extent in light x and y (0.1% margin), with the origin on the axis through the bounds' centre,
//    just behind the scene (0.1% of the bounds' radius before the nearest corner).
//
// A Stable fit (LightMapFit, raster.h) changes three things, so that a light moving a little from
// frame to frame leaves the texel grid where it was (engines do the same to their cascades):
//  - axis: a sphere's or a segment's axis (towards the scene's centre) is rounded to the centre of
//    its cell in a kStableAxisCells^2 octahedral grid of directions (cells about 4 to 8 degrees
//    wide; straight down is a cell's centre), so it turns only when the light crosses a cell; planar and directional
//    lights keep their own axis;
//  - extent: tanHalfFov (halfWidth) is rounded up to a power of 2^(1/kStableExtentSteps), after a
//    margin of one texel a side for the snap, so the texel size changes only at those steps;
//  - origin: snapped to a lattice fixed in the world, along the map's axes, whose step is one texel
//    at the reference depth (the scene centre's depth from the light, rounded up to a power of
//    2^(1/16); orthographic: one texel, across the axis only). A light moving within one lattice cell
//    leaves the map bit for bit as it was; a step to the next cell moves the whole projection by one
//    texel on the reference plane, so what lies there is rasterized exactly as before, one texel
//    over (elsewhere the parallax of the step remains: it is the shadow's own motion). The map then
//    looks from up to sqrt(3)/2 lattice steps away from the light's centre sample.
// A perspective stable map is fitted from its snapped origin and widened a step at a time until it
// holds every corner of the scene's bounds (light_map_test checks that over a long path).
//
// An Aligned fit is a Stable one whose axis is, where it can be, the world axis nearest the quantized
// one (within kStableWorldAxisDegrees, every corner of the bounds in front of the light), as a cube
// map's face. Such a map cannot stay centred on its axis: its window is centred on the scene a whole
// number of texels off the axis (LightMap::windowOffset), and the lattice's reference depth is the
// bounds' far face along the axis. Why: at a lattice step what lies at depth z moves by zRef / z - 1
// of a texel against the grid; with the Stable axis tilted a few degrees from a floor, the floor's
// depth varies across the map, its pixels change texels at some steps while the occluders' images
// move the other way, and a pixel at a shadow's edge can flip more than once where the exact edge
// crosses it once. Along the axis the floor has one depth, the reference one, and keeps its texels.
// A planar light (own axis) along a world axis gets the same window and lattice.
//
// With LightMapLayers::NearestAndFarthest (or NearestDepthAndFarthest) the same rasterization also
// keeps each texel's deepest surface (lsFarDepth, from the rasterizer's farthest layer): the ribbon
// techniques' far layer costs no second pass over the triangles. rasterizeLightMap keeps it only in
// the tiles its caller names (fitLightMap first gives the projection they are chosen from): in the
// others the rasterizer runs its near-only loop.
#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image_fill.h"
#include "penumbra/error.h"
#include "penumbra/raster.h"
#include "rasterizer.h"

namespace penumbra {

namespace {

constexpr float kMaxFovDegrees = 150.0f;
constexpr float kFitMargin = 1.001f;
constexpr int kStableAxisCells = 31;    //!< octahedral grid cells per side for the stable axis (odd: see below)
constexpr int kStableExtentSteps = 16;  //!< stable extents per octave (steps of 2^(1/16), 4.4%)
// A stable map of a sphere or segment light looks along the world axis nearest its quantized axis
// when the two are at most this far apart (degrees).
constexpr float kStableWorldAxisDegrees = 30.0f;
// An orthographic map's margin (world units) around the scene's bounds: its origin stands this far
// behind them, and its depth key's range reaches this far beyond zFar (fitLightMap, rasterizeLightMap).
float orthographicPad(const Bounds3& bounds) { return 1e-3f * std::max(bounds.radius(), 1e-6f); }

// Octahedral map of a unit direction to [-1, 1]^2 and back (Meyer et al. 2010, "On floating-point
// normal vectors"): cells of equal size in the square are of similar solid angle on the sphere. The
// octahedron's pole is straight down (-y), the most common light axis: it maps to the square's
// centre, which an odd cell count puts at the centre of a cell, so a light straight above the scene
// sits in the middle of its cell, not on an edge where the slightest move would turn the axis.
Vec2 octahedralEncode(const Vec3& wsD) {
  const Vec3 d(wsD.x, wsD.z, -wsD.y);
  const Vec3 a = d / (std::abs(d.x) + std::abs(d.y) + std::abs(d.z));
  if (a.z >= 0.0f) return Vec2(a.x, a.y);
  return Vec2((1.0f - std::abs(a.y)) * (a.x >= 0.0f ? 1.0f : -1.0f),
              (1.0f - std::abs(a.x)) * (a.y >= 0.0f ? 1.0f : -1.0f));
}

Vec3 octahedralDecode(const Vec2& e) {
  Vec3 d(e.x, e.y, 1.0f - std::abs(e.x) - std::abs(e.y));
  if (d.z < 0.0f) {
    d.x = (1.0f - std::abs(e.y)) * (e.x >= 0.0f ? 1.0f : -1.0f);
    d.y = (1.0f - std::abs(e.x)) * (e.y >= 0.0f ? 1.0f : -1.0f);
  }
  return glm::normalize(Vec3(d.x, -d.z, d.y));
}

// The centre of the octahedral cell holding direction d.
Vec3 quantizeDirection(const Vec3& d) {
  const float cell = 2.0f / static_cast<float>(kStableAxisCells);
  const Vec2 e = octahedralEncode(d);
  auto centre = [&](float v) {
    const float i = std::clamp(std::floor((v + 1.0f) / cell), 0.0f, static_cast<float>(kStableAxisCells - 1));
    return -1.0f + (i + 0.5f) * cell;
  };
  return octahedralDecode(Vec2(centre(e.x), centre(e.y)));
}

// The smallest power of 2^(1/kStableExtentSteps) at least x (x > 0).
float quantizeExtentUp(float x) {
  const double steps = std::ceil(std::log2(static_cast<double>(x)) * kStableExtentSteps - 1e-9);
  return static_cast<float>(std::exp2(steps / kStableExtentSteps));
}

std::array<Vec3, 8> corners(const Bounds3& b) {
  std::array<Vec3, 8> c;
  for (int i = 0; i < 8; ++i)
    c[i] = Vec3((i & 1) ? b.upper.x : b.lower.x, (i & 2) ? b.upper.y : b.lower.y, (i & 4) ? b.upper.z : b.lower.z);
  return c;
}

// p with its coordinates along the frame's axes (only x and y when !alongZ) rounded to multiples of
// `step` (world units). Rounded in double, since coordinates of tens of units meet steps of
// thousandths, and rebuilt from the lattice coordinates alone, so that every p in one cell gives the
// same point to the last bit.
Vec3 snapToLattice(const Vec3& p, const Frame& frame, double step, bool alongZ) {
  auto onLattice = [&](const Vec3& axis) {
    return static_cast<float>(std::round(glm::dot(p, axis) / step) * step) * axis;
  };
  return onLattice(frame.x) + onLattice(frame.y) + (alongZ ? onLattice(frame.z) : glm::dot(p, frame.z) * frame.z);
}

// The perspective frustum from origin o along frame.z that holds the corners.
struct FrustumFit {
  float tanHalf = 0.0f;                      //!< the corners' largest |x| / z and |y| / z (without margin)
  Vec2 lower{kInfinity}, upper{-kInfinity};  //!< the corners' (x / z, y / z) box
  float minZ = kInfinity, maxZ = -kInfinity;
  bool behind = false;  //!< some corner at z <= 0
};

FrustumFit fitFrustum(const Frame& frame, const Vec3& o, const std::array<Vec3, 8>& wsCorners) {
  FrustumFit f;
  for (const Vec3& p : wsCorners) {
    const Vec3 l = frame.toLocal(p - o);
    f.minZ = std::min(f.minZ, l.z);
    f.maxZ = std::max(f.maxZ, l.z);
    if (l.z > 0.0f) {
      const Vec2 u(l.x / l.z, l.y / l.z);
      f.tanHalf = std::max(f.tanHalf, std::max(std::abs(l.x), std::abs(l.y)) / l.z);
      f.lower = glm::min(f.lower, u);
      f.upper = glm::max(f.upper, u);
    } else {
      f.behind = true;
    }
  }
  return f;
}

// The world axis (+-x, +-y or +-z) nearest to d: the face of a cube map that d points into.
Vec3 nearestWorldAxis(const Vec3& d) {
  const Vec3 a = glm::abs(d);
  const int k = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
  Vec3 axis(0.0f);
  axis[k] = d[k] < 0.0f ? -1.0f : 1.0f;
  return axis;
}

bool isWorldAxis(const Vec3& d) { return (d.x == 0.0f) + (d.y == 0.0f) + (d.z == 0.0f) == 2; }

void checkMapSize(int size, const char* caller) {
  if (size < 1 || size > raster::kMaxImageSize)
    fail("{}: map size must be within 1..{} texels (got {})", caller, raster::kMaxImageSize, size);
}

// Which of a map's optional layers `layers` asks for.
bool keepsIds(LightMapLayers layers) {
  return layers == LightMapLayers::Nearest || layers == LightMapLayers::NearestAndFarthest;
}
bool keepsFarthest(LightMapLayers layers) {
  return layers == LightMapLayers::NearestAndFarthest || layers == LightMapLayers::NearestDepthAndFarthest;
}

}  // namespace

Vec3 LightMap::unproject(float s, float t, float z) const {
  const float ndcX = 2.0f * s / static_cast<float>(size) - 1.0f;
  const float ndcY = 1.0f - 2.0f * t / static_cast<float>(size);
  const float scale = orthographic ? halfWidth : z * tanHalfFov;
  return wsOrigin + lsFrame.fromLocal(Vec3((ndcX + windowOffset.x) * scale, (ndcY + windowOffset.y) * scale, z));
}

Frame lightMapFrame(const Light& light, const Bounds3& sceneBounds, LightMapFit fit) {
  const Frame frame = light.lightFrame(sceneBounds);
  const bool ownAxis = light.isDirectional() || light.shape() == LightShape::Disk ||
                       light.shape() == LightShape::Rect || light.shape() == LightShape::Polygon;
  if (fit == LightMapFit::Tight || ownAxis) return frame;
  const Vec3 cell = quantizeDirection(frame.z);
  if (fit == LightMapFit::Stable) return Frame::fromZ(cell);
  // A world axis within kStableWorldAxisDegrees of the cell, with the whole scene well in front of
  // the light along it (its nearest corner at least a tenth of the scene's diagonal away).
  const Vec3 axis = nearestWorldAxis(cell);
  bool inFront = !sceneBounds.empty();
  for (const Vec3& p : corners(sceneBounds))
    inFront = inFront && glm::dot(p - light.center(), axis) > 0.2f * sceneBounds.radius();
  if (inFront && glm::dot(cell, axis) >= std::cos(radians(kStableWorldAxisDegrees))) return Frame::fromZ(axis);
  return Frame::fromZ(cell);
}

LightMap renderLightMap(const Scene& scene, const Light& light, int size, LightMapFit fit) {
  LightMap m;
  renderLightMap(scene, light, size, m, fit);
  return m;
}

void reserveLightMap(LightMap& out, int size, LightMapLayers layers) {
  checkMapSize(size, "reserveLightMap");
  // The fills renderLightMap starts from, so the pages are touched by the threads that fill them.
  resetInParallel(out.lsDepth, size, size, kInfinity);
  if (keepsIds(layers)) resetInParallel(out.objectId, size, size, kNoObject);
  if (keepsFarthest(layers)) resetInParallel(out.lsFarDepth, size, size, kInfinity);
}

void renderLightMap(const Scene& scene, const Light& light, int size, LightMap& out, LightMapFit fit,
                    LightMapLayers layers) {
  fitLightMap(scene, light, size, out, fit);
  rasterizeLightMap(scene, out, layers);
}

void fitLightMap(const Scene& scene, const Light& light, int size, LightMap& out, LightMapFit fit) {
  checkMapSize(size, "fitLightMap");
  // Every field from its default, the images' storage from `out` (rasterizeLightMap sizes them).
  LightMap fresh;
  fresh.lsDepth = std::move(out.lsDepth);
  fresh.objectId = std::move(out.objectId);
  fresh.lsFarDepth = std::move(out.lsFarDepth);
  fresh.farTiles = std::move(out.farTiles);
  out = std::move(fresh);
  LightMap& m = out;
  m.size = size;
  const Bounds3 bounds = scene.bounds();
  m.lsFrame = lightMapFrame(light, bounds, fit);
  m.orthographic = light.isDirectional();
  m.wsOrigin = light.isDirectional() ? bounds.center() : light.center();
  if (bounds.empty()) return;

  const std::array<Vec3, 8> wsCorners = corners(bounds);
  const bool stable = fit != LightMapFit::Tight;
  // A stable extent keeps a texel of margin on each side for the snap of the origin.
  const float snapMargin = 1.0f / (1.0f - 2.0f / static_cast<float>(size));
  if (light.isDirectional()) {
    const Vec3 c = bounds.center();
    float extent = 0.0f, behind = -kInfinity, ahead = -kInfinity;
    for (const Vec3& p : wsCorners) {
      const Vec3 l = m.lsFrame.toLocal(p - c);
      extent = std::max({extent, std::abs(l.x), std::abs(l.y)});
      behind = std::max(behind, -l.z);
      ahead = std::max(ahead, l.z);
    }
    const float pad = orthographicPad(bounds);
    m.halfWidth = extent > 0.0f ? extent * kFitMargin : pad;
    m.wsOrigin = c - m.lsFrame.z * (behind + pad);
    if (stable) {
      m.halfWidth = quantizeExtentUp(m.halfWidth * snapMargin);
      // Across the axis only: depth along it does not move the grid.
      m.wsOrigin = snapToLattice(m.wsOrigin, m.lsFrame, 2.0 * m.halfWidth / size, false);
    }
    m.zNear = pad;
    m.zFar = behind + pad + ahead;
    if (stable)  // the snapped origin's float rounding may bring the nearest corner a little nearer
      for (const Vec3& p : wsCorners) m.zNear = std::min(m.zNear, m.lsFromWs(p).z);
  } else {
    const float maxTanHalf = std::tan(0.5f * radians(kMaxFovDegrees));
    FrustumFit f = fitFrustum(m.lsFrame, m.wsOrigin, wsCorners);
    // Along a world axis (Aligned) the window is centred on the scene, not on the axis: the half-width
    // it needs about a centre.
    const bool offAxis = fit == LightMapFit::Aligned && isWorldAxis(m.lsFrame.z);
    auto halfWidthAbout = [&](const FrustumFit& frustum, const Vec2& centre) {
      return offAxis ? std::max({frustum.upper.x - centre.x, centre.x - frustum.lower.x, frustum.upper.y - centre.y,
                                 centre.y - frustum.lower.y})
                     : frustum.tanHalf;
    };
    const float needed = halfWidthAbout(f, offAxis ? 0.5f * (f.lower + f.upper) : Vec2(0.0f));
    m.tanHalfFov = f.behind ? maxTanHalf : std::clamp(needed * kFitMargin, 1e-6f, maxTanHalf);
    if (stable) {
      // The lattice steps a whole texel at the reference depth zRef. Along a world axis that is the
      // depth of the scene's far face (the floor under a light above the scene), which lies in the
      // map's plane: there the receivers keep their texels while the map steps, and only what stands
      // above them moves against the grid (its shadow's own motion). Otherwise the scene's centre.
      const float zCentre = m.lsFromWs(bounds.center()).z;
      const float zFace = offAxis ? f.maxZ : zCentre;
      const double zRef = quantizeExtentUp(zFace > 0.0f ? zFace : std::max(f.maxZ, 1e-6f));
      if (!f.behind) m.tanHalfFov = std::min(quantizeExtentUp(m.tanHalfFov * snapMargin), maxTanHalf);
      // Widen a step at a time until the frustum from the snapped origin holds the corners (the
      // margin makes that the first try but for corners very near the light).
      for (;;) {
        m.wsOrigin = snapToLattice(light.center(), m.lsFrame, zRef * 2.0 * m.tanHalfFov / size, true);
        const double texel = 2.0 * m.tanHalfFov / size;  // in x / z
        f = fitFrustum(m.lsFrame, m.wsOrigin, wsCorners);
        Vec2 centre(0.0f);
        if (offAxis)  // a whole number of texels off the axis, so the texel grid stays on the lattice
          for (int k = 0; k < 2; ++k)
            centre[k] = static_cast<float>(std::round(0.5 * (f.lower[k] + f.upper[k]) / texel) * texel);
        m.windowOffset = centre / m.tanHalfFov;
        if (f.behind || m.tanHalfFov >= maxTanHalf || halfWidthAbout(f, centre) * kFitMargin <= m.tanHalfFov) break;
        m.tanHalfFov = std::min(quantizeExtentUp(m.tanHalfFov * 1.001f), maxTanHalf);
      }
      if (f.behind) {
        m.tanHalfFov = maxTanHalf;
        m.windowOffset = Vec2(0.0f);
      }
    }
    if (!(f.maxZ > 0.0f)) {  // the whole scene is behind the light: nothing to see
      m.zNear = 0.0f;
      m.zFar = 0.0f;
      return;
    }
    m.zNear = std::max(f.minZ * 0.999f, f.maxZ * 1e-6f);
    m.zFar = f.maxZ;
  }
}

void rasterizeLightMap(const Scene& scene, LightMap& m, LightMapLayers layers, std::span<const uint8_t> farTiles) {
  const int size = m.size;
  checkMapSize(size, "rasterizeLightMap");
  const bool farthest = keepsFarthest(layers), ids = keepsIds(layers);
  const int tiles = (size + kFarLayerTile - 1) / kFarLayerTile;
  if (farthest && !farTiles.empty() && farTiles.size() != static_cast<size_t>(tiles) * tiles)
    fail("rasterizeLightMap: expected one far-layer flag per {}-texel tile ({} x {}), got {}", kFarLayerTile, tiles,
         tiles, farTiles.size());
  resetInParallel(m.lsDepth, size, size, kInfinity);
  if (ids)
    resetInParallel(m.objectId, size, size, kNoObject);
  else
    m.objectId.resizeForOverwrite(0, 0);  // keeps its storage for a later map that wants ids
  // The far layer is written whole in each tile that has it (the tile visitor below), so it is not
  // filled first: that fill was a pass over 4 MB at 1024^2.
  if (farthest) {
    m.lsFarDepth.resizeForOverwrite(size, size);
    m.farTiles.assign(farTiles.begin(), farTiles.end());
  } else {
    m.lsFarDepth.resizeForOverwrite(0, 0);
    m.farTiles.clear();
  }
  const Bounds3 bounds = scene.bounds();
  // Nothing in front of the light (fitLightMap's depth range is empty) or no scene: no surface anywhere.
  if (bounds.empty() || !(m.zFar > 0.0f)) {
    if (farthest) resetInParallel(m.lsFarDepth, size, size, kInfinity);
    return;
  }
  // Clip-space z and w from light-space z (see the header comment).
  float clipZScale = 0.0f, clipZOffset = 0.0f, clipWScale = 1.0f, clipWOffset = 0.0f;
  if (m.orthographic) {
    // Linear key over [0, zFar]: z_clip = 2 z / zFar' - 1 >= -1 clips at the origin's plane.
    const float range = m.zFar * kFitMargin + orthographicPad(bounds);
    clipZScale = 2.0f / range;
    clipZOffset = -1.0f;
    clipWScale = 0.0f;
    clipWOffset = 1.0f;
  } else {
    clipZOffset = -m.zNear;  // reversed, infinite-far key -zNear / z
    clipWScale = 1.0f;
  }

  raster::ScratchVector<Vec4> clip;
  raster::ScratchVector<float> lsZ;
  raster::ScratchVector<glm::uvec3> triangles;
  raster::ScratchVector<int32_t> payloads;
  triangles.reserve(scene.triangleCount());
  payloads.reserve(scene.triangleCount());
  for (const Object& object : scene.objects) {
    const auto offset = static_cast<uint32_t>(clip.size());
    for (const glm::uvec3& t : object.mesh.triangles) {
      triangles.push_back(t + glm::uvec3(offset));
      payloads.push_back(object.id);
    }
    clip.resize(clip.size() + object.mesh.positions.size());
  }
  lsZ.resize(clip.size());
  const float xyScale = 1.0f / (m.orthographic ? m.halfWidth : m.tanHalfFov);
  const bool offset = m.windowOffset != Vec2(0.0f);
  size_t base = 0;
  for (const Object& object : scene.objects) {
    const Mesh& mesh = object.mesh;
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, mesh.positions.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
          for (size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 l = m.lsFromWs(mesh.positions[i]);
            const float w = clipWScale * l.z + clipWOffset;
            // The window's offset in clip space (x_clip / w is the map's ndc); none for most maps, where
            // subtracting 0 leaves x and y as they were, to the bit.
            const Vec2 o = offset ? m.windowOffset * w : Vec2(0.0f);
            clip[base + i] = Vec4(l.x * xyScale - o.x, l.y * xyScale - o.y, clipZScale * l.z + clipZOffset, w);
            lsZ[base + i] = l.z;
          }
        });
    base += mesh.positions.size();
  }

  raster::RasterInput input;
  input.width = size;
  input.height = size;
  input.clipPositions = clip;
  input.triangles = triangles;
  input.farthestLayer = farthest;
  input.farthestTiles = farTiles;
  static_assert(kFarLayerTile == raster::kTileSize, "a far-layer tile is one of the rasterizer's");
  raster::rasterize(input, [&](const raster::TileSamples& samples) {
    if (samples.farTriangle)  // the tile has the far layer
      for (int j = 0; j < samples.height; ++j) {
        float* row = m.lsFarDepth.row(samples.y0 + j) + samples.x0;
        for (int i = 0; i < samples.width; ++i) {
          const int k = j * raster::kTileSize + i;
          const int32_t triangle = samples.farTriangle[k];
          if (triangle < 0) {
            row[i] = kInfinity;
            continue;
          }
          const glm::uvec3& t = triangles[static_cast<size_t>(triangle)];
          const Vec3& b = samples.farBarycentrics[k];
          row[i] = b.x * lsZ[t.x] + b.y * lsZ[t.y] + b.z * lsZ[t.z];
        }
      }
    for (int j = 0; j < samples.height; ++j)
      for (int i = 0; i < samples.width; ++i) {
        const int k = j * raster::kTileSize + i;
        const int32_t triangle = samples.triangle[k];
        if (triangle < 0) continue;
        const glm::uvec3& t = triangles[static_cast<size_t>(triangle)];
        const Vec3& b = samples.barycentrics[k];
        m.lsDepth(samples.x0 + i, samples.y0 + j) = b.x * lsZ[t.x] + b.y * lsZ[t.y] + b.z * lsZ[t.z];
        if (ids) m.objectId(samples.x0 + i, samples.y0 + j) = payloads[static_cast<size_t>(triangle)];
      }
  });
}

}  // namespace penumbra
