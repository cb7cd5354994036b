// RayScene: the Embree 3 wrapper of src/rt/ray_scene.h. One device and one scene per
// RayScene, one triangle geometry per object whose geometry id is the object's index, so a hit maps
// to (object id, triangle index) without a lookup table keyed by Embree's own numbering.
//
// The scene is built with RTC_SCENE_FLAG_ROBUST (Embree's watertight, conservative traversal: no
// rays slip through shared edges of a closed mesh, at a small cost in speed) and high build quality
// (more build time for faster rays: the reference traces billions of rays against one BVH).
// Embree's error callback only records the message; it is turned into a penumbra::Error after each
// call that can fail, because throwing through Embree's C frames is not allowed.
// Single precision throughout, as Embree is.
#include "rt/ray_scene.h"

#include <algorithm>
#include <cstddef>
#include <mutex>
#include <string>
#include <vector>

#include <embree3/rtcore.h>
#include <tbb/concurrent_vector.h>

#include "core/mesh_fingerprint.h"
#include "core/scene_caches.h"
#include "penumbra/error.h"

namespace penumbra {

struct RayScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<int32_t> objectIds;  // geometry id (= object index) -> object id
  PacketLog* log = nullptr;        // attachLog's; RayScene is otherwise immutable once built

  std::mutex errorMutex;
  std::string firstError;  // first message reported by Embree since the last check

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  static void onError(void* userPtr, RTCError code, const char* message) {
    auto* self = static_cast<Impl*>(userPtr);
    std::lock_guard<std::mutex> lock(self->errorMutex);
    if (self->firstError.empty())
      self->firstError = fmt::format("{} (code {})", message ? message : "no message", static_cast<int>(code));
  }

  // Throws the recorded Embree error, if any, naming what was being done.
  void check(std::string_view what) {
    const RTCError code = device ? rtcGetDeviceError(device) : RTC_ERROR_UNKNOWN;
    std::string message;
    {
      std::lock_guard<std::mutex> lock(errorMutex);
      message.swap(firstError);
    }
    if (code != RTC_ERROR_NONE || !message.empty())
      fail("ray tracing (Embree): {} failed: {}", what,
           message.empty() ? fmt::format("error code {}", static_cast<int>(code)) : message);
  }
};

namespace {

// RayPacket16 and RayHitPacket16 are handed to Embree as its own packet types.
static_assert(sizeof(RayPacket16) == sizeof(RTCRay16) && alignof(RayPacket16) == alignof(RTCRay16));
static_assert(offsetof(RayPacket16, orgX) == offsetof(RTCRay16, org_x) &&
              offsetof(RayPacket16, tMin) == offsetof(RTCRay16, tnear) &&
              offsetof(RayPacket16, dirX) == offsetof(RTCRay16, dir_x) &&
              offsetof(RayPacket16, time) == offsetof(RTCRay16, time) &&
              offsetof(RayPacket16, tMax) == offsetof(RTCRay16, tfar) &&
              offsetof(RayPacket16, mask) == offsetof(RTCRay16, mask) &&
              offsetof(RayPacket16, id) == offsetof(RTCRay16, id) &&
              offsetof(RayPacket16, flags) == offsetof(RTCRay16, flags));
static_assert(RTC_MAX_INSTANCE_LEVEL_COUNT == 1 && sizeof(RayHitPacket16) == sizeof(RTCRayHit16) &&
              offsetof(RayHitPacket16, hit) == offsetof(RTCRayHit16, hit) &&
              offsetof(HitPacket16, ngX) == offsetof(RTCHit16, Ng_x) &&
              offsetof(HitPacket16, u) == offsetof(RTCHit16, u) &&
              offsetof(HitPacket16, primId) == offsetof(RTCHit16, primID) &&
              offsetof(HitPacket16, geomId) == offsetof(RTCHit16, geomID) &&
              offsetof(HitPacket16, instId) == offsetof(RTCHit16, instID));
static_assert(HitPacket16::kNoHit == RTC_INVALID_GEOMETRY_ID);

// Embree's single-ray layout from ours. mask = all bits so no geometry masking applies.
inline void fillRay(RTCRay& r, const Ray& ray) {
  r.org_x = ray.origin.x;
  r.org_y = ray.origin.y;
  r.org_z = ray.origin.z;
  r.tnear = ray.tMin;
  r.dir_x = ray.direction.x;
  r.dir_y = ray.direction.y;
  r.dir_z = ray.direction.z;
  r.time = 0.0f;
  r.tfar = ray.tMax;
  r.mask = 0xffffffffu;
  r.id = 0;
  r.flags = 0;
}

// A packet of `count` <= 16 of our rays; the other lanes keep the packet's valid empty rays, and
// the valid mask keeps Embree from tracing them.
inline void toPacket(const Ray* rays, int count, RayPacket16& packet) {
  for (int i = 0; i < count; ++i) packet.set(i, rays[i]);
}

// What a packet query passes besides the rays: a coherent context (the callers group rays that share
// an origin region and a direction cone) and the valid mask of lanes [0, count).
struct PacketQuery {
  RTCIntersectContext context;
  alignas(64) int valid[16];

