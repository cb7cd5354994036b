// Tests of the Embree wrapper (src/rt/ray_scene.cpp): closest hits and occlusion on quads whose
// answers are known exactly (t, object id, triangle id, barycentrics, normal), packets against
// single rays, the packet log, the empty scene, degenerate triangles, bad indices, and the shadow-ray epsilon.
#include <cmath>

#include <gtest/gtest.h>

#include "penumbra/error.h"
#include "penumbra/sampling.h"
#include "rt/ray_scene.h"
#include "rt/rt_test_scenes.h"
#include "rt/shadow_ray.h"

namespace penumbra {
namespace {

using testing::makeObject;
using testing::makeScene;
using testing::quadMesh;

Ray makeRay(const Vec3& o, const Vec3& d, float tMin = 0.0f, float tMax = kInfinity) {
  Ray r;
  r.origin = o;
  r.direction = d;
  r.tMin = tMin;
  r.tMax = tMax;
  return r;
}

// Quad A (id 3) spans [-1, 1]^2 at z = 0 facing +z; quad B (id 9) spans [0, 2] x [-1, 1] at z = 1 facing -z.
Scene twoQuads() {
  return makeScene({makeObject(3, quadMesh(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)), "a"),
                    makeObject(9, quadMesh(Vec3(1, 0, 1), Vec3(0, 1, 0), Vec3(1, 0, 0)), "b")});
}

TEST(RayScene, IntersectReportsTheExactHit) {
  const Scene scene = twoQuads();
  const RayScene rays(scene);
  // x < 0: only quad A is below.
  const auto hit = rays.intersect(makeRay(Vec3(-0.2f, 0.3f, 5.0f), Vec3(0, 0, -1)));
  ASSERT_TRUE(hit.has_value());
  EXPECT_FLOAT_EQ(hit->t, 5.0f);
  EXPECT_EQ(hit->objectId, 3);
  // The diagonal from (-1,-1) to (1,1) splits the quad: triangle 0 below it (x > y), triangle 1 above.
  EXPECT_EQ(hit->triangleId, 1);
  const Mesh& mesh = scene.objects[0].mesh;
  const glm::uvec3 tri = mesh.triangles[1];
  const Vec2 b = hit->barycentrics;
  const Vec3 p = (1.0f - b.x - b.y) * mesh.positions[tri.x] + b.x * mesh.positions[tri.y] + b.y * mesh.positions[tri.z];
  EXPECT_NEAR(p.x, -0.2f, 1e-6f);
  EXPECT_NEAR(p.y, 0.3f, 1e-6f);
  EXPECT_NEAR(p.z, 0.0f, 1e-6f);
  EXPECT_NEAR(glm::length(hit->wsGeometricNormal - mesh.faceNormal(1)), 0.0f, 1e-6f);
  EXPECT_NEAR(hit->wsGeometricNormal.z, 1.0f, 1e-6f);

  // x > 0 from above: quad B (z = 1) first; its winding faces -z and is reported as wound, not flipped.
  const auto hitB = rays.intersect(makeRay(Vec3(0.5f, -0.25f, 5.0f), Vec3(0, 0, -1)));
  ASSERT_TRUE(hitB.has_value());
  EXPECT_FLOAT_EQ(hitB->t, 4.0f);
  EXPECT_EQ(hitB->objectId, 9);
  EXPECT_NEAR(hitB->wsGeometricNormal.z, -1.0f, 1e-6f);
  EXPECT_EQ(hitB->triangleId, 0);  // local (u, v) = (y, x - 1) = (-0.25, -0.5): below the diagonal u > v

  // From below, going up: A is first at t = 1.
  const auto hitUp = rays.intersect(makeRay(Vec3(0.5f, -0.25f, -1.0f), Vec3(0, 0, 1)));
  ASSERT_TRUE(hitUp.has_value());
  EXPECT_EQ(hitUp->objectId, 3);
  EXPECT_FLOAT_EQ(hitUp->t, 1.0f);
}

TEST(RayScene, RayParameterIsInUnitsOfTheDirection) {
  const RayScene rays(twoQuads());
  const auto hit = rays.intersect(makeRay(Vec3(-0.5f, 0, 5.0f), Vec3(0, 0, -2.0f)));
  ASSERT_TRUE(hit.has_value());
  EXPECT_FLOAT_EQ(hit->t, 2.5f);
}

TEST(RayScene, IntervalIsRespected) {
  const RayScene rays(twoQuads());
  const Vec3 o(0.5f, 0.0f, 5.0f), d(0, 0, -1);
  EXPECT_FALSE(rays.intersect(makeRay(o, d, 0.0f, 3.9f)).has_value());
  EXPECT_FALSE(rays.occluded(makeRay(o, d, 0.0f, 3.9f)));
  EXPECT_TRUE(rays.occluded(makeRay(o, d, 0.0f, 4.1f)));
  // Starting past B (t = 4) finds A at t = 5.
  const auto hit = rays.intersect(makeRay(o, d, 4.5f));
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->objectId, 3);
  EXPECT_FLOAT_EQ(hit->t, 5.0f);
  EXPECT_FALSE(rays.occluded(makeRay(o, d, 5.5f)));
  EXPECT_FALSE(rays.occluded(makeRay(Vec3(5.0f, 5.0f, 5.0f), d)));  // misses everything
}

