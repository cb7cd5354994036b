// Tiny scenes built in code for the ray-tracing and technique tests: quads (2-triangle meshes),
// fine regular polygons standing in for disks, and hand-made G-buffers of a few pixels, so a test
// evaluates V exactly where its closed form is known instead of rendering whole images.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "penumbra/gbuffer.h"
#include "penumbra/scene.h"

namespace penumbra::testing {

// The parallelogram c +- u +- v, wound so its face normal is cross(u, v).
inline Mesh quadMesh(const Vec3& c, const Vec3& u, const Vec3& v) {
  Mesh m;
  m.positions = {c - u - v, c + u - v, c + u + v, c - u + v};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

// A regular polygon with `sides` vertices on the circle of `radius` (inscribed), in the plane
// through c spanned by the unit vectors u and v, as a triangle fan around c.
inline Mesh regularPolygonMesh(const Vec3& c, const Vec3& u, const Vec3& v, float radius, int sides) {
  Mesh m;
  m.positions.push_back(c);
  for (int i = 0; i < sides; ++i) {
    const double a = 2.0 * 3.14159265358979323846 * i / sides;
    m.positions.push_back(c + radius * (static_cast<float>(std::cos(a)) * u + static_cast<float>(std::sin(a)) * v));
  }
  for (int i = 0; i < sides; ++i)
    m.triangles.push_back({0u, static_cast<unsigned>(1 + i), static_cast<unsigned>(1 + (i + 1) % sides)});
  return m;
}

inline Object makeObject(int32_t id, Mesh mesh, const std::string& name = "object") {
  Object o;
  o.name = name;
  o.id = id;
  o.mesh = std::move(mesh);
  return o;
}

inline Scene makeScene(std::vector<Object> objects) {
  Scene s;
  s.name = "test";
  s.source = "test scene";
  s.objects = std::move(objects);
  return s;
}

// A G-buffer of points.size() x 1 pixels, all on object `objectId` with the same normal.
inline GBuffer pointsGBuffer(const std::vector<Vec3>& points, const Vec3& wsNormal, int32_t objectId) {
  GBuffer g(static_cast<int>(points.size()), 1);
  for (size_t i = 0; i < points.size(); ++i) {
    const int x = static_cast<int>(i);
    g.wsPosition(x, 0) = points[i];
    g.wsNormal(x, 0) = wsNormal;
    g.wsGeometricNormal(x, 0) = wsNormal;
    g.objectId(x, 0) = objectId;
    g.triangleId(x, 0) = 0;
    g.csDepth(x, 0) = 1.0f;
  }
  return g;
}

}  // namespace penumbra::testing
