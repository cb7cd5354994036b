// Tests of the mesh topology module (src/techniques/silhouette/mesh_topology.cpp): welding by exact position, and
// welding and adjacency of closed meshes (every edge has a neighbour, Euler's formula), reflex-edge
// detection on the concave U slab of `concave`, silhouettes as rings with counts known in closed
// form (a box seen from above and from a corner direction, a torus seen along its axis), planar
// open meshes as two-sided sheets, degenerate triangles dropped, and occluders that are not closed
// 2-manifolds (mesh_topology.h's rule): a box with a hole, with a flipped triangle, two boxes
// sharing an edge, a fin on a box, duplicated triangles, a bowl, a Moebius strip and a "book" of
// pages on one edge each give a topology whose neighbours are symmetric and run opposite ways,
// whose boundary of any triangle set (random sets, and the facets facing points around it) splits
// into closed rings, and whose facing set's boundary, projected from a point, winds around
// exactly the points of the ground hidden from it by the mesh's triangles (an independent
// segment-triangle test); for shells the winding equals the number of triangles crossed.
// Orientation repair makes a closed box with a flipped triangle, and an inside-out box, solids,
// and winds a shell consistently.
#include "techniques/silhouette/mesh_topology.h"

#include <gtest/gtest.h>

#include <cmath>

#include "penumbra/error.h"
#include "penumbra/primitives.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

std::vector<uint8_t> facing(const MeshTopology& m, const Vec3& point) {
  std::vector<uint8_t> f(m.triangles.size());
  for (size_t t = 0; t < f.size(); ++t) f[t] = glm::dot(m.faceNormals[t], point - m.positions[m.triangles[t].x]) > 0.0f;
  return f;
}

void expectRingsChain(const std::vector<std::vector<SilhouetteEdge>>& rings) {
  for (const auto& ring : rings)
    for (size_t i = 0; i < ring.size(); ++i) EXPECT_EQ(ring[i].b, ring[(i + 1) % ring.size()].a);
}

// Every half-edge has a neighbour across it, which has the same edge running the other way and has
// this triangle across it.
void expectClosedOriented(const MeshTopology& m, const std::string& what) {
  ASSERT_EQ(m.neighbours.size(), m.triangles.size()) << what;
  size_t bad = 0;
  for (uint32_t t = 0; t < m.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = m.neighbours[t][k];
      if (u == kNoNeighbour || u >= m.triangleCount()) {
        ++bad;
        continue;
      }
      const uint32_t a = m.triangles[t][k], b = m.triangles[t][(k + 1) % 3];
      int back = -1;
      for (int j = 0; j < 3; ++j)
        if (m.triangles[u][j] == b && m.triangles[u][(j + 1) % 3] == a) back = j;
      bad += back < 0 || m.neighbours[u][back] != t;
    }
  EXPECT_EQ(bad, 0u) << what << ": half-edges without an opposite partner";
}

// The boundary of `inSet` splits into closed rings using every boundary edge once.
void expectRingsClose(const MeshTopology& m, const std::vector<uint8_t>& inSet, const std::string& what) {
  const std::vector<SilhouetteEdge> edges = boundaryEdges(m, inSet);
  std::vector<std::vector<SilhouetteEdge>> rings;
  ASSERT_NO_THROW(rings = silhouetteRings(m, edges)) << what;
  size_t total = 0;
  for (const auto& ring : rings) {
    total += ring.size();
    for (size_t i = 0; i < ring.size(); ++i) ASSERT_EQ(ring[i].b, ring[(i + 1) % ring.size()].a) << what;
  }
  EXPECT_EQ(total, edges.size()) << what;
}

// Segment p -> q crosses triangle (a, b, c) (Moeller-Trumbore, in double).
bool segmentCrosses(const glm::dvec3& p, const glm::dvec3& q, const glm::dvec3& a, const glm::dvec3& b,
                    const glm::dvec3& c) {
  const glm::dvec3 d = q - p, e1 = b - a, e2 = c - a;
  const glm::dvec3 h = glm::cross(d, e2);
  const double det = glm::dot(e1, h);
  if (std::abs(det) < 1e-300) return false;
  const glm::dvec3 s = p - a;
  const double u = glm::dot(s, h) / det;
  if (u < 0.0 || u > 1.0) return false;
  const glm::dvec3 qv = glm::cross(s, e1);
  const double v = glm::dot(d, qv) / det;
  if (v < 0.0 || u + v > 1.0) return false;
  const double t = glm::dot(e2, qv) / det;
  return t > 0.0 && t < 1.0;
}