TEST(RayScene, Occluded16MatchesSingleRays) {
  const RayScene rays(twoQuads());
  // Deterministic pseudo-random rays from above towards z = 0.5 +- 1, half of them hitting something.
  std::vector<Ray> all;
  for (uint32_t i = 0; i < 160; ++i) {
    auto u = [&](uint32_t k) { return static_cast<float>(hash32(i * 8u + k) >> 8) * (1.0f / 16777216.0f); };
    const Vec3 o(4.0f * u(0) - 2.0f, 4.0f * u(1) - 2.0f, 3.0f);
    const Vec3 target(4.0f * u(2) - 2.0f, 4.0f * u(3) - 2.0f, -0.5f);
    all.push_back(makeRay(o, target - o, 0.0f, 0.2f + 1.2f * u(4)));
  }
  int hits = 0;
  for (int count = 1; count <= 16; ++count) {
    for (size_t first = 0; first + count <= all.size(); first += 16) {
      bool out[16];
      rays.occluded16(&all[first], count, out);
      for (int i = 0; i < count; ++i) {
        EXPECT_EQ(out[i], rays.occluded(all[first + i])) << "ray " << first + i << " of a packet of " << count;
        hits += out[i];
      }
    }
  }
  EXPECT_GT(hits, 100);  // both answers occur
  EXPECT_LT(hits, 1000);
}

// Five quads stacked along z over [-2, 2]^2, facing +z (towards a ray from above) or -z: object k + 1
// at z = 0 (+z), 1 (-z), 2 (+z), 3 (-z), and object 5 at z = 3 (+z), coincident with object 4.
Scene stackedQuads() {
  const Vec3 x(2, 0, 0), y(0, 2, 0);
  return makeScene(
      {makeObject(1, quadMesh(Vec3(0, 0, 0), x, y), "z0 up"), makeObject(2, quadMesh(Vec3(0, 0, 1), y, x), "z1 down"),
       makeObject(3, quadMesh(Vec3(0, 0, 2), x, y), "z2 up"), makeObject(4, quadMesh(Vec3(0, 0, 3), y, x), "z3 down"),
       makeObject(5, quadMesh(Vec3(0, 0, 3), x, y), "z3 up")});
}

// What the filtered query's tests accept: hits whose face turns towards the ray (as plm's walk
// does), or hits beyond a per-ray distance.
struct FilterTestState {
  float dirZ[16];
  float minT[16];
};
bool facesTheRay(const void* state, uint32_t rayId, float, const Vec3& ng) {
  return ng.z * -static_cast<const FilterTestState*>(state)->dirZ[rayId] > 0.0f;
}
bool beyondMinT(const void* state, uint32_t rayId, float t, const Vec3&) {
  return t > static_cast<const FilterTestState*>(state)->minT[rayId];
}