  explicit PacketQuery(int count) {
    if (count > 16) fail("internal: a packet holds at most 16 rays (got {})", count);
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (int i = 0; i < 16; ++i) valid[i] = i < count ? -1 : 0;
  }
};

// A filtered query's context: Embree hands the filter a pointer to `context`, the first member, from
// which filterHits finds the caller's HitFilter.
struct FilteredQuery {
  PacketQuery query;
  const HitFilter* filter;
};
static_assert(offsetof(FilteredQuery, query) == 0 && offsetof(PacketQuery, context) == 0);

// The context filter of filtered queries: rejects (valid = 0) each hit the caller's filter does not
// accept. Embree passes the hit's distance as the ray's tfar.
void filterHits(const RTCFilterFunctionNArguments* args) {
  const HitFilter& filter = *reinterpret_cast<const FilteredQuery*>(args->context)->filter;
  const unsigned n = args->N;
  for (unsigned i = 0; i < n; ++i) {
    if (args->valid[i] == 0) continue;
    const Vec3 ng(RTCHitN_Ng_x(args->hit, n, i), RTCHitN_Ng_y(args->hit, n, i), RTCHitN_Ng_z(args->hit, n, i));
    if (!filter.accept(filter.state, RTCRayN_id(args->ray, n, i), RTCRayN_tfar(args->ray, n, i), ng))
      args->valid[i] = 0;
  }
}

}  // namespace

