// Tests of the silhouette family's shared stages (src/techniques/silhouette/stages.cpp), LightSectors:
// the light polygon's area by direction, which penumbra wedges (wedges.cpp) read their fan areas
// from. Against the definition, the light's area inside the triangle (0, a, b) clipped with
// clipHalfPlane, on random segments around lights of several shapes (a square, a thin rect, a
// triangle, an off-centre heptagon): a segment outside the light gives sweep(b) - sweep(a) plus the
// area at each crossing of the +x axis, one inside gives its own triangle; and a closed ring around
// the light, every edge outside it, sums to the light's area times its winding (the chain rule over
// a whole ring); closed rings of random points projected from random receivers give, through the
// sectors, what clipping every edge gives (penumbra wedges' sum). Lights include hexagons with a
// vertex on the +x axis or within rounding of it. A polygon that does not hold the origin strictly
// inside is refused.
//
// EdgeChunk: a chunk of a ring's edges a receiver lies beyond projects past one side of the light,
// and the edge that stands for it gives the ring's fan area and winding.
//
// OccluderCache: kept for a copy of the scene under a moved light, made again when an object's mesh
// moves; ssv and wedges carried across such a change give the V of a fresh instance.
#include "techniques/silhouette/stages.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <utility>
#include <vector>

#include "penumbra/primitives.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

using silhouette::clipHalfPlane;
using silhouette::crossingOfPositiveX;
using silhouette::LightSectors;

// The light's area inside the triangle (0, a, b), signed by the triangle's orientation: the polygon
// clipped to the triangle's three half-planes.
double fanAreaByClipping(const std::vector<Vec2>& light, const Vec2& a0, const Vec2& b0) {
  const float cross = a0.x * b0.y - a0.y * b0.x;
  if (cross == 0.0f) return 0.0;
  const Vec2 a = cross > 0.0f ? a0 : b0, b = cross > 0.0f ? b0 : a0;
  std::array<Vec2, 64> bufA{}, bufB{};
  std::copy(light.begin(), light.end(), bufA.begin());
  int n = static_cast<int>(light.size());
  const Vec2 corners[3] = {Vec2(0.0f), a, b};
  Vec2* in = bufA.data();
  Vec2* out = bufB.data();
  for (int e = 0; e < 3 && n > 0; ++e) {
    const Vec2 s = corners[e], t = corners[(e + 1) % 3];
    const Vec2 outward(t.y - s.y, s.x - t.x);
    n = clipHalfPlane(in, n, out, outward, glm::dot(outward, s));
    std::swap(in, out);
  }
  double twice = 0.0;
  for (int i = 0; i < n; ++i) twice += double(in[i].x) * in[(i + 1) % n].y - double(in[i].y) * in[(i + 1) % n].x;
  return (cross > 0.0f ? 0.5 : -0.5) * twice;
}

std::vector<std::vector<Vec2>> lights() {
  std::vector<Vec2> heptagon;
  for (int k = 0; k < 7; ++k) {
    const float angle = 2.0f * kPi * static_cast<float>(k) / 7.0f + 0.3f;
    heptagon.push_back(Vec2(0.35f, -0.2f) + Vec2(std::cos(angle), std::sin(angle)));  // the origin off its centre
  }
  std::vector<std::vector<Vec2>> all{{{-1, -1}, {1, -1}, {1, 1}, {-1, 1}},
                                     {{-2.0f, -0.05f}, {2.0f, -0.05f}, {2.0f, 0.05f}, {-2.0f, 0.05f}},
                                     {{-1.0f, -0.6f}, {1.2f, -0.4f}, {0.1f, 1.3f}},
                                     heptagon};
  // Regular hexagons with a vertex on the +x axis or within rounding of it (a hexagon light's x runs
  // along its first edge, which puts a vertex there), where the axis splits an edge into a part of
  // about an ulp.
  for (const float turn : {0.0f, 1e-7f, -1e-7f, 3e-8f, 0.02f}) {
    std::vector<Vec2> hexagon;
    for (int k = 0; k < 6; ++k) {
      const float angle = kPi / 3.0f * static_cast<float>(k) + turn;
      hexagon.push_back(0.7f * Vec2(std::cos(angle), std::sin(angle)));
    }
    all.push_back(hexagon);
  }
  return all;
}

double polygonArea(const std::vector<Vec2>& p) {
  double twice = 0.0;
  for (size_t i = 0; i < p.size(); ++i)
    twice += double(p[i].x) * p[(i + 1) % p.size()].y - double(p[i].y) * p[(i + 1) % p.size()].x;
  return 0.5 * twice;
}