TEST(RayScene, FilteredIntersect16ReturnsTheNearestAcceptedHit) {
  const RayScene rays(stackedQuads());
  const float planes[5] = {0.0f, 1.0f, 2.0f, 3.0f, 3.0f};
  const bool up[5] = {true, false, true, false, true};
  int checked = 0;
  for (int count = 1; count <= 16; ++count) {
    RayHitPacket16 packet;
    FilterTestState state;
    for (int lane = 0; lane < count; ++lane) {
      auto u = [&](uint32_t k) {
        return static_cast<float>(hash32(static_cast<uint32_t>(count * 64 + lane * 4) + k) >> 8) * (1.0f / 16777216.0f);
      };
      const Vec3 o(2.0f * u(0) - 1.0f, 2.0f * u(1) - 1.0f, 5.0f), d(0.2f * u(2) - 0.1f, 0.2f * u(3) - 0.1f, -1.0f);
      packet.ray.orgX[lane] = o.x;
      packet.ray.orgY[lane] = o.y;
      packet.ray.orgZ[lane] = o.z;
      packet.ray.dirX[lane] = d.x;
      packet.ray.dirY[lane] = d.y;
      packet.ray.dirZ[lane] = d.z;
      packet.ray.tMin[lane] = 0.0f;
      packet.ray.tMax[lane] = kInfinity;
      packet.ray.id[lane] = static_cast<uint32_t>(lane);
      state.dirZ[lane] = d.z;
      state.minT[lane] = 6.0f * u(4);
    }
    // Facing the ray: the nearest is z = 3's upward face, never the coincident downward one, whichever
    // the traversal meets first.
    RayHitPacket16 facing = packet;
    rays.intersect16(facing, count, HitFilter{&facesTheRay, &state});
    for (int lane = 0; lane < count; ++lane) {
      ASSERT_NE(facing.hit.geomId[lane], HitPacket16::kNoHit) << "lane " << lane;
      EXPECT_EQ(facing.hit.geomId[lane], 4u) << "lane " << lane;  // object 5, the scene's fifth
      EXPECT_NEAR(facing.ray.tMax[lane], 2.0f, 1e-5f);
    }
    // Beyond a distance: the nearest quad past it, whatever it faces (at z = 3 either of the two).
    RayHitPacket16 beyond = packet;
    rays.intersect16(beyond, count, HitFilter{&beyondMinT, &state});
    for (int lane = 0; lane < count; ++lane) {
      float expected = kInfinity;
      for (int k = 0; k < 5; ++k) {
        const float t = (5.0f - planes[k]) / -packet.ray.dirZ[lane];
        if (t > state.minT[lane] + 1e-4f && t < expected) expected = t;
      }
      if (expected == kInfinity) {
        EXPECT_EQ(beyond.hit.geomId[lane], HitPacket16::kNoHit) << "lane " << lane;
        continue;
      }
      ASSERT_NE(beyond.hit.geomId[lane], HitPacket16::kNoHit) << "lane " << lane;
      EXPECT_NEAR(beyond.ray.tMax[lane], expected, 1e-5f) << "lane " << lane;
      const uint32_t g = beyond.hit.geomId[lane];
      EXPECT_EQ(beyond.hit.ngZ[lane] > 0.0f, up[g]) << "lane " << lane;
      ++checked;
    }
  }
  EXPECT_GT(checked, 80);  // most lanes hit something past their distance
}

TEST(RayScene, AnAttachedLogKeepsEachUnfilteredPacketAsItWasHandedToEmbree) {
  const RayScene rays(twoQuads());
  // Lane 0 hits quad A (t = 3 along -z), lane 1 misses both quads; a third lane is not traced.
  RayHitPacket16 packet;
  for (int lane = 0; lane < 3; ++lane) {
    packet.ray.orgX[lane] = lane == 1 ? 5.0f : -0.5f;
    packet.ray.orgZ[lane] = 3.0f;
    packet.ray.dirZ[lane] = -1.0f;
    packet.ray.tMax[lane] = 10.0f;
  }
  PacketLog log;
  rays.attachLog(&log);
  RayPacket16 occlusion = packet.ray;
  rays.occluded16(occlusion, 2);
  rays.intersect16(packet, 2);
  RayHitPacket16 filtered = packet;  // a filtered query: not logged, a replay would not have its filter
  for (int lane = 0; lane < 2; ++lane) filtered.ray.tMax[lane] = 10.0f;
  const HitFilter acceptAll{[](const void*, uint32_t, float, const Vec3&) { return true; }, nullptr};
  rays.intersect16(filtered, 2, acceptAll);
  EXPECT_FLOAT_EQ(filtered.ray.tMax[0], 3.0f);
  rays.attachLog(nullptr);
  rays.occluded16(occlusion, 2);  // detached: not logged
  EXPECT_TRUE(occlusion.blocked(0));
  EXPECT_FLOAT_EQ(packet.ray.tMax[0], 3.0f);

  const std::vector<LoggedPacket> logged = log.packets();
  ASSERT_EQ(logged.size(), 2u);
  int closest = 0;
  for (const LoggedPacket& p : logged) {
    EXPECT_EQ(p.count, 2);
    closest += p.closestHit;
    // The rays before the traversal wrote tMax.
    EXPECT_EQ(p.rays.tMax[0], 10.0f);
    EXPECT_EQ(p.rays.orgX[1], 5.0f);
    EXPECT_EQ(p.rays.dirZ[1], -1.0f);
  }
  EXPECT_EQ(closest, 1);
}

