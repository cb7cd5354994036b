// Tests of the lights (src/core/light.cpp): samples lie on each shape's emitter (the silhouette disk
// for spheres), their means are the emitter's centroid, segment samples are uniform along it,
// directional samples stay within half the angular diameter, limb-darkened weights average 1,
// irradiance matches closed forms, concave polygons (an L, a U) are sampled uniformly inside and
// tiled by their convex parts, and every degenerate light is rejected by its factory with a message
// that names what is wrong.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "penumbra/error.h"
#include "penumbra/light.h"
#include "penumbra/sampling.h"

namespace penumbra {
namespace {

constexpr double kPiD = 3.14159265358979323846;

// The point a sample reaches (finite lights).
Vec3 samplePoint(const Vec3& p, const LightSample& s) { return p + s.distance * s.wsDirection; }

std::vector<LightSample> samples(const Light& light, const Vec3& p, uint32_t count, uint32_t pattern = 11) {
  const CmjSampler sampler(count);
  std::vector<LightSample> out;
  for (uint32_t i = 0; i < count; ++i) out.push_back(light.sample(p, sampler.sample(i, pattern)));
  return out;
}

const Vec3 kP(0.3f, -0.2f, -1.0f);  // a shaded point below every local light of these tests

TEST(LightSample, DiskSamplesLieOnTheDiskAndAverageToItsCentre) {
  const Vec3 c(0.5f, 1.0f, 3.0f), n = glm::normalize(Vec3(0.2f, -0.3f, 1.0f));
  const Light light = Light::disk(c, n, 0.75f);
  DVec3 mean(0.0);
  const auto ss = samples(light, kP, 4096);
  for (const LightSample& s : ss) {
    EXPECT_NEAR(glm::length(s.wsDirection), 1.0f, 1e-5f);
    EXPECT_EQ(s.weight, 1.0f);
    const Vec3 x = samplePoint(kP, s);
    EXPECT_NEAR(glm::dot(x - c, n), 0.0f, 1e-5f);
    EXPECT_LE(glm::length(x - c), 0.75f * (1.0f + 1e-5f));
    mean += DVec3(x);
  }
  mean /= static_cast<double>(ss.size());
  EXPECT_NEAR(glm::length(Vec3(mean) - c), 0.0f, 1e-3f);
}

TEST(LightSample, RectSamplesLieOnTheRectAndAverageToItsCentre) {
  const Vec3 c(-1.0f, 2.0f, 4.0f), u(0.8f, 0.0f, 0.6f), v(0.0f, 0.3f, 0.0f);
  const Light light = Light::rect(c, u, v);
  DVec3 mean(0.0);
  const auto ss = samples(light, kP, 4096);
  for (const LightSample& s : ss) {
    const Vec3 x = samplePoint(kP, s);
    EXPECT_NEAR(glm::dot(x - c, light.normal()), 0.0f, 1e-5f);
    EXPECT_LE(std::abs(glm::dot(x - c, u)) / glm::dot(u, u), 1.0f + 1e-5f);
    EXPECT_LE(std::abs(glm::dot(x - c, v)) / glm::dot(v, v), 1.0f + 1e-5f);
    mean += DVec3(x);
  }
  mean /= static_cast<double>(ss.size());
  EXPECT_NEAR(glm::length(Vec3(mean) - c), 0.0f, 1e-3f);
  ASSERT_EQ(light.vertices().size(), 4u);
  EXPECT_NEAR(glm::length(light.vertices()[2] - (c + u + v)), 0.0f, 1e-6f);
}

// Area centroid by the shoelace formula.
Vec2 shoelaceCentroid(const std::vector<Vec2>& q, double* area = nullptr) {
  double a = 0.0, cx = 0.0, cy = 0.0;
  for (size_t i = 0; i < q.size(); ++i) {
    const Vec2 p0 = q[i], p1 = q[(i + 1) % q.size()];
    const double cr = static_cast<double>(p0.x) * p1.y - static_cast<double>(p1.x) * p0.y;
    a += cr;
    cx += (p0.x + p1.x) * cr;
    cy += (p0.y + p1.y) * cr;
  }
  if (area) *area = 0.5 * std::abs(a);
  return Vec2(static_cast<float>(cx / (3.0 * a)), static_cast<float>(cy / (3.0 * a)));
}

TEST(LightSample, PolygonSamplesLieInsideAndAverageToTheAreaCentroid) {
  // An irregular convex pentagon in the plane z = 2.
  const std::vector<Vec2> q = {Vec2(-1.0f, -0.6f), Vec2(0.8f, -0.8f), Vec2(1.2f, 0.2f), Vec2(0.3f, 0.9f),
                               Vec2(-0.9f, 0.5f)};
  std::vector<Vec3> vs;
  for (const Vec2& p : q) vs.push_back(Vec3(p.x, p.y, 2.0f));
  const Light light = Light::polygon(vs);
  // The area centroid, independent of the light's fan triangulation.
  const Vec2 centroid = shoelaceCentroid(q);
  EXPECT_NEAR(light.center().x, centroid.x, 1e-5);
  EXPECT_NEAR(light.center().y, centroid.y, 1e-5);
  DVec3 mean(0.0);
  const auto ss = samples(light, kP, 4096);
  for (const LightSample& s : ss) {
    const Vec3 x = samplePoint(kP, s);
    EXPECT_NEAR(x.z, 2.0f, 1e-5f);
    for (size_t i = 0; i < q.size(); ++i) {  // left of every counter-clockwise edge
      const Vec2 e = q[(i + 1) % q.size()] - q[i], r = Vec2(x.x, x.y) - q[i];
      EXPECT_GE(e.x * r.y - e.y * r.x, -1e-5f);
    }
    mean += DVec3(x);
  }
  mean /= static_cast<double>(ss.size());
  EXPECT_NEAR(mean.x, centroid.x, 2e-3);
  EXPECT_NEAR(mean.y, centroid.y, 2e-3);
}

// An L (three unit squares: [0,2] x [0,1] and [0,1] x [1,2]) and a U (a 3 x 2 block with a 1 x 1.5
// notch from the top), in the plane z = 2, counter-clockwise.
const std::vector<Vec2> kL = {Vec2(0, 0), Vec2(2, 0), Vec2(2, 1), Vec2(1, 1), Vec2(1, 2), Vec2(0, 2)};
const std::vector<Vec2> kU = {Vec2(0, 0),    Vec2(3, 0),    Vec2(3, 2), Vec2(2, 2),
                              Vec2(2, 0.5f), Vec2(1, 0.5f), Vec2(1, 2), Vec2(0, 2)};

std::vector<Vec3> inPlaneZ2(const std::vector<Vec2>& q) {
  std::vector<Vec3> vs;
  for (const Vec2& p : q) vs.push_back(Vec3(p.x, p.y, 2.0f));
  return vs;
}

// Point in polygon by the crossing number (independent of the light's triangulation).
bool insidePolygon(const std::vector<Vec2>& q, const Vec2& x) {
  bool in = false;
  for (size_t i = 0, j = q.size() - 1; i < q.size(); j = i++)
    if ((q[i].y > x.y) != (q[j].y > x.y) && x.x < (q[j].x - q[i].x) * (x.y - q[i].y) / (q[j].y - q[i].y) + q[i].x)
      in = !in;
  return in;
}

TEST(LightSample, ConcavePolygonSamplesAreUniformInsideAndAverageToTheAreaCentroid) {
  for (const auto& [name, q, pieces] : {std::tuple{"L", kL, 2}, std::tuple{"U", kU, 3}}) {
    SCOPED_TRACE(name);
    for (const bool reversed : {false, true}) {  // either orientation
      std::vector<Vec2> order = q;
      if (reversed) std::reverse(order.begin(), order.end());
      const Light light = Light::polygon(inPlaneZ2(order));
      EXPECT_FALSE(light.convex());
      double area = 0.0;
      const Vec2 c = shoelaceCentroid(q, &area);
      EXPECT_NEAR(light.area(), area, 1e-5);
      EXPECT_NEAR(light.center().x, c.x, 1e-5);
      EXPECT_NEAR(light.center().y, c.y, 1e-5);
      // The convex parts tile the polygon: their areas add up to its own, and there are as few as
      // the shape allows (an L needs 2, a U 3), rectangles (cuts continue the edges).
      const auto parts = light.convexParts();
      EXPECT_EQ(parts.size(), static_cast<size_t>(pieces));
      double partsArea = 0.0;
      for (const auto& part : parts) {
        EXPECT_EQ(part.size(), 4u);
        const Light piece = Light::polygon(part);
        EXPECT_TRUE(piece.convex());
        partsArea += piece.area();
      }
      EXPECT_NEAR(partsArea, area, 1e-5);
      // 4096 CMJ samples: all inside, their mean the area centroid, and each unit cell of the shape
      // gets its share of the area (the sampling is uniform, not just centred).
      DVec3 mean(0.0);
      std::map<std::pair<int, int>, int> cells;
      const auto ss = samples(light, kP, 4096);
      int outside = 0;
      for (const LightSample& s : ss) {
        const Vec3 x = samplePoint(kP, s);
        EXPECT_NEAR(x.z, 2.0f, 1e-5f);
        outside += !insidePolygon(q, Vec2(x.x, x.y));
        mean += DVec3(x);
        cells[{static_cast<int>(std::floor(x.x * 2.0f)), static_cast<int>(std::floor(x.y * 2.0f))}]++;
      }
      EXPECT_EQ(outside, 0);
      mean /= static_cast<double>(ss.size());
      EXPECT_NEAR(mean.x, c.x, 2e-3);
      EXPECT_NEAR(mean.y, c.y, 2e-3);
      // Half-unit cells wholly inside hold 0.25 / area of the samples, to a few percent (the
      // stratification holds within each triangle, not across cell borders).
      for (const auto& [cell, count] : cells) {
        const Vec2 centre((cell.first + 0.5f) * 0.5f, (cell.second + 0.5f) * 0.5f);
        bool whole = true;
        for (const Vec2 corner : {Vec2(-0.24f, -0.24f), Vec2(0.24f, -0.24f), Vec2(0.24f, 0.24f), Vec2(-0.24f, 0.24f)})
          whole = whole && insidePolygon(q, centre + corner);
        if (whole) {
          EXPECT_NEAR(count / 4096.0, 0.25 / area, 0.15 * 0.25 / area) << "cell " << cell.first << "," << cell.second;
        }
      }
    }
  }
}

TEST(LightSample, SegmentSamplesAreUniformAlongIt) {
  const Vec3 a(-1.0f, 0.5f, 3.0f), b(2.0f, 0.5f, 2.0f);
  const Light light = Light::segment(a, b);
  EXPECT_NEAR(glm::length(light.center() - 0.5f * (a + b)), 0.0f, 1e-6f);
  const uint32_t n = 1024;  // 32 x 32: CMJ puts exactly one sample in each 1/1024 of the length
  std::vector<float> ts;
  for (const LightSample& s : samples(light, kP, n)) {
    const Vec3 x = samplePoint(kP, s);
    const float t = glm::dot(x - a, b - a) / glm::dot(b - a, b - a);
    EXPECT_NEAR(glm::length(x - (a + t * (b - a))), 0.0f, 1e-5f);  // on the line
    ts.push_back(t);
  }
  std::sort(ts.begin(), ts.end());
  for (uint32_t k = 0; k < n; ++k) {
    EXPECT_GE(ts[k], (k - 0.01f) / n);
    EXPECT_LE(ts[k], (k + 1.01f) / n);
  }
}

TEST(LightSample, SphereSamplesLieOnItsSilhouetteDisk) {
  const Vec3 c(0.0f, 1.0f, 3.0f);
  const float R = 1.2f;
  const Light light = Light::sphere(c, R);
  const float d = glm::length(c - kP);
  const Vec3 w = (c - kP) / d;
  const float cosMax = std::sqrt(d * d - R * R) / d;  // the silhouette cone
  DVec3 meanDir(0.0);
  for (const LightSample& s : samples(light, kP, 4096)) {
    // The ray ends on the sphere's near surface, inside the cone of the silhouette.
    EXPECT_NEAR(glm::length(samplePoint(kP, s) - c), R, 1e-4f);
    EXPECT_LE(glm::dot(s.wsDirection, (samplePoint(kP, s) - c)), 1e-4f);  // near side: facing p
    EXPECT_GE(glm::dot(s.wsDirection, w), cosMax - 1e-6f);
    // Where the ray meets the silhouette plane, it is inside the silhouette disk.
    const float planeDist = (d * d - R * R) / d;
    const Vec3 onPlane = kP + (planeDist / glm::dot(s.wsDirection, w)) * s.wsDirection;
    EXPECT_LE(glm::length(onPlane - (kP + planeDist * w)), R * std::sqrt(d * d - R * R) / d * (1.0f + 1e-5f));
    meanDir += DVec3(s.wsDirection);
  }
  EXPECT_GT(glm::dot(glm::normalize(Vec3(meanDir)), w), 1.0f - 1e-6f);  // symmetric about the axis
  // A point inside the light: nothing can occlude, distance 0.
  EXPECT_EQ(light.sample(c, Vec2(0.3f, 0.7f)).distance, 0.0f);
}

// A pattern's u-only halves (Light::patternPoint), made once and used from many points as plm's probes
// use them, give every point the sample that sample() gives it, on every shape; a sphere's samples from
// a point inside it keep sample()'s distance 0.
TEST(LightSample, PatternPointsMadeOnceGiveEveryPointItsSample) {
  const std::vector<Light> lights = {
      Light::sphere(Vec3(0, 1, 3), 1.2f),
      Light::disk(Vec3(0, 0, 2), Vec3(0.2f, 0.1f, -1.0f), 0.75f),
      Light::rect(Vec3(0, 0, 2), Vec3(0.6f, 0, 0), Vec3(0, 0.4f, 0.1f)),
      Light::segment(Vec3(-1, 0, 2), Vec3(1, 0.5f, 2)),
      Light::polygon({Vec3(0, 0, 2), Vec3(2, 0, 2), Vec3(2, 1, 2), Vec3(1, 1, 2), Vec3(1, 2, 2), Vec3(0, 2, 2)}),
      Light::directional(Vec3(0, 1, 1), radians(8.0f), LightProfile::LimbDarkened)};
  const CmjSampler sampler(16);
  for (const Light& light : lights) {
    std::vector<Vec2> us;
    std::vector<LightPatternPoint> pattern;
    for (uint32_t i = 0; i < sampler.count(); ++i) {
      us.push_back(sampler.sample(i, 5));
      pattern.push_back(light.patternPoint(us.back()));
    }
    for (const Vec3& p : {kP, Vec3(1.5f, 0.5f, -3.0f), Vec3(-2.0f, 0.0f, 0.5f), Vec3(0.0f, 1.0f, 3.0f)})
      for (size_t k = 0; k < us.size(); ++k) {
        const LightSample a = light.sampleFrom(p, pattern[k]), b = light.sample(p, us[k]);
        EXPECT_EQ(a.wsDirection, b.wsDirection) << toString(light.shape()) << " sample " << k;
        EXPECT_EQ(a.distance, b.distance) << toString(light.shape()) << " sample " << k;
        EXPECT_EQ(a.weight, b.weight) << toString(light.shape()) << " sample " << k;
      }
  }
  EXPECT_EQ(lights[0].sampleFrom(Vec3(0, 1, 3), lights[0].patternPoint(Vec2(0.3f, 0.7f))).distance, 0.0f);
}

TEST(LightSample, DirectionalSamplesStayWithinHalfTheAngularDiameter) {
  const Vec3 dir = glm::normalize(Vec3(0.3f, 1.0f, -0.4f));
  const float theta = radians(8.0f);
  const Light light = Light::directional(dir, theta);
  DVec3 mean(0.0);
  float widest = 0.0f;
  for (const LightSample& s : samples(light, kP, 4096)) {
    EXPECT_EQ(s.distance, kInfinity);
    EXPECT_EQ(s.weight, 1.0f);
    const float angle = std::acos(std::min(1.0f, glm::dot(s.wsDirection, dir)));
    EXPECT_LE(angle, 0.5f * theta + 1e-4f);
    widest = std::max(widest, angle);
    mean += DVec3(s.wsDirection);
  }
  EXPECT_GT(widest, 0.48f * theta);  // the whole disk is covered
  EXPECT_GT(glm::dot(glm::normalize(Vec3(mean)), dir), 1.0f - 1e-6f);
}

TEST(LightSample, LimbDarkenedWeightsAverageOneAndDarkenTheLimb) {
  const Vec3 dir(0.0f, 0.0f, 1.0f);
  const Light light = Light::directional(dir, radians(10.0f), LightProfile::LimbDarkened);
  double sum = 0.0;
  float centre = 0.0f, limb = 10.0f;
  for (const LightSample& s : samples(light, kP, 4096)) {
    sum += s.weight;
    const float angle = std::acos(std::min(1.0f, glm::dot(s.wsDirection, dir)));
    if (angle < radians(0.5f)) centre = std::max(centre, s.weight);
    if (angle > radians(4.95f)) limb = std::min(limb, s.weight);
  }
  EXPECT_NEAR(sum / 4096.0, 1.0, 1e-3);
  // The law's ends: 1 / (1 - u/3) at the centre, (1 - u) / (1 - u/3) at the limb.
  EXPECT_NEAR(centre, 1.0f / (1.0f - kLimbDarkeningU / 3.0f), 2e-3f);
  EXPECT_NEAR(limb, (1.0f - kLimbDarkeningU) / (1.0f - kLimbDarkeningU / 3.0f), 0.05f);
}

TEST(LightIrradiance, DiskOnItsAxis) {
  // E = L pi r^2 / (r^2 + h^2) on the axis of a disk facing the point. Light::irradiance integrates
  // planar lights with a fixed 64-sample quadrature: measured relative error 0.92% at h = r,
  // 0.22% at h = 2r, 0.03% at h = 6r; the tolerance is 2%.
  const float r = 0.5f;
  const Light light = Light::disk(Vec3(0, 0, 0), Vec3(0, 0, 1), r);
  for (const float h : {0.5f, 1.0f, 3.0f}) {
    const double exact = kPiD * r * r / (r * r + h * h);
    EXPECT_NEAR(light.irradiance(Vec3(0, 0, -h), Vec3(0, 0, 1)), exact, 0.02 * exact) << "h = " << h;
  }
}

// Irradiance under a corner of an a x b rectangle parallel to the receiver at height h (the
// differential-area-to-rectangle form factor times pi L).
double cornerIrradiance(double a, double b, double h) {
  const double A = a / h, B = b / h;
  return 0.5 * (A / std::sqrt(1 + A * A) * std::atan(B / std::sqrt(1 + A * A)) +
                B / std::sqrt(1 + B * B) * std::atan(A / std::sqrt(1 + B * B)));
}

TEST(LightIrradiance, RectAboveACentredPoint) {
  // Measured relative error of the quadrature: 2e-5 at the centre, 4.4e-4 under a corner.
  const Light light = Light::rect(Vec3(0, 0, 2), Vec3(0.6f, 0, 0), Vec3(0, 0.4f, 0));
  const double exact = 4.0 * cornerIrradiance(0.6, 0.4, 2.0);
  EXPECT_NEAR(light.irradiance(Vec3(0.0f), Vec3(0, 0, 1)), exact, 0.002 * exact);
  // Under a corner: the same formula with the full edges.
  const double corner = cornerIrradiance(1.2, 0.8, 2.0);
  EXPECT_NEAR(light.irradiance(Vec3(-0.6f, -0.4f, 0.0f), Vec3(0, 0, 1)), corner, 0.002 * corner);
}

// Lambert's closed form for a uniform polygon of unit radiance seen from p with normal n: E = 1/2
// sum over edges of the angle the edge subtends at p times n . (the unit normal of the plane through p
// and the edge) (Arvo 1995, "Applications of irradiance tensors"). A contour integral: it holds for
// concave polygons too.
double lambertIrradiance(const std::vector<Vec3>& vs, const Vec3& p, const Vec3& n) {
  double sum = 0.0;
  for (size_t i = 0; i < vs.size(); ++i) {
    const DVec3 a = glm::normalize(DVec3(vs[i]) - DVec3(p)),
                b = glm::normalize(DVec3(vs[(i + 1) % vs.size()]) - DVec3(p));
    const double angle = std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));
    sum += angle * glm::dot(DVec3(n), glm::normalize(glm::cross(a, b)));
  }
  return 0.5 * std::abs(sum);
}