// The silhouette seen from the point `eye` above the mesh (the boundary of the facets facing it),
// projected from `eye` onto the plane y = 0, must wind around a point q of that plane exactly when
// the segment eye -> q crosses a triangle of the input mesh; an all-shell topology winds once per
// triangle crossed. Checked on a grid of points (offset so no segment grazes an edge).
void expectSilhouetteWindsAroundShadow(const Mesh& mesh, const MeshTopology& m, const Vec3& eye,
                                       const std::string& what) {
  const std::vector<SilhouetteEdge> edges = boundaryEdges(m, facing(m, eye));
  const glm::dvec3 e(eye);
  auto project = [&](const Vec3& x) {
    const glm::dvec3 d = glm::dvec3(x) - e;
    return glm::dvec2(e.x + d.x * (-e.y / d.y), e.z + d.z * (-e.y / d.y));
  };
  const bool allShell = m.solidComponents == 0;
  size_t checked = 0, hidden = 0, wrong = 0;
  for (int iy = 0; iy < 41; ++iy)
    for (int ix = 0; ix < 41; ++ix) {
      const glm::dvec2 q(-3.0 + 6.0 * (ix + 0.3183) / 41.0, -3.0 + 6.0 * (iy + 0.2718) / 41.0);
      int winding = 0;
      for (const SilhouetteEdge& s : edges) {
        const glm::dvec2 a = project(m.positions[s.a]), b = project(m.positions[s.b]);
        const double side = (b.x - a.x) * (q.y - a.y) - (q.x - a.x) * (b.y - a.y);
        if (a.y <= q.y)
          winding += (b.y > q.y && side > 0.0) ? 1 : 0;
        else
          winding -= (b.y <= q.y && side < 0.0) ? 1 : 0;
      }
      int crossed = 0;
      for (const glm::uvec3& t : mesh.triangles)
        crossed += segmentCrosses(e, glm::dvec3(q.x, 0.0, q.y), glm::dvec3(mesh.positions[t.x]),
                                  glm::dvec3(mesh.positions[t.y]), glm::dvec3(mesh.positions[t.z]));
      ++checked;
      hidden += crossed > 0;
      wrong += (winding != 0) != (crossed > 0);
      // Duplicated triangles are one triangle of the topology: compare with the distinct ones.
      if (allShell && m.droppedDuplicates == 0) wrong += std::abs(winding) != crossed;
    }
  EXPECT_GT(hidden, 20u) << what << ": the mesh hides part of the grid";
  EXPECT_LT(hidden, checked) << what;
  EXPECT_EQ(wrong, 0u) << what << ": the silhouette's winding disagrees with the segment test";
}

// The checks above, for the facets facing points around the mesh and for random triangle sets.
void expectUsableOccluder(const Mesh& mesh, const std::string& what) {
  const MeshTopology m = occluderTopology(mesh);
  expectClosedOriented(m, what);
  ASSERT_EQ(m.surfaceTriangles + m.copyOf.size(), m.triangleCount()) << what;
  for (const Vec3& eye :
       {Vec3(0.3f, 5.0f, 0.2f), Vec3(5.0f, 6.0f, 7.0f), Vec3(-4.0f, -3.0f, 1.0f), Vec3(0.1f, 0.2f, 0.3f)})
    expectRingsClose(m, facing(m, eye), what + " (facing a point)");
  uint32_t state = 12345u;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<uint8_t> set(m.triangleCount());
    for (uint8_t& x : set) {
      state = state * 1664525u + 1013904223u;
      x = (state >> 16) % 3 == 0;
    }
    expectRingsClose(m, set, what + " (random set)");
  }
  expectSilhouetteWindsAroundShadow(mesh, m, Vec3(0.31f, 6.0f, 0.17f), what + " (from above)");
  expectSilhouetteWindsAroundShadow(mesh, m, Vec3(2.1f, 4.0f, -1.3f), what + " (from the side)");
}

Mesh lifted(Mesh mesh, float y = 1.0f) {
  for (Vec3& p : mesh.positions) p.y += y;
  return mesh;
}

