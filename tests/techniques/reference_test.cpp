// Tests of the `reference` technique (src/techniques/reference.cpp) against closed-form visibility:
// parallel rect / disk / polygon / segment lights over parallel occluders (the occluder's central
// projection from p onto the light's plane gives V = 1 - overlap / light measure), an L-shaped
// (concave) polygon light over half-plane occluders (the same, by area), a sphere light on
// its axis (its silhouette disk), and a directional solar disk behind a straight edge (a circular
// segment; with limb darkening, the segment integral of the linear law in closed form).
// Every estimate must lie within 3 of its own standard errors of the exact value and within 1/255.
// Measured at 4096 spp: largest error 0.54/255, largest error / standard error 0.8 (the standard
// error is conservative for stratified samples). Part of the error is the shadow-ray origin offset
// (shadowRayEpsilon: 0.005 in the edge scenes, whose occluder is 1 unit up), which shifts the
// penumbra by eps / h and V by up to ~0.4/255 there.
#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <map>

#include "penumbra/error.h"
#include "penumbra/reference.h"
#include "penumbra/registry.h"
#include "rt/ray_scene.h"
#include "rt/rt_test_scenes.h"

namespace penumbra {
namespace {

using testing::makeObject;
using testing::makeScene;
using testing::pointsGBuffer;
using testing::quadMesh;
using testing::regularPolygonMesh;

constexpr double kPiD = 3.14159265358979323846;
constexpr uint32_t kSpp = 4096;
constexpr int32_t kReceiverId = 7;

// A large receiver quad at z = 0 (normal +z) plus the given occluders.
Scene withReceiver(std::vector<Object> occluders) {
  occluders.push_back(makeObject(kReceiverId, quadMesh(Vec3(0.0f), Vec3(20, 0, 0), Vec3(0, 20, 0)), "receiver"));
  return makeScene(std::move(occluders));
}

struct Estimate {
  std::vector<float> v, stdError;
};

Estimate runReference(const Scene& scene, const Light& light, const std::vector<Vec3>& points, uint32_t spp = kSpp,
                      uint64_t seed = 1) {
  ReferenceTechnique reference(ReferenceOptions{spp, seed});
  reference.prepare(scene, light);
  const GBuffer g = pointsGBuffer(points, Vec3(0, 0, 1), kReceiverId);
  Image<float> v;
  reference.visibility(g, v);
  Estimate e;
  for (int x = 0; x < g.width(); ++x) {
    e.v.push_back(v(x, 0));
    e.stdError.push_back(reference.standardError()(x, 0));
  }
  return e;
}

void expectMatches(const Estimate& e, const std::vector<double>& exact) {
  ASSERT_EQ(e.v.size(), exact.size());
  for (size_t i = 0; i < exact.size(); ++i) {
    SCOPED_TRACE(::testing::Message() << "point " << i << ": exact V = " << exact[i] << ", estimate " << e.v[i]
                                      << " +- " << e.stdError[i]);
    EXPECT_LE(std::abs(e.v[i] - exact[i]), 3.0 * e.stdError[i] + 1e-6);
    EXPECT_LE(std::abs(e.v[i] - exact[i]), 1.0 / 255.0);
  }
}

double overlap1D(double a0, double a1, double b0, double b1) {
  return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

// Area of the lens where two circles (radii r1, r2, centres d apart) overlap.
double lensArea(double r1, double r2, double d) {
  if (d >= r1 + r2) return 0.0;
  if (d <= std::abs(r1 - r2)) return kPiD * std::min(r1, r2) * std::min(r1, r2);
  const double a1 = std::acos((d * d + r1 * r1 - r2 * r2) / (2.0 * d * r1));
  const double a2 = std::acos((d * d + r2 * r2 - r1 * r1) / (2.0 * d * r2));
  return r1 * r1 * a1 + r2 * r2 * a2 - 0.5 * std::sqrt((-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2));
}

// Geometry shared by the parallel cases: light plane z = 4, occluder plane z = 2, receiver z = 0, so
// the central projection from a receiver point p of an occluder point q lands at 2q - p.
constexpr float kLightZ = 4.0f, kOccluderZ = 2.0f;

TEST(Reference, RectLightOverParallelRectOccluder) {
  const Light light = Light::rect(Vec3(0, 0, kLightZ), Vec3(1.0f, 0, 0), Vec3(0, 0.5f, 0));
  const Vec3 occCenter(0.12f, -0.05f, kOccluderZ);
  const double ox = 0.65, oy = 0.4;  // occluder half extents
  const Scene scene = withReceiver({makeObject(1, quadMesh(occCenter, Vec3(ox, 0, 0), Vec3(0, oy, 0)), "occluder")});
  const std::vector<Vec3> points = {Vec3(0, 0, 0),       Vec3(0.5f, 0, 0),      Vec3(1.5f, 0.5f, 0),
                                    Vec3(1.0f, 0.9f, 0), Vec3(-0.7f, -0.6f, 0), Vec3(3.0f, 0, 0)};
  std::vector<double> exact;
  for (const Vec3& p : points) {
    const double cx = 2.0 * occCenter.x - p.x, cy = 2.0 * occCenter.y - p.y;
    const double area = overlap1D(cx - 2 * ox, cx + 2 * ox, -1.0, 1.0) * overlap1D(cy - 2 * oy, cy + 2 * oy, -0.5, 0.5);
    exact.push_back(1.0 - area / 2.0);
  }
  // The set covers umbra, penumbra and fully lit points.
  EXPECT_EQ(exact.front(), 0.0);
  EXPECT_EQ(exact.back(), 1.0);
  expectMatches(runReference(scene, light, points), exact);
}

TEST(Reference, DiskLightOverParallelDiskOccluder) {
  // The occluder is a 512-gon inscribed in its circle: its area is short by (2 pi / 512)^2 / 6 = 2.5e-5
  // of the disk's and its edge lies within 1.9e-5 r of the circle, far below the 1/255 tolerance.
  const Light light = Light::disk(Vec3(0, 0, kLightZ), Vec3(0, 0, -1), 1.0f);
  const Vec3 occCenter(0.0f, 0.0f, kOccluderZ);
  const double rOcc = 0.6;
  const Scene scene =
      withReceiver({makeObject(1, regularPolygonMesh(occCenter, Vec3(1, 0, 0), Vec3(0, 1, 0), rOcc, 512), "disk")});
  const std::vector<Vec3> points = {Vec3(0, 0, 0), Vec3(0.5f, 0, 0), Vec3(1.2f, 0.9f, 0), Vec3(-0.3f, 1.4f, 0),
                                    Vec3(2.5f, 0, 0)};
  std::vector<double> exact;
  for (const Vec3& p : points) {
    const double d = std::hypot(2.0 * occCenter.x - p.x, 2.0 * occCenter.y - p.y);
    exact.push_back(1.0 - lensArea(1.0, 2.0 * rOcc, d) / kPiD);
  }
  EXPECT_EQ(exact.front(), 0.0);
  EXPECT_EQ(exact.back(), 1.0);
  expectMatches(runReference(scene, light, points), exact);
}

TEST(Reference, SphereLightOnItsAxisSeesItsSilhouetteDisk) {
  // From p = 0 the sphere (centre z = 4, R = 1) shows the disk of radius R sqrt(H^2 - R^2) / H at
  // z = (H^2 - R^2) / H = 3.75; an occluder disk at half that height projects at twice its size.
  const double H = 4.0, R = 1.0, D = (H * H - R * R) / H, rs = R * std::sqrt(H * H - R * R) / H;
  const Light light = Light::sphere(Vec3(0, 0, static_cast<float>(H)), static_cast<float>(R));
  const double rOcc = 0.4, zOcc = D / 2.0;
  for (const double cx : {0.0, 0.5, 0.75, 1.0}) {
    SCOPED_TRACE(::testing::Message() << "occluder offset " << cx);
    const Vec3 c(static_cast<float>(cx), 0.0f, static_cast<float>(zOcc));
    const Scene scene = withReceiver(
        {makeObject(1, regularPolygonMesh(c, Vec3(1, 0, 0), Vec3(0, 1, 0), static_cast<float>(rOcc), 512))});
    const double exact = 1.0 - lensArea(rs, 2.0 * rOcc, 2.0 * cx) / (kPiD * rs * rs);
    expectMatches(runReference(scene, light, {Vec3(0.0f)}), {exact});
  }
}

// Area of a convex polygon (shoelace) and its clip against an axis-aligned rectangle (Sutherland–Hodgman).
double polygonArea(const std::vector<Vec2>& poly) {
  double a = 0.0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const Vec2& p = poly[i];
    const Vec2& q = poly[(i + 1) % poly.size()];
    a += static_cast<double>(p.x) * q.y - static_cast<double>(q.x) * p.y;
  }
  return 0.5 * std::abs(a);
}

std::vector<Vec2> clipToBox(std::vector<Vec2> poly, const Vec2& lo, const Vec2& hi) {
  // Each half-plane as (axis, bound, keep-below).
  const struct {
    int axis;
    float bound;
    bool below;
  } planes[4] = {{0, lo.x, false}, {0, hi.x, true}, {1, lo.y, false}, {1, hi.y, true}};
  for (const auto& pl : planes) {
    std::vector<Vec2> out;
    auto inside = [&](const Vec2& p) { return pl.below ? p[pl.axis] <= pl.bound : p[pl.axis] >= pl.bound; };
    for (size_t i = 0; i < poly.size(); ++i) {
      const Vec2 a = poly[i], b = poly[(i + 1) % poly.size()];
      if (inside(a)) out.push_back(a);
      if (inside(a) != inside(b)) {
        const float t = (pl.bound - a[pl.axis]) / (b[pl.axis] - a[pl.axis]);
        out.push_back(a + t * (b - a));
      }
    }
    poly = std::move(out);
    if (poly.empty()) break;
  }
  return poly;
}

TEST(Reference, ConvexPolygonLightOverParallelRectOccluder) {
  const std::vector<Vec2> lightPoly = {Vec2(-1.0f, -0.6f), Vec2(0.8f, -0.8f), Vec2(1.2f, 0.2f), Vec2(0.3f, 0.9f),
                                       Vec2(-0.9f, 0.5f)};
  std::vector<Vec3> vertices;
  for (const Vec2& q : lightPoly) vertices.push_back(Vec3(q.x, q.y, kLightZ));
  const Light light = Light::polygon(vertices);
  const double ox = 0.5, oy = 0.3;
  const Scene scene = withReceiver({makeObject(1, quadMesh(Vec3(0, 0, kOccluderZ), Vec3(ox, 0, 0), Vec3(0, oy, 0)))});
  const std::vector<Vec3> points = {Vec3(0, 0, 0), Vec3(0.6f, 0.2f, 0), Vec3(-0.4f, 0.7f, 0), Vec3(1.3f, -0.9f, 0)};
  std::vector<double> exact;
  const double lightArea = polygonArea(lightPoly);
  for (const Vec3& p : points) {
    const Vec2 c(-p.x, -p.y);  // projected occluder centre 2 * 0 - p
    const auto clipped = clipToBox(lightPoly, c - Vec2(2 * ox, 2 * oy), c + Vec2(2 * ox, 2 * oy));
    exact.push_back(1.0 - (clipped.size() >= 3 ? polygonArea(clipped) : 0.0) / lightArea);
  }
  expectMatches(runReference(scene, light, points), exact);
}

// The part of a (possibly concave) polygon on the side dot(x, m) >= c of a line, by Sutherland–Hodgman
// against one half-plane: for a concave polygon the result may run along the line and back, which
// adds no area, so the shoelace area is still the area of the part.
std::vector<Vec2> clipToHalfPlane(const std::vector<Vec2>& poly, const Vec2& m, float c) {
  std::vector<Vec2> out;
  for (size_t i = 0; i < poly.size(); ++i) {
    const Vec2 a = poly[i], b = poly[(i + 1) % poly.size()];
    const float da = glm::dot(a, m) - c, db = glm::dot(b, m) - c;
    if (da >= 0.0f) out.push_back(a);
    if ((da >= 0.0f) != (db >= 0.0f)) out.push_back(a + (da / (da - db)) * (b - a));
  }
  return out;
}

TEST(Reference, LShapedLightOverHalfPlaneOccluder) {
  // An L of three unit squares ([-1, 1] x [-1, 0] and [-1, 0] x [0, 1]) at z = 4 over a half-plane
  // occluder at z = 2 whose edge runs through the origin: from p the occluder hides the light's part
  // beyond the edge's projection 2q - p, so V is the fraction of the L's area on the lit side. Edge
  // along y (occluder x < 0): V = ((1 - s) + max(0, -s)) / 3 with s = -p.x clamped to [-1, 1]; edge
  // along the diagonal (occluder x + y < 0): the L clipped by x + y >= -(p.x + p.y).
  // Listed from a corner that does not see the whole L, so a fan from vertex 0 would leave it.
  const std::vector<Vec2> lightPoly = {Vec2(1, 0), Vec2(0, 0), Vec2(0, 1), Vec2(-1, 1), Vec2(-1, -1), Vec2(1, -1)};
  std::vector<Vec3> vertices;
  for (const Vec2& q : lightPoly) vertices.push_back(Vec3(q.x, q.y, kLightZ));
  const Light light = Light::polygon(vertices);
  ASSERT_FALSE(light.convex());
  const double lightArea = polygonArea(lightPoly);
  ASSERT_NEAR(lightArea, 3.0, 1e-6);
  const std::vector<Vec3> points = {Vec3(-1.5f, 0.1f, 0), Vec3(-0.7f, 0.3f, 0), Vec3(-0.2f, -0.5f, 0),
                                    Vec3(0.0f, 0.0f, 0),  Vec3(0.4f, 0.2f, 0),  Vec3(0.9f, -0.4f, 0),
                                    Vec3(1.5f, 0.0f, 0)};
  {
    SCOPED_TRACE("edge along y");
    const Scene scene = withReceiver(
        {makeObject(1, quadMesh(Vec3(-25.0f, 0, kOccluderZ), Vec3(25.0f, 0, 0), Vec3(0, 25.0f, 0)), "half-plane")});
    std::vector<double> exact;
    for (const Vec3& p : points) {
      const double s = std::clamp(-static_cast<double>(p.x), -1.0, 1.0);
      exact.push_back(((1.0 - s) + std::max(0.0, -s)) / 3.0);
    }
    EXPECT_EQ(exact.front(), 0.0);
    EXPECT_EQ(exact.back(), 1.0);
    expectMatches(runReference(scene, light, points), exact);
  }
  {
    SCOPED_TRACE("diagonal edge");
    const float h = 25.0f * std::sqrt(0.5f);  // the half-plane x + y < 0 as a 50 x 50 square beside its edge
    const Vec3 along(h, -h, 0), across(-h, -h, 0);
    const Scene scene =
        withReceiver({makeObject(1, quadMesh(Vec3(0, 0, kOccluderZ) + across, across, along), "half-plane")});
    std::vector<double> exact;
    for (const Vec3& p : points) {
      const auto lit = clipToHalfPlane(lightPoly, Vec2(1, 1), -(p.x + p.y));
      exact.push_back(lit.size() >= 3 ? polygonArea(lit) / lightArea : 0.0);
    }
    expectMatches(runReference(scene, light, points), exact);
  }
}

TEST(Reference, SegmentLightOverParallelRectOccluder) {
  // A linear light along x at z = 4: V is the unoccluded fraction of its length.
  const Light light = Light::segment(Vec3(-1.0f, 0.2f, kLightZ), Vec3(1.0f, 0.2f, kLightZ));
  const double ox = 0.4;
  const Scene scene = withReceiver({makeObject(1, quadMesh(Vec3(0, 0, kOccluderZ), Vec3(ox, 0, 0), Vec3(0, 1.0f, 0)))});
  const std::vector<Vec3> points = {Vec3(0, 0, 0), Vec3(0.5f, 0.1f, 0), Vec3(-1.1f, 0, 0), Vec3(2.0f, 0, 0)};
  std::vector<double> exact;
  for (const Vec3& p : points) exact.push_back(1.0 - overlap1D(-p.x - 2 * ox, -p.x + 2 * ox, -1.0, 1.0) / 2.0);
  expectMatches(runReference(scene, light, points), exact);
}

// The solar disk (uniform in area in the tangent plane, radius rho = tan(theta / 2)) behind the
// straight edge x = 0 of a half-plane occluder at height h: from p = (x, 0, 0) the rays are blocked
// where the sample's x offset is below -x / h, i.e. beyond a chord at normalized distance t = x / (h rho).
double segmentFraction(double t) {  // fraction of the unit disk with x < -t
  if (t >= 1.0) return 0.0;
  if (t <= -1.0) return 1.0;
  return (std::acos(t) - t * std::sqrt(1.0 - t * t)) / kPiD;
}

// The same for the linear limb-darkening law I = 1 - u (1 - mu), mu = sqrt(1 - rho^2): the strip at x
// carries (1 - u) 2 w + u pi w^2 / 2 (w = sqrt(1 - x^2)), whose integral from -1 to -t is
// (1 - u)(acos t - t sqrt(1 - t^2)) + u pi / 2 (2/3 - t + t^3 / 3); the whole disk gives pi (1 - u / 3).
double limbDarkenedSegmentFraction(double t, double u) {
  if (t >= 1.0) return 0.0;
  if (t <= -1.0) return 1.0;
  const double blocked =
      (1.0 - u) * (std::acos(t) - t * std::sqrt(1.0 - t * t)) + u * kPiD / 2.0 * (2.0 / 3.0 - t + t * t * t / 3.0);
  return blocked / (kPiD * (1.0 - u / 3.0));
}

struct EdgeSetup {
  float h = 1.0f;
  float theta = radians(10.0f);
  double rho() const { return std::tan(0.5 * theta); }
  Scene scene() const {
    // The half-plane x < 0 at height h (50 units: far beyond the 0.09-unit penumbra).
    return withReceiver({makeObject(1, quadMesh(Vec3(-25.0f, 0, h), Vec3(25.0f, 0, 0), Vec3(0, 25.0f, 0)), "edge")});
  }
  std::vector<Vec3> points() const {
    std::vector<Vec3> ps;
    for (const double t : {-1.5, -0.8, -0.3, 0.0, 0.25, 0.5, 0.9, 1.5})
      ps.push_back(Vec3(static_cast<float>(t * h * rho()), 0.0f, 0.0f));
    return ps;
  }
};

TEST(Reference, DirectionalDiskBehindStraightEdge) {
  const EdgeSetup setup;
  const Light light = Light::directional(Vec3(0, 0, 1), setup.theta);
  std::vector<double> exact;
  for (const Vec3& p : setup.points()) exact.push_back(1.0 - segmentFraction(p.x / (setup.h * setup.rho())));
  expectMatches(runReference(setup.scene(), light, setup.points()), exact);
}

TEST(Reference, LimbDarkenedDirectionalBehindStraightEdge) {
  const EdgeSetup setup;
  const Light light = Light::directional(Vec3(0, 0, 1), setup.theta, LightProfile::LimbDarkened);
  std::vector<double> exact, uniform;
  for (const Vec3& p : setup.points()) {
    const double t = p.x / (setup.h * setup.rho());
    exact.push_back(1.0 - limbDarkenedSegmentFraction(t, kLimbDarkeningU));
    uniform.push_back(1.0 - segmentFraction(t));
  }
  // The profile matters by more than the tolerance at the penumbra points, so this test tells them apart.
  EXPECT_GT(std::abs(exact[5] - uniform[5]), 3.0 / 255.0);
  expectMatches(runReference(setup.scene(), light, setup.points()), exact);
}

TEST(Reference, RaytracedHardMissesThePenumbraByALot) {
  // A wrong (hard) answer fails the checks above: at the edge's penumbra points the centre ray gives
  // 0 or 1 while the exact V lies in between.
  const EdgeSetup setup;
  const Light light = Light::directional(Vec3(0, 0, 1), setup.theta);
  auto hard = createTechnique("raytraced-hard");
  hard->prepare(setup.scene(), light);
  const auto points = setup.points();
  Image<float> v;
  hard->visibility(pointsGBuffer(points, Vec3(0, 0, 1), kReceiverId), v);
  for (size_t i = 2; i <= 5; ++i) {  // t in [-0.3, 0.5]
    const double exact = 1.0 - segmentFraction(points[i].x / (setup.h * setup.rho()));
    EXPECT_GT(std::abs(v(static_cast<int>(i), 0) - exact), 0.05) << "point " << i;
  }
}

TEST(Reference, UnoccludedPixelsAreExactlyOneAndMissesAreOne) {
  const Light light = Light::rect(Vec3(0, 0, kLightZ), Vec3(1, 0, 0), Vec3(0, 1, 0));
  const Scene scene = withReceiver({});
  ReferenceTechnique reference(ReferenceOptions{64, 3});
  reference.prepare(scene, light);
  GBuffer g = pointsGBuffer({Vec3(0.0f), Vec3(5.0f, -3.0f, 0.0f), Vec3(0.0f)}, Vec3(0, 0, 1), kReceiverId);
  g.objectId(2, 0) = kNoObject;  // a pixel that sees nothing
  Image<float> v;
  reference.visibility(g, v);
  EXPECT_EQ(v(0, 0), 1.0f);
  EXPECT_EQ(v(1, 0), 1.0f);
  EXPECT_EQ(v(2, 0), 1.0f);
  EXPECT_EQ(reference.standardError()(0, 0), 0.0f);
}

// A small rendered scene for the determinism and statistics tests.
struct SmallRender {
  Scene scene;
  Light light = Light::disk(Vec3(0, 0, kLightZ), Vec3(0, 0, -1), 1.0f);
  GBuffer g;
  SmallRender() {
    scene = withReceiver(
        {makeObject(1, regularPolygonMesh(Vec3(0.2f, 0, kOccluderZ), Vec3(1, 0, 0), Vec3(0, 1, 0), 0.5f, 64))});
    scene.camera.position = Vec3(0.5f, -3.0f, 6.0f);
    scene.camera.lookAt = Vec3(0.0f);
    scene.camera.up = Vec3(0, 0, 1);
    scene.camera.fovYDegrees = 50.0f;
    RayScene rays(scene);
    g = traceGBuffer(scene, rays, 40, 24);
  }
  Image<float> run(uint64_t seed) const {
    ReferenceTechnique reference(ReferenceOptions{32, seed});
    reference.prepare(scene, light);
    Image<float> v;
    reference.visibility(g, v);
    return v;
  }
};

bool bitIdentical(const Image<float>& a, const Image<float>& b) {
  return a.width() == b.width() && a.height() == b.height() &&
         std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(Reference, DeterministicPerSeedAndThreadCount) {
  const SmallRender r;
  const Image<float> a = r.run(1), b = r.run(1), c = r.run(2);
  EXPECT_TRUE(bitIdentical(a, b));
  EXPECT_FALSE(bitIdentical(a, c));
  Image<float> one, two;
  tbb::task_arena(1).execute([&] { one = r.run(5); });
  tbb::task_arena(2).execute([&] { two = r.run(5); });
  EXPECT_TRUE(bitIdentical(one, two));
  // The render has a penumbra (else determinism would be trivial).
  int penumbra = 0;
  for (float x : a) penumbra += x > 0.0f && x < 1.0f;
  EXPECT_GT(penumbra, 10);
}

// At up to 8 spp a packet holds several pixels' rays (reference.cpp); which pixels share a packet
// must not change any pixel's V or standard error. With every other pixel hidden, each remaining
// pixel shares its packets with other neighbours, and must get the same bits.
TEST(Reference, PixelsSharingAPacketGetTheirOwnV) {
  const SmallRender r;
  GBuffer sparse = r.g;
  for (int y = 0; y < sparse.height(); ++y)
    for (int x = 1; x < sparse.width(); x += 2) sparse.objectId(x, y) = kNoObject;
  for (uint32_t spp : {1u, 3u, 4u, 8u, 9u}) {
    ReferenceTechnique reference(ReferenceOptions{spp, 1});
    reference.prepare(r.scene, r.light);
    Image<float> full, fewer;
    reference.visibility(r.g, full);
    const Image<float> fullError = reference.standardError();
    reference.visibility(sparse, fewer);
    int compared = 0, penumbra = 0;
    for (int y = 0; y < sparse.height(); ++y)
      for (int x = 0; x < sparse.width(); x += 2) {
        if (!sparse.hit(x, y)) continue;
        ++compared;
        penumbra += full(x, y) > 0.0f && full(x, y) < 1.0f;
        EXPECT_EQ(std::memcmp(&full(x, y), &fewer(x, y), sizeof(float)), 0)
            << "spp " << spp << " (" << x << ", " << y << ")";
        EXPECT_EQ(std::memcmp(&fullError(x, y), &reference.standardError()(x, y), sizeof(float)), 0) << "spp " << spp;
      }
    EXPECT_GT(compared, 100);
    if (spp > 1) {
      EXPECT_GT(penumbra, 5) << "spp " << spp;
    }
  }
}

TEST(Reference, StatsCountRaysAndStandardErrors) {
  const SmallRender r;
  ReferenceTechnique reference(ReferenceOptions{32, 1});
  reference.prepare(r.scene, r.light);
  int hits = 0;
  for (int y = 0; y < r.g.height(); ++y)
    for (int x = 0; x < r.g.width(); ++x) hits += r.g.hit(x, y);
  std::vector<double> progress;
  reference.setProgressCallback([&](double f) { progress.push_back(f); });  // one thread at a time here
  Image<float> v;
  tbb::task_arena(1).execute([&] { reference.visibility(r.g, v); });
  const auto statList = reference.stats();
  const std::map<std::string, double> stats(statList.begin(), statList.end());
  EXPECT_EQ(stats.at("rays"), 32.0 * hits);
  EXPECT_GT(stats.at("rays_per_second"), 0.0);
  EXPECT_GT(stats.at("max_std_error"), 0.0);
  EXPECT_LE(stats.at("mean_std_error"), stats.at("max_std_error"));
  // Standard error: zero where V is 0 or 1 (every sample agreed) and on misses, positive in the penumbra.
  double sum = 0.0;
  for (int y = 0; y < r.g.height(); ++y)
    for (int x = 0; x < r.g.width(); ++x) {
      const float se = reference.standardError()(x, y);
      if (!r.g.hit(x, y) || v(x, y) == 0.0f || v(x, y) == 1.0f)
        EXPECT_EQ(se, 0.0f);
      else {
        // For a uniform light: sqrt(V (1 - V) n / (n - 1)) / sqrt(n).
        const double V = v(x, y);
        EXPECT_NEAR(se, std::sqrt(V * (1.0 - V) * 32.0 / 31.0) / std::sqrt(32.0), 1e-5);
      }
      if (r.g.hit(x, y)) sum += se;
    }
  EXPECT_NEAR(stats.at("mean_std_error"), sum / hits, 1e-9);
  ASSERT_FALSE(progress.empty());
  EXPECT_LE(progress.size(), 101u);
  EXPECT_DOUBLE_EQ(progress.back(), 1.0);
  const PassTimings t = reference.timings();
  ASSERT_EQ(t.passes.size(), 2u);
  EXPECT_EQ(t.passes[0].first, "prepare");
  EXPECT_EQ(t.passes[1].first, "visibility");
}

TEST(Reference, EveryLightShapeIsSupported) {
  // Under a large occluder (umbra) V = 0, beside it (fully lit) V = 1, for every shape.
  const Scene scene = withReceiver({makeObject(1, quadMesh(Vec3(0, 0, kOccluderZ), Vec3(3, 0, 0), Vec3(0, 3, 0)))});
  const std::vector<Light> lights = {
      Light::sphere(Vec3(0, 0, kLightZ), 0.3f),
      Light::disk(Vec3(0, 0, kLightZ), Vec3(0, 0, 1), 0.3f),
      Light::rect(Vec3(0, 0, kLightZ), Vec3(0.3f, 0, 0), Vec3(0, 0.2f, 0)),
      Light::segment(Vec3(-0.3f, 0, kLightZ), Vec3(0.3f, 0, kLightZ)),
      Light::polygon({Vec3(-0.3f, -0.3f, kLightZ), Vec3(0.3f, -0.3f, kLightZ), Vec3(0, 0.3f, kLightZ)}),
      Light::directional(Vec3(0, 0, 1), radians(2.0f)),
      Light::directional(Vec3(0, 0, 1), radians(2.0f), LightProfile::LimbDarkened),
  };
  for (const char* technique : {"reference", "raytraced-hard", "none"}) {
    for (const Light& light : lights) {
      SCOPED_TRACE(::testing::Message() << technique << " with a " << toString(light.shape()) << " light");
      auto t = createTechnique(technique);
      ASSERT_NO_THROW(t->prepare(scene, light));
      Image<float> v;
      t->visibility(pointsGBuffer({Vec3(0.0f), Vec3(15.0f, 0.0f, 0.0f)}, Vec3(0, 0, 1), kReceiverId), v);
      EXPECT_EQ(v(0, 0), std::string(technique) == "none" ? 1.0f : 0.0f);
      EXPECT_EQ(v(1, 0), 1.0f);
    }
  }
}

TEST(Reference, RegistryValidatesParameters) {
  const TechniqueInfo& info = findTechnique("reference");
  EXPECT_TRUE(info.hasParam("spp"));
  EXPECT_TRUE(info.hasParam("seed"));
  ParamSet bad;
  bad.set("spp", int64_t{0}, "test");
  EXPECT_THROW(createTechnique("reference", bad), Error);
  ParamSet negativeSeed;
  negativeSeed.set("seed", int64_t{-1}, "test");
  EXPECT_THROW(createTechnique("reference", negativeSeed), Error);
  ParamSet good;
  good.set("spp", std::string("16"), "command line");
  auto t = createTechnique("reference", good);
  auto* reference = dynamic_cast<ReferenceTechnique*>(t.get());
  ASSERT_NE(reference, nullptr);
  EXPECT_EQ(reference->options().samplesPerPixel, 16u);
  EXPECT_EQ(reference->options().seed, 1u);
}

TEST(Reference, VisibilityBeforePrepareIsAnError) {
  ReferenceTechnique reference(ReferenceOptions{});
  Image<float> v;
  try {
    reference.visibility(GBuffer(2, 2), v);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("prepare"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace penumbra