TEST(LightIrradiance, ConcavePolygonMatchesLambertsFormula) {
  // The L and the U 2 units above points under and beside them, with a level and a tilted receiver.
  // The area integral estimated from 16384 samples of Light::sample must match the closed form
  // (uniform sampling by area; measured relative error up to 0.04%); Light::irradiance, a 64-sample
  // quadrature for shading, measured up to 1.7% (these points are as near the light as it is wide);
  // tolerances 0.3% and 2%.
  for (const auto& q : {kL, kU}) {
    const std::vector<Vec3> vs = inPlaneZ2(q);
    const Light light = Light::polygon(vs);
    for (const Vec3& p :
         {Vec3(0.5f, 0.5f, 0.0f), Vec3(1.5f, 1.5f, 0.0f), Vec3(-1.0f, 0.3f, 0.0f), Vec3(2.0f, 2.0f, -1.0f)})
      for (const Vec3& n : {Vec3(0, 0, 1), glm::normalize(Vec3(0.3f, -0.2f, 1.0f))}) {
        SCOPED_TRACE(::testing::Message() << "p = (" << p.x << ", " << p.y << ", " << p.z << ")");
        const double exact = lambertIrradiance(vs, p, n);
        double sum = 0.0;
        for (const LightSample& s : samples(light, p, 16384))
          sum += std::max(0.0f, glm::dot(n, s.wsDirection)) * std::abs(s.wsDirection.z) / (s.distance * s.distance);
        const double sampled = light.area() * sum / 16384.0;
        EXPECT_NEAR(sampled, exact, 0.003 * exact);
        EXPECT_NEAR(light.irradiance(p, n), exact, 0.02 * exact);
      }
  }
  // The closed form checks itself against a case with a known answer: a rect's corner formula.
  const Light rect = Light::rect(Vec3(0, 0, 2), Vec3(0.6f, 0, 0), Vec3(0, 0.4f, 0));
  EXPECT_NEAR(lambertIrradiance(rect.vertices(), Vec3(0.0f), Vec3(0, 0, 1)), 4.0 * cornerIrradiance(0.6, 0.4, 2.0),
              1e-6);
}

