// lightAboveHorizon and clampToHorizon of horizon.h.
#include "core/horizon.h"

#include "core/target_clones.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace penumbra {
namespace {

// The share of a uniformly filled disk (centre c, unit normal m, radius r) on the side of the plane
// through p where n . (x - p) > 0. Over the disk n . (x - p) runs over s +- r |n - (n . m) m|, s its
// value at the centre; the part on either side of 0 is a circular segment.
float diskShare(const Vec3& c, const Vec3& m, float r, const Vec3& p, const Vec3& n) {
  const float s = glm::dot(n, c - p);
  const float reach = r * glm::length(n - glm::dot(n, m) * m);
  if (!(s < reach)) return 1.0f;
  const float t = std::clamp(s / reach, -1.0f, 1.0f);  // the plane's distance from the centre, in radii
  return 1.0f - (std::acos(t) - t * std::sqrt(std::max(0.0f, 1.0f - t * t))) / kPi;
}

// The share of a planar polygon's area on the side n . (x - p) > 0: one Sutherland-Hodgman clip
// against the plane, whose output has the right signed area for a concave polygon too.
float polygonShare(const std::vector<Vec3>& vertices, const Vec3& normal, const Vec3& p, const Vec3& n) {
  const size_t count = vertices.size();
  bool anyBelow = false;
  for (const Vec3& v : vertices) anyBelow = anyBelow || glm::dot(n, v - p) < 0.0f;
  if (!anyBelow) return 1.0f;
  auto twiceArea = [&](const Vec3* loop, size_t size) {
    Vec3 sum(0.0f);
    for (size_t i = 0; i < size; ++i) sum += glm::cross(loop[i], loop[i + 1 < size ? i + 1 : 0]);
    return glm::dot(sum, normal);
  };
  // The clip adds at most one vertex per edge it cuts; a light of many vertices clips into the heap.
  std::array<Vec3, 40> local;
  std::vector<Vec3> heap;
  if (2 * count > local.size()) heap.resize(2 * count);
  Vec3* clipped = heap.empty() ? local.data() : heap.data();
  size_t size = 0;
  for (size_t i = 0; i < count; ++i) {
    const Vec3 &a = vertices[i], &b = vertices[i + 1 < count ? i + 1 : 0];
    const float sa = glm::dot(n, a - p), sb = glm::dot(n, b - p);
    if (sa >= 0.0f) clipped[size++] = a;
    if ((sa >= 0.0f) != (sb >= 0.0f)) clipped[size++] = a + (b - a) * (sa / (sa - sb));
  }
  const float whole = twiceArea(vertices.data(), count);
  if (size < 3 || !(std::abs(whole) > 0.0f)) return 0.0f;
  return std::clamp(twiceArea(clipped, size) / whole, 0.0f, 1.0f);
}

}  // namespace

float lightAboveHorizon(const Light& light, const Vec3& p, const Vec3& ng) {
  if (!(glm::dot(ng, ng) > 0.0f)) return 1.0f;
  switch (light.shape()) {
    case LightShape::Rect:
    case LightShape::Polygon:
      return polygonShare(light.vertices(), light.normal(), p, ng);
    case LightShape::Disk:
      return diskShare(light.center(), light.normal(), light.radius(), p, ng);
    case LightShape::Sphere: {
      // Light::sample fills the silhouette disk seen from p: centre (d^2 - R^2) / d along w, radius
      // R sqrt(d^2 - R^2) / d.
      const Vec3 toCentre = light.center() - p;
      const float d2 = glm::dot(toCentre, toCentre), r2 = light.radius() * light.radius();
      if (!(d2 > r2)) return 1.0f;  // p inside the light
      const float d = std::sqrt(d2);
      const Vec3 w = toCentre / d;
      return diskShare(p + ((d2 - r2) / d) * w, w, light.radius() * std::sqrt(d2 - r2) / d, p, ng);
    }
    case LightShape::Directional:
      // Directions through the disk of radius tan(angular diameter / 2) at unit distance.
      return diskShare(p + light.direction(), light.direction(), std::tan(0.5f * light.angularDiameter()), p, ng);
    case LightShape::Segment: {
      const float sa = glm::dot(ng, light.a() - p), sb = glm::dot(ng, light.b() - p);
      if (sa >= 0.0f && sb >= 0.0f) return 1.0f;
      if (sa <= 0.0f && sb <= 0.0f) return 0.0f;
      return std::max(sa, sb) / (std::abs(sa) + std::abs(sb));
    }
  }
  return 1.0f;
}

