// Tests of the built-in primitives (src/core/primitives.cpp) against exact properties: triangle and
// vertex counts, bounds, watertightness by index (every edge shared by exactly two triangles with
// opposite orientation), outward winding (signed volume > 0 and close to the analytic volume), and
// vertex normals that agree with the analytic surface normal.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include "penumbra/error.h"
#include "penumbra/primitives.h"

namespace penumbra {
namespace {

// Every directed edge appears once, and its reverse appears once: closed, manifold, consistently
// oriented. Returns a description of the first violation, or "" when closed.
std::string closedViolation(const Mesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  for (const auto& [edge, count] : directed) {
    if (count != 1) return fmt::format("directed edge {}->{} used {} times", edge.first, edge.second, count);
    auto it = directed.find({edge.second, edge.first});
    if (it == directed.end()) return fmt::format("edge {}->{} has no opposite", edge.first, edge.second);
  }
  return "";
}

// Divergence theorem: sum over triangles of a . (b x c) / 6.
double signedVolume(const Mesh& m) {
  double v = 0.0;
  for (const glm::uvec3& t : m.triangles)
    v += glm::dot(DVec3(m.positions[t.x]), glm::cross(DVec3(m.positions[t.y]), DVec3(m.positions[t.z]))) / 6.0;
  return v;
}

double surfaceArea(const Mesh& m) {
  double a = 0.0;
  for (const glm::uvec3& t : m.triangles)
    a += 0.5 * glm::length(
                   glm::cross(DVec3(m.positions[t.y] - m.positions[t.x]), DVec3(m.positions[t.z] - m.positions[t.x])));
  return a;
}

void expectIndicesValid(const Mesh& m) {
  for (const glm::uvec3& t : m.triangles) {
    ASSERT_LT(t.x, m.positions.size());
    ASSERT_LT(t.y, m.positions.size());
    ASSERT_LT(t.z, m.positions.size());
  }
  if (!m.normals.empty()) {
    ASSERT_EQ(m.normals.size(), m.positions.size());
  }
  for (const Vec3& n : m.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
}

// Each vertex normal of a triangle leans the same way as the triangle's face normal.
void expectNormalsAgreeWithWinding(const Mesh& m) {
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    const Vec3 fn = m.faceNormal(i);
    for (int k = 0; k < 3; ++k) EXPECT_GT(glm::dot(fn, m.normals[m.triangles[i][k]]), 0.0f) << "triangle " << i;
  }
}

void expectBounds(const Mesh& m, const Vec3& lower, const Vec3& upper, float tol) {
  const Bounds3 b = m.bounds();
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(b.lower[k], lower[k], tol) << "axis " << k;
    EXPECT_NEAR(b.upper[k], upper[k], tol) << "axis " << k;
  }
}

TEST(Primitives, PlaneIsTwoUpFacingTriangles) {
  const Mesh m = makePlane(4.0f, 2.0f);
  expectIndicesValid(m);
  EXPECT_EQ(m.triangleCount(), 2u);
  expectBounds(m, Vec3(-2, 0, -1), Vec3(2, 0, 1), 0.0f);
  for (size_t i = 0; i < m.triangleCount(); ++i) EXPECT_EQ(m.faceNormal(i), Vec3(0, 1, 0));
  EXPECT_NEAR(surfaceArea(m), 8.0, 1e-6);
}

TEST(Primitives, BoxIsClosedWithExactVolume) {
  const Mesh m = makeBox(Vec3(1.0f, 2.0f, 3.0f));
  expectIndicesValid(m);
  EXPECT_EQ(m.triangleCount(), 12u);
  EXPECT_EQ(m.positions.size(), 8u);
  EXPECT_TRUE(m.normals.empty());  // flat faces
  EXPECT_EQ(closedViolation(m), "");
  expectBounds(m, Vec3(-0.5f, -1.0f, -1.5f), Vec3(0.5f, 1.0f, 1.5f), 0.0f);
  EXPECT_NEAR(signedVolume(m), 6.0, 1e-5);
  EXPECT_NEAR(surfaceArea(m), 22.0, 1e-5);
  // Every face normal is an axis pointing away from the centre.
  for (size_t i = 0; i < m.triangleCount(); ++i) {
    const glm::uvec3& t = m.triangles[i];
    const Vec3 centroid = (m.positions[t.x] + m.positions[t.y] + m.positions[t.z]) / 3.0f;
    EXPECT_GT(glm::dot(m.faceNormal(i), centroid), 0.0f);
  }
}

TEST(Primitives, SphereIsClosedOutwardAndConverges) {
  const int segments = 64, rings = 32;
  const Mesh m = makeSphere(2.0f, segments, rings);
  expectIndicesValid(m);
  EXPECT_EQ(m.triangleCount(), static_cast<size_t>(2 * segments * (rings - 1)));
  EXPECT_EQ(m.positions.size(), static_cast<size_t>(2 + segments * (rings - 1)));  // no seam duplicates
  EXPECT_EQ(closedViolation(m), "");
  expectBounds(m, Vec3(-2.0f), Vec3(2.0f), 1e-5f);
  // Inscribed polyhedron: volume slightly below 4/3 pi r^3; measured relative deficit 0.32% at 64x32.
  const double exact = 4.0 / 3.0 * M_PI * 8.0;
  const double v = signedVolume(m);
  EXPECT_LT(v, exact);
  EXPECT_NEAR(v / exact, 1.0, 0.005);
  for (size_t i = 0; i < m.positions.size(); ++i)
    EXPECT_NEAR(glm::distance(m.normals[i], m.positions[i] / 2.0f), 0.0f, 1e-5f);
  expectNormalsAgreeWithWinding(m);
}

TEST(Primitives, CoarseSphereStillClosed) {
  const Mesh m = makeSphere(1.0f, 3, 2);  // two triangular pyramids glued: 6 triangles
  EXPECT_EQ(m.triangleCount(), 6u);
  EXPECT_EQ(closedViolation(m), "");
  EXPECT_GT(signedVolume(m), 0.0);
}

TEST(Primitives, TorusIsClosedOutwardAndConverges) {
  const float R = 1.5f, r = 0.5f;
  const Mesh m = makeTorus(R, r, 96, 48);
  expectIndicesValid(m);
  EXPECT_EQ(m.triangleCount(), static_cast<size_t>(2 * 96 * 48));
  EXPECT_EQ(m.positions.size(), static_cast<size_t>(96 * 48));
  EXPECT_EQ(closedViolation(m), "");
  expectBounds(m, Vec3(-R - r, -r, -R - r), Vec3(R + r, r, R + r), 1e-5f);
  // Exact volume of this polyhedron: each of the M wedges holds sin(2 pi / M) times the integral of
  // the distance to the axis over the regular m-gon cross-section, i.e. sin(2 pi / M) R A_m (the
  // m-gon's centroid lies on the centre circle). It tends to 2 pi^2 R r^2.
  const double polygonArea = 0.5 * 48 * r * r * std::sin(2.0 * M_PI / 48);
  const double exact = 96 * std::sin(2.0 * M_PI / 96) * R * polygonArea;
  EXPECT_NEAR(signedVolume(m) / exact, 1.0, 1e-5);
  EXPECT_NEAR(exact / (2.0 * M_PI * M_PI * R * r * r), 1.0, 0.004);
  // The normal points from the tube's centre circle to the vertex.
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Vec3 p = m.positions[i];
    const Vec3 onCircle = R * glm::normalize(Vec3(p.x, 0.0f, p.z));
    EXPECT_NEAR(glm::distance(m.normals[i], (p - onCircle) / r), 0.0f, 1e-4f);
  }
  expectNormalsAgreeWithWinding(m);
}