TEST(LightIrradiance, DirectionalSphereAndIntensity) {
  Light sun = Light::directional(Vec3(0, 1, 1), radians(1.0f));
  sun.setIntensity(3.0f);
  EXPECT_NEAR(sun.irradiance(Vec3(0.0f), Vec3(0, 1, 0)), 3.0f * std::sqrt(0.5f), 1e-5f);
  EXPECT_EQ(sun.irradiance(Vec3(0.0f), Vec3(0, -1, 0)), 0.0f);
  // Sphere: E = pi L (R / d)^2 cos(theta).
  const Light ball = Light::sphere(Vec3(0, 0, 4), 1.0f);
  EXPECT_NEAR(ball.irradiance(Vec3(0.0f), Vec3(0, 0, 1)), kPiD / 16.0, 1e-6);
  EXPECT_NEAR(ball.irradiance(Vec3(0.0f), glm::normalize(Vec3(1, 0, 1))), kPiD / 16.0 * std::sqrt(0.5), 1e-6);
}

TEST(LightGeometry, ExtentAndApparentRadius) {
  const Light disk = Light::disk(Vec3(0.0f), Vec3(0, 1, 0), 2.0f);
  EXPECT_FLOAT_EQ(disk.extent(), 2.0f);
  EXPECT_NEAR(disk.apparentRadius(Vec3(0, -4, 0)), std::asin(0.5f), 1e-6f);
  const Light rect = Light::rect(Vec3(0.0f), Vec3(3, 0, 0), Vec3(0, 4, 0));
  EXPECT_FLOAT_EQ(rect.extent(), 5.0f);
  const Light sun = Light::directional(Vec3(0, 1, 0), radians(2.0f));
  EXPECT_NEAR(sun.apparentRadius(Vec3(5.0f)), radians(1.0f), 1e-7f);
  EXPECT_NEAR(sun.extent(), std::tan(radians(1.0f)), 1e-7f);
  EXPECT_EQ(sun.distanceToCenter(Vec3(0.0f)), kInfinity);
  // The light frame's +z points towards the scene.
  Bounds3 scene;
  scene.extend(Vec3(-1, -5, -1));
  scene.extend(Vec3(1, -3, 1));
  EXPECT_NEAR(sun.lightFrame(scene).z.y, -1.0f, 1e-6f);
  const Light ceiling = Light::disk(Vec3(0, 2, 0), Vec3(0, 1, 0), 0.5f);  // normal pointing away from the scene
  EXPECT_NEAR(ceiling.lightFrame(scene).z.y, -1.0f, 1e-6f);
}