TEST(MeshTopology, WeldingMergesBitIdenticalPositionsInOrderOfFirstOccurrence) {
  // -0 and +0 are one point; a position one ulp away is another; ids follow first occurrence.
  const float next = std::nextafter(1.0f, 2.0f);
  const std::vector<Vec3> positions = {Vec3(1.0f, 0.0f, 2.0f), Vec3(3.0f), Vec3(1.0f, -0.0f, 2.0f),
                                       Vec3(next, 0.0f, 2.0f), Vec3(3.0f), Vec3(1.0f, 0.0f, 2.0f)};
  EXPECT_EQ(firstVertexAtSamePosition(positions), (std::vector<uint32_t>{0, 1, 0, 3, 1, 0}));
  std::vector<Vec3> welded;
  EXPECT_EQ(weldVertices(positions, welded), (std::vector<uint32_t>{0, 1, 0, 2, 1, 0}));
  ASSERT_EQ(welded.size(), 3u);
  EXPECT_EQ(welded[2], Vec3(next, 0.0f, 2.0f));
  EXPECT_TRUE(weldVertices({}, welded).empty());
  EXPECT_TRUE(welded.empty());
}

TEST(MeshTopology, BoxIsClosedWeldedAndConvex) {
  const MeshTopology m = buildMeshTopology(makeBox(Vec3(1.0f, 2.0f, 3.0f)));
  EXPECT_EQ(m.vertexCount(), 8u);  // corners repeated per face are welded
  EXPECT_EQ(m.triangleCount(), 12u);
  EXPECT_TRUE(m.closed());
  // Euler: V - E + F = 2 with E = 3F/2 for a closed triangle mesh of genus 0.
  EXPECT_EQ(int(m.vertexCount()) - int(3 * m.triangleCount() / 2) + int(m.triangleCount()), 2);
  for (uint32_t t = 0; t < m.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) {
      ASSERT_NE(m.neighbours[t][k], kNoNeighbour);
      EXPECT_TRUE(m.convexEdge(t, k));
    }
}

TEST(MeshTopology, ConcaveSlabHasExactlyTheNotchEdgesReflex) {
  const Scene scene = loadScene("concave");
  const MeshTopology m = occluderTopology(scene.objects.at(1).mesh);
  ASSERT_TRUE(m.closed());
  int reflexHalfEdges = 0;
  for (uint32_t t = 0; t < m.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) reflexHalfEdges += !m.convexEdge(t, k);
  // The two vertical edges at the inner corners of the notch, seen from both of their triangles.
  EXPECT_EQ(reflexHalfEdges, 4);
}

TEST(MeshTopology, BoxSilhouettes) {
  const MeshTopology m = buildMeshTopology(makeBox(Vec3(1.0f)));
  // From straight above: only the top face faces the point; its outline, 4 edges, one ring.
  auto rings = silhouetteRings(m, boundaryEdges(m, facing(m, Vec3(0.0f, 5.0f, 0.0f))));
  ASSERT_EQ(rings.size(), 1u);
  EXPECT_EQ(rings[0].size(), 4u);
  expectRingsChain(rings);
  // From a corner direction: three faces, a hexagonal outline.
  rings = silhouetteRings(m, boundaryEdges(m, facing(m, Vec3(5.0f, 6.0f, 7.0f))));
  ASSERT_EQ(rings.size(), 1u);
  EXPECT_EQ(rings[0].size(), 6u);
  expectRingsChain(rings);
}

TEST(MeshTopology, TorusSeenAlongItsAxisHasTwoRings) {
  const MeshTopology m = buildMeshTopology(makeTorus(1.0f, 0.3f, 48, 24));
  ASSERT_TRUE(m.closed());
  const auto rings = silhouetteRings(m, boundaryEdges(m, facing(m, Vec3(0.0f, 50.0f, 0.0f))));
  ASSERT_EQ(rings.size(), 2u);  // the outer and the inner contour
  EXPECT_EQ(rings[0].size(), 48u);
  EXPECT_EQ(rings[1].size(), 48u);
  expectRingsChain(rings);
}

TEST(MeshTopology, PlanarOpenMeshIsATwoSidedSheet) {
  const MeshTopology plain = buildMeshTopology(makePlane(4.0f, 4.0f));
  EXPECT_EQ(plain.boundaryEdges, 4u);
  EXPECT_TRUE(plain.planar);
  const MeshTopology m = occluderTopology(makePlane(4.0f, 4.0f));
  EXPECT_TRUE(m.twoSidedSheet);
  EXPECT_EQ(m.triangleCount(), 4u);
  for (uint32_t t = 0; t < m.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k) ASSERT_NE(m.neighbours[t][k], kNoNeighbour);
  // From above, the front face is lit and the back face is not: the sheet's outline is one ring.
  const auto rings = silhouetteRings(m, boundaryEdges(m, facing(m, Vec3(0.3f, 5.0f, 0.2f))));
  ASSERT_EQ(rings.size(), 1u);
  EXPECT_EQ(rings[0].size(), 4u);
  expectRingsChain(rings);
}