TEST(LightSectors, FanAreasOfSegmentsOutsideAndInsideTheLightMatchClipping) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coordinate(-3.0f, 3.0f);
  for (const std::vector<Vec2>& light : lights()) {
    LightSectors sectors;
    ASSERT_TRUE(sectors.build(light));
    const double area = polygonArea(light);
    EXPECT_NEAR(sectors.area(), area, 1e-5 * area);
    int outside = 0, inside = 0;
    std::uniform_real_distribution<float> weight(0.0f, 1.0f);
    // A random point of the light (a convex combination of its vertices).
    auto inLight = [&]() {
      Vec2 sum(0.0f);
      float total = 0.0f;
      for (const Vec2& v : light) {
        const float w = weight(rng);
        sum += w * v;
        total += w;
      }
      return sum / total;
    };
    for (int i = 0; i < 20000; ++i) {
      // Every fourth segment inside the light, the others anywhere around it.
      const bool within = i % 4 == 0;
      const Vec2 a = within ? inLight() : Vec2(coordinate(rng), coordinate(rng));
      const Vec2 b = within ? inLight() : Vec2(coordinate(rng), coordinate(rng));
      const uint32_t ca = sectors.outcode(a), cb = sectors.outcode(b);
      const double expected = fanAreaByClipping(light, a, b);
      if ((ca | cb) == 0) {
        ++inside;
        EXPECT_NEAR(0.5 * (double(a.x) * b.y - double(a.y) * b.x), expected, 1e-5 * area);
      } else if (sectors.outside(a, b, ca, cb)) {
        ++outside;
        float sweepA = 0.0f, sweepB = 0.0f;
        ASSERT_TRUE(sectors.sweep(a, sweepA) && sectors.sweep(b, sweepB));
        const double chain = double(sweepB) - sweepA + area * crossingOfPositiveX(a, b);
        EXPECT_NEAR(chain, expected, 2e-5 * area) << "a " << a.x << "," << a.y << " b " << b.x << "," << b.y;
      }
    }
    // Ends exactly on the +x axis, where the sweep and the crossing rule must agree (the axis is
    // swept whole, as "a.y <= 0 is below" counts it).
    for (const auto& [a, b] : std::vector<std::pair<Vec2, Vec2>>{{{3.0f, 0.0f}, {2.5f, 1.0f}},
                                                                 {{2.5f, -1.0f}, {3.0f, 0.0f}},
                                                                 {{3.0f, 0.0f}, {2.5f, -1.0f}},
                                                                 {{2.5f, 1.0f}, {3.0f, 0.0f}},
                                                                 {{3.0f, -0.5f}, {3.0f, 0.5f}},
                                                                 {{3.0f, 0.5f}, {3.0f, -0.5f}}}) {
      ASSERT_TRUE(sectors.outside(a, b, sectors.outcode(a), sectors.outcode(b)));
      float sweepA = 0.0f, sweepB = 0.0f;
      ASSERT_TRUE(sectors.sweep(a, sweepA) && sectors.sweep(b, sweepB));
      EXPECT_NEAR(double(sweepB) - sweepA + area * crossingOfPositiveX(a, b), fanAreaByClipping(light, a, b),
                  2e-5 * area);
    }
    // Both cases occur often, or the test would say little.
    EXPECT_GT(outside, 2000);
    EXPECT_GT(inside, 4000);
  }
}

TEST(LightSectors, ARingAroundTheLightSumsToItsAreaTimesItsWinding) {
  for (const std::vector<Vec2>& light : lights()) {
    LightSectors sectors;
    ASSERT_TRUE(sectors.build(light));
    for (const int turns : {1, -1, 2}) {
      // A ring of 60 points on a circle of radius 4 around the origin, `turns` times around: every
      // edge lies outside the light, so the whole ring is one chain from its first point back to it.
      const int n = 60;
      std::vector<Vec2> ring;
      for (int k = 0; k < n; ++k) {
        const float angle = 2.0f * kPi * static_cast<float>(turns * k) / static_cast<float>(n) + 0.1f;
        ring.push_back(4.0f * Vec2(std::cos(angle), std::sin(angle)));
      }
      int crossings = 0;
      double byClipping = 0.0;
      for (int k = 0; k < n; ++k) {
        const Vec2 &a = ring[k], &b = ring[(k + 1) % n];
        ASSERT_TRUE(sectors.outside(a, b, sectors.outcode(a), sectors.outcode(b)));
        crossings += crossingOfPositiveX(a, b);
        byClipping += fanAreaByClipping(light, a, b);
      }
      EXPECT_EQ(crossings, turns);
      EXPECT_NEAR(byClipping, sectors.area() * turns, 1e-4 * std::abs(turns) * sectors.area());
    }
  }
}