namespace {

// Which pixels of a row the clamp may lower (cand[x] = 1): those that see geometry, have V > 0, and
// whose plane does not leave the light's bounding sphere (directional: its cone of directions) wholly
// on the normal's side, the quick accept of clampToHorizon. The dot products in glm's order (x, y,
// then z) and no fused multiply-add (CMakeLists.txt), so each target decides as the scalar form does.
PENUMBRA_CLONES_AVX512 void horizonCandidates(int width, const Vec3* __restrict p, const Vec3* __restrict ng,
                                              const int32_t* __restrict ids, const float* __restrict v, Vec3 centre,
                                              bool directional, float reach, uint8_t* __restrict cand) {
  const float keep = directional ? 0.0f : 1.0f;  // directional: the centre is a direction, not a point
  for (int x = 0; x < width; ++x) {
    const float dx = centre.x - keep * p[x].x, dy = centre.y - keep * p[x].y, dz = centre.z - keep * p[x].z;
    const float nx = ng[x].x, ny = ng[x].y, nz = ng[x].z;
    const float facing = nx * dx + ny * dy + nz * dz;
    const float length = std::sqrt(nx * nx + ny * ny + nz * nz);
    cand[x] = static_cast<uint8_t>((ids[x] != kNoObject) & (v[x] > 0.0f) & !(facing >= reach * length));
  }
}

// Facing: V = 0 at every pixel of a run that sees geometry and whose face turns from the light's centre
// (towards: the centre, or for a directional light its direction), in one vector loop; the dot product
// in glm's order and unfused, as rt::lightSide takes it.
PENUMBRA_CLONES_AVX512 void zeroFacingAway(int width, const Vec3* __restrict p, const Vec3* __restrict ng,
                                           const int32_t* __restrict ids, Vec3 towards, bool directional,
                                           float* __restrict v) {
  const float keep = directional ? 0.0f : 1.0f;
  for (int x = 0; x < width; ++x) {
    const float dx = towards.x - keep * p[x].x, dy = towards.y - keep * p[x].y, dz = towards.z - keep * p[x].z;
    const float facing = ng[x].x * dx + ng[x].y * dy + ng[x].z * dz;
    v[x] = (ids[x] != kNoObject) & (facing < 0.0f) ? 0.0f : v[x];
  }
}

}  // namespace

void clampRowToHorizon(const GBuffer& gbuffer, const HorizonBound& bound, int y, float* v) {
  if (!bound) return;
  const Light& light = *bound.light;
  const bool directional = light.isDirectional();
  const Vec3 centre = directional ? light.direction() : light.center();
  const Vec3* positions = gbuffer.wsPosition.row(y);
  const Vec3* normals = gbuffer.wsGeometricNormal.row(y);
  const int32_t* ids = gbuffer.objectId.row(y);
  if (bound.mode == HorizonClamp::Facing) {
    zeroFacingAway(gbuffer.width(), positions, normals, ids, centre, directional, v);
    return;
  }
  // Plane. Most receivers see all of the light above their plane: the light's bounding sphere
  // (directional: its cone of directions) wholly on the normal's side decides that with one dot
  // product, in one vector loop over a run of the row; the closed form runs on the rest.
  const float reach = directional ? std::sin(0.5f * light.angularDiameter()) : light.extent();
  constexpr int kRun = 256;
  uint8_t cand[kRun];
  for (int x0 = 0; x0 < gbuffer.width(); x0 += kRun) {
    const int n = std::min(kRun, gbuffer.width() - x0);
    horizonCandidates(n, positions + x0, normals + x0, ids + x0, v + x0, centre, directional, reach, cand);
    std::fill(cand + n, cand + kRun, uint8_t{0});
    // Eight flags at a time: most runs hold no candidate at all.
    for (int k0 = 0; k0 < n; k0 += 8) {
      uint64_t flags;
      std::memcpy(&flags, cand + k0, sizeof(flags));
      if (flags == 0) continue;
      for (int k = k0; k < k0 + 8; ++k)
        if (cand[k]) v[x0 + k] = std::min(v[x0 + k], lightAboveHorizon(light, positions[x0 + k], normals[x0 + k]));
    }
  }
}

void clampToHorizon(const GBuffer& gbuffer, const HorizonBound& bound, Image<float>& v) {
  tbb::parallel_for(tbb::blocked_range<int>(0, gbuffer.height()), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) clampRowToHorizon(gbuffer, bound, y, v.row(y));
  });
}

}  // namespace penumbra
