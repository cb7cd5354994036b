// Embree 3 wrapper: one BVH over every object of a Scene, with occlusion and closest-hit queries.
// Geometry ids map to scene objects, so a hit reports the object id and the triangle index in its
// mesh. Errors from Embree become penumbra::Error at this boundary.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "penumbra/gbuffer.h"
#include "penumbra/math.h"
#include "penumbra/scene.h"

namespace penumbra {

struct RayHit {
  float t = kInfinity;  //!< ray parameter of the hit (in units of |direction|)
  int32_t objectId = kNoObject;
  int32_t triangleId = -1;       //!< index into the object's mesh triangles
  Vec2 barycentrics{0.0f};       //!< (b1, b2) of the hit in the triangle (b0 = 1 - b1 - b2)
  Vec3 wsGeometricNormal{0.0f};  //!< unit face normal, as wound (not flipped towards the ray)
};

class RayScene {
 public:
  explicit RayScene(const Scene& scene);
  ~RayScene();
  RayScene(RayScene&&) noexcept;
  RayScene& operator=(RayScene&&) noexcept;
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  // True if anything lies on the ray within [tMin, tMax]. Thread-safe.
  bool occluded(const Ray& ray) const;
  // Occlusion of `count` <= 16 rays at once (one Embree packet); out[i] is set for each ray.
  void occluded16(const Ray* rays, int count, bool* out) const;
  // The closest hit's distance of `count` <= 16 rays at once (one Embree packet): tHit[i] is the ray
  // parameter of ray i's first hit within [tMin, tMax], kInfinity where it hits nothing. For shadow
  // rays that need the blocker's distance (a penumbra's width), at the cost of a closest-hit query.
  void intersect16(const Ray* rays, int count, float* tHit) const;
  // The closest hit within [tMin, tMax], or nothing. Thread-safe.
  std::optional<RayHit> intersect(const Ray& ray) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The camera G-buffer by ray casting one primary ray through each pixel centre: the independent
// oracle the rasterizer's G-buffer is tested against (and a fallback for tests).
GBuffer traceGBuffer(const Scene& scene, const RayScene& rays, int width, int height);

// Offset along the normal used to start shadow rays off a surface, scaled to the scene's size:
// far enough to avoid self-intersection of float positions, small enough not to skip occluders.
float shadowRayEpsilon(const Bounds3& sceneBounds);

}  // namespace penumbra