TEST(LightSectors, RingsFromRandomReceiversGiveWhatClippingEveryEdgeGives) {
  // Closed rings of random points (inside, around and across the light, some far outside), projected
  // from random receivers: the fan areas read off the sectors sum to what clipping each edge gives,
  // and the windings agree.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), depth(0.3f, 1.5f), size(0.05f, 3.0f);
  std::uniform_int_distribution<int> count(3, 40);
  for (const std::vector<Vec2>& light : lights()) {
    LightSectors sectors;
    ASSERT_TRUE(sectors.build(light));
    const double area = polygonArea(light);
    int bySectors = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      const Vec3 p(unit(rng), unit(rng), 2.0f + depth(rng));
      const Vec2 centre(2.0f * unit(rng), 2.0f * unit(rng));
      const float radius = size(rng);
      std::vector<Vec3> ring;
      for (int k = 0, n = count(rng); k < n; ++k)
        ring.emplace_back(centre.x + radius * unit(rng), centre.y + radius * unit(rng), depth(rng));
      float clipped = 0.0f, read = 0.0f;
      int clippedWinding = 0, readWinding = 0;
      silhouette::ringFansByClipping(light, p, ring.data(), ring.size(), clipped, clippedWinding);
      if (!silhouette::ringFansBySectors(sectors, light, p, ring.data(), ring.size(), read, readWinding)) continue;
      ++bySectors;
      EXPECT_EQ(readWinding, clippedWinding);
      EXPECT_NEAR(read, clipped, 1e-4 * area * static_cast<double>(ring.size())) << "trial " << trial;
    }
    EXPECT_GT(bySectors, 2900);
  }
}

// EdgeChunk (ssv and wedges pass over a chunk of a ring's edges that a receiver lies beyond): such a
// chunk, projected from the receiver, lies past one side of the light's bounding rectangle, every
// point of it; and a ring with the chunk replaced by one edge from its first point to its last has
// the same fan area and winding as the whole ring (clipping every edge, for each of the lights).
TEST(EdgeChunk, AChunkBeyondEveryEdgeShadowProjectsPastOneSideOfTheLight) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), depth(0.3f, 1.5f), spread(0.05f, 2.0f);
  for (const std::vector<Vec2>& light : lights()) {
    silhouette::LightPlane plane;
    plane.vertices = light;
    plane.lower = plane.upper = light[0];
    for (const Vec2& v : light) {
      plane.lower = glm::min(plane.lower, v);
      plane.upper = glm::max(plane.upper, v);
    }
    const double area = polygonArea(light);
    int beyond = 0;
    for (int trial = 0; trial < 4000; ++trial) {
      const Vec3 p(2.0f * unit(rng), 2.0f * unit(rng), 2.0f + depth(rng));
      // A ring: a chunk of kChunkEdges edges (its kChunkEdges + 1 points) and a few more points.
      const Vec2 centre(3.0f * unit(rng), 3.0f * unit(rng));
      const float radius = spread(rng);
      std::vector<Vec3> ring;
      for (uint32_t k = 0; k < silhouette::kChunkEdges + 4; ++k)
        ring.emplace_back(centre.x + radius * unit(rng), centre.y + radius * unit(rng), depth(rng));
      silhouette::EdgeChunk chunk;
      for (uint32_t k = 0; k <= silhouette::kChunkEdges; ++k)
        chunk.add(Vec2(ring[k].x, ring[k].y) / ring[k].z, ring[k].z);
      if (!chunk.beyond(plane, Vec2(p.x, p.y) / p.z, p.z)) continue;
      ++beyond;
      bool side[4] = {true, true, true, true};  // every point past x lower, x upper, y lower, y upper
      for (uint32_t k = 0; k <= silhouette::kChunkEdges; ++k) {
        const Vec2 q = silhouette::projectFrom(p, ring[k]);
        side[0] = side[0] && q.x < plane.lower.x;
        side[1] = side[1] && q.x > plane.upper.x;
        side[2] = side[2] && q.y < plane.lower.y;
        side[3] = side[3] && q.y > plane.upper.y;
      }
      EXPECT_TRUE(side[0] || side[1] || side[2] || side[3]) << "trial " << trial;
      std::vector<Vec3> passed{ring[0]};
      passed.insert(passed.end(), ring.begin() + silhouette::kChunkEdges, ring.end());
      float whole = 0.0f, replaced = 0.0f;
      int wholeWinding = 0, replacedWinding = 0;
      silhouette::ringFansByClipping(light, p, ring.data(), ring.size(), whole, wholeWinding);
      silhouette::ringFansByClipping(light, p, passed.data(), passed.size(), replaced, replacedWinding);
      EXPECT_EQ(replacedWinding, wholeWinding) << "trial " << trial;
      EXPECT_NEAR(replaced, whole, 1e-4 * area * static_cast<double>(ring.size())) << "trial " << trial;
    }
    std::printf("[ measured ] %d of 4000 chunks beyond\n", beyond);
    EXPECT_GT(beyond, 400);  // measured: 567 to 2693 of the 4000 per light
  }
}