TEST(RayScene, EmptySceneHitsNothing) {
  const RayScene rays(makeScene({}));
  const Ray r = makeRay(Vec3(0.0f), Vec3(0, 0, -1));
  EXPECT_FALSE(rays.intersect(r).has_value());
  EXPECT_FALSE(rays.occluded(r));
  Ray packet[16];
  for (Ray& p : packet) p = r;
  bool out[16];
  std::fill(std::begin(out), std::end(out), true);
  rays.occluded16(packet, 16, out);
  for (bool o : out) EXPECT_FALSE(o);
  // Objects without triangles are as empty, and later objects keep their ids.
  Scene s = makeScene(
      {makeObject(1, Mesh{}, "empty"), makeObject(2, quadMesh(Vec3(0, 0, -1), Vec3(1, 0, 0), Vec3(0, 1, 0)))});
  const RayScene rays2(s);
  const auto hit = rays2.intersect(r);
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->objectId, 2);
}

TEST(RayScene, DegenerateTrianglesDoNotCrashOrHit) {
  Mesh m;
  m.positions = {Vec3(-1, 0, 0),   Vec3(0, 0, 0),   Vec3(1, 0, 0),  // collinear
                 Vec3(0, 1, 0),                                     // for a repeated-index triangle
                 Vec3(-1, -1, -1), Vec3(1, -1, -1), Vec3(0, 1, -1)};
  m.triangles = {{0, 1, 2}, {3, 3, 3}, {1, 3, 3}, {4, 5, 6}};
  const RayScene rays(makeScene({makeObject(4, m)}));
  // Straight down through the degenerate line at x = 0.5: passes it, hits the real triangle at z = -1.
  const auto hit = rays.intersect(makeRay(Vec3(0.5f, 0.0f, 1.0f), Vec3(0, 0, -1)));
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->triangleId, 3);
  EXPECT_FLOAT_EQ(hit->t, 2.0f);
  EXPECT_FALSE(rays.occluded(makeRay(Vec3(0.5f, 0.0f, 1.0f), Vec3(0, 0, -1), 0.0f, 1.5f)));
}

TEST(RayScene, BadIndexIsAnErrorNamingTheObject) {
  Mesh m = quadMesh(Vec3(0.0f), Vec3(1, 0, 0), Vec3(0, 1, 0));
  m.triangles.push_back({0, 1, 7});
  try {
    const RayScene rays(makeScene({makeObject(1, m, "broken-quad")}));
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("broken-quad"), std::string::npos) << msg;
    EXPECT_NE(msg.find("7"), std::string::npos) << msg;
  }
}

TEST(RayScene, MovedSceneStillWorks) {
  RayScene a(twoQuads());
  RayScene b(std::move(a));
  EXPECT_TRUE(b.occluded(makeRay(Vec3(0.0f, 0.0f, 5.0f), Vec3(0, 0, -1))));
}

TEST(RaySceneCache, KeepsTheSceneWhileTheGeometryIsTheSameAndRebuildsItOtherwise) {
  Scene scene = twoQuads();
  RaySceneCache cache;
  const Ray down = makeRay(Vec3(0.5f, -0.25f, 5.0f), Vec3(0, 0, -1));
  EXPECT_FLOAT_EQ(cache.get(scene).intersect(down)->t, 4.0f);
  EXPECT_TRUE(cache.rebuilt());
  // The same geometry, also in another Scene object (a copy, with a moved camera): kept.
  cache.get(scene);
  EXPECT_FALSE(cache.rebuilt());
  Scene copy = scene;
  copy.camera.position += Vec3(1.0f, 0.0f, 0.0f);
  cache.get(copy);
  EXPECT_FALSE(cache.rebuilt());
  // One vertex of quad B written in place, lifting its corner: rebuilt, and the ray sees the new geometry.
  for (Vec3& p : scene.objects[1].mesh.positions) p.z += 1.0f;
  EXPECT_FLOAT_EQ(cache.get(scene).intersect(down)->t, 3.0f);
  EXPECT_TRUE(cache.rebuilt());
  EXPECT_FLOAT_EQ(cache.bounds().upper.z, 2.0f);
  // Another id for the same mesh: rebuilt (hits report object ids).
  scene.objects[1].id = 11;
  EXPECT_EQ(cache.get(scene).intersect(down)->objectId, 11);
  EXPECT_TRUE(cache.rebuilt());
  // An object removed: rebuilt.
  scene.objects.pop_back();
  EXPECT_EQ(cache.get(scene).intersect(down)->objectId, 3);
  EXPECT_TRUE(cache.rebuilt());
}

