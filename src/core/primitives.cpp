// Built-in primitives as indexed triangle meshes in their local frame (include/penumbra/primitives.h).
//
// Every closed primitive is watertight by index: each edge is shared by exactly two triangles with
// opposite orientation, with no duplicated seam or pole vertices, because the Rouf et al. 2007
// silhouette extraction walks edges by vertex index. Triangles are wound counter-clockwise seen from
// outside, so face normals point outwards.
//
// Normals: curved primitives (sphere, torus, cylinder side) carry smooth per-vertex normals taken
// from the analytic surface; the box and the single triangle carry none (flat face normals), which
// is exact for them. A vertex holds one normal, so where a cylinder's side meets a cap the rim
// vertex gets the bisector of the two; to keep that interpolated band thin, the cylinder has an
// extra ring of vertices on each cap and on the side at kCylinderBevel of the radius/height from the
// rim (flat geometry, only normals change there). Units: world units of the scene file.
#include "penumbra/primitives.h"

#include <cmath>

#include "penumbra/error.h"

namespace penumbra {

namespace {

void requirePositive(float value, const char* what) {
  if (!(value > 0.0f) || !std::isfinite(value)) fail("{} must be a finite number > 0 (got {})", what, value);
}

void requireAtLeast(int value, int minimum, const char* what) {
  if (value < minimum) fail("{} must be an integer >= {} (got {})", what, minimum, value);
}

// Adds the two triangles of quad (a, b, c, d), given counter-clockwise seen from outside.
void addQuad(Mesh& m, uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
  m.triangles.emplace_back(a, b, c);
  m.triangles.emplace_back(a, c, d);
}

// Fraction of the cylinder's radius (caps) and height (side) over which normals blend at a rim.
constexpr float kCylinderBevel = 0.01f;

}  // namespace

Mesh makePlane(float sizeX, float sizeZ) {
  requirePositive(sizeX, "plane size x");
  requirePositive(sizeZ, "plane size z");
  const float hx = 0.5f * sizeX, hz = 0.5f * sizeZ;
  Mesh m;
  m.positions = {{-hx, 0.0f, -hz}, {-hx, 0.0f, hz}, {hx, 0.0f, hz}, {hx, 0.0f, -hz}};
  m.normals.assign(4, Vec3(0.0f, 1.0f, 0.0f));
  addQuad(m, 0, 1, 2, 3);  // (b - a) x (c - a) = +y
  return m;
}

Mesh makeBox(const Vec3& size) {
  requirePositive(size.x, "box size x");
  requirePositive(size.y, "box size y");
  requirePositive(size.z, "box size z");
  const Vec3 h = 0.5f * size;
  Mesh m;
  // Vertex i has x = +h.x if bit 0 is set, y if bit 1, z if bit 2.
  for (uint32_t i = 0; i < 8; ++i)
    m.positions.emplace_back((i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z);
  addQuad(m, 0, 4, 6, 2);  // -x
  addQuad(m, 1, 3, 7, 5);  // +x
  addQuad(m, 0, 1, 5, 4);  // -y
  addQuad(m, 2, 6, 7, 3);  // +y
  addQuad(m, 0, 2, 3, 1);  // -z
  addQuad(m, 4, 5, 7, 6);  // +z
  return m;                // flat: no vertex normals
}

Mesh makeSphere(float radius, int segments, int rings) {
  requirePositive(radius, "sphere radius");
  requireAtLeast(segments, 3, "sphere segments");
  requireAtLeast(rings, 2, "sphere rings");
  Mesh m;
  // Vertex 0: north pole (+y); then rings-1 latitude circles of `segments` vertices; last: south pole.
  m.positions.emplace_back(0.0f, radius, 0.0f);
  for (int r = 1; r < rings; ++r) {
    const float theta = kPi * static_cast<float>(r) / static_cast<float>(rings);
    for (int s = 0; s < segments; ++s) {
      const float phi = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(segments);
      m.positions.emplace_back(radius * std::sin(theta) * std::cos(phi), radius * std::cos(theta),
                               -radius * std::sin(theta) * std::sin(phi));
    }
  }
  m.positions.emplace_back(0.0f, -radius, 0.0f);
  m.normals.reserve(m.positions.size());
  for (const Vec3& p : m.positions) m.normals.push_back(p / radius);

  const auto ring = [&](int r, int s) { return static_cast<uint32_t>(1 + (r - 1) * segments + (s % segments)); };
  const uint32_t south = static_cast<uint32_t>(m.positions.size() - 1);
  // phi grows counter-clockwise seen from +y (x towards -z), so seen from outside, going along +phi
  // then towards the south pole is counter-clockwise.
  for (int s = 0; s < segments; ++s) m.triangles.emplace_back(0u, ring(1, s), ring(1, s + 1));
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) addQuad(m, ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s + 1));
  for (int s = 0; s < segments; ++s) m.triangles.emplace_back(south, ring(rings - 1, s + 1), ring(rings - 1, s));
  return m;
}

