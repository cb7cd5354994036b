// The silhouette family's shared stages (stages.h): the light's plane, the occluders, convex
// clipping, the light-space binning grid and the centre ray.
#include "techniques/silhouette/stages.h"

#include <algorithm>
#include <array>
#include <optional>

#include "penumbra/error.h"
#include "rt/ray_scene.h"
#include "rt/shadow_ray.h"

namespace penumbra {
namespace silhouette {

LightPlane makeLightPlane(const Light& light, const Bounds3& sceneBounds, std::string_view technique, bool back) {
  if (light.shape() != LightShape::Rect && light.shape() != LightShape::Polygon)
    fail(
        "{}: a {} light is not supported; {} needs a planar convex polygonal light: rect or polygon (triangle, quad, "
        "hexagon, ...)",
        technique, toString(light.shape()), technique);
  if (!light.convex())
    fail("{}: the polygon light is concave; {} runs on its convex parts (Light::convexParts), one at a time", technique,
         technique);
  const std::vector<Vec3>& ws = light.vertices();
  if (ws.size() > static_cast<size_t>(kMaxLightVertices))
    fail("{}: the polygon light has {} vertices; at most {} are supported", technique, ws.size(), kMaxLightVertices);
  LightPlane plane;
  plane.wsOrigin = light.center();
  const Vec3 z = back ? -light.lightFrame(sceneBounds).z : light.lightFrame(sceneBounds).z;
  Vec3 x = ws[1] - ws[0];
  x = glm::normalize(x - z * glm::dot(x, z));
  plane.lsFrame.z = z;
  plane.lsFrame.x = x;
  plane.lsFrame.y = glm::cross(z, x);
  for (const Vec3& v : ws) {
    const Vec3 l = plane.lsFromWs(v);
    plane.vertices.push_back(Vec2(l.x, l.y));
  }
  float twiceArea = 0.0f;
  for (size_t i = 0; i < plane.vertices.size(); ++i) {
    const Vec2 &a = plane.vertices[i], &b = plane.vertices[(i + 1) % plane.vertices.size()];
    twiceArea += a.x * b.y - a.y * b.x;
  }
  if (twiceArea < 0.0f) std::reverse(plane.vertices.begin(), plane.vertices.end());
  plane.area = 0.5f * std::abs(twiceArea);
  plane.lower = plane.upper = plane.vertices[0];
  for (const Vec2& v : plane.vertices) {
    plane.extent = std::max(plane.extent, glm::length(v));
    plane.lower = glm::min(plane.lower, v);
    plane.upper = glm::max(plane.upper, v);
  }
  return plane;
}

std::vector<Occluder> makeOccluders(const Scene& scene) {
  std::vector<Occluder> occluders;
  for (const Object& object : scene.objects) {
    Occluder o;
    o.objectId = object.id;
    o.name = object.name;
    o.topology = occluderTopology(object.mesh);
    if (o.topology.triangles.empty()) continue;
    o.sheet = o.topology.twoSidedSheet;
    occluders.push_back(std::move(o));
  }
  return occluders;
}

const std::vector<Occluder>& OccluderCache::get(const Scene& scene) {
  std::vector<Key> keys;
  keys.reserve(scene.objects.size());
  for (const Object& object : scene.objects) keys.push_back({object.id, object.name, meshFingerprint(object.mesh)});
  if (!made_ || keys != keys_) {
    occluders_ = makeOccluders(scene);
    keys_ = std::move(keys);
    made_ = true;
    ++builds_;
  }
  return occluders_;
}

LightSpaceGeometry toLightSpace(const Occluder& o, const LightPlane& plane) {
  LightSpaceGeometry g;
  g.positions.reserve(o.topology.positions.size());
  g.normals.reserve(o.topology.faceNormals.size());
  for (const Vec3& p : o.topology.positions) g.positions.push_back(plane.lsFromWs(p));
  for (const Vec3& n : o.topology.faceNormals) g.normals.push_back(plane.lsFrame.toLocal(n));
  return g;
}

// Clips a convex polygon to the half-plane dot(n, x) <= d (Sutherland-Hodgman).
int clipHalfPlane(const Vec2* in, int count, Vec2* out, const Vec2& n, float d) {
  int m = 0;
  for (int i = 0; i < count; ++i) {
    const Vec2 &a = in[i], &b = in[(i + 1) % count];
    const float da = glm::dot(n, a) - d, db = glm::dot(n, b) - d;
    if (da <= 0.0f) out[m++] = a;
    if ((da < 0.0f) != (db < 0.0f) && da != 0.0f && db != 0.0f) out[m++] = a + (b - a) * (da / (da - db));
  }
  return m;
}

bool LightSectors::build(const std::vector<Vec2>& polygon) {
  *this = LightSectors{};
  const size_t n = polygon.size();
  if (n < 3 || n > 32) return false;  // an outcode has 32 bits
  for (size_t k = 0; k < n; ++k)
    if (!(cross2(polygon[k], polygon[(k + 1) % n]) > 0.0f)) return false;  // the origin on or outside edge k
  // The outcodes' lines are the polygon's own edges (an edge split below would give its short part a
  // normal made of rounding).
  for (size_t k = 0; k < n; ++k) {
    const Vec2 e = polygon[(k + 1) % n] - polygon[k];
    outward_.emplace_back(e.y, -e.x);  // right of a counter-clockwise edge
    offset_.push_back(glm::dot(outward_.back(), polygon[k]));
  }
  // The cones start where the +x axis leaves the polygon (the edge that crosses it upwards), there
  // exactly on the axis, so that sweeps start at 0 on it.
  std::vector<Vec2> outline;
  for (size_t k = 0; k < n && outline.empty(); ++k) {
    const Vec2 &v = polygon[k], &next = polygon[(k + 1) % n];
    if (!(v.y <= 0.0f && next.y > 0.0f)) continue;
    const Vec2 onAxis(v.x + (next.x - v.x) * (-v.y / (next.y - v.y)), 0.0f);
    if (!(onAxis.x > 0.0f)) return false;
    outline.push_back(onAxis);
    for (size_t j = 1; j <= n; ++j) {
      const Vec2& w = polygon[(k + j) % n];
      if (j < n || w != onAxis) outline.push_back(w);  // v itself when it lies off the axis
    }
  }
  const size_t m = outline.size();
  if (m < 3) return false;
  prefix_.assign(m + 1, 0.0f);
  for (size_t k = 0; k < m; ++k) {
    const float cone = 0.5f * cross2(outline[k], outline[(k + 1) % m]);
    if (!(cone > 0.0f)) return false;
    coneArea_.push_back(cone);
    prefix_[k + 1] = prefix_[k] + cone;
  }
  polygon_ = polygon;
  outline_ = std::move(outline);
  area_ = prefix_[m];
  return true;
}

bool LightSectors::outside(const Vec2& a, const Vec2& b, uint32_t ca, uint32_t cb) const {
  if (ca == ~0u || cb == ~0u) return false;  // not finite: left to clipping
  if (ca & cb) return true;
  if ((ca | cb) == 0) return false;
  const Vec2 normal(b.y - a.y, a.x - b.x);
  bool anyAbove = false, anyBelow = false;
  for (const Vec2& v : polygon_) {
    const float side = glm::dot(normal, v - a);
    anyAbove = anyAbove || !(side < 0.0f);
    anyBelow = anyBelow || !(side > 0.0f);
  }
  return anyAbove != anyBelow;
}

bool LightSectors::sweep(const Vec2& q, float& swept) const {
  if (q.y == 0.0f && q.x > 0.0f) {
    swept = area_;
    return true;
  }
  const size_t n = outline_.size();
  for (size_t k = 0; k < n; ++k) {
    const Vec2 &v = outline_[k], &next = outline_[(k + 1) % n];
    if (!(cross2(v, q) >= 0.0f && cross2(q, next) > 0.0f)) continue;
    // The cones before k and the triangle (0, v, x), x where q's direction meets the edge
    // v -> next: x = s q with s = cross(v, e) / cross(q, e).
    const Vec2 e = next - v;
    const float s = cross2(v, e) / cross2(q, e);
    swept = prefix_[k] + std::clamp(0.5f * s * cross2(v, q), 0.0f, coneArea_[k]);
    return true;
  }
  return false;
}

float clippedFanArea(const std::vector<Vec2>& poly, const Vec2& a0, const Vec2& b0) {
  const float cross = cross2(a0, b0);
  if (cross == 0.0f) return 0.0f;
  const Vec2 a = cross > 0.0f ? a0 : b0, b = cross > 0.0f ? b0 : a0;
  std::array<Vec2, kMaxLightVertices + 4> bufA, bufB;
  int n = static_cast<int>(poly.size());
  std::copy(poly.begin(), poly.end(), bufA.begin());
  // Inside of the counter-clockwise triangle (0, a, b): left of 0->a, a->b, b->0.
  const Vec2 corners[3] = {Vec2(0.0f), a, b};
  Vec2* in = bufA.data();
  Vec2* out = bufB.data();
  for (int e = 0; e < 3 && n > 0; ++e) {
    const Vec2 s = corners[e], t = corners[(e + 1) % 3];
    const Vec2 nOut(t.y - s.y, s.x - t.x);  // right normal: outside
    n = clipHalfPlane(in, n, out, nOut, glm::dot(nOut, s));
    std::swap(in, out);
  }
  float twice = 0.0f;
  for (int i = 0; i < n; ++i) {
    const Vec2 &p = in[i], &q = in[(i + 1) % n];
    twice += p.x * q.y - p.y * q.x;
  }
  return (cross > 0.0f ? 0.5f : -0.5f) * twice;
}

void ringFansByClipping(const std::vector<Vec2>& light, const Vec3& p, const Vec3* ring, size_t n, float& covered,
                        int& winding) {
  covered = 0.0f;
  winding = 0;
  const Vec2 first = projectFrom(p, ring[0]);
  Vec2 a = first;
  for (size_t i = 0; i < n; ++i) {
    const Vec2 b = i + 1 < n ? projectFrom(p, ring[i + 1]) : first;
    covered -= clippedFanArea(light, a, b);
    winding += crossingOfPositiveX(a, b);
    a = b;
  }
}

bool ringFansBySectors(const LightSectors& sectors, const std::vector<Vec2>& light, const Vec3& p, const Vec3* ring,
                       size_t n, float& covered, int& winding) {
  covered = 0.0f;
  winding = 0;
  const Vec2 first = projectFrom(p, ring[0]);
  const uint32_t firstCode = sectors.outcode(first);
  Vec2 a = first;
  uint32_t ca = firstCode;
  bool chain = false;  // a chain of edges outside the light is open: its first point's sweep, its crossings
  float chainStart = 0.0f;
  int chainCrossings = 0;
  auto endChain = [&](const Vec2& q) {
    float end;
    if (!sectors.sweep(q, end)) return false;
    covered -= end - chainStart + sectors.area() * static_cast<float>(chainCrossings);
    chain = false;
    return true;
  };
  for (size_t i = 0; i < n; ++i) {
    const bool last = i + 1 == n;
    const Vec2 b = last ? first : projectFrom(p, ring[i + 1]);
    const uint32_t cb = last ? firstCode : sectors.outcode(b);
    const int crossing = crossingOfPositiveX(a, b);
    winding += crossing;
    if (sectors.outside(a, b, ca, cb)) {
      if (!chain) {
        if (!sectors.sweep(a, chainStart)) return false;
        chain = true;
        chainCrossings = 0;
      }
      chainCrossings += crossing;
    } else {
      if (chain && !endChain(a)) return false;
      covered -= (ca | cb) == 0 ? 0.5f * cross2(a, b) : clippedFanArea(light, a, b);
    }
    a = b;
    ca = cb;
  }
  return !chain || endChain(first);
}

namespace {
// The cell of u in a grid of res x res cells over lower + [0, res / scale]: -1 outside.
int cellOf(const Vec2& lower, const Vec2& scale, int res, const Vec2& u) {
  const Vec2 g = (u - lower) * scale;
  if (!(g.x >= 0.0f && g.y >= 0.0f && g.x <= res && g.y <= res) || res == 0) return -1;
  const int x = std::min(res - 1, static_cast<int>(g.x)), y = std::min(res - 1, static_cast<int>(g.y));
  return y * res + x;
}

Vec2 gridScale(const Vec2& lower, const Vec2& upper, int res) {
  return Vec2(static_cast<float>(res)) / glm::max(upper - lower, Vec2(1e-20f));
}
}  // namespace

void UGrid::build(const Vec2& lower, const Vec2& upper, int resolution, const std::vector<Vec2>& itemLower,
                  const std::vector<Vec2>& itemUpper) {
  res_ = resolution;
  lower_ = lower;
  scale_ = gridScale(lower, upper, res_);
  start_.assign(size_t(res_) * res_ + 1, 0);
  auto range = [&](size_t i, int& x0, int& y0, int& x1, int& y1) {
    const Vec2 lo = (itemLower[i] - lower_) * scale_, hi = (itemUpper[i] - lower_) * scale_;
    if (!(hi.x >= 0.0f && hi.y >= 0.0f && lo.x < res_ && lo.y < res_)) return false;
    x0 = static_cast<int>(std::max(lo.x, 0.0f));  // clamped before the conversion: lo can be far below 0
    y0 = static_cast<int>(std::max(lo.y, 0.0f));
    x1 = std::min(res_ - 1, static_cast<int>(std::min(hi.x, float(res_ - 1))));
    y1 = std::min(res_ - 1, static_cast<int>(std::min(hi.y, float(res_ - 1))));
    return true;
  };
  int x0, y0, x1, y1;
  for (size_t i = 0; i < itemLower.size(); ++i)
    if (range(i, x0, y0, x1, y1))
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) ++start_[size_t(y) * res_ + x + 1];
  for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  items_.resize(start_.back());
  std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < itemLower.size(); ++i)
    if (range(i, x0, y0, x1, y1))
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) items_[fill[size_t(y) * res_ + x]++] = static_cast<uint32_t>(i);
}

