// Embree 3 wrapper: one BVH over every object of a Scene, with occlusion and closest-hit queries.
// Geometry ids map to scene objects, so a hit reports the object id and the triangle index in its
// mesh. Errors from Embree become penumbra::Error at this boundary.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

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

// Sixteen rays as structure of arrays, in the layout of Embree's packet queries (RTCRay16, field for
// field; ray_scene.cpp checks it), so code that builds rays lane by lane writes them where the
// traversal reads them, with no copy. tMin and tMax bound t along direction (which need not be unit);
// after occluded16, tMax[i] < 0 where ray i is blocked.
struct alignas(64) RayPacket16 {
  float orgX[16], orgY[16], orgZ[16], tMin[16];
  float dirX[16], dirY[16], dirZ[16], time[16];
  float tMax[16];
  uint32_t mask[16], id[16], flags[16];

  RayPacket16();  // every lane a valid empty ray: origin 0, direction +z, tMin = tMax = 0, time 0, mask all
  // Lane `lane` becomes `ray` (origin, direction, tMin, tMax; the other fields are kept).
  void set(int lane, const Ray& ray) {
    orgX[lane] = ray.origin.x;
    orgY[lane] = ray.origin.y;
    orgZ[lane] = ray.origin.z;
    tMin[lane] = ray.tMin;
    dirX[lane] = ray.direction.x;
    dirY[lane] = ray.direction.y;
    dirZ[lane] = ray.direction.z;
    tMax[lane] = ray.tMax;
  }
  bool blocked(int lane) const { return tMax[lane] < 0.0f; }
};

// The closest hits of a packet (RTCHit16 with one instance level): geomId[i] is kNoHit where ray i
// hit nothing.
struct alignas(64) HitPacket16 {
  static constexpr uint32_t kNoHit = 0xffffffffu;
  float ngX[16], ngY[16], ngZ[16], u[16], v[16];
  uint32_t primId[16], geomId[16], instId[16];
};
struct alignas(64) RayHitPacket16 {
  RayPacket16 ray;
  HitPacket16 hit;
};

// A packet query as it was handed to Embree: the rays before the traversal wrote them, the lanes
// [0, count) traced, and the query (closest hit or occlusion).
struct LoggedPacket {
  RayPacket16 rays;
  int count = 0;
  bool closestHit = false;
};

// The packets a RayScene traces while the log is attached (RayScene::attachLog), from any thread:
// what a benchmark replays through Embree alone to compare a technique's ray throughput with Embree's
// on the very same rays (bench/few_ray_bench.cpp). Single-ray queries are not logged, nor filtered
// ones (intersect16 with a HitFilter): replayed without the caller's filter they would be another query.
class PacketLog {
 public:
  PacketLog();
  ~PacketLog();
  void add(const RayPacket16& rays, int count, bool closestHit);
  // Every packet logged so far, in no particular order between threads.
  std::vector<LoggedPacket> packets() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A caller's test of the hits of a filtered closest-hit query (RayScene::intersect16 with a filter):
// Embree asks it of every hit it finds on a ray, in no particular order and a hit possibly more than
// once, and the query returns the nearest hit it accepted. `rayId` is the lane's RayPacket16::id, `t`
// the hit's distance, `ng` Embree's geometric normal (v1 - v0) x (v2 - v0), unnormalized. It must be
// a function of its arguments and `state` alone, and safe to call from any thread.
struct HitFilter {
  bool (*accept)(const void* state, uint32_t rayId, float t, const Vec3& ng) = nullptr;
  const void* state = nullptr;
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
  // Occlusion of lanes [0, count) of a packet built in place (count <= 16): afterwards
  // packet.blocked(i) says whether ray i is blocked.
  void occluded16(RayPacket16& packet, int count) const;
  // The closest hits of lanes [0, count) of a packet built in place (count <= 16): afterwards
  // packet.ray.tMax[i] is ray i's hit distance where packet.hit.geomId[i] != HitPacket16::kNoHit.
  // With a filter (accept not null), each ray's nearest hit that `filter` accepts: one traversal, where
  // stepping from hit to hit restarts it at every hit the caller would pass over.
  void intersect16(RayHitPacket16& packet, int count, const HitFilter& filter = {}) const;
  // The closest hit within [tMin, tMax], or nothing. Thread-safe.
  std::optional<RayHit> intersect(const Ray& ray) const;

  // Logs every packet query into `log` from now on (nullptr: stops). For measurements: attached, each
  // query copies its packet; detached, a query pays one load and branch. Not to be changed while
  // another thread traces.
  void attachLog(PacketLog* log) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A RayScene kept while the geometry it was built from stays the same: every object's id, positions
// and triangles the same to the bit (meshFingerprint), as under a light or camera moving over a static
// scene. Each ray-traced technique holds one, so its steady prepare builds no BVH; any change to the
// geometry (or another scene with other geometry) builds it afresh. The RayScene itself lives in the
// scene's caches (Scene::caches), so every technique prepared on a scene, or on a copy of it, shares
// one; a scene without caches gets one of its own here.
class RaySceneCache {
 public:
  const RayScene& get(const Scene& scene);
  // Whether the last get() built the scene (rather than finding it built, by this or another technique).
  bool rebuilt() const { return rebuilt_; }
  // The bounds of the geometry of the last get() (Scene::bounds, kept with the BVH).
  const Bounds3& bounds() const { return bounds_; }

 private:
  std::shared_ptr<const RayScene> rays_;  //!< held while this technique may trace it
  std::vector<uint64_t> key_;             //!< per object: id, fingerprint.a, fingerprint.b
  bool rebuilt_ = false;
  Bounds3 bounds_;
};

// The camera G-buffer by ray casting one primary ray through each pixel centre: the independent
// oracle the rasterizer's G-buffer is tested against (and a fallback for tests).
GBuffer traceGBuffer(const Scene& scene, const RayScene& rays, int width, int height);

// Offset along the normal used to start shadow rays off a surface, scaled to the scene's size:
// far enough to avoid self-intersection of float positions, small enough not to skip occluders.
float shadowRayEpsilon(const Bounds3& sceneBounds);

}  // namespace penumbra