template <class F>
void expectError(F&& f, const std::string& fragment) {
  try {
    f();
    ADD_FAILURE() << "expected an Error mentioning '" << fragment << "'";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(LightFactories, RejectDegenerateLights) {
  const float nan = std::nanf("");
  const Vec3 o(0.0f), z(0, 0, 1);
  expectError([&] { Light::sphere(o, 0.0f); }, "radius");
  expectError([&] { Light::sphere(o, -1.0f); }, "radius");
  expectError([&] { Light::sphere(o, kInfinity); }, "radius");
  expectError([&] { Light::sphere(Vec3(nan, 0, 0), 1.0f); }, "center");
  expectError([&] { Light::disk(o, z, 0.0f); }, "radius");
  expectError([&] { Light::disk(o, Vec3(0.0f), 1.0f); }, "normal");
  expectError([&] { Light::disk(o, Vec3(nan), 1.0f); }, "normal");
  expectError([&] { Light::rect(o, Vec3(0.0f), Vec3(0, 1, 0)); }, "non-zero");
  expectError([&] { Light::rect(o, Vec3(1, 0, 0), Vec3(1, 1, 0)); }, "perpendicular");
  expectError([&] { Light::rect(o, Vec3(1, 0, 0), Vec3(0, nan, 0)); }, "rect v");
  expectError([&] { Light::segment(Vec3(1.0f), Vec3(1.0f)); }, "differ");
  expectError([&] { Light::segment(Vec3(1.0f), Vec3(kInfinity)); }, "segment b");
  expectError([&] { Light::polygon({Vec3(0.0f), Vec3(1, 0, 0)}); }, "at least 3");
  expectError([&] { Light::polygon({Vec3(0.0f), Vec3(1, 0, 0), Vec3(2, 0, 0)}); }, "zero area");
  expectError([&] { Light::polygon({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0.5f), Vec3(0, 1, 0)}); }, "not planar");
  // Simple polygons only: the messages name the vertices or edges (edge i runs from vertex i to i + 1).
  expectError(
      [&] {
        Light::polygon({Vec3(0, 0, 0), Vec3(1, 1, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
      },
      "polygon edges 0 and 2 cross; expected a simple polygon");
  expectError(
      [&] {
        Light::polygon({Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(2, 2, 0), Vec3(0, 2, 0), Vec3(1, -1, 0)});
      },
      "polygon edges 0 and 3 cross");
  expectError(
      [&] {
        Light::polygon({Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0)});
      },
      "polygon edges 0 and 1 overlap");
  expectError(
      [&] {
        Light::polygon({Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(2, 2, 0), Vec3(1, 0, 0), Vec3(0, 2, 0)});
      },
      "polygon edges 0 and 2 touch");
  expectError(
      [&] {
        Light::polygon({Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, 1, 0), Vec3(2, 2, 0), Vec3(1, 1, 0), Vec3(0, 2, 0)});
      },
      "polygon vertices 2 and 4 coincide; expected distinct vertices");
  expectError(
      [&] {
        Light::polygon({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
      },
      "vertices 1 and 2 coincide");
  // A bow tie has no net area, but its crossing is what is wrong with it.
  expectError(
      [&] {
        Light::polygon({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)});
      },
      "edges 1 and 3 cross");
  expectError(
      [&] {
        Light::polygon({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0.5f), Vec3(0.5f, 0.5f, 0), Vec3(0, 1, 0)});
      },
      "not planar");
  expectError([&] { Light::polygon({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(nan, 1, 0)}); }, "vertex 2");
  expectError([&] { Light::directional(z, 0.0f); }, "angular_diameter");
  expectError([&] { Light::directional(z, kPi); }, "angular_diameter");
  expectError([&] { Light::directional(z, nan); }, "angular_diameter");
  expectError([&] { Light::directional(Vec3(0.0f), radians(1.0f)); }, "direction");
  Light ok = Light::sphere(o, 1.0f);
  expectError([&] { ok.setIntensity(-1.0f); }, "intensity");
  expectError([&] { ok.setIntensity(nan); }, "intensity");
  EXPECT_NO_THROW(Light::polygon({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)}));
  // Concave polygons are lights too; a straight corner (collinear vertices) is no problem.
  EXPECT_FALSE(Light::polygon({Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0.5f, 0.5f, 0), Vec3(0, 2, 0)}).convex());
  EXPECT_TRUE(Light::polygon({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(2, 1, 0), Vec3(0, 1, 0)}).convex());
}

}  // namespace
}  // namespace penumbra
