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
#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "penumbra/error.h"
#include "penumbra/raster.h"
#include "rasterizer.h"

namespace penumbra {

namespace {

constexpr float kMaxFovDegrees = 150.0f;
constexpr float kFitMargin = 1.001f;

std::array<Vec3, 8> corners(const Bounds3& b) {
  std::array<Vec3, 8> c;
  for (int i = 0; i < 8; ++i)
    c[i] = Vec3((i & 1) ? b.upper.x : b.lower.x, (i & 2) ? b.upper.y : b.lower.y, (i & 4) ? b.upper.z : b.lower.z);
  return c;
}

}  // namespace

Vec3 LightMap::unproject(float s, float t, float z) const {
  const float ndcX = 2.0f * s / static_cast<float>(size) - 1.0f;
  const float ndcY = 1.0f - 2.0f * t / static_cast<float>(size);
  const float scale = orthographic ? halfWidth : z * tanHalfFov;
  return wsOrigin + lsFrame.fromLocal(Vec3(ndcX * scale, ndcY * scale, z));
}

LightMap renderLightMap(const Scene& scene, const Light& light, int size) {
  LightMap m;
  renderLightMap(scene, light, size, m);
  return m;
}

void renderLightMap(const Scene& scene, const Light& light, int size, LightMap& out) {
  if (size < 1 || size > raster::kMaxImageSize)
    fail("renderLightMap: map size must be within 1..{} texels (got {})", raster::kMaxImageSize, size);
  // Every field from its default, the images' storage from `out`.
  LightMap fresh;
  fresh.lsDepth = std::move(out.lsDepth);
  fresh.objectId = std::move(out.objectId);
  out = std::move(fresh);
  LightMap& m = out;
  m.size = size;
  m.lsDepth.reset(size, size, kInfinity);
  m.objectId.reset(size, size, kNoObject);
  const Bounds3 bounds = scene.bounds();
  m.lsFrame = light.lightFrame(bounds);
  m.orthographic = light.isDirectional();
  m.wsOrigin = light.isDirectional() ? bounds.center() : light.center();
  if (bounds.empty()) return;

  const std::array<Vec3, 8> wsCorners = corners(bounds);
  // Clip-space z and w from light-space z (see the header comment).
  float clipZScale = 0.0f, clipZOffset = 0.0f, clipWScale = 1.0f, clipWOffset = 0.0f;
  if (light.isDirectional()) {
    const Vec3 c = bounds.center();
    float extent = 0.0f, behind = -kInfinity, ahead = -kInfinity;
    for (const Vec3& p : wsCorners) {
      const Vec3 l = m.lsFrame.toLocal(p - c);
      extent = std::max({extent, std::abs(l.x), std::abs(l.y)});
      behind = std::max(behind, -l.z);
      ahead = std::max(ahead, l.z);
    }
    const float pad = 1e-3f * std::max(bounds.radius(), 1e-6f);
    m.halfWidth = extent > 0.0f ? extent * kFitMargin : pad;
    m.wsOrigin = c - m.lsFrame.z * (behind + pad);
    m.zNear = pad;
    m.zFar = behind + pad + ahead;
    // Linear key over [0, zFar]: z_clip = 2 z / zFar' - 1 >= -1 clips at the origin's plane.
    const float range = m.zFar * kFitMargin + pad;
    clipZScale = 2.0f / range;
    clipZOffset = -1.0f;
    clipWScale = 0.0f;
    clipWOffset = 1.0f;
  } else {
    float minZ = kInfinity, maxZ = -kInfinity, tanHalf = 0.0f;
    bool behind = false;
    for (const Vec3& p : wsCorners) {
      const Vec3 l = m.lsFromWs(p);
      minZ = std::min(minZ, l.z);
      maxZ = std::max(maxZ, l.z);
      if (l.z > 0.0f)
        tanHalf = std::max(tanHalf, std::max(std::abs(l.x), std::abs(l.y)) / l.z);
      else
        behind = true;
    }
    const float maxTanHalf = std::tan(0.5f * radians(kMaxFovDegrees));
    m.tanHalfFov = behind ? maxTanHalf : std::clamp(tanHalf * kFitMargin, 1e-6f, maxTanHalf);
    if (!(maxZ > 0.0f)) {  // the whole scene is behind the light: nothing to see
      m.zNear = 0.0f;
      m.zFar = 0.0f;
      return;
    }
    m.zNear = std::max(minZ * 0.999f, maxZ * 1e-6f);
    m.zFar = maxZ;
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
  size_t base = 0;
  for (const Object& object : scene.objects) {
    const Mesh& mesh = object.mesh;
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, mesh.positions.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
          for (size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 l = m.lsFromWs(mesh.positions[i]);
            clip[base + i] =
                Vec4(l.x * xyScale, l.y * xyScale, clipZScale * l.z + clipZOffset, clipWScale * l.z + clipWOffset);
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
  raster::rasterize(input, [&](const raster::TileSamples& samples) {
    for (int j = 0; j < samples.height; ++j)
      for (int i = 0; i < samples.width; ++i) {
        const int k = j * raster::kTileSize + i;
        const int32_t triangle = samples.triangle[k];
        if (triangle < 0) continue;
        const glm::uvec3& t = triangles[static_cast<size_t>(triangle)];
        const Vec3& b = samples.barycentrics[k];
        m.lsDepth(samples.x0 + i, samples.y0 + j) = b.x * lsZ[t.x] + b.y * lsZ[t.y] + b.z * lsZ[t.z];
        m.objectId(samples.x0 + i, samples.y0 + j) = payloads[static_cast<size_t>(triangle)];
      }
  });
}

}  // namespace penumbra