RayScene::RayScene(const Scene& scene) : impl_(std::make_unique<Impl>()) {
  Impl& im = *impl_;
  im.device = rtcNewDevice(nullptr);
  if (!im.device)
    fail("ray tracing (Embree): could not create a device (error code {})",
         static_cast<int>(rtcGetDeviceError(nullptr)));
  rtcSetDeviceErrorFunction(im.device, &Impl::onError, &im);

  im.scene = rtcNewScene(im.device);
  im.check("creating the scene");
  // The context filter lets a query skip hits its caller passes over (HitFilter); a query without one
  // pays a null test per hit.
  rtcSetSceneFlags(im.scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
  rtcSetSceneBuildQuality(im.scene, RTC_BUILD_QUALITY_HIGH);

  im.objectIds.reserve(scene.objects.size());
  for (size_t index = 0; index < scene.objects.size(); ++index) {
    const Object& object = scene.objects[index];
    const Mesh& mesh = object.mesh;
    im.objectIds.push_back(object.id);
    if (mesh.triangles.empty() || mesh.positions.empty()) continue;  // nothing to hit; keeps ids = indices
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const glm::uvec3& tri = mesh.triangles[t];
      if (tri.x >= mesh.positions.size() || tri.y >= mesh.positions.size() || tri.z >= mesh.positions.size())
        fail("{}: object '{}' triangle {} uses vertex index {} but the mesh has {} vertices", scene.source, object.name,
             t, std::max({tri.x, tri.y, tri.z}), mesh.positions.size());
    }

    RTCGeometry geom = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // rtcSetNewGeometryBuffer pads the buffer so Embree's 16-byte loads of the last vertex stay inside it.
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), mesh.positions.size()));
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(uint32_t), mesh.triangles.size()));
    if (!vertices || !indices) {
      rtcReleaseGeometry(geom);
      im.check(fmt::format("allocating the buffers of object '{}'", object.name));
      fail("ray tracing (Embree): could not allocate the buffers of object '{}'", object.name);
    }
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
      vertices[3 * i + 0] = mesh.positions[i].x;
      vertices[3 * i + 1] = mesh.positions[i].y;
      vertices[3 * i + 2] = mesh.positions[i].z;
    }
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
      indices[3 * i + 0] = mesh.triangles[i].x;
      indices[3 * i + 1] = mesh.triangles[i].y;
      indices[3 * i + 2] = mesh.triangles[i].z;
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(im.scene, geom, static_cast<unsigned>(index));
    rtcReleaseGeometry(geom);  // the scene holds its own reference
    im.check(fmt::format("adding object '{}'", object.name));
  }
  // Degenerate (zero-area) and non-finite triangles are dropped by Embree's builder; they cannot be hit.
  rtcCommitScene(im.scene);
  im.check("building the BVH");
}

RayPacket16::RayPacket16() {
  for (int i = 0; i < 16; ++i) {
    orgX[i] = orgY[i] = orgZ[i] = 0.0f;
    dirX[i] = dirY[i] = 0.0f;
    dirZ[i] = 1.0f;
    tMin[i] = tMax[i] = time[i] = 0.0f;
    mask[i] = 0xffffffffu;
    id[i] = static_cast<uint32_t>(i);
    flags[i] = 0;
  }
}

RayScene::~RayScene() = default;
const RayScene& RaySceneCache::get(const Scene& scene) {
  if (scene.caches && scene.geometryRevision != 0) {
    // Declared geometry that the shared scene was built from (or proved equal to): nothing to hash.
    SceneCaches& caches = *scene.caches;
    std::lock_guard lock(caches.mutex);
    if (caches.rayScene && caches.rayRevision == scene.geometryRevision) {
      rebuilt_ = false;
      rays_ = std::static_pointer_cast<const RayScene>(caches.rayScene);
      bounds_ = caches.rayBounds;
      key_ = caches.rayKey;
      return *rays_;
    }
  }
  std::vector<uint64_t> key;
  key.reserve(3 * scene.objects.size());
  for (const Object& object : scene.objects) {
    const MeshFingerprint fingerprint = meshFingerprint(object.mesh);
    key.insert(key.end(), {static_cast<uint64_t>(static_cast<uint32_t>(object.id)), fingerprint.a, fingerprint.b});
  }
  SceneCaches local;  // a scene without caches: this technique's own
  SceneCaches& caches = scene.caches ? *scene.caches : local;
  std::lock_guard lock(caches.mutex);
  if (!scene.caches && rays_ && key == key_) {  // kept by this technique alone
    rebuilt_ = false;
    return *rays_;
  }
  rebuilt_ = !caches.rayScene || caches.rayKey != key;
  if (rebuilt_) {
    rays_.reset();            // this technique's hold on the old one: freed before the new one is
    caches.rayScene.reset();  // built unless another technique still traces it
    caches.rayScene = std::make_shared<const RayScene>(scene);
    caches.rayKey = key;
    caches.rayBounds = scene.bounds();
  }
  caches.rayRevision = scene.geometryRevision;  // built from, or proved equal to, this revision
  rays_ = std::static_pointer_cast<const RayScene>(caches.rayScene);
  bounds_ = caches.rayBounds;
  key_ = std::move(key);
  return *rays_;
}