TEST(MeshTopology, BoxWithAHoleIsADoubledShell) {
  Mesh hole = lifted(makeBox(Vec3(1.0f)));
  hole.triangles.pop_back();
  const MeshTopology m = occluderTopology(hole);
  EXPECT_EQ(m.boundaryEdges, 3u);
  EXPECT_EQ(m.solidComponents, 0u);
  EXPECT_EQ(m.shellComponents, 1u);
  EXPECT_EQ(m.triangleCount(), 22u);
  EXPECT_FALSE(m.twoSidedSheet);
  // The hole's three edges join each triangle at the hole to its own reversed copy.
  size_t toOwnCopy = 0;
  for (size_t i = 0; i < m.copyOf.size(); ++i)
    for (int k = 0; k < 3; ++k) toOwnCopy += m.neighbours[m.surfaceTriangles + i][k] == m.copyOf[i];
  EXPECT_EQ(toOwnCopy, 3u);
  expectUsableOccluder(hole, "box with a hole");

  // With a flipped triangle too: the shell is wound consistently (as its first triangle), so its
  // front sides are all outside or all inside (wedges tells a shell's two layers apart by this).
  Mesh flipped = hole;
  std::swap(flipped.triangles[4].y, flipped.triangles[4].z);
  const MeshTopology f = occluderTopology(flipped);
  EXPECT_EQ(f.shellComponents, 1u);
  EXPECT_EQ(f.flippedTriangles, 1u);
  for (size_t t = 0; t < f.surfaceTriangles; ++t) EXPECT_GT(glm::dot(f.faceNormals[t], hole.faceNormal(t)), 0.99f) << t;
  expectUsableOccluder(flipped, "box with a hole and a flipped triangle");
}

TEST(MeshTopology, OrientationRepairMakesABoxWithAFlippedTriangleASolid) {
  Mesh flipped = lifted(makeBox(Vec3(1.0f)));
  std::swap(flipped.triangles[5].y, flipped.triangles[5].z);
  const MeshTopology m = occluderTopology(flipped);
  EXPECT_EQ(m.inconsistentEdges, 3u);
  EXPECT_EQ(m.solidComponents, 1u);
  EXPECT_EQ(m.shellComponents, 0u);
  EXPECT_EQ(m.flippedTriangles, 1u);
  ASSERT_EQ(m.triangleCount(), 12u);
  // Repaired: the box's own winding (outwards) everywhere.
  const Mesh box = lifted(makeBox(Vec3(1.0f)));
  for (size_t t = 0; t < 12; ++t) EXPECT_GT(glm::dot(m.faceNormals[t], box.faceNormal(t)), 0.99f) << t;
  expectUsableOccluder(flipped, "box with a flipped triangle");

  // Inside out: every triangle reversed. The component is flipped as a whole.
  Mesh inverted = lifted(makeBox(Vec3(1.0f)));
  for (glm::uvec3& t : inverted.triangles) std::swap(t.y, t.z);
  const MeshTopology inv = occluderTopology(inverted);
  EXPECT_EQ(inv.solidComponents, 1u);
  EXPECT_EQ(inv.flippedTriangles, 12u);
  for (size_t t = 0; t < 12; ++t) EXPECT_GT(glm::dot(inv.faceNormals[t], box.faceNormal(t)), 0.99f) << t;
}

TEST(MeshTopology, TwoBoxesSharingAnEdgeAreTwoSolids) {
  // Two unit boxes touching along the edge x = 0, y = 1.5 (four triangles on it): each is closed on
  // its own, so both stay solids, paired within each box at the shared edge.
  Mesh m = lifted(makeBox(Vec3(1.0f)), 1.0f);
  for (Vec3& p : m.positions) p += Vec3(-0.5f, 0.0f, 0.0f);
  Mesh other = lifted(makeBox(Vec3(1.0f)), 2.0f);
  for (Vec3& p : other.positions) p += Vec3(0.5f, 0.0f, 0.0f);
  const auto n = static_cast<uint32_t>(m.positions.size());
  m.positions.insert(m.positions.end(), other.positions.begin(), other.positions.end());
  for (const glm::uvec3& t : other.triangles) m.triangles.push_back(t + glm::uvec3(n));
  const MeshTopology t = occluderTopology(m);
  EXPECT_EQ(t.nonManifoldEdges, 1u);
  EXPECT_EQ(t.solidComponents, 2u);
  EXPECT_EQ(t.shellComponents, 0u);
  EXPECT_EQ(t.triangleCount(), 24u);
  expectUsableOccluder(m, "two boxes sharing an edge");
}

