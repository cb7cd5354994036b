// Tests of the vector shadow-ray builder (src/rt/shadow_packet.h): every lane is the ray the scalar
// path builds (rt::shadowRay towards Light::sample) for every light shape, to float rounding, the
// degenerate lanes exactly; the rays of lanes sharing one point (buildShadowRaysFromOnePoint) and the rays
// built with their origins (buildShadowRaysAndOrigins) are the per-lane builder's to the bit; the lanes' origins are
// rt::offsetOrigin's to the bit, and the rays to the light's centre rt::shadowRay's; the polynomial sine and cosine are
// within a few ulp of libm's; packets built in place trace as the same rays traced one at a time.
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "penumbra/light.h"
#include "penumbra/sampling.h"
#include "rt/ray_scene.h"
#include "rt/rt_test_scenes.h"
#include "rt/shadow_packet.h"
#include "rt/shadow_ray.h"

namespace penumbra {
namespace {

float unit(uint32_t i) { return static_cast<float>(hash32(i) >> 8) * 0x1p-24f; }

// Lane i's point P and an origin O made here (rt::offsetOrigins makes it in the techniques).
void setPoint(rt::ShadowLanes& lanes, int i, const Vec3& wsP, const Vec3& wsOrigin) {
  lanes.px[i] = wsP.x;
  lanes.py[i] = wsP.y;
  lanes.pz[i] = wsP.z;
  lanes.ox[i] = wsOrigin.x;
  lanes.oy[i] = wsOrigin.y;
  lanes.oz[i] = wsOrigin.z;
}

// Lane i's point P and geometric normal Ng from hash k: P anywhere around the lights (or `at` where
// given), Ng turned every way, lane 5's across the direction to the light.
void setRandomSurface(rt::ShadowLanes& lanes, int i, uint32_t k, const Light& light, const Vec3* at) {
  const Vec3 p = at ? *at : Vec3(6.0f * unit(k) - 3.0f, 5.0f * unit(k + 1) - 1.0f, 6.0f * unit(k + 2) - 3.0f);
  Vec3 n = glm::normalize(Vec3(unit(k + 3) - 0.5f, unit(k + 4) - 0.5f, unit(k + 5) - 0.5f));
  if (i == 5) n = glm::normalize(glm::cross(light.directionToCenter(p), Vec3(0.3f, 0.1f, 0.9f)));
  lanes.setSurface(i, p, n);
}

std::vector<std::pair<const char*, Light>> everyShape() {
  return {{"sphere", Light::sphere(Vec3(0.3f, 4.0f, -0.2f), 0.7f)},
          {"large near sphere", Light::sphere(Vec3(0.0f, 1.9f, 0.5f), 1.2f)},
          {"small far sphere", Light::sphere(Vec3(-2.0f, 9.0f, 0.5f), 0.05f)},
          {"disk", Light::disk(Vec3(0.0f, 3.5f, 0.5f), glm::normalize(Vec3(0.2f, -1.0f, 0.1f)), 0.9f)},
          {"rect", Light::rect(Vec3(0.5f, 3.0f, 0.0f), Vec3(0.8f, 0.0f, 0.1f), Vec3(-0.05f, 0.0f, 0.4f))},
          {"segment", Light::segment(Vec3(-1.0f, 3.0f, 0.0f), Vec3(1.5f, 3.2f, 0.4f))},
          {"polygon", Light::polygon({Vec3(-1, 3, -1), Vec3(1, 3, -1), Vec3(1, 3, 0), Vec3(0, 3, 0), Vec3(0, 3, 1),
                                      Vec3(-1, 3, 1)})},
          {"directional", Light::directional(glm::normalize(Vec3(0.3f, 1.0f, 0.2f)), radians(8.0f))},
          {"limb-darkened sun",
           Light::directional(glm::normalize(Vec3(-0.2f, 1.0f, 0.4f)), radians(12.0f), LightProfile::LimbDarkened)}};
}

// Lane i of a packet against the scalar path for the same point, origin and u.
void expectLaneMatches(const Light& light, const rt::ShadowLanes& lanes, int i, const RayPacket16& packet,
                       const float* weight, float epsilon) {
  const Vec3 wsP(lanes.px[i], lanes.py[i], lanes.pz[i]), wsO(lanes.ox[i], lanes.oy[i], lanes.oz[i]);
  const LightSample s = light.sample(wsP, Vec2(lanes.ux[i], lanes.uy[i]));
  const Ray ray = rt::shadowRay(wsP, wsO, s.wsDirection, s.distance, epsilon);
  SCOPED_TRACE(::testing::Message() << "lane " << i << " u (" << lanes.ux[i] << ", " << lanes.uy[i] << ")");
  EXPECT_EQ(packet.orgX[i], ray.origin.x);
  EXPECT_EQ(packet.orgY[i], ray.origin.y);
  EXPECT_EQ(packet.orgZ[i], ray.origin.z);
  EXPECT_EQ(packet.tMin[i], 0.0f);
  EXPECT_NEAR(packet.dirX[i], ray.direction.x, 2e-6f);
  EXPECT_NEAR(packet.dirY[i], ray.direction.y, 2e-6f);
  EXPECT_NEAR(packet.dirZ[i], ray.direction.z, 2e-6f);
  if (ray.tMax == kInfinity) {
    EXPECT_EQ(packet.tMax[i], kInfinity);
  } else if (light.shape() == LightShape::Sphere) {
    // Where the ray grazes the sphere (the silhouette disk's rim) the distance to its front surface
    // is ill-conditioned (a square root of nearly 0), so the segment's end is checked instead: on the
    // sphere, epsilon short of its surface.
    const Vec3 end = wsO + (packet.tMax[i] + epsilon) * Vec3(packet.dirX[i], packet.dirY[i], packet.dirZ[i]);
    // There b^2 - h^2 ~ 0 carries a rounding of a few ulp of b^2, and its square root ~ 5e-4 b: the
    // distance moves by up to dt ~ 1e-3 t, and the end, along a ray tangent to the sphere, leaves
    // its surface by dt^2 / 2R.
    const float dt = 1e-3f * ray.tMax;
    EXPECT_NEAR(packet.tMax[i], ray.tMax, dt);
    EXPECT_NEAR(glm::length(end - light.center()), light.radius(), 1e-5f + dt * dt / (2.0f * light.radius()));
  } else {
    EXPECT_NEAR(packet.tMax[i], ray.tMax, 2e-6f * std::max(1.0f, ray.tMax));
  }
  // The limb-darkened weight needs mu = sqrt(1 - |q|^2), whose slope grows without bound at the limb:
  // a rounding of |q|^2 there moves it by about 1e-7 / mu.
  const float mu = 1.0f - (1.0f - s.weight * (1.0f - kLimbDarkeningU / 3.0f)) / kLimbDarkeningU;
  EXPECT_NEAR(weight[i], s.weight, light.profile() == LightProfile::Uniform ? 0.0f : 1e-6f + 1e-7f / mu);
}

TEST(ShadowPacket, LanesAreTheScalarRaysForEveryShape) {
  const float epsilon = 1e-4f;
  for (const auto& [name, light] : everyShape()) {
    SCOPED_TRACE(name);
    for (uint32_t trial = 0; trial < 64; ++trial) {
      rt::ShadowLanes lanes;
      const int count = 1 + static_cast<int>(trial % 16);
      for (int i = 0; i < count; ++i) {
        const uint32_t k = trial * 97 + static_cast<uint32_t>(i) * 7;
        const Vec3 p(4.0f * unit(k) - 2.0f, 0.5f * unit(k + 1), 4.0f * unit(k + 2) - 2.0f);
        const Vec3 n = glm::normalize(Vec3(unit(k + 3) - 0.5f, 1.0f, unit(k + 4) - 0.5f));
        setPoint(lanes, i, p, rt::offsetOrigin(light, p, n, epsilon));
        // The corners and the centre of [0,1)^2 as well as random points: the concentric map's axes
        // and diagonals, where its wedge changes.
        const float corners[5] = {0.0f, 0.5f, 0x1.fffffep-1f, 0.25f, 0.75f};
        lanes.ux[i] = trial < 25 ? corners[trial % 5] : unit(k + 5);
        lanes.uy[i] = trial < 25 ? corners[trial / 5] : unit(k + 6);
      }
      RayPacket16 packet;
      float weight[16];
      rt::buildShadowRays(light, lanes, count, epsilon, packet, weight);
      for (int i = 0; i < count; ++i) expectLaneMatches(light, lanes, i, packet, weight, epsilon);
    }
  }
}

// Lanes [0, count) of two packets and their weights are the same, bit for bit.
void expectSameRays(const RayPacket16& actual, const float* actualWeight, const RayPacket16& expected,
                    const float* expectedWeight, int count) {
  for (int i = 0; i < count; ++i) {
    SCOPED_TRACE(::testing::Message() << "lane " << i);
    EXPECT_EQ(actual.orgX[i], expected.orgX[i]);
    EXPECT_EQ(actual.orgY[i], expected.orgY[i]);
    EXPECT_EQ(actual.orgZ[i], expected.orgZ[i]);
    EXPECT_EQ(actual.tMin[i], expected.tMin[i]);
    EXPECT_EQ(actual.dirX[i], expected.dirX[i]);
    EXPECT_EQ(actual.dirY[i], expected.dirY[i]);
    EXPECT_EQ(actual.dirZ[i], expected.dirZ[i]);
    EXPECT_EQ(actual.tMax[i], expected.tMax[i]);
    EXPECT_EQ(actualWeight[i], expectedWeight[i]);
  }
}

TEST(ShadowPacket, OnePointRaysAreTheLaneRaysToTheBit) {
  // buildShadowRaysFromOnePoint (the light's per-point set-up made once) builds, for lanes that all
  // hold one point, the rays and weights buildShadowRays builds, bit for bit, on every shape; points
  // inside the sphere light among them (the scalar path's lanes).
  const float epsilon = 1e-4f;
  for (const auto& [name, light] : everyShape()) {
    SCOPED_TRACE(name);
    for (uint32_t trial = 0; trial < 32; ++trial) {
      rt::ShadowLanes lanes;
      const int count = 1 + static_cast<int>((trial * 7) % 16);
      const Vec3 inside = light.center() + Vec3(0.0f, 0.01f, 0.0f);
      setRandomSurface(lanes, 0, trial * 977, light, trial == 3 && !light.isDirectional() ? &inside : nullptr);
      for (int i = 1; i < count; ++i)
        lanes.setSurface(i, Vec3(lanes.px[0], lanes.py[0], lanes.pz[0]), Vec3(lanes.nx[0], lanes.ny[0], lanes.nz[0]));
      rt::offsetOrigins(light, epsilon, count, lanes);
      for (int i = 0; i < count; ++i) {
        lanes.ux[i] = unit(trial * 131 + static_cast<uint32_t>(i));
        lanes.uy[i] = unit(trial * 131 + static_cast<uint32_t>(i) + 64);
      }
      RayPacket16 perLane, onePoint;
      float perLaneWeight[16], onePointWeight[16];
      rt::buildShadowRays(light, lanes, count, epsilon, perLane, perLaneWeight);
      rt::buildShadowRaysFromOnePoint(light, lanes, count, epsilon, onePoint, onePointWeight);
      expectSameRays(onePoint, onePointWeight, perLane, perLaneWeight, count);
    }
  }
}

TEST(ShadowPacket, RaysWithTheirOriginsAreTheTwoStepsToTheBit) {
  // buildShadowRaysAndOrigins (one pass for a sphere light) gives the origins, rays and weights of
  // offsetOrigins followed by buildShadowRays, bit for bit, on every shape; the light's centre and a
  // point inside the sphere among the points (the scalar path's lanes).
  const float epsilon = 1e-4f;
  for (const auto& [name, light] : everyShape()) {
    SCOPED_TRACE(name);
    for (uint32_t trial = 0; trial < 32; ++trial) {
      rt::ShadowLanes lanes;
      const int count = 1 + static_cast<int>((trial * 5) % 16);
      const Vec3 centre = light.center(), inside = light.center() + Vec3(0.0f, 0.01f, 0.0f);
      for (int i = 0; i < count; ++i) {
        const bool local = !light.isDirectional();
        setRandomSurface(lanes, i, trial * 313 + static_cast<uint32_t>(i) * 17, light,
                         local && i == 2   ? &centre
                         : local && i == 4 ? &inside
                                           : nullptr);
        lanes.ux[i] = unit(trial * 71 + static_cast<uint32_t>(i));
        lanes.uy[i] = unit(trial * 71 + static_cast<uint32_t>(i) + 32);
      }
      rt::ShadowLanes twoSteps = lanes;
      RayPacket16 expected, fused;
      float expectedWeight[16], fusedWeight[16];
      rt::offsetOrigins(light, epsilon, count, twoSteps);
      rt::buildShadowRays(light, twoSteps, count, epsilon, expected, expectedWeight);
      rt::buildShadowRaysAndOrigins(light, lanes, count, epsilon, fused, fusedWeight);
      expectSameRays(fused, fusedWeight, expected, expectedWeight, count);
    }
  }
}

TEST(ShadowPacket, OffsetOriginsAreTheScalarOriginsToTheBit) {
  const float epsilon = 1e-3f;
  for (const auto& [name, light] : everyShape()) {
    SCOPED_TRACE(name);
    for (uint32_t trial = 0; trial < 16; ++trial) {
      rt::ShadowLanes lanes;
      const int count = 1 + static_cast<int>((trial * 5) % 16);
      for (int i = 0; i < count; ++i) {
        // The light's centre itself among the points (where the direction to it is +z).
        const Vec3 centre = light.center();
        setRandomSurface(lanes, i, trial * 131 + static_cast<uint32_t>(i) * 11, light,
                         i == 3 && !light.isDirectional() ? &centre : nullptr);
      }
      rt::offsetOrigins(light, epsilon, count, lanes);
      for (int i = 0; i < count; ++i) {
        const Vec3 o = rt::offsetOrigin(light, Vec3(lanes.px[i], lanes.py[i], lanes.pz[i]),
                                        Vec3(lanes.nx[i], lanes.ny[i], lanes.nz[i]), epsilon);
        EXPECT_EQ(lanes.ox[i], o.x) << "lane " << i;
        EXPECT_EQ(lanes.oy[i], o.y) << "lane " << i;
        EXPECT_EQ(lanes.oz[i], o.z) << "lane " << i;
      }
    }
  }
}

TEST(ShadowPacket, DegenerateLanesTakeTheScalarPathExactly) {
  const float epsilon = 1e-3f;
  const Light sphere = Light::sphere(Vec3(0.0f, 2.0f, 0.0f), 0.5f);
  const Light rect = Light::rect(Vec3(0.0f, 2.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 1.0f));
  rt::ShadowLanes lanes;
  // Lane 0: inside the sphere light (nothing can occlude: a ray of length 0). Lane 1: on the rect
  // light's sample point itself. Lane 2: an ordinary point below both.
  const Vec3 points[3] = {Vec3(0.1f, 2.1f, 0.0f), Vec3(0.0f, 2.0f, 0.0f), Vec3(0.3f, 0.0f, 0.2f)};
  for (int i = 0; i < 3; ++i) {
    setPoint(lanes, i, points[i], points[i] + Vec3(0.0f, epsilon, 0.0f));
    lanes.ux[i] = 0.5f;
    lanes.uy[i] = 0.5f;
  }
  // The sphere's degenerate lanes are 0 and 1 (the sphere's centre is inside it too), the rect's lane 1.
  const std::pair<const Light*, std::vector<int>> cases[2] = {{&sphere, {0, 1}}, {&rect, {1}}};
  for (const auto& [light, degenerate] : cases) {
    RayPacket16 packet;
    float weight[16];
    rt::buildShadowRays(*light, lanes, 3, epsilon, packet, weight);
    for (const int i : degenerate) {
      const LightSample s = light->sample(points[i], Vec2(0.5f));
      const Ray ray =
          rt::shadowRay(points[i], points[i] + Vec3(0.0f, epsilon, 0.0f), s.wsDirection, s.distance, epsilon);
      EXPECT_EQ(packet.dirX[i], ray.direction.x) << i;
      EXPECT_EQ(packet.dirY[i], ray.direction.y) << i;
      EXPECT_EQ(packet.dirZ[i], ray.direction.z) << i;
      EXPECT_EQ(packet.tMax[i], ray.tMax) << i;
      EXPECT_EQ(packet.tMax[i], 0.0f) << i;  // inside the sphere or on the rect's point: an empty segment
    }
    expectLaneMatches(*light, lanes, 2, packet, weight, epsilon);
  }
}

// raytraced-hard's and parker's rays: rt::shadowRay from rt::offsetOrigin towards the light's centre,
// to the bit, with the facing term whose sign picks the side; the lanes rt::shadowRay treats apart
// (a point at the centre, coordinates whose squared distance overflows, a point not a number) too.
TEST(ShadowPacket, CenterRaysAreTheScalarRaysToTheBit) {
  const float epsilon = 1e-3f;
  for (const auto& [name, light] : everyShape()) {
    SCOPED_TRACE(name);
    for (uint32_t trial = 0; trial < 32; ++trial) {
      rt::ShadowLanes lanes;
      const int count = 1 + static_cast<int>((trial * 7) % 16);
      for (int i = 0; i < count; ++i) {
        // In a quarter of the trials, lanes 2, 4 and 6 at the light's centre, far enough out that the
        // squared distance overflows, and not a number.
        const Vec3 special[3] = {light.center(), Vec3(3e19f, -2e19f, 1.0f), Vec3(std::nanf(""), 0.0f, 0.0f)};
        const bool isSpecial = !light.isDirectional() && trial % 4 == 1 && (i == 2 || i == 4 || i == 6);
        setRandomSurface(lanes, i, trial * 173 + static_cast<uint32_t>(i) * 13, light,
                         isSpecial ? &special[i / 2 - 1] : nullptr);
      }
      RayPacket16 packet;
      float facing[16];
      rt::buildCenterRays(light, lanes, count, epsilon, packet, facing);
      for (int i = 0; i < count; ++i) {
        SCOPED_TRACE(::testing::Message() << "trial " << trial << " lane " << i);
        const Vec3 p(lanes.px[i], lanes.py[i], lanes.pz[i]), n(lanes.nx[i], lanes.ny[i], lanes.nz[i]);
        const Vec3 toLight = light.directionToCenter(p);
        const float f = glm::dot(n, toLight);
        const Ray ray = rt::shadowRay(p, rt::offsetOrigin(p, n, f >= 0.0f ? 1.0f : -1.0f, epsilon), toLight,
                                      light.distanceToCenter(p), epsilon);
        // Bit for bit (memcmp-like: NaN lanes compare equal when their bits are the same).
        const float got[9] = {packet.orgX[i], packet.orgY[i], packet.orgZ[i], packet.dirX[i], packet.dirY[i],
                              packet.dirZ[i], packet.tMin[i], packet.tMax[i], facing[i]};
        const float want[9] = {ray.origin.x,    ray.origin.y,    ray.origin.z,
                               ray.direction.x, ray.direction.y, ray.direction.z,
                               ray.tMin,        ray.tMax,        f};
        for (int c = 0; c < 9; ++c)
          EXPECT_EQ(std::bit_cast<uint32_t>(got[c]), std::bit_cast<uint32_t>(want[c])) << "component " << c;
      }
    }
  }
}

TEST(ShadowPacket, PolynomialSineAndCosineWithinAFewUlp) {
  float worst = 0.0f;
  for (int k = -100000; k <= 100000; ++k) {
    const float a = (kPi / 4.0f) * static_cast<float>(k) / 100000.0f;
    float s, c;
    rt::sinCosQuarterPi(a, s, c);
    worst = std::max({worst, std::abs(s - static_cast<float>(std::sin(static_cast<double>(a)))),
                      std::abs(c - static_cast<float>(std::cos(static_cast<double>(a))))});
  }
  EXPECT_LT(worst, 3e-7f);  // a few ulp of values up to 1
}

TEST(ShadowPacket, PacketsBuiltInPlaceTraceAsSingleRays) {
  // A quad occluder halfway to a rect light: some lanes blocked, some not; occluded16 and
  // intersect16 on the packets agree with occluded() and intersect() on the same rays.
  Scene scene = testing::makeScene(
      {testing::makeObject(4, testing::quadMesh(Vec3(0.3f, 1.5f, 0.0f), Vec3(0.6f, 0, 0), Vec3(0, 0, 0.6f)), "quad")});
  const RayScene rays(scene);
  const Light light = Light::rect(Vec3(0.0f, 3.0f, 0.0f), Vec3(1.0f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 1.0f));
  const float epsilon = 1e-4f;
  int blocked = 0, total = 0;
  for (uint32_t trial = 0; trial < 40; ++trial) {
    rt::ShadowLanes lanes;
    const int count = 1 + static_cast<int>(trial % 16);
    for (int i = 0; i < count; ++i) {
      const uint32_t k = trial * 131 + static_cast<uint32_t>(i) * 5;
      const Vec3 p(3.0f * unit(k) - 1.5f, 0.0f, 3.0f * unit(k + 1) - 1.5f);
      setPoint(lanes, i, p, p + Vec3(0.0f, epsilon, 0.0f));
      lanes.ux[i] = unit(k + 2);
      lanes.uy[i] = unit(k + 3);
    }
    RayHitPacket16 packet;
    float weight[16];
    rt::buildShadowRays(light, lanes, count, epsilon, packet.ray, weight);
    const RayPacket16 built = packet.ray;
    RayPacket16 occlusion = packet.ray;
    rays.occluded16(occlusion, count);
    rays.intersect16(packet, count);
    for (int i = 0; i < count; ++i) {
      Ray ray;
      ray.origin = Vec3(built.orgX[i], built.orgY[i], built.orgZ[i]);
      ray.direction = Vec3(built.dirX[i], built.dirY[i], built.dirZ[i]);
      ray.tMin = built.tMin[i];
      ray.tMax = built.tMax[i];
      const bool single = rays.occluded(ray);
      EXPECT_EQ(occlusion.blocked(i), single) << "trial " << trial << " lane " << i;
      const auto hit = rays.intersect(ray);
      ASSERT_EQ(packet.hit.geomId[i] != HitPacket16::kNoHit, hit.has_value()) << "trial " << trial << " lane " << i;
      if (hit) {
        EXPECT_NEAR(packet.ray.tMax[i], hit->t, 1e-5f);
      }
      blocked += single;
      ++total;
    }
  }
  EXPECT_GT(blocked, total / 10);  // both answers occur
  EXPECT_LT(blocked, total - total / 10);
}

}  // namespace
}  // namespace penumbra