RayScene::RayScene(RayScene&&) noexcept = default;
RayScene& RayScene::operator=(RayScene&&) noexcept = default;

bool RayScene::occluded(const Ray& ray) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r;
  fillRay(r, ray);
  rtcOccluded1(impl_->scene, &context, &r);
  return r.tfar < 0.0f;  // Embree sets tfar to -inf on an occlusion
}

void RayScene::occluded16(const Ray* rays, int count, bool* out) const {
  if (count <= 0) return;
  RayPacket16 packet;
  toPacket(rays, std::min(count, 16), packet);
  occluded16(packet, count);
  for (int i = 0; i < count; ++i) out[i] = packet.blocked(i);
}

struct PacketLog::Impl {
  tbb::concurrent_vector<LoggedPacket> packets;
};

PacketLog::PacketLog() : impl_(std::make_unique<Impl>()) {}
PacketLog::~PacketLog() = default;

void PacketLog::add(const RayPacket16& rays, int count, bool closestHit) {
  impl_->packets.push_back(LoggedPacket{rays, count, closestHit});
}

std::vector<LoggedPacket> PacketLog::packets() const {
  return std::vector<LoggedPacket>(impl_->packets.begin(), impl_->packets.end());
}

void RayScene::attachLog(PacketLog* log) const { impl_->log = log; }

void RayScene::occluded16(RayPacket16& packet, int count) const {
  if (count <= 0) return;
  if (impl_->log) impl_->log->add(packet, count, false);
  PacketQuery query(count);
  rtcOccluded16(query.valid, impl_->scene, &query.context, reinterpret_cast<RTCRay16*>(&packet));
}

void RayScene::intersect16(RayHitPacket16& packet, int count, const HitFilter& filter) const {
  if (count <= 0) return;
  if (impl_->log && !filter.accept) impl_->log->add(packet.ray, count, true);  // see PacketLog
  FilteredQuery filtered{PacketQuery(count), &filter};
  if (filter.accept) filtered.query.context.filter = &filterHits;
  for (int i = 0; i < 16; ++i) {
    packet.hit.geomId[i] = HitPacket16::kNoHit;
    packet.hit.instId[i] = HitPacket16::kNoHit;
  }
  rtcIntersect16(filtered.query.valid, impl_->scene, &filtered.query.context, reinterpret_cast<RTCRayHit16*>(&packet));
}

std::optional<RayHit> RayScene::intersect(const Ray& ray) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  fillRay(rh.ray, ray);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  RayHit hit;
  hit.t = rh.ray.tfar;
  hit.objectId = impl_->objectIds[rh.hit.geomID];
  hit.triangleId = static_cast<int32_t>(rh.hit.primID);
  hit.barycentrics = Vec2(rh.hit.u, rh.hit.v);
  // Embree's Ng is (v1 - v0) x (v2 - v0), unnormalized: the winding's normal, as Mesh::faceNormal.
  const Vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  const float len = glm::length(ng);
  hit.wsGeometricNormal = len > 0.0f ? ng / len : Vec3(0.0f);
  return hit;
}

float shadowRayEpsilon(const Bounds3& sceneBounds) {
  // A float position of magnitude M is exact to about M * 2^-23 ~ 1.2e-7 M, and a hit point
  // interpolated from three vertices to a few times that. 1e-4 of the scene's scale is ~1000 such
  // ulps (no self-shadowing "acne" even on large, grazing receivers) while occluders are far thicker
  // than 1e-4 of the scene (a 10 m scene would need a 1 mm gap or plate to leak). The scale is the
  // larger of the scene's size and its distance from the origin, since float spacing grows with |p|.
  if (sceneBounds.empty()) return 1e-4f;
  const Vec3 farCorner = glm::max(glm::abs(sceneBounds.lower), glm::abs(sceneBounds.upper));
  const float scale = std::max(sceneBounds.radius(), std::max(farCorner.x, std::max(farCorner.y, farCorner.z)));
  return 1e-4f * std::max(scale, 1e-6f);
}

}  // namespace penumbra
