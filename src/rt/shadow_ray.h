// Shadow rays from a G-buffer point towards a light sample, shared by the ray-traced techniques
// (reference, raytraced-hard) so they offset and clip rays identically.
//
// The origin moves by `epsilon` (shadowRayEpsilon: a scale-relative distance, world units) along
// the geometric normal, to the side of the light's centre, so the ray does not hit the surface it
// starts on. The offset goes to the light's side rather than to each sample's side: a sample below
// the receiver's tangent plane is then blocked by the receiver itself, as it physically is, and a
// facet of a smooth-shaded mesh that faces slightly away from the light near the shadow terminator
// (while its shading normal faces the light) does not shadow itself, as the smooth surface it
// approximates would not (pbrt's rule, offsetting to the side the ray leaves). On a surface facing
// away from the light V is not meaningful (a zero-thickness wall is seen through): the error mask
// excludes such pixels and shading multiplies V by an irradiance of 0 there. The ray
// stops `epsilon` short of the sample, so emitter geometry modelled in the scene (a lamp's panel)
// does not occlude its own light.
#pragma once

#include <algorithm>
#include <limits>

#include "penumbra/light.h"
#include "penumbra/math.h"

namespace penumbra::rt {

// `side` is +1 or -1: which side of the surface the light's centre lies on (see lightSide).
inline Vec3 offsetOrigin(const Vec3& wsP, const Vec3& wsGeometricNormal, float side, float epsilon) {
  return wsP + (side * epsilon) * wsGeometricNormal;
}

inline float lightSide(const Light& light, const Vec3& wsP, const Vec3& wsGeometricNormal) {
  return glm::dot(wsGeometricNormal, light.directionToCenter(wsP)) >= 0.0f ? 1.0f : -1.0f;
}

// The origin of shadow rays from wsP towards `light`: offset to the side of the light's centre.
inline Vec3 offsetOrigin(const Light& light, const Vec3& wsP, const Vec3& wsGeometricNormal, float epsilon) {
  return offsetOrigin(wsP, wsGeometricNormal, lightSide(light, wsP, wsGeometricNormal), epsilon);
}

// The segment from the offset origin to the sample seen from wsP (unit direction, t in world units),
// stopping epsilon short of it. Re-aiming at the sample from the offset origin (rather than keeping
// the direction seen from wsP) halves the ray's displacement where it passes an occluder halfway to
// the light; keeping the direction shifts the whole ray by epsilon and measurably biases V.
inline Ray shadowRay(const Vec3& wsP, const Vec3& wsOrigin, const Vec3& wsDirection, float distance, float epsilon) {
  Ray ray;
  ray.origin = wsOrigin;
  ray.tMin = 0.0f;
  if (distance == kInfinity) {  // directional light: every ray is parallel to the sample direction
    ray.direction = wsDirection;
    ray.tMax = kInfinity;
    return ray;
  }
  const Vec3 d = (wsP + distance * wsDirection) - wsOrigin;
  const float len = glm::length(d);
  if (!(len < kInfinity)) {
    // A sample some 1e19 units away (or more) overflows the squared length: at that distance the
    // offset of the origin does not turn the ray, so it keeps the direction seen from wsP.
    ray.direction = wsDirection;
    ray.tMax = std::numeric_limits<float>::max();
    return ray;
  }
  ray.direction = len > 0.0f ? d / len : wsDirection;
  ray.tMax = std::max(0.0f, len - epsilon);
  return ray;
}

// Puts a just-built ray into a packet slot field by field: a whole-struct copy of it stalls on
// store forwarding (the struct is still in flight in the store buffer as separate fields).
inline void storeRay(Ray& slot, const Ray& ray) {
  slot.origin = ray.origin;
  slot.direction = ray.direction;
  slot.tMin = ray.tMin;
  slot.tMax = ray.tMax;
}

}  // namespace penumbra::rt