TEST(LightSectors, RefusesAPolygonThatDoesNotHoldTheOriginInside) {
  LightSectors sectors;
  EXPECT_FALSE(sectors.build({{0.5f, -1.0f}, {2.0f, -1.0f}, {2.0f, 1.0f}, {0.5f, 1.0f}}));  // beside it
  EXPECT_FALSE(sectors.valid());
  EXPECT_FALSE(sectors.build({{0.0f, -1.0f}, {2.0f, -1.0f}, {2.0f, 1.0f}, {0.0f, 1.0f}}));  // on its edge
  EXPECT_TRUE(sectors.build({{-1.0f, -1.0f}, {2.0f, -1.0f}, {2.0f, 1.0f}, {-1.0f, 1.0f}}));
}

TEST(OccluderCache, KeepsTheOccludersWhileTheGeometryStaysAndMakesThemAgainWhenAMeshMoves) {
  Scene scene = loadScene("concave");
  silhouette::OccluderCache cache;
  const std::vector<silhouette::Occluder>& first = cache.get(scene);
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(cache.builds(), 1u);
  const Vec3 corner = first.front().topology.positions.front();

  Scene lightMoved = scene;  // a copy, its light elsewhere: the same occluders, not made again
  lightMoved.lights.at(0) = Light::rect(Vec3(0.3f, 4.0f, 0.0f), Vec3(0.5f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 0.5f));
  cache.get(lightMoved);
  EXPECT_EQ(cache.builds(), 1u);

  Scene meshMoved = scene;
  transformMesh(meshMoved.objects.front().mesh, glm::translate(Mat4(1.0f), Vec3(0.0f, 0.25f, 0.0f)));
  const std::vector<silhouette::Occluder>& moved = cache.get(meshMoved);
  EXPECT_EQ(cache.builds(), 2u);
  const std::vector<silhouette::Occluder> fresh = silhouette::makeOccluders(meshMoved);
  ASSERT_EQ(moved.size(), fresh.size());
  for (size_t i = 0; i < moved.size(); ++i) {
    EXPECT_EQ(moved[i].objectId, fresh[i].objectId);
    EXPECT_EQ(moved[i].topology.positions, fresh[i].topology.positions);
    EXPECT_EQ(moved[i].topology.triangles, fresh[i].topology.triangles);
  }
  EXPECT_NE(moved.front().topology.positions.front(), corner);
}

TEST(OccluderCache, SsvAndWedgesCarriedAcrossAMovedMeshGiveAFreshInstancesV) {
  Scene scene = loadScene("concave");
  Scene moved = scene;
  for (Object& object : moved.objects)
    if (object.name != "ground") transformMesh(object.mesh, glm::translate(Mat4(1.0f), Vec3(0.2f, 0.15f, 0.0f)));
  const GBuffer gbuffer = renderGBuffer(moved, 96, 96);
  for (const char* name : {"ssv", "wedges"}) {
    auto carried = createTechnique(name);
    Image<float> v, fresh;
    carried->prepare(scene, scene.lights.at(0));
    carried->visibility(gbuffer, v);
    carried->prepare(moved, moved.lights.at(0));
    carried->visibility(gbuffer, v);
    auto made = createTechnique(name);
    made->prepare(moved, moved.lights.at(0));
    made->visibility(gbuffer, fresh);
    ASSERT_EQ(v.size(), fresh.size());
    size_t differing = 0;
    for (size_t i = 0; i < v.size(); ++i) differing += v[i] != fresh[i] ? 1 : 0;
    EXPECT_EQ(differing, 0u) << name;
  }
}

}  // namespace
}  // namespace penumbra