TEST(Primitives, CylinderIsClosedOutwardAndConverges) {
  const int segments = 128;
  const Mesh m = makeCylinder(0.5f, 2.0f, segments);
  expectIndicesValid(m);
  EXPECT_EQ(m.triangleCount(), static_cast<size_t>(12 * segments));
  EXPECT_EQ(closedViolation(m), "");
  expectBounds(m, Vec3(-0.5f, -1.0f, -0.5f), Vec3(0.5f, 1.0f, 0.5f), 1e-5f);
  // A prism over the inscribed regular polygon (the extra rim rings lie in the cap and side planes).
  const double exact = 2.0 * 0.5 * segments * 0.25 * std::sin(2.0 * M_PI / segments);
  EXPECT_NEAR(signedVolume(m) / exact, 1.0, 1e-5);
  expectNormalsAgreeWithWinding(m);
  // Away from the rims the normal is the analytic one: radial on the side, +-y on the caps.
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const Vec3 p = m.positions[i];
    const float rho = std::hypot(p.x, p.z);
    if (std::abs(std::abs(p.y) - 1.0f) > 0.05f) {
      EXPECT_NEAR(glm::distance(m.normals[i], Vec3(p.x, 0, p.z) / rho), 0.0f, 1e-5f);
    } else if (rho < 0.45f) {
      EXPECT_EQ(m.normals[i], Vec3(0, std::copysign(1.0f, p.y), 0));
    }
  }
}

