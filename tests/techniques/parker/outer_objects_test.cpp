// Tests of the outer objects and their hierarchy (src/techniques/parker/outer_objects.cpp): Parker, Shirley and
// Smits 1998, "Single Sample Soft Shadows", Section 3 and the Appendix. Against an oracle written
// here in double precision that reads no hierarchy: every analytic sphere and every open
// triangle's edges (all of them are boundary edges, so the outline needs no silhouette test) are
// evaluated for every ray, and combined by min, product or sum. A bound that left out a capsule a
// ray can reach would show as an error of the order of the penumbra's depth. The rays walk the
// hierarchy in groups whose bounds are shared: neighbouring rays, one ray at a time, and groups of
// rays scattered over the ground must all give the same bits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "penumbra/error.h"
#include "penumbra/primitives.h"
#include "penumbra/sampling.h"
#include "rt/rt_test_scenes.h"
#include "techniques/parker/outer_objects.h"

namespace penumbra {
namespace {

using testing::makeObject;

// A deterministic uniform number in [lo, hi) from a counter.
float uniform(uint64_t index, float lo, float hi) {
  return lo + (hi - lo) * static_cast<float>(hash32(index) >> 8) * (1.0f / 16777216.0f);
}

struct Capsule {
  glm::dvec3 p0, e;
  double radius;
  int object;
};

// Spheres (analytic, over their tessellation), open triangles, and the ground's outline, each its
// own object; the capsules the oracle evaluates.
struct OracleScene {
  Scene scene;
  std::vector<Capsule> capsules;
  int objects = 0;
};

OracleScene makeOracleScene() {
  OracleScene o;
  o.scene.name = "outer objects test";
  o.scene.source = "outer objects test scene";
  const float half = 4.0f;
  o.scene.objects.push_back(makeObject(0, makePlane(2.0f * half, 2.0f * half), "ground"));
  const glm::dvec3 corners[4] = {{-half, 0, -half}, {half, 0, -half}, {half, 0, half}, {-half, 0, half}};
  for (int k = 0; k < 4; ++k) o.capsules.push_back({corners[k], corners[(k + 1) % 4] - corners[k], 0.0, 0});
  int id = 1;
  for (int i = 0; i < 10; ++i, ++id) {
    const Vec3 c(uniform(100 + i, -2.0f, 2.0f), uniform(200 + i, 0.6f, 2.5f), uniform(300 + i, -2.0f, 2.0f));
    const float r = uniform(400 + i, 0.05f, 0.4f);
    Mesh mesh = makeSphere(r, 24, 12);
    transformMesh(mesh, glm::translate(Mat4(1.0f), c));
    Object object = makeObject(id, std::move(mesh), "sphere");
    object.sphere = AnalyticSphere{c, r};
    o.scene.objects.push_back(std::move(object));
    o.capsules.push_back({glm::dvec3(c), glm::dvec3(0.0), r, id});
  }
  for (int i = 0; i < 14; ++i, ++id) {
    const Vec3 c(uniform(500 + i, -2.0f, 2.0f), uniform(600 + i, 0.5f, 2.5f), uniform(700 + i, -2.0f, 2.0f));
    Vec3 p[3];
    for (int k = 0; k < 3; ++k)
      p[k] = c + Vec3(uniform(800 + 3 * i + k, -0.5f, 0.5f), uniform(900 + 3 * i + k, -0.3f, 0.3f),
                      uniform(1000 + 3 * i + k, -0.5f, 0.5f));
    o.scene.objects.push_back(makeObject(id, makeTriangle(p[0], p[1], p[2]), "triangle"));
    for (int k = 0; k < 3; ++k) o.capsules.push_back({glm::dvec3(p[k]), glm::dvec3(p[(k + 1) % 3] - p[k]), 0.0, id});
  }
  o.objects = id;
  return o;
}

// The Appendix for one capsule: the point of the segment nearest the ray's line (the minimum of a
// convex quadratic in the segment parameter), t0 and d there, b = bScale t0. +inf where the
// capsule does not shadow (t0 <= 0 or t0 >= A).
double oracleTau(const Capsule& c, const glm::dvec3& o, const glm::dvec3& v, double toLight, double bScale) {
  const glm::dvec3 w = c.p0 - o;
  const glm::dvec3 wp = w - glm::dot(w, v) * v, ep = c.e - glm::dot(c.e, v) * v;
  const double ee = glm::dot(ep, ep);
  const double u = ee > 0.0 ? std::clamp(-glm::dot(wp, ep) / ee, 0.0, 1.0) : 0.0;
  const glm::dvec3 q = c.p0 + u * c.e;
  const double t0 = glm::dot(q - o, v);
  if (t0 <= 0.0 || t0 >= toLight) return INFINITY;
  return (glm::length(o + t0 * v - q) - c.radius) / (bScale * t0);
}

double oracleFalloff(double tau) {
  const double t = std::clamp(tau, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// s for one ray: per object the smallest tau over its capsules, then Section 3's combination.
double oracleS(const OracleScene& o, const glm::dvec3& origin, const glm::dvec3& v, double toLight, double bScale,
               rt::OuterCombine combine) {
  std::vector<double> objectTau(static_cast<size_t>(o.objects), INFINITY);
  for (const Capsule& c : o.capsules)
    objectTau[static_cast<size_t>(c.object)] =
        std::min(objectTau[static_cast<size_t>(c.object)], oracleTau(c, origin, v, toLight, bScale));
  double s = 1.0;
  for (double tau : objectTau) {
    const double si = tau <= 0.0 ? 0.0 : oracleFalloff(tau);
    s = combine == rt::OuterCombine::Min       ? std::min(s, si)
        : combine == rt::OuterCombine::Product ? s * si
                                               : s - (1.0 - si);
  }
  return std::max(0.0, s);
}

struct TestRays {
  std::vector<Ray> rays;
  std::vector<float> toLight;
};

// Rays from ground points (just above y = 0) to the light's centre, as parker traces them.
TestRays groundRays(const Light& light, int count) {
  TestRays t;
  for (int i = 0; i < count; ++i) {
    const Vec3 p(uniform(2000 + i, -3.5f, 3.5f), 1e-3f, uniform(3000 + i, -3.5f, 3.5f));
    Ray r;
    r.origin = p;
    r.direction = light.directionToCenter(p);
    t.rays.push_back(r);
    t.toLight.push_back(light.distanceToCenter(p));
  }
  return t;
}

std::vector<float> attenuations(const rt::OuterObjects& outer, const TestRays& t, rt::OuterCombine combine,
                                rt::OuterObjects::Seeds* seeds = nullptr) {
  std::vector<float> s(t.rays.size());
  for (size_t i = 0; i < t.rays.size(); i += 16) {
    const int count = static_cast<int>(std::min<size_t>(16, t.rays.size() - i));
    outer.attenuations(t.rays.data() + i, t.toLight.data() + i, count, rt::OuterFalloff::Bernstein, combine,
                       s.data() + i, seeds);
  }
  return s;
}

const char* name(rt::OuterCombine c) {
  return c == rt::OuterCombine::Min ? "min" : c == rt::OuterCombine::Product ? "product" : "sum";
}

void expectOracle(const Light& light, float diameter, double bScaleTimesDistance, int minPenumbra, int minUmbra) {
  const OracleScene o = makeOracleScene();
  const TestRays t = groundRays(light, 3000);
  for (const rt::OuterCombine combine : {rt::OuterCombine::Min, rt::OuterCombine::Product, rt::OuterCombine::Sum}) {
    SCOPED_TRACE(name(combine));
    std::vector<double> expected(t.rays.size());
    int penumbra = 0, umbra = 0;
    for (size_t i = 0; i < t.rays.size(); ++i) {
      const double toLight = light.isDirectional() ? INFINITY : static_cast<double>(t.toLight[i]);
      const double bScale = light.isDirectional() ? bScaleTimesDistance : bScaleTimesDistance / toLight;
      expected[i] = oracleS(o, glm::dvec3(t.rays[i].origin), glm::dvec3(t.rays[i].direction), toLight, bScale, combine);
      penumbra += expected[i] > 0.0 && expected[i] < 1.0;
      umbra += expected[i] == 0.0;
    }
    rt::OuterObjectOptions options;
    options.lightDiameter = diameter;
    const rt::OuterObjects outer(o.scene, light, options);
    // Groups of 16 neighbours along the ray list's order (the rays are scattered: the groups are
    // wide, their bounds loose).
    const std::vector<float> s = attenuations(outer, t, combine);
    double worst = 0.0;
    for (size_t i = 0; i < s.size(); ++i) worst = std::max(worst, std::abs(static_cast<double>(s[i]) - expected[i]));
    // float against double: measured at most 4.0e-7 (min), 4.4e-7 (product), 5.9e-7 (sum) for
    // the local light, 5.9e-7 for the directional one. A capsule missing from the walk errs by
    // the depth of its penumbra there, up to 1.
    EXPECT_LT(worst, 1e-5);
    // The narrower builds of the walk (8 and 4 lanes; the widest the CPU has ran above), the same bits.
    for (const int lanes : {8, 4}) {
      rt::OuterObjects narrow(o.scene, light, options);
      narrow.limitLanes(lanes);
      const std::vector<float> narrowS = attenuations(narrow, t, combine);
      for (size_t i = 0; i < s.size(); ++i) ASSERT_EQ(narrowS[i], s[i]) << lanes << " lanes, ray " << i;
    }
    // One ray at a time, the same bits.
    for (size_t i = 0; i < s.size(); i += 7)
      EXPECT_EQ(
          outer.attenuation(t.rays[i].origin, t.rays[i].direction, t.toLight[i], rt::OuterFalloff::Bernstein, combine),
          s[i]);
    // Coherent groups: the rays sorted along x then z, so that each group of 16 covers a small
    // patch of the ground, as parker's 4 x 4 pixel tiles do; the same bits.
    std::vector<size_t> order(t.rays.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
      const Vec3 &p = t.rays[a].origin, &q = t.rays[b].origin;
      const int ca = static_cast<int>(std::floor(p.x * 4.0f)), cb = static_cast<int>(std::floor(q.x * 4.0f));
      return ca != cb ? ca < cb : p.z < q.z;
    });
    TestRays sorted;
    for (const size_t i : order) {
      sorted.rays.push_back(t.rays[i]);
      sorted.toLight.push_back(t.toLight[i]);
    }
    const std::vector<float> sortedS = attenuations(outer, sorted, combine);
    for (size_t k = 0; k < order.size(); ++k) EXPECT_EQ(sortedS[k], s[order[k]]);
    // Each group first reading the capsules of the group before's minima (parker's tiles along a
    // row), the coherent groups and then the scattered ones with the seeds the first left: the
    // same bits (the seeds serve the min combination). Seeds naming an entry these outer objects do
    // not have (left by others built at the same address) are dropped.
    rt::OuterObjects::Seeds seeds;
    const std::vector<float> seededSorted = attenuations(outer, sorted, combine, &seeds);
    for (size_t k = 0; k < order.size(); ++k) EXPECT_EQ(seededSorted[k], sortedS[k]);
    if (combine == rt::OuterCombine::Min) {
      EXPECT_EQ(seeds.owner, &outer);
    }
    const std::vector<float> seededScattered = attenuations(outer, t, combine, &seeds);
    for (size_t i = 0; i < s.size(); ++i) EXPECT_EQ(seededScattered[i], s[i]);
    rt::OuterObjects::Seeds stale{&outer, 1, {}};
    stale.entry[0] = 1 << 30;
    float first = -1.0f;
    outer.attenuations(t.rays.data(), t.toLight.data(), 1, rt::OuterFalloff::Bernstein, combine, &first, &stale);
    EXPECT_EQ(first, s[0]);
    // The rays cross many penumbrae and umbrae (measured in the callers' comments).
    EXPECT_GT(penumbra, minPenumbra);
    EXPECT_GT(umbra, minUmbra);
  }
}

TEST(OuterObjects, LocalLightMatchesTheAppendixOracleInEveryGrouping) {
  // Measured of 3,000 rays: 1,584 (min, product) and 1,283 (sum) in a penumbra, 230 and 531 at 0.
  const Light light = Light::sphere(Vec3(0.5f, 7.0f, -0.3f), 0.8f);
  expectOracle(light, 1.6f, 1.6, 1000, 150);
}

TEST(OuterObjects, DirectionalLightMatchesTheAppendixOracleInEveryGrouping) {
  // Measured of 3,000 rays: 709 (min, product) and 620 (sum) in a penumbra, 126 and 215 at 0.
  const Light light = Light::directional(Vec3(0.2f, 1.0f, 0.1f), radians(10.0f));
  const float diameter = 2.0f * std::tan(radians(5.0f));
  expectOracle(light, diameter, static_cast<double>(diameter), 450, 80);
}

// The silhouette of meshes whose faces do not share vertex indices (split normals, separate
// parts touching): edges are matched by position. Against a brute-force silhouette (every pair of
// triangles compared by their vertices' positions): a box with split vertices (24), the same box
// sharing 8, a tessellated sphere, and two boxes sharing a face's edge (non-manifold edges, kept).
std::vector<Capsule> bruteForceSilhouette(const Mesh& mesh, const Vec3& lightCenter, int object) {
  struct Face {
    Vec3 p[3];
    bool front;
  };
  std::vector<Face> faces;
  for (const glm::uvec3& t : mesh.triangles) {
    Face f{{mesh.positions[t.x], mesh.positions[t.y], mesh.positions[t.z]}, false};
    f.front = glm::dot(glm::cross(f.p[1] - f.p[0], f.p[2] - f.p[0]), lightCenter - f.p[0]) > 0.0f;
    faces.push_back(f);
  }
  std::vector<Capsule> edges;
  std::vector<std::pair<Vec3, Vec3>> seen;
  for (size_t i = 0; i < faces.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const Vec3 a = faces[i].p[k], b = faces[i].p[(k + 1) % 3];
      bool done = false;
      for (const auto& [x, y] : seen) done |= (x == a && y == b) || (x == b && y == a);
      if (done) continue;
      seen.emplace_back(a, b);
      int count = 0, fronts = 0;
      for (const Face& f : faces)
        for (int m = 0; m < 3; ++m) {
          const Vec3 c = f.p[m], d = f.p[(m + 1) % 3];
          if ((c == a && d == b) || (c == b && d == a)) {
            ++count;
            fronts += f.front;
          }
        }
      if (count != 2 || fronts == 1) edges.push_back({glm::dvec3(a), glm::dvec3(b - a), 0.0, object});
    }
  return edges;
}

TEST(OuterObjects, SilhouettesAreMatchedByPosition) {
  const Light light = Light::sphere(Vec3(0.7f, 6.0f, 0.4f), 0.8f);
  Mesh shared;  // the box with 8 shared vertices
  {
    const Mesh split = makeBox(Vec3(1.0f, 0.4f, 0.6f));
    for (const glm::uvec3& t : split.triangles) {
      glm::uvec3 w;
      for (int k = 0; k < 3; ++k) {
        const Vec3 p = split.positions[t[k]];
        uint32_t index = 0;
        while (index < shared.positions.size() && shared.positions[index] != p) ++index;
        if (index == shared.positions.size()) shared.positions.push_back(p);
        w[k] = index;
      }
      shared.triangles.push_back(w);
    }
    ASSERT_EQ(shared.positions.size(), 8u);
  }
  Mesh pair = makeBox(Vec3(0.5f));  // two boxes side by side: the shared face's edges have 4 faces
  {
    Mesh second = makeBox(Vec3(0.5f));
    transformMesh(second, glm::translate(Mat4(1.0f), Vec3(0.5f, 0.0f, 0.0f)));
    const uint32_t base = static_cast<uint32_t>(pair.positions.size());
    pair.positions.insert(pair.positions.end(), second.positions.begin(), second.positions.end());
    for (const glm::uvec3& t : second.triangles) pair.triangles.push_back(t + glm::uvec3(base));
  }
  const std::pair<const char*, Mesh> meshes[] = {{"split box", makeBox(Vec3(1.0f, 0.4f, 0.6f))},
                                                 {"shared box", shared},
                                                 {"sphere", makeSphere(0.6f, 24, 12)},
                                                 {"touching boxes", pair}};
  const TestRays t = groundRays(light, 1500);
  for (const auto& [label, base] : meshes) {
    SCOPED_TRACE(label);
    Mesh mesh = base;
    transformMesh(mesh, glm::translate(Mat4(1.0f), Vec3(0.2f, 1.5f, -0.1f)));
    OracleScene o;
    o.scene.name = label;
    o.scene.source = "outer objects test scene";
    o.scene.objects.push_back(makeObject(0, mesh, label));
    o.capsules = bruteForceSilhouette(mesh, light.center(), 0);
    o.objects = 1;
    rt::OuterObjectOptions options;
    options.lightDiameter = 1.6f;
    const rt::OuterObjects outer(o.scene, light, options);
    EXPECT_EQ(outer.silhouetteEdgeCount(), o.capsules.size());
    const std::vector<float> s = attenuations(outer, t, rt::OuterCombine::Min);
    int penumbra = 0;
    double worst = 0.0;
    for (size_t i = 0; i < s.size(); ++i) {
      const double expected = oracleS(o, glm::dvec3(t.rays[i].origin), glm::dvec3(t.rays[i].direction), t.toLight[i],
                                      1.6 / static_cast<double>(t.toLight[i]), rt::OuterCombine::Min);
      worst = std::max(worst, std::abs(static_cast<double>(s[i]) - expected));
      penumbra += expected > 0.0 && expected < 1.0;
    }
    EXPECT_LT(worst, 1e-5);
    EXPECT_GT(penumbra, 50);  // the rays cross the penumbra
  }
}

// 600 triangles spaced ever farther apart (each 3% farther than the last), the kind of spread a
// surface-area split could peel off a few at a time: the hierarchy stays shallow (below 24 levels
// the builder halves runs at their median in any case) and matches the oracle.
TEST(OuterObjects, AnySpacingKeepsTheHierarchyShallow) {
  OracleScene o;
  o.scene.name = "spaced";
  o.scene.source = "outer objects test scene";
  Mesh strip;
  float x = 0.01f;
  for (int i = 0; i < 600; ++i, x *= 1.03f) {
    const uint32_t base = static_cast<uint32_t>(strip.positions.size());
    const Vec3 a(x - 3.0f, 1.0f, 0.0f), b(x - 3.0f, 1.2f, 0.05f), c(x - 2.99f, 1.1f, 0.1f);
    strip.positions.insert(strip.positions.end(), {a, b, c});
    strip.triangles.push_back(glm::uvec3(base, base + 1, base + 2));
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = strip.positions[base + k], q = strip.positions[base + (k + 1) % 3];
      o.capsules.push_back({glm::dvec3(p), glm::dvec3(q - p), 0.0, 0});
    }
  }
  o.scene.objects.push_back(makeObject(0, strip, "strip"));
  o.objects = 1;
  const Light light = Light::sphere(Vec3(0.0f, 6.0f, 0.0f), 0.8f);
  rt::OuterObjectOptions options;
  options.lightDiameter = 1.6f;
  const rt::OuterObjects outer(o.scene, light, options);
  EXPECT_LT(outer.treeDepth(), 16);  // measured 9
  const TestRays t = groundRays(light, 500);
  const std::vector<float> s = attenuations(outer, t, rt::OuterCombine::Min);
  double worst = 0.0;
  for (size_t i = 0; i < s.size(); ++i)
    worst =
        std::max(worst, std::abs(static_cast<double>(s[i]) -
                                 oracleS(o, glm::dvec3(t.rays[i].origin), glm::dvec3(t.rays[i].direction), t.toLight[i],
                                         1.6 / static_cast<double>(t.toLight[i]), rt::OuterCombine::Min)));
  EXPECT_LT(worst, 1e-5);
}

// The edge cache keeps each mesh's matched edges while its geometry is the same: under another
// light only the silhouette is chosen again, with the same result as without a cache; a mesh that
// changed is matched again.
TEST(OuterObjects, EdgeCacheMatchesAMeshOnlyWhenItChanged) {
  OracleScene o = makeOracleScene();
  const Light first = Light::sphere(Vec3(0.5f, 7.0f, -0.3f), 0.8f),
              second = Light::sphere(Vec3(-1.0f, 5.0f, 1.0f), 0.6f);
  rt::OuterObjectOptions options;
  options.lightDiameter = 1.6f;
  options.analyticSpheres = false;  // every object a mesh
  rt::OuterObjects::EdgeCache cache;
  const size_t meshes = o.scene.objects.size();
  for (const Light& light : {first, second}) {
    const rt::OuterObjects cached(o.scene, light, options, &cache);
    const rt::OuterObjects fresh(o.scene, light, options);
    EXPECT_EQ(cached.silhouetteEdgeCount(), fresh.silhouetteEdgeCount());
    const TestRays t = groundRays(light, 500);
    EXPECT_EQ(attenuations(cached, t, rt::OuterCombine::Min), attenuations(fresh, t, rt::OuterCombine::Min));
  }
  EXPECT_EQ(cache.matchCount(), meshes);  // each mesh matched once for both lights
  transformMesh(o.scene.objects[3].mesh, glm::translate(Mat4(1.0f), Vec3(0.1f, 0.0f, 0.0f)));
  const rt::OuterObjects moved(o.scene, first, options, &cache);
  EXPECT_EQ(cache.matchCount(), meshes + 1);
}

// A ray whose smallest tau is 1 or more is lit (s = 1): the walk starts from tau = 1 and skips
// everything at or beyond it, which is exact because both falloffs are exactly 1 there.
TEST(OuterObjects, FalloffsAreExactlyOneAtTheOuterBoundary) {
  for (const rt::OuterFalloff f : {rt::OuterFalloff::Bernstein, rt::OuterFalloff::Sinusoid}) {
    EXPECT_EQ(rt::outerFalloff(1.0f, f), 1.0f);
    EXPECT_EQ(rt::outerFalloff(std::numeric_limits<float>::max(), f), 1.0f);
    EXPECT_EQ(rt::outerFalloff(0.0f, f), 0.0f);
  }
}

TEST(OuterObjects, RejectsABadDiameter) {
  const OracleScene o = makeOracleScene();
  const Light light = Light::sphere(Vec3(0.0f, 7.0f, 0.0f), 0.5f);
  for (const float diameter : {0.0f, -1.0f, NAN, INFINITY}) {
    rt::OuterObjectOptions options;
    options.lightDiameter = diameter;
    try {
      rt::OuterObjects outer(o.scene, light, options);
      FAIL() << "diameter " << diameter << " must be rejected";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("light diameter"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace penumbra
