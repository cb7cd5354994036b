// Light shapes, sampling and irradiance. See include/penumbra/light.h for the conventions.
#include "penumbra/light.h"

#include <cmath>

#include "core/planar_polygon.h"
#include "penumbra/error.h"
#include "penumbra/sampling.h"

namespace penumbra {

std::string_view toString(LightShape shape) {
  switch (shape) {
    case LightShape::Sphere:
      return "sphere";
    case LightShape::Disk:
      return "disk";
    case LightShape::Rect:
      return "rect";
    case LightShape::Segment:
      return "segment";
    case LightShape::Polygon:
      return "polygon";
    case LightShape::Directional:
      return "directional";
  }
  return "unknown";
}

std::string_view toString(LightProfile profile) {
  return profile == LightProfile::Uniform ? "uniform" : "limb-darkened";
}

namespace {

void requireFinite(const Vec3& v, std::string_view what) {
  if (!isFinite(v)) fail("light: {} must be finite", what);
}

Vec3 unitOrFail(const Vec3& v, std::string_view what) {
  requireFinite(v, what);
  const float len = glm::length(v);
  if (!(len > 1e-12f)) fail("light: {} must be a non-zero vector", what);
  return v / len;
}

// Newell's normal of a polygon (robust for nearly collinear vertices), not normalized: its length is
// twice the polygon's area.
Vec3 newellNormal(const std::vector<Vec3>& vs) {
  DVec3 n(0.0);
  for (size_t i = 0; i < vs.size(); ++i) {
    const DVec3 a(vs[i]), b(vs[(i + 1) % vs.size()]);
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
  }
  return Vec3(n);
}

// A corner turns the wrong way (the polygon is concave there) when the cross product of its two
// edges is below -kTurnTolerance times the polygon's squared size: rounding of float coordinates
// stays far below that.
constexpr double kTurnTolerance = 1e-6;

// The polygon in its plane (normal n, unit): 2D coordinates about the vertex mean, along axes x, y
// with x cross y = n, so vertices that turn counter-clockwise about n are counter-clockwise here.
std::vector<polygon2d::DVec2> inPlane(const std::vector<Vec3>& vs, const DVec3& n) {
  DVec3 o(0.0);
  for (const Vec3& v : vs) o += DVec3(v);
  o /= static_cast<double>(vs.size());
  const DVec3 helper = std::abs(n.x) < 0.9 ? DVec3(1.0, 0.0, 0.0) : DVec3(0.0, 1.0, 0.0);
  const DVec3 x = glm::normalize(glm::cross(helper, n));
  const DVec3 y = glm::cross(n, x);
  std::vector<polygon2d::DVec2> out;
  out.reserve(vs.size());
  for (const Vec3& v : vs) out.emplace_back(glm::dot(DVec3(v) - o, x), glm::dot(DVec3(v) - o, y));
  return out;
}

}  // namespace

Light Light::sphere(const Vec3& center, float radius) {
  requireFinite(center, "sphere center");
  if (!(radius > 0.0f) || !std::isfinite(radius)) fail("light: sphere radius must be > 0 (got {})", radius);
  Light l;
  l.shape_ = LightShape::Sphere;
  l.center_ = center;
  l.radius_ = radius;
  return l;
}

Light Light::disk(const Vec3& center, const Vec3& normal, float radius) {
  requireFinite(center, "disk center");
  if (!(radius > 0.0f) || !std::isfinite(radius)) fail("light: disk radius must be > 0 (got {})", radius);
  Light l;
  l.shape_ = LightShape::Disk;
  l.center_ = center;
  l.normal_ = unitOrFail(normal, "disk normal");
  l.radius_ = radius;
  return l;
}

Light Light::rect(const Vec3& center, const Vec3& u, const Vec3& v) {
  requireFinite(center, "rect center");
  requireFinite(u, "rect u");
  requireFinite(v, "rect v");
  const float lu = glm::length(u), lv = glm::length(v);
  if (!(lu > 0.0f) || !(lv > 0.0f)) fail("light: rect half-edges u and v must be non-zero vectors");
  if (std::abs(glm::dot(u, v)) > 1e-4f * lu * lv)
    fail("light: rect half-edges u and v must be perpendicular (u.v = {})", glm::dot(u, v));
  Light l;
  l.shape_ = LightShape::Rect;
  l.center_ = center;
  l.u_ = u;
  l.v_ = v;
  l.normal_ = glm::normalize(glm::cross(u, v));
  l.vertices_ = {center - u - v, center + u - v, center + u + v, center - u + v};
  l.convex_ = true;
  return l;
}

Light Light::segment(const Vec3& a, const Vec3& b) {
  requireFinite(a, "segment a");
  requireFinite(b, "segment b");
  if (!(glm::length(b - a) > 0.0f)) fail("light: segment end points a and b must differ");
  Light l;
  l.shape_ = LightShape::Segment;
  l.a_ = a;
  l.b_ = b;
  l.center_ = 0.5f * (a + b);
  return l;
}

Light Light::polygon(const std::vector<Vec3>& vertices) {
  if (vertices.size() < 3) fail("light: polygon needs at least 3 vertices (got {})", vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) requireFinite(vertices[i], fmt::format("polygon vertex {}", i));
  Vec3 centroid(0.0f);
  float size = 0.0f;
  for (const Vec3& p : vertices) centroid += p;
  centroid /= static_cast<float>(vertices.size());
  for (const Vec3& p : vertices) size = std::max(size, glm::length(p - centroid));
  // Distances below a millionth of the polygon's size are float rounding of its coordinates.
  const double lengthTolerance = 1e-6 * size;
  for (size_t i = 0; i < vertices.size(); ++i)
    for (size_t j = i + 1; j < vertices.size(); ++j)
      if (glm::length(DVec3(vertices[i]) - DVec3(vertices[j])) <= lengthTolerance)
        fail("light: polygon vertices {} and {} coincide; expected distinct vertices", i, j);
  const Vec3 nn = newellNormal(vertices);
  const float area = 0.5f * glm::length(nn);
  const bool hasArea = area > 1e-8f * size * size;
  // The plane: Newell's normal, or where that vanishes (a polygon whose loops cancel, a bow tie) the
  // widest triangle of vertex 0, the vertex farthest from it and a third, so that the crossing
  // edges are found and named below.
  DVec3 n = hasArea ? glm::normalize(DVec3(nn)) : DVec3(0.0);
  if (!hasArea) {
    size_t far = 0;
    for (size_t i = 1; i < vertices.size(); ++i)
      if (glm::length(vertices[i] - vertices[0]) > glm::length(vertices[far] - vertices[0])) far = i;
    const DVec3 e = DVec3(vertices[far]) - DVec3(vertices[0]);
    for (const Vec3& v : vertices) {
      const DVec3 c = glm::cross(e, DVec3(v) - DVec3(vertices[0]));
      if (glm::length(c) > glm::length(n)) n = c;
    }
    if (!(glm::length(n) > 1e-8 * size * size)) fail("light: polygon has zero area (its vertices lie on one line)");
    n = glm::normalize(n);
  }
  for (size_t i = 0; i < vertices.size(); ++i) {
    const double off = std::abs(glm::dot(DVec3(vertices[i]) - DVec3(centroid), n));
    if (off > 1e-3 * size)
      fail("light: polygon is not planar (vertex {} is {} off its plane); expected all vertices in one plane", i, off);
  }
  const std::vector<polygon2d::DVec2> flat = inPlane(vertices, n);
  if (const std::string problem = polygon2d::simplePolygonProblem(flat, lengthTolerance); !problem.empty())
    fail("light: polygon {}; expected a simple polygon (no edge crossing or touching another, each vertex once)",
         problem);
  if (!hasArea) fail("light: polygon has zero area");
  Light l;
  l.shape_ = LightShape::Polygon;
  l.vertices_ = vertices;
  l.normal_ = nn / (2.0f * area);
  l.convex_ = polygon2d::isConvex(flat, kTurnTolerance * size * size);
  if (l.convex_) {
    for (uint32_t i = 1; i + 1 < vertices.size(); ++i) l.triangles_.push_back({0, i, i + 1});
  } else {
    l.triangles_ = polygon2d::earClip(flat);
  }
  // Area-weighted centroid: the centre sample.
  Vec3 c(0.0f);
  float total = 0.0f;
  for (const auto& t : l.triangles_) {
    const Vec3 &a = vertices[t[0]], &b = vertices[t[1]], &d = vertices[t[2]];
    const float ai = 0.5f * glm::length(glm::cross(b - a, d - a));
    c += ai * (a + b + d) / 3.0f;
    total += ai;
    l.triangleCdf_.push_back(total);
  }
  for (float& f : l.triangleCdf_) f /= total;
  l.triangleCdf_.back() = 1.0f;
  l.center_ = c / total;
  return l;
}

std::vector<std::vector<Vec3>> Light::convexParts() const {
  if (shape_ != LightShape::Rect && shape_ != LightShape::Polygon) return {};
  if (convex_) return {vertices_};
  float size = 0.0f;
  Vec3 mean(0.0f);
  for (const Vec3& p : vertices_) mean += p;
  mean /= static_cast<float>(vertices_.size());
  for (const Vec3& p : vertices_) size = std::max(size, glm::length(p - mean));
  const double tolerance = kTurnTolerance * size * size;
  const std::vector<polygon2d::DVec2> flat = inPlane(vertices_, DVec3(normal_));
  const polygon2d::ConvexPartition partition = polygon2d::convexPartition(flat, tolerance);
  // A corner of a piece: a vertex, or a point on an edge (where the cut continues an edge).
  const auto corner3 = [&](uint32_t id) {
    if (id < vertices_.size()) return vertices_[id];
    const polygon2d::ConvexPartition::EdgePoint& e = partition.added[id - vertices_.size()];
    const DVec3 a(vertices_[e.edge]), b(vertices_[(e.edge + 1) % vertices_.size()]);
    return Vec3(a + e.t * (b - a));
  };
  std::vector<std::vector<Vec3>> parts;
  for (const std::vector<uint32_t>& piece : partition.pieces) {
    // Straight corners (a vertex of the polygon on a piece's side) add nothing to a convex piece.
    std::vector<Vec3> part;
    const size_t m = piece.size();
    for (size_t k = 0; k < m; ++k) {
      const polygon2d::DVec2 a = partition.corner(flat, piece[(k + m - 1) % m]), b = partition.corner(flat, piece[k]),
                             d = partition.corner(flat, piece[(k + 1) % m]);
      const double turn = (b.x - a.x) * (d.y - b.y) - (b.y - a.y) * (d.x - b.x);
      if (std::abs(turn) > tolerance) part.push_back(corner3(piece[k]));
    }
    if (part.size() < 3) {
      part.clear();
      for (uint32_t k : piece) part.push_back(corner3(k));
    }
    parts.push_back(std::move(part));
  }
  return parts;
}

float Light::area() const {
  switch (shape_) {
    case LightShape::Disk:
      return kPi * radius_ * radius_;
    case LightShape::Rect:
      return 4.0f * glm::length(glm::cross(u_, v_));
    case LightShape::Polygon:
      return 0.5f * glm::length(newellNormal(vertices_));
    default:
      return 0.0f;
  }
}

Light Light::directional(const Vec3& wsToLight, float angularDiameterRadians, LightProfile profile) {
  if (!(angularDiameterRadians > 0.0f) || !(angularDiameterRadians < kPi) || !std::isfinite(angularDiameterRadians))
    fail("light: directional angular_diameter must be in (0, 180) degrees (got {} degrees)",
         degrees(angularDiameterRadians));
  Light l;
  l.shape_ = LightShape::Directional;
  l.direction_ = unitOrFail(wsToLight, "directional direction");
  l.angularDiameter_ = angularDiameterRadians;
  l.profile_ = profile;
  return l;
}

void Light::setIntensity(float intensity) {
  if (!(intensity >= 0.0f) || !std::isfinite(intensity))
    fail("light: intensity must be finite and >= 0 (got {})", intensity);
  intensity_ = intensity;
}

Vec3 Light::directionToCenter(const Vec3& wsP) const {
  if (isDirectional()) return direction_;
  const Vec3 d = center_ - wsP;
  const float len = glm::length(d);
  return len > 0.0f ? d / len : Vec3(0.0f, 0.0f, 1.0f);
}

float Light::distanceToCenter(const Vec3& wsP) const {
  return isDirectional() ? kInfinity : glm::length(center_ - wsP);
}

float Light::extent() const {
  switch (shape_) {
    case LightShape::Sphere:
    case LightShape::Disk:
      return radius_;
    case LightShape::Rect:
      return glm::length(u_ + v_);
    case LightShape::Segment:
      return 0.5f * glm::length(b_ - a_);
    case LightShape::Polygon: {
      float r = 0.0f;
      for (const Vec3& p : vertices_) r = std::max(r, glm::length(p - center_));
      return r;
    }
    case LightShape::Directional:
      return std::tan(0.5f * angularDiameter_);
  }
  return 0.0f;
}

float Light::apparentRadius(const Vec3& wsP) const {
  if (isDirectional()) return 0.5f * angularDiameter_;
  const float d = glm::length(center_ - wsP);
  const float r = extent();
  if (d <= r) return 0.5f * kPi;
  return std::asin(r / d);
}

LightSample Light::sample(const Vec3& wsP, const Vec2& u) const { return sampleFrom(wsP, patternPoint(u)); }

LightPatternPoint Light::patternPoint(const Vec2& u) const {
  LightPatternPoint point;
  switch (shape_) {
    case LightShape::Sphere:
      point.disk = concentricDisk(u);
      break;
    case LightShape::Disk: {
      const Frame f = Frame::fromZ(normal_);
      const Vec2 q = concentricDisk(u) * radius_;
      point.onLight = center_ + q.x * f.x + q.y * f.y;
      break;
    }
    case LightShape::Rect:
      point.onLight = center_ + (2.0f * u.x - 1.0f) * u_ + (2.0f * u.y - 1.0f) * v_;
      break;
    case LightShape::Segment:
      point.onLight = a_ + u.x * (b_ - a_);
      break;
    case LightShape::Polygon: {
      // Pick a triangle by area with u.x, reuse the remainder of u.x inside it: stratified u stays
      // stratified within each triangle.
      size_t i = 0;
      while (i + 1 < triangleCdf_.size() && u.x >= triangleCdf_[i]) ++i;
      const float lo = i == 0 ? 0.0f : triangleCdf_[i - 1];
      const float ux = std::min((u.x - lo) / (triangleCdf_[i] - lo), 0x1.fffffep-1f);
      const Vec2 bc = uniformTriangle(Vec2(ux, u.y));
      const auto& t = triangles_[i];
      point.onLight = bc.x * vertices_[t[0]] + bc.y * vertices_[t[1]] + (1.0f - bc.x - bc.y) * vertices_[t[2]];
      break;
    }
    case LightShape::Directional: {
      const Frame f = Frame::fromZ(direction_);
      const Vec2 q = concentricDisk(u);
      const Vec2 offset = q * std::tan(0.5f * angularDiameter_);
      if (profile_ == LightProfile::LimbDarkened) {
        const float mu = std::sqrt(std::max(0.0f, 1.0f - glm::dot(q, q)));
        // Divide by the law's mean over the disk, 1 - u/3, so the weights average to 1.
        point.weight = (1.0f - kLimbDarkeningU * (1.0f - mu)) / (1.0f - kLimbDarkeningU / 3.0f);
      }
      point.onLight = glm::normalize(direction_ + offset.x * f.x + offset.y * f.y);
      break;
    }
  }
  return point;
}

LightSample Light::sampleFrom(const Vec3& wsP, const LightPatternPoint& point) const {
  switch (shape_) {
    case LightShape::Sphere: {
      const Vec3 toCenter = center_ - wsP;
      const float d2 = glm::dot(toCenter, toCenter);
      const float r2 = radius_ * radius_;
      if (d2 <= r2) return {directionToCenter(wsP), 0.0f, 1.0f};  // p inside the light: nothing can occlude
      const float d = std::sqrt(d2);
      const Vec3 w = toCenter / d;
      const Frame f = Frame::fromZ(w);
      // The silhouette disk seen from p: centre at (d^2 - R^2)/d along w, radius R sqrt(d^2 - R^2)/d.
      const float h = std::sqrt(d2 - r2);
      const Vec2 q = point.disk * (radius_ * h / d);
      const Vec3 dir = glm::normalize((d2 - r2) / d * w + q.x * f.x + q.y * f.y);
      // The ray reaches the light at its front surface: the nearer root of |p + t dir - c| = R.
      const float b = glm::dot(dir, toCenter);
      const float t = b - std::sqrt(std::max(0.0f, b * b - (d2 - r2)));
      return {dir, t, 1.0f};
    }
    case LightShape::Directional:
      return {point.onLight, kInfinity, point.weight};
    default:
      break;
  }
  const Vec3 d = point.onLight - wsP;
  const float len = glm::length(d);
  if (!(len > 0.0f)) return {directionToCenter(wsP), 0.0f, 1.0f};
  return {d / len, len, 1.0f};
}

float Light::irradiance(const Vec3& wsP, const Vec3& wsN) const {
  switch (shape_) {
    case LightShape::Directional:
      return intensity_ * std::max(0.0f, glm::dot(wsN, direction_));
    case LightShape::Sphere: {
      // Exact for a sphere wholly above p's horizon: E = pi L sin^2(alpha) cos(theta).
      const float d = glm::length(center_ - wsP);
      if (d <= radius_) return 0.0f;
      const float s = radius_ / d;
      return intensity_ * kPi * s * s * std::max(0.0f, glm::dot(wsN, (center_ - wsP) / d));
    }
    default:
      break;
  }
  // Planar and linear lights: a fixed 8x8 stratified quadrature of the area (or length) integral.
  const CmjSampler sampler(64);
  float measure;
  switch (shape_) {
    case LightShape::Segment:
      measure = glm::length(b_ - a_);
      break;
    default:
      measure = area();
      break;
  }
  float sum = 0.0f;
  for (uint32_t i = 0; i < sampler.count(); ++i) {
    const LightSample s = sample(wsP, sampler.sample(i, 0));
    if (!(s.distance > 0.0f)) continue;
    const float cosP = std::max(0.0f, glm::dot(wsN, s.wsDirection));
    const float cosL = shape_ == LightShape::Segment ? 1.0f : std::abs(glm::dot(normal_, s.wsDirection));
    sum += cosP * cosL / (s.distance * s.distance);
  }
  return intensity_ * measure * sum / static_cast<float>(sampler.count());
}

Frame Light::lightFrame(const Bounds3& sceneBounds) const {
  const Vec3 target = sceneBounds.empty() ? center_ - Vec3(0.0f, 1.0f, 0.0f) : sceneBounds.center();
  Vec3 z;
  switch (shape_) {
    case LightShape::Directional:
      z = -direction_;
      break;
    case LightShape::Disk:
    case LightShape::Rect:
    case LightShape::Polygon:
      z = glm::dot(normal_, target - center_) >= 0.0f ? normal_ : -normal_;
      break;
    default: {
      const Vec3 d = target - center_;
      z = glm::length(d) > 0.0f ? glm::normalize(d) : Vec3(0.0f, -1.0f, 0.0f);
    }
  }
  return Frame::fromZ(z);
}

}  // namespace penumbra