TEST(RaySceneCache, TechniquesOnOneSceneOrItsCopiesShareOneRayScene) {
  Scene scene = twoQuads();
  RaySceneCache first, second, third;
  const RayScene& a = first.get(scene);
  EXPECT_TRUE(first.rebuilt());
  const Scene copy = scene;  // a copy shares the caches
  const RayScene& b = second.get(copy);
  EXPECT_FALSE(second.rebuilt()) << "a second technique built its own Embree scene";
  EXPECT_EQ(&a, &b);
  // Geometry changed in the original: the next technique builds anew; the first still holds the old
  // one until its own next get().
  for (Vec3& p : scene.objects[0].mesh.positions) p.z -= 1.0f;
  const RayScene& c = third.get(scene);
  EXPECT_TRUE(third.rebuilt());
  EXPECT_NE(&c, &a);
  EXPECT_FLOAT_EQ(a.intersect(makeRay(Vec3(-0.5f, 0.0f, 5.0f), Vec3(0, 0, -1)))->t, 5.0f);  // still valid
  EXPECT_FLOAT_EQ(c.intersect(makeRay(Vec3(-0.5f, 0.0f, 5.0f), Vec3(0, 0, -1)))->t, 6.0f);
  // A scene without caches: each technique its own, kept while the geometry is the same.
  Scene alone = twoQuads();
  alone.caches = nullptr;
  RaySceneCache own;
  const RayScene& d = own.get(alone);
  EXPECT_TRUE(own.rebuilt());
  EXPECT_EQ(&own.get(alone), &d);
  EXPECT_FALSE(own.rebuilt());
}

// Declared geometry (Scene::declareGeometry): kept without being hashed, so a mesh changed without
// declaring again is traced as declared (the owner's promise, which this shows is taken); declaring
// again rebuilds; a copy that changes its mesh and declares gets a revision of its own, and each is
// traced as it is; undeclared again (0), a change is found by the hash.
TEST(RaySceneCache, DeclaredGeometryIsKeptWithoutProofAndRebuiltWhenDeclaredAgain) {
  Scene scene = twoQuads();
  const Ray down = makeRay(Vec3(0.5f, -0.25f, 5.0f), Vec3(0, 0, -1));  // onto quad B, at z = 1
  RaySceneCache cache;
  scene.declareGeometry();
  const uint64_t declared = scene.geometryRevision;
  EXPECT_NE(declared, 0u);
  for (const bool first : {true, false}) {
    EXPECT_FLOAT_EQ(cache.get(scene).intersect(down)->t, 4.0f);
    EXPECT_EQ(cache.rebuilt(), first);
  }
  for (Vec3& p : scene.objects[1].mesh.positions) p.z += 1.0f;
  EXPECT_FLOAT_EQ(cache.get(scene).intersect(down)->t, 4.0f) << "a declared revision is not proved again";
  EXPECT_FALSE(cache.rebuilt());
  scene.declareGeometry();
  EXPECT_NE(scene.geometryRevision, declared);
  EXPECT_FLOAT_EQ(cache.get(scene).intersect(down)->t, 3.0f);
  EXPECT_TRUE(cache.rebuilt());
  EXPECT_FLOAT_EQ(cache.bounds().upper.z, 2.0f);
  Scene copy = scene;  // shares the caches and, until it declares, the revision
  for (Vec3& p : copy.objects[1].mesh.positions) p.z += 1.0f;
  copy.declareGeometry();
  EXPECT_NE(copy.geometryRevision, scene.geometryRevision);
  EXPECT_NE(copy.geometryRevision, declared);
  RaySceneCache other;
  EXPECT_FLOAT_EQ(other.get(copy).intersect(down)->t, 2.0f);
  EXPECT_TRUE(other.rebuilt());
  EXPECT_FLOAT_EQ(cache.get(scene).intersect(down)->t, 3.0f);
  EXPECT_TRUE(cache.rebuilt()) << "the caches held the copy's geometry";
  scene.geometryRevision = 0;
  for (Vec3& p : scene.objects[1].mesh.positions) p.z += 0.5f;
  EXPECT_FLOAT_EQ(cache.get(scene).intersect(down)->t, 2.5f);
  EXPECT_TRUE(cache.rebuilt());
  // A scene without caches has nothing to declare against: undeclared, hashed as before.
  Scene alone = twoQuads();
  alone.caches = nullptr;
  alone.declareGeometry();
  EXPECT_EQ(alone.geometryRevision, 0u);
}

