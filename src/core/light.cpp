// Light shapes, sampling and irradiance. See include/penumbra/light.h for the conventions.
#include "penumbra/light.h"

#include <cmath>

#include "penumbra/error.h"
#include "penumbra/sampling.h"

namespace penumbra {

std::string_view toString(LightShape shape) {
  switch (shape) {
    case LightShape::Sphere: return "sphere";
    case LightShape::Disk: return "disk";
    case LightShape::Rect: return "rect";
    case LightShape::Segment: return "segment";
    case LightShape::Polygon: return "polygon";
    case LightShape::Directional: return "directional";
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
  const Vec3 nn = newellNormal(vertices);
  const float area = 0.5f * glm::length(nn);
  Vec3 centroid(0.0f);
  float size = 0.0f;
  for (const Vec3& p : vertices) centroid += p;
  centroid /= static_cast<float>(vertices.size());
  for (const Vec3& p : vertices) size = std::max(size, glm::length(p - centroid));
  if (!(area > 1e-8f * size * size) || !(size > 0.0f)) fail("light: polygon has zero area");
  const Vec3 n = nn / (2.0f * area);
  for (size_t i = 0; i < vertices.size(); ++i) {
    const float off = std::abs(glm::dot(vertices[i] - centroid, n));
    if (off > 1e-3f * size) fail("light: polygon is not planar (vertex {} is {} off its plane)", i, off);
    // Convex and consistently ordered: every turn has the same sign as the polygon's normal.
    const Vec3& p0 = vertices[i];
    const Vec3& p1 = vertices[(i + 1) % vertices.size()];
    const Vec3& p2 = vertices[(i + 2) % vertices.size()];
    if (glm::dot(glm::cross(p1 - p0, p2 - p1), n) < -1e-6f * size * size)
      fail("light: polygon is not convex (turn at vertex {} goes the wrong way)", (i + 1) % vertices.size());
  }
  Light l;
  l.shape_ = LightShape::Polygon;
  l.vertices_ = vertices;
  l.normal_ = n;
  // Area-weighted centroid: the centre sample.
  Vec3 c(0.0f);
  float total = 0.0f;
  for (size_t i = 1; i + 1 < vertices.size(); ++i) {
    const float ai = 0.5f * glm::length(glm::cross(vertices[i] - vertices[0], vertices[i + 1] - vertices[0]));
    c += ai * (vertices[0] + vertices[i] + vertices[i + 1]) / 3.0f;
    total += ai;
    l.triangleCdf_.push_back(total);
  }
  for (float& f : l.triangleCdf_) f /= total;
  l.triangleCdf_.back() = 1.0f;
  l.center_ = c / total;
  return l;
}

Light Light::directional(const Vec3& wsToLight, float angularDiameterRadians, LightProfile profile) {
  if (!(angularDiameterRadians > 0.0f) || !(angularDiameterRadians < kPi) || !std::isfinite(angularDiameterRadians))
    fail("light: directional angular_diameter must be in (0, 180) degrees (got {} degrees)", degrees(angularDiameterRadians));
  Light l;
  l.shape_ = LightShape::Directional;
  l.direction_ = unitOrFail(wsToLight, "directional direction");
  l.angularDiameter_ = angularDiameterRadians;
  l.profile_ = profile;
  return l;
}

void Light::setIntensity(float intensity) {
  if (!(intensity >= 0.0f) || !std::isfinite(intensity)) fail("light: intensity must be finite and >= 0 (got {})", intensity);
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
    case LightShape::Disk: return radius_;
    case LightShape::Rect: return glm::length(u_ + v_);
    case LightShape::Segment: return 0.5f * glm::length(b_ - a_);
    case LightShape::Polygon: {
      float r = 0.0f;
      for (const Vec3& p : vertices_) r = std::max(r, glm::length(p - center_));
      return r;
    }
    case LightShape::Directional: return std::tan(0.5f * angularDiameter_);
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

LightSample Light::sample(const Vec3& wsP, const Vec2& u) const {
  Vec3 x;
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
      const Vec2 q = concentricDisk(u) * (radius_ * h / d);
      const Vec3 dir = glm::normalize((d2 - r2) / d * w + q.x * f.x + q.y * f.y);
      // The ray reaches the light at its front surface: the nearer root of |p + t dir - c| = R.
      const float b = glm::dot(dir, toCenter);
      const float t = b - std::sqrt(std::max(0.0f, b * b - (d2 - r2)));
      return {dir, t, 1.0f};
    }
    case LightShape::Disk: {
      const Frame f = Frame::fromZ(normal_);
      const Vec2 q = concentricDisk(u) * radius_;
      x = center_ + q.x * f.x + q.y * f.y;
      break;
    }
    case LightShape::Rect: x = center_ + (2.0f * u.x - 1.0f) * u_ + (2.0f * u.y - 1.0f) * v_; break;
    case LightShape::Segment: x = a_ + u.x * (b_ - a_); break;
    case LightShape::Polygon: {
      // Pick a fan triangle by area with u.x, reuse the remainder of u.x inside it.
      size_t i = 0;
      while (i + 1 < triangleCdf_.size() && u.x >= triangleCdf_[i]) ++i;
      const float lo = i == 0 ? 0.0f : triangleCdf_[i - 1];
      const float ux = std::min((u.x - lo) / (triangleCdf_[i] - lo), 0x1.fffffep-1f);
      const Vec2 bc = uniformTriangle(Vec2(ux, u.y));
      x = bc.x * vertices_[0] + bc.y * vertices_[i + 1] + (1.0f - bc.x - bc.y) * vertices_[i + 2];
      break;
    }
    case LightShape::Directional: {
      const Frame f = Frame::fromZ(direction_);
      const Vec2 q = concentricDisk(u);
      const Vec2 offset = q * std::tan(0.5f * angularDiameter_);
      float weight = 1.0f;
      if (profile_ == LightProfile::LimbDarkened) {
        const float mu = std::sqrt(std::max(0.0f, 1.0f - glm::dot(q, q)));
        // Divide by the law's mean over the disk, 1 - u/3, so the weights average to 1.
        weight = (1.0f - kLimbDarkeningU * (1.0f - mu)) / (1.0f - kLimbDarkeningU / 3.0f);
      }
      return {glm::normalize(direction_ + offset.x * f.x + offset.y * f.y), kInfinity, weight};
    }
  }
  const Vec3 d = x - wsP;
  const float len = glm::length(d);
  if (!(len > 0.0f)) return {directionToCenter(wsP), 0.0f, 1.0f};
  return {d / len, len, 1.0f};
}

Light::Sampler Light::samplerAt(const Vec3& wsP) const {
  Sampler s;
  s.light_ = this;
  s.wsP_ = wsP;
  switch (shape_) {
    case LightShape::Sphere: {
      // The set-up half of Light::sample's sphere case, in the same operations.
      s.toCenter_ = center_ - wsP;
      const float d2 = glm::dot(s.toCenter_, s.toCenter_);
      const float r2 = radius_ * radius_;
      s.inside_ = d2 <= r2;
      if (s.inside_) break;
      const float d = std::sqrt(d2);
      const Vec3 w = s.toCenter_ / d;
      s.frame_ = Frame::fromZ(w);
      const float h = std::sqrt(d2 - r2);
      s.d2MinusR2_ = d2 - r2;
      s.diskRadius_ = radius_ * h / d;
      s.axial_ = (d2 - r2) / d * w;
      break;
    }
    case LightShape::Disk:
      s.frame_ = Frame::fromZ(normal_);
      s.diskRadius_ = radius_;
      break;
    case LightShape::Directional:
      s.frame_ = Frame::fromZ(direction_);
      s.diskRadius_ = std::tan(0.5f * angularDiameter_);
      break;
    default: break;  // rect, segment, polygon: nothing depends on p before the sample point
  }
  return s;
}

LightSample Light::Sampler::sample(const Vec2& u) const {
  LightSample s;
  sample(&u, 1, &s);
  return s;
}

// The sample half of Light::sample, per shape, with the per-point values samplerAt computed.
void Light::Sampler::sample(const Vec2* u, int count, LightSample* out) const {
  const Light& l = *light_;
  switch (l.shape_) {
    case LightShape::Sphere:
      if (inside_) {
        for (int i = 0; i < count; ++i) out[i] = {l.directionToCenter(wsP_), 0.0f, 1.0f};
        return;
      }
      for (int i = 0; i < count; ++i) {
        const Vec2 q = concentricDisk(u[i]) * diskRadius_;
        const Vec3 dir = glm::normalize(axial_ + q.x * frame_.x + q.y * frame_.y);
        const float b = glm::dot(dir, toCenter_);
        const float t = b - std::sqrt(std::max(0.0f, b * b - d2MinusR2_));
        out[i] = {dir, t, 1.0f};
      }
      return;
    case LightShape::Disk:
      for (int i = 0; i < count; ++i) {
        const Vec2 q = concentricDisk(u[i]) * diskRadius_;
        const Vec3 d = l.center_ + q.x * frame_.x + q.y * frame_.y - wsP_;
        const float len = glm::length(d);
        out[i] = len > 0.0f ? LightSample{d / len, len, 1.0f} : LightSample{l.directionToCenter(wsP_), 0.0f, 1.0f};
      }
      return;
    case LightShape::Directional:
      for (int i = 0; i < count; ++i) {
        const Vec2 q = concentricDisk(u[i]);
        const Vec2 offset = q * diskRadius_;
        float weight = 1.0f;
        if (l.profile_ == LightProfile::LimbDarkened) {
          const float mu = std::sqrt(std::max(0.0f, 1.0f - glm::dot(q, q)));
          weight = (1.0f - kLimbDarkeningU * (1.0f - mu)) / (1.0f - kLimbDarkeningU / 3.0f);
        }
        out[i] = {glm::normalize(l.direction_ + offset.x * frame_.x + offset.y * frame_.y), kInfinity, weight};
      }
      return;
    default:  // rect, segment, polygon: no per-point set-up to hoist
      for (int i = 0; i < count; ++i) out[i] = l.sample(wsP_, u[i]);
      return;
  }
}

float Light::irradiance(const Vec3& wsP, const Vec3& wsN) const {
  switch (shape_) {
    case LightShape::Directional: return intensity_ * std::max(0.0f, glm::dot(wsN, direction_));
    case LightShape::Sphere: {
      // Exact for a sphere wholly above p's horizon: E = pi L sin^2(alpha) cos(theta).
      const float d = glm::length(center_ - wsP);
      if (d <= radius_) return 0.0f;
      const float s = radius_ / d;
      return intensity_ * kPi * s * s * std::max(0.0f, glm::dot(wsN, (center_ - wsP) / d));
    }
    default: break;
  }
  // Planar and linear lights: a fixed 8x8 stratified quadrature of the area (or length) integral.
  const CmjSampler sampler(64);
  float measure;
  switch (shape_) {
    case LightShape::Disk: measure = kPi * radius_ * radius_; break;
    case LightShape::Rect: measure = 4.0f * glm::length(glm::cross(u_, v_)); break;
    case LightShape::Segment: measure = glm::length(b_ - a_); break;
    default: measure = 0.5f * glm::length(newellNormal(vertices_)); break;
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
    case LightShape::Directional: z = -direction_; break;
    case LightShape::Disk:
    case LightShape::Rect:
    case LightShape::Polygon: z = glm::dot(normal_, target - center_) >= 0.0f ? normal_ : -normal_; break;
    default: {
      const Vec3 d = target - center_;
      z = glm::length(d) > 0.0f ? glm::normalize(d) : Vec3(0.0f, -1.0f, 0.0f);
    }
  }
  return Frame::fromZ(z);
}

}  // namespace penumbra