TEST(MeshTopology, FinOnABoxAndABookOfPages) {
  // A box with one extra triangle on one of its edges: the box stays a solid, the fin is a shell.
  Mesh fin = lifted(makeBox(Vec3(1.0f)));
  const glm::uvec3 t0 = fin.triangles[0];
  fin.positions.push_back(Vec3(1.5f, 2.5f, 1.5f));
  fin.triangles.push_back({t0.x, t0.y, static_cast<uint32_t>(fin.positions.size() - 1)});
  const MeshTopology f = occluderTopology(fin);
  EXPECT_EQ(f.nonManifoldEdges, 1u);
  EXPECT_EQ(f.solidComponents, 1u);
  EXPECT_EQ(f.shellComponents, 1u);
  EXPECT_EQ(f.triangleCount(), 14u);
  expectUsableOccluder(fin, "fin on a box");

  // Five pages on one edge, wound either way, at angles out of order: every sector between two
  // pages is closed by the two sides facing it.
  Mesh book;
  book.positions = {Vec3(-0.8f, 1.5f, 0.0f), Vec3(0.8f, 1.5f, 0.0f)};
  const float angles[5] = {200.0f, 20.0f, 290.0f, 65.0f, 120.0f};
  for (int page = 0; page < 5; ++page) {
    const float a = radians(angles[page]);
    book.positions.push_back(Vec3(0.1f * page, 1.5f + std::sin(a), std::cos(a)));
    const auto c = static_cast<uint32_t>(book.positions.size() - 1);
    book.triangles.push_back(page % 2 ? glm::uvec3(0u, 1u, c) : glm::uvec3(1u, 0u, c));
  }
  const MeshTopology b = occluderTopology(book);
  EXPECT_EQ(b.nonManifoldEdges, 1u);
  EXPECT_EQ(b.shellComponents, 5u);
  // Across the shared edge each side's neighbour is the next page in the direction the side faces
  // (the sector it bounds); across its free edges, its own other side.
  const Vec3 axis(1.0f, 0.0f, 0.0f);
  auto angleOf = [&](uint32_t page) {
    const Vec3 r = book.positions[2 + page] - book.positions[0];
    return std::atan2(-r.y, r.z);  // right-handed about +x: from +z towards cross(+x, +z) = -y
  };
  for (uint32_t t = 0; t < b.triangleCount(); ++t) {
    const uint32_t page = t < b.surfaceTriangles ? t : b.copyOf[t - b.surfaceTriangles];
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = b.neighbours[t][k];
      const uint32_t other = u < b.surfaceTriangles ? u : b.copyOf[u - b.surfaceTriangles];
      const bool sharedEdge = std::max(b.triangles[t][k], b.triangles[t][(k + 1) % 3]) == 1u;
      if (!sharedEdge) {
        EXPECT_EQ(other, page) << t << " " << k;
        continue;
      }
      const Vec3 r = book.positions[2 + page] - book.positions[0];
      const float turn = glm::dot(b.faceNormals[t], glm::cross(axis, r)) > 0.0f ? 1.0f : -1.0f;
      uint32_t next = page;
      float best = 10.0f;
      for (uint32_t q = 0; q < 5; ++q) {
        if (q == page) continue;
        float d = turn * (angleOf(q) - angleOf(page));
        while (d <= 0.0f) d += 2.0f * kPi;
        if (d < best) {
          best = d;
          next = q;
        }
      }
      EXPECT_EQ(other, next) << "side " << t << " of page " << page;
    }
  }
  expectUsableOccluder(book, "book of pages");
}