Mesh makeTorus(float majorRadius, float minorRadius, int majorSegments, int minorSegments) {
  requirePositive(majorRadius, "torus major radius");
  requirePositive(minorRadius, "torus minor radius");
  if (!(minorRadius < majorRadius))
    fail("torus minor radius must be smaller than the major radius (got {} and {})", minorRadius, majorRadius);
  requireAtLeast(majorSegments, 3, "torus major segments");
  requireAtLeast(minorSegments, 3, "torus minor segments");
  Mesh m;
  for (int i = 0; i < majorSegments; ++i) {
    const float phi = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(majorSegments);
    const Vec3 radial(std::cos(phi), 0.0f, -std::sin(phi));  // counter-clockwise seen from +y
    for (int j = 0; j < minorSegments; ++j) {
      const float psi = 2.0f * kPi * static_cast<float>(j) / static_cast<float>(minorSegments);
      const Vec3 n = std::cos(psi) * radial + Vec3(0.0f, std::sin(psi), 0.0f);
      m.positions.push_back(majorRadius * radial + minorRadius * n);
      m.normals.push_back(n);
    }
  }
  const auto index = [&](int i, int j) {
    return static_cast<uint32_t>((i % majorSegments) * minorSegments + (j % minorSegments));
  };
  for (int i = 0; i < majorSegments; ++i)
    for (int j = 0; j < minorSegments; ++j)
      addQuad(m, index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
  return m;
}

Mesh makeCylinder(float radius, float height, int segments) {
  requirePositive(radius, "cylinder radius");
  requirePositive(height, "cylinder height");
  requireAtLeast(segments, 3, "cylinder segments");
  const float h = 0.5f * height;
  const float capInner = radius * (1.0f - kCylinderBevel);
  const float sideInner = h - height * kCylinderBevel;
  Mesh m;
  // Rings from bottom to top: (radius, y, normal's radial and y weights).
  struct Ring {
    float r, y, nRadial, nY;
  };
  const float bisector = 1.0f / std::sqrt(2.0f);
  const Ring rings[6] = {{capInner, -h, 0.0f, -1.0f},      {radius, -h, bisector, -bisector},
                         {radius, -sideInner, 1.0f, 0.0f}, {radius, sideInner, 1.0f, 0.0f},
                         {radius, h, bisector, bisector},  {capInner, h, 0.0f, 1.0f}};
  for (const Ring& ring : rings) {
    for (int s = 0; s < segments; ++s) {
      const float phi = 2.0f * kPi * static_cast<float>(s) / static_cast<float>(segments);
      const Vec3 radial(std::cos(phi), 0.0f, -std::sin(phi));
      m.positions.push_back(ring.r * radial + Vec3(0.0f, ring.y, 0.0f));
      m.normals.push_back(ring.nRadial * radial + Vec3(0.0f, ring.nY, 0.0f));
    }
  }
  const uint32_t bottom = static_cast<uint32_t>(m.positions.size());
  m.positions.emplace_back(0.0f, -h, 0.0f);
  m.normals.emplace_back(0.0f, -1.0f, 0.0f);
  const uint32_t top = bottom + 1;
  m.positions.emplace_back(0.0f, h, 0.0f);
  m.normals.emplace_back(0.0f, 1.0f, 0.0f);

  const auto index = [&](int ring, int s) { return static_cast<uint32_t>(ring * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) {
    m.triangles.emplace_back(bottom, index(0, s + 1), index(0, s));  // seen from -y: counter-clockwise
    for (int ring = 0; ring < 5; ++ring)
      addQuad(m, index(ring, s), index(ring, s + 1), index(ring + 1, s + 1), index(ring + 1, s));
    m.triangles.emplace_back(top, index(5, s), index(5, s + 1));
  }
  return m;
}

Mesh makeTriangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  if (!isFinite(a) || !isFinite(b) || !isFinite(c)) fail("triangle vertices must be finite");
  if (!(glm::length(glm::cross(b - a, c - a)) > 0.0f)) fail("triangle vertices must not be collinear (zero area)");
  Mesh m;
  m.positions = {a, b, c};
  m.triangles.emplace_back(0u, 1u, 2u);
  return m;
}

void transformMesh(Mesh& mesh, const Mat4& wsFromObject) {
  const Mat3 linear(wsFromObject);
  const float det = glm::determinant(linear);
  if (!std::isfinite(det) || det == 0.0f)
    fail(
        "transform is singular or overflows (determinant {}); expected non-zero scale factors whose product is within "
        "float range",
        det);
  for (Vec3& p : mesh.positions) p = Vec3(wsFromObject * Vec4(p, 1.0f));
  const Mat3 normalFromObject = glm::transpose(glm::inverse(linear));
  for (Vec3& n : mesh.normals) {
    const Vec3 t = normalFromObject * n;
    const float len = glm::length(t);
    n = len > 0.0f ? t / len : t;
  }
  // A mirroring transform turns counter-clockwise into clockwise: swap two corners so face
  // normals keep pointing outwards.
  if (det < 0.0f)
    for (glm::uvec3& t : mesh.triangles) std::swap(t.y, t.z);
}

}  // namespace penumbra