TEST(ShadowRayEpsilon, ScalesWithTheSceneAndItsDistanceFromTheOrigin) {
  Bounds3 unit;
  unit.extend(Vec3(-1.0f));
  unit.extend(Vec3(1.0f));
  Bounds3 big;
  big.extend(Vec3(-100.0f));
  big.extend(Vec3(100.0f));
  Bounds3 far;  // small but far from the origin: float spacing there is coarse
  far.extend(Vec3(1000.0f));
  far.extend(Vec3(1001.0f));
  const float e1 = shadowRayEpsilon(unit), e100 = shadowRayEpsilon(big), eFar = shadowRayEpsilon(far);
  EXPECT_GT(e1, 0.0f);
  EXPECT_NEAR(e100 / e1, 100.0f, 1e-3f * 100.0f);
  // Well above the float spacing at the far corner (1001 * 2^-23 = 1.2e-4).
  EXPECT_GT(eFar, 100.0f * 1001.0f * 0x1p-23f);
  EXPECT_GT(shadowRayEpsilon(Bounds3{}), 0.0f);
}

TEST(ShadowRayEpsilon, PreventsSelfIntersectionOnAGrazingPlane) {
  // A large tilted plane, points on it from barycentric interpolation (as the G-buffer makes them),
  // rays leaving at 1 degree above the surface from the offset origin must not hit it.
  const Vec3 n = glm::normalize(Vec3(0.3f, 1.0f, 0.2f));
  const Frame f = Frame::fromZ(n);
  const Vec3 c(3.0f, -2.0f, 5.0f);
  const Mesh m = quadMesh(c, 50.0f * f.x, 50.0f * f.y);
  const Scene scene = makeScene({makeObject(1, m)});
  const RayScene rays(scene);
  const float eps = shadowRayEpsilon(scene.bounds());
  int selfHits = 0;
  for (uint32_t i = 0; i < 2000; ++i) {
    const float b1 = static_cast<float>(hash32(2 * i) >> 8) / 16777216.0f;
    const float b2 = (1.0f - b1) * static_cast<float>(hash32(2 * i + 1) >> 8) / 16777216.0f;
    const glm::uvec3 t = m.triangles[i % 2];
    const Vec3 p = (1.0f - b1 - b2) * m.positions[t.x] + b1 * m.positions[t.y] + b2 * m.positions[t.z];
    const float a = radians(1.0f);
    const Vec3 dir = std::cos(a) * glm::normalize(f.x + 0.3f * f.y) + std::sin(a) * n;
    selfHits += rays.occluded(makeRay(p + eps * n, dir));
  }
  EXPECT_EQ(selfHits, 0);
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

// A sample so far away that its squared distance overflows still gives a valid ray (unit direction
// towards it, finite length): Embree aborts on a zero or NaN direction.
TEST(ShadowRay, AFarSampleKeepsAUnitDirection) {
  const Vec3 p(0.0f), origin(0.0f, 1e-4f, 0.0f), toLight = glm::normalize(Vec3(0.1f, 1.0f, 0.0f));
  const Ray far = rt::shadowRay(p, origin, toLight, 3e38f, 1e-4f);
  EXPECT_NEAR(glm::length(far.direction), 1.0f, 1e-6f);
  EXPECT_GT(glm::dot(far.direction, toLight), 0.999f);
  EXPECT_TRUE(std::isfinite(far.tMax));
  const Ray near = rt::shadowRay(p, origin, toLight, 5.0f, 1e-4f);
  EXPECT_NEAR(glm::length(near.direction), 1.0f, 1e-6f);
  EXPECT_NEAR(near.tMax, glm::length(p + 5.0f * toLight - origin) - 1e-4f, 1e-5f);
}

}  // namespace
}  // namespace penumbra