TEST(MeshTopology, DuplicatedTrianglesAreOne) {
  // A box whose every triangle is there twice, and once more reversed: the box, a solid.
  const Mesh box = lifted(makeBox(Vec3(1.0f)));
  Mesh dup = box;
  for (const glm::uvec3& t : box.triangles) dup.triangles.push_back(t);
  for (const glm::uvec3& t : box.triangles) dup.triangles.push_back({t.x, t.z, t.y});
  const MeshTopology m = occluderTopology(dup);
  EXPECT_EQ(m.droppedDuplicates, 24u);
  EXPECT_EQ(m.solidComponents, 1u);
  EXPECT_EQ(m.triangleCount(), 12u);
  expectUsableOccluder(dup, "box with duplicated triangles");

  // A duplicated triangle in an open mesh, and two triangles that overlap in a coincident edge and
  // plane but are not the same (a zero-width sector between them).
  Mesh open = lifted(makeBox(Vec3(1.0f)));
  open.triangles.resize(8);
  open.triangles.push_back(open.triangles[3]);
  const glm::uvec3 t3 = open.triangles[3];
  open.positions.push_back(0.5f * (open.positions[t3.z] + open.positions[t3.x]));
  open.triangles.push_back({t3.x, t3.y, static_cast<uint32_t>(open.positions.size() - 1)});
  const MeshTopology o = occluderTopology(open);
  EXPECT_EQ(o.droppedDuplicates, 1u);
  EXPECT_EQ(o.solidComponents, 0u);
  expectClosedOriented(o, "open box with overlapping triangles");
  for (const Vec3& eye : {Vec3(0.3f, 5.0f, 0.2f), Vec3(5.0f, 6.0f, 7.0f), Vec3(0.1f, 0.2f, 0.3f)})
    expectRingsClose(o, facing(o, eye), "open box with overlapping triangles");
}

TEST(MeshTopology, BowlAndMoebiusStrip) {
  // A bowl: the lower half of a sphere, open at the top.
  Mesh bowl = makeSphere(1.0f, 24, 12);
  std::vector<glm::uvec3> lower;
  for (const glm::uvec3& t : bowl.triangles)
    if (bowl.positions[t.x].y + bowl.positions[t.y].y + bowl.positions[t.z].y < 0.0f) lower.push_back(t);
  bowl.triangles = lower;
  bowl = lifted(bowl, 1.5f);
  const MeshTopology m = occluderTopology(bowl);
  EXPECT_EQ(m.boundaryEdges, 24u);
  EXPECT_EQ(m.shellComponents, 1u);
  EXPECT_EQ(m.triangleCount(), 2 * bowl.triangles.size());
  expectUsableOccluder(bowl, "bowl");

  // A Moebius strip cannot be wound consistently: a shell.
  Mesh strip;
  const int segments = 24;
  for (int s = 0; s < segments; ++s) {
    const float a = 2.0f * kPi * s / segments;
    for (const float w : {-0.3f, 0.3f}) {
      const float r = 1.0f + w * std::cos(0.5f * a);
      strip.positions.push_back(Vec3(r * std::cos(a), 1.5f + w * std::sin(0.5f * a), r * std::sin(a)));
    }
  }
  for (int s = 0; s < segments; ++s) {
    const auto a0 = uint32_t(2 * s), a1 = uint32_t(2 * s + 1);
    // The last segment joins the first with its two rails swapped (the half twist).
    const uint32_t b0 = s + 1 < segments ? a0 + 2 : 1u, b1 = s + 1 < segments ? a1 + 2 : 0u;
    strip.triangles.push_back({a0, b0, b1});
    strip.triangles.push_back({a0, b1, a1});
  }
  const MeshTopology mo = occluderTopology(strip);
  EXPECT_EQ(mo.solidComponents, 0u);
  EXPECT_EQ(mo.shellComponents, 1u);
  expectUsableOccluder(strip, "Moebius strip");
}

TEST(MeshTopology, DegenerateTrianglesAreDropped) {
  Mesh box = makeBox(Vec3(1.0f));
  const auto n = static_cast<uint32_t>(box.positions.size());
  box.positions.push_back(Vec3(0.2f, 0.2f, 0.1f));
  box.positions.push_back(Vec3(0.2f, 0.2f, 0.1f));
  box.positions.push_back(Vec3(0.4f, 0.4f, 0.3f));
  box.positions.push_back(Vec3(0.6f, 0.6f, 0.5f));
  box.triangles.push_back({n, n + 1, n + 2});
  box.triangles.push_back({n, n + 2, n + 3});
  box.triangles.push_back({0u, 0u, 0u});
  const MeshTopology m = occluderTopology(box);
  EXPECT_EQ(m.droppedDegenerate, 3u);
  EXPECT_TRUE(m.closed());
  EXPECT_EQ(m.triangleCount(), 12u);
}

}  // namespace
}  // namespace penumbra