TEST(Primitives, TriangleAsGiven) {
  const Mesh m = makeTriangle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0));
  EXPECT_EQ(m.triangleCount(), 1u);
  EXPECT_EQ(m.faceNormal(0), Vec3(0, 0, 1));
  EXPECT_TRUE(m.normals.empty());
}

TEST(Primitives, RejectsDegenerateSizes) {
  EXPECT_THROW(makePlane(0.0f, 1.0f), Error);
  EXPECT_THROW(makeBox(Vec3(1.0f, -1.0f, 1.0f)), Error);
  EXPECT_THROW(makeSphere(1.0f, 2, 8), Error);
  EXPECT_THROW(makeSphere(NAN, 8, 8), Error);
  EXPECT_THROW(makeTorus(1.0f, 1.0f, 8, 8), Error);  // self-intersecting
  EXPECT_THROW(makeCylinder(1.0f, INFINITY, 8), Error);
  EXPECT_THROW(makeTriangle(Vec3(0), Vec3(1), Vec3(2)), Error);  // collinear
  try {
    makeSphere(1.0f, 8, 1);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("sphere rings"), std::string::npos) << e.what();
  }
}

TEST(Primitives, TransformMovesPositionsAndKeepsNormalsPerpendicular) {
  Mesh m = makeSphere(1.0f, 32, 16);
  const Mat4 wsFromObject = glm::scale(glm::translate(Mat4(1.0f), Vec3(1, 2, 3)), Vec3(2.0f, 1.0f, 0.5f));
  transformMesh(m, wsFromObject);
  expectBounds(m, Vec3(-1.0f, 1.0f, 2.5f), Vec3(3.0f, 3.0f, 3.5f), 1e-5f);
  EXPECT_EQ(closedViolation(m), "");
  EXPECT_NEAR(signedVolume(m) / (4.0 / 3.0 * M_PI), 1.0, 0.02);
  // The ellipsoid's normal at p is the gradient of sum(((p - c)_k / a_k)^2): (p - c) / a^2.
  const Vec3 c(1, 2, 3), a(2.0f, 1.0f, 0.5f);
  for (size_t i = 0; i < m.positions.size(); ++i)
    EXPECT_NEAR(glm::distance(m.normals[i], glm::normalize((m.positions[i] - c) / (a * a))), 0.0f, 1e-5f);
  expectNormalsAgreeWithWinding(m);
}

TEST(Primitives, MirrorTransformKeepsOutwardWinding) {
  Mesh m = makeTorus(1.0f, 0.25f, 24, 12);
  const double before = signedVolume(m);
  transformMesh(m, glm::scale(Mat4(1.0f), Vec3(-1.0f, 1.0f, 1.0f)));
  EXPECT_EQ(closedViolation(m), "");
  EXPECT_NEAR(signedVolume(m), before, 1e-5 * before);
  expectNormalsAgreeWithWinding(m);
  EXPECT_THROW(transformMesh(m, glm::scale(Mat4(1.0f), Vec3(1.0f, 0.0f, 1.0f))), Error);
}

}  // namespace
}  // namespace penumbra