void UGrid::buildInfluence(const Vec2& lower, const Vec2& upper, int resolution, const std::vector<Vec2>& itemLower,
                           const std::vector<Vec2>& itemUpper, const std::vector<float>& itemNear,
                           const std::vector<float>& cellFar, const std::vector<uint32_t>& keys) {
  res_ = resolution;
  lower_ = lower;
  scale_ = gridScale(lower, upper, res_);
  const size_t cells = size_t(res_) * res_;
  start_.assign(cells + 1, 0);
  items_.clear();
  float nearestFar = kInfinity;
  for (const float f : cellFar) nearestFar = std::min(nearestFar, f);
  if (!(nearestFar < kInfinity)) return;  // no receivers
  const Vec2 cellSize = Vec2(1.0f) / scale_;
  // A cell's rectangle, padded by a little of its size so float rounding of cellOf cannot put a
  // receiver just outside the rectangle of its own cell.
  const Vec2 pad = 1e-3f * cellSize;
  auto visit = [&](size_t i, auto&& add) {
    const float growMost = itemNear[i] - nearestFar;
    if (!(growMost >= 0.0f)) return;
    const Vec2 lo = (itemLower[i] - growMost - lower_) * scale_, hi = (itemUpper[i] + growMost - lower_) * scale_;
    if (!(hi.x >= 0.0f && hi.y >= 0.0f && lo.x < res_ && lo.y < res_)) return;
    const int x0 = static_cast<int>(std::max(lo.x, 0.0f)), y0 = static_cast<int>(std::max(lo.y, 0.0f));
    const int x1 = std::min(res_ - 1, static_cast<int>(std::min(hi.x, float(res_ - 1))));
    const int y1 = std::min(res_ - 1, static_cast<int>(std::min(hi.y, float(res_ - 1))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const size_t c = size_t(y) * res_ + x;
        const float grow = itemNear[i] - cellFar[c];
        if (!(grow >= 0.0f)) continue;
        const Vec2 cellLo = lower_ + Vec2(float(x), float(y)) * cellSize - pad, cellHi = cellLo + cellSize + 2.0f * pad;
        const Vec2 gap = glm::max(Vec2(0.0f), glm::max(itemLower[i] - cellHi, cellLo - itemUpper[i]));
        if (gap.x <= grow && gap.y <= grow) add(c);
      }
  };
  constexpr uint32_t kNone = 0xffffffffu;
  std::vector<uint32_t> last(cells, kNone);
  auto keyOf = [&](size_t i) { return keys.empty() ? static_cast<uint32_t>(i) : keys[i]; };
  for (size_t i = 0; i < itemLower.size(); ++i)
    visit(i, [&](size_t c) {
      if (last[c] == keyOf(i)) return;
      last[c] = keyOf(i);
      ++start_[c + 1];
    });
  for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  items_.resize(start_.back());
  std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
  std::fill(last.begin(), last.end(), kNone);
  for (size_t i = 0; i < itemLower.size(); ++i)
    visit(i, [&](size_t c) {
      if (last[c] == keyOf(i)) return;
      last[c] = keyOf(i);
      items_[fill[c]++] = keyOf(i);
    });
}

int UGrid::cellIndex(const Vec2& u) const { return cellOf(lower_, scale_, res_, u); }

std::pair<const uint32_t*, const uint32_t*> UGrid::cell(const Vec2& u) const {
  const int c = cellIndex(u);
  if (c < 0) return {nullptr, nullptr};
  return {items_.data() + start_[c], items_.data() + start_[c + 1]};
}

bool anyReceiverBehind(const GBuffer& gbuffer, const LightPlane& plane) {
  for (int y = 0; y < gbuffer.height(); ++y)
    for (int x = 0; x < gbuffer.width(); ++x)
      if (gbuffer.hit(x, y) && !(plane.lsFromWs(gbuffer.wsPosition(x, y)).z > 0.0f)) return true;
  return false;
}

bool receiverRange(const GBuffer& gbuffer, const LightPlane& plane, float zMin, Vec2& lower, Vec2& upper) {
  lower = Vec2(kInfinity);
  upper = Vec2(-kInfinity);
  for (int y = 0; y < gbuffer.height(); ++y)
    for (int x = 0; x < gbuffer.width(); ++x) {
      if (!gbuffer.hit(x, y)) continue;
      const Vec3 p = plane.lsFromWs(gbuffer.wsPosition(x, y));
      if (!(p.z > zMin)) continue;
      const Vec2 u(p.x / p.z, p.y / p.z);
      lower = glm::min(lower, u);
      upper = glm::max(upper, u);
    }
  return lower.x <= upper.x;
}

std::vector<float> receiverCellFar(const GBuffer& gbuffer, const LightPlane& plane, float zMin, const Vec2& lower,
                                   const Vec2& upper, int resolution) {
  const Vec2 scale = gridScale(lower, upper, resolution);
  std::vector<float> deepest(size_t(resolution) * resolution, 0.0f);
  for (int y = 0; y < gbuffer.height(); ++y)
    for (int x = 0; x < gbuffer.width(); ++x) {
      if (!gbuffer.hit(x, y)) continue;
      const Vec3 p = plane.lsFromWs(gbuffer.wsPosition(x, y));
      if (!(p.z > zMin)) continue;
      const int c = cellOf(lower, scale, resolution, Vec2(p.x / p.z, p.y / p.z));
      if (c >= 0) deepest[size_t(c)] = std::max(deepest[size_t(c)], p.z);
    }
  std::vector<float> far(deepest.size());
  for (size_t c = 0; c < far.size(); ++c) far[c] = deepest[c] > 0.0f ? plane.extent / deepest[c] : kInfinity;
  return far;
}

int32_t centreBlockerAt(const RayScene& rays, const Light& light, const GBuffer& gbuffer, int x, int y, float epsilon) {
  const Vec3 wsP = gbuffer.wsPosition(x, y);
  const Vec3 wsNg = gbuffer.wsGeometricNormal(x, y);
  const Vec3 wsOrigin = rt::offsetOrigin(light, wsP, wsNg, epsilon);
  const std::optional<RayHit> hit =
      rays.intersect(rt::shadowRay(wsP, wsOrigin, light.directionToCenter(wsP), light.distanceToCenter(wsP), epsilon));
  return hit ? hit->objectId : kNoObject;
}

int32_t blockerToward(const RayScene& rays, const Light& light, const GBuffer& gbuffer, int x, int y,
                      const Vec3& wsLightPoint, float epsilon) {
  const Vec3 wsP = gbuffer.wsPosition(x, y);
  const Vec3 wsOrigin = rt::offsetOrigin(light, wsP, gbuffer.wsGeometricNormal(x, y), epsilon);
  const Vec3 toLight = wsLightPoint - wsP;
  const float distance = glm::length(toLight);
  if (!(distance > 0.0f)) return kNoObject;
  const std::optional<RayHit> hit = rays.intersect(rt::shadowRay(wsP, wsOrigin, toLight / distance, distance, epsilon));
  return hit ? hit->objectId : kNoObject;
}

}  // namespace silhouette

}  // namespace penumbra
