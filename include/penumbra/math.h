// Small math vocabulary shared by every part of penumbra: glm vector aliases, bounds, frames.
// Names carry their space as a prefix where it matters (wsPosition, lsDepth, csDepth), following
// Filament; transforms are named X-from-Y (lsFromWs, cameraFromWs), following pbrt-v4.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

namespace penumbra {

using Vec2 = glm::vec2;
using Vec3 = glm::vec3;
using Vec4 = glm::vec4;
using Mat3 = glm::mat3;
using Mat4 = glm::mat4;
using DVec3 = glm::dvec3;

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInfinity = std::numeric_limits<float>::infinity();

inline float radians(float degrees) { return degrees * (kPi / 180.0f); }
inline float degrees(float radians) { return radians * (180.0f / kPi); }

inline bool isFinite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Axis-aligned bounding box; empty when lower > upper on any axis.
struct Bounds3 {
  Vec3 lower{kInfinity};
  Vec3 upper{-kInfinity};

  bool empty() const { return lower.x > upper.x || lower.y > upper.y || lower.z > upper.z; }
  void extend(const Vec3& p) {
    lower = glm::min(lower, p);
    upper = glm::max(upper, p);
  }
  void extend(const Bounds3& b) {
    lower = glm::min(lower, b.lower);
    upper = glm::max(upper, b.upper);
  }
  Vec3 center() const { return 0.5f * (lower + upper); }
  Vec3 diagonal() const { return upper - lower; }
  float radius() const { return 0.5f * glm::length(diagonal()); }  // of the bounding sphere
};

// An orthonormal frame: x, y, z axes in world space. toLocal/fromLocal rotate directions.
struct Frame {
  Vec3 x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};

  // A frame whose z axis is the given unit vector (Duff et al. 2017, "Building an orthonormal basis,
  // revisited"): continuous everywhere except the sign flip at z.z = 0, which is harmless here.
  static Frame fromZ(const Vec3& z) {
    const float sign = std::copysign(1.0f, z.z);
    const float a = -1.0f / (sign + z.z);
    const float b = z.x * z.y * a;
    Frame f;
    f.x = Vec3(1.0f + sign * z.x * z.x * a, sign * b, -sign * z.x);
    f.y = Vec3(b, sign + z.y * z.y * a, -z.y);
    f.z = z;
    return f;
  }
  Vec3 toLocal(const Vec3& v) const { return Vec3(glm::dot(v, x), glm::dot(v, y), glm::dot(v, z)); }
  Vec3 fromLocal(const Vec3& v) const { return v.x * x + v.y * y + v.z * z; }
};

}  // namespace penumbra

namespace penumbra {

// A ray segment: points origin + t * direction for t in [tMin, tMax]. direction need not be unit.
struct Ray {
  Vec3 origin{0.0f};
  Vec3 direction{0.0f, 0.0f, -1.0f};
  float tMin = 0.0f;
  float tMax = kInfinity;
};

}  // namespace penumbra
