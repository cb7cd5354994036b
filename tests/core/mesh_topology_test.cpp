// Tests of the mesh topology module (src/core/mesh_topology.cpp): welding by exact position, and
// welding and adjacency of closed
// meshes (every edge has a neighbour, Euler's formula), reflex-edge detection on the concave U slab
// of `concave`, silhouettes as rings with counts known in closed form (a box seen from above and
// from a corner direction, a torus seen along its axis), planar open meshes as two-sided sheets,
// and the occluder checks of Rouf 2007 Section 1.3: a hole, a flipped triangle and a fin each give
// an Error naming the object and the defect; degenerate triangles are dropped.
#include "penumbra/mesh_topology.h"

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

std::string errorOf(const Mesh& mesh) {
  try {
    occluderTopology(mesh, "the mesh", "ssv");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
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
  const MeshTopology m = occluderTopology(scene.objects.at(1).mesh, "U", "ssv");
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
  const MeshTopology m = occluderTopology(makePlane(4.0f, 4.0f), "ground", "ssv");
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

TEST(MeshTopology, BrokenOccludersAreRefusedWithTheDefectNamed) {
  Mesh hole = makeBox(Vec3(1.0f));
  hole.triangles.pop_back();
  std::string e = errorOf(hole);
  EXPECT_NE(e.find("'the mesh'"), std::string::npos) << e;
  EXPECT_NE(e.find("not closed"), std::string::npos) << e;
  EXPECT_NE(e.find("hole"), std::string::npos) << e;

  Mesh flipped = makeBox(Vec3(1.0f));
  std::swap(flipped.triangles[0].y, flipped.triangles[0].z);
  e = errorOf(flipped);
  EXPECT_NE(e.find("inconsistent winding"), std::string::npos) << e;

  Mesh fin = makeBox(Vec3(1.0f));
  const glm::uvec3 t0 = fin.triangles[0];
  fin.positions.push_back(Vec3(3.0f, 3.0f, 3.0f));
  fin.triangles.push_back({t0.x, t0.y, static_cast<uint32_t>(fin.positions.size() - 1)});
  e = errorOf(fin);
  EXPECT_NE(e.find("non-manifold"), std::string::npos) << e;

  // A non-planar open mesh is not a sheet: two faces of a box.
  Mesh corner = makeBox(Vec3(1.0f));
  corner.triangles.resize(4);
  e = errorOf(corner);
  EXPECT_NE(e.find("not closed"), std::string::npos) << e;
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
  const MeshTopology m = occluderTopology(box, "box", "ssv");
  EXPECT_EQ(m.droppedDegenerate, 3u);
  EXPECT_TRUE(m.closed());
  EXPECT_EQ(m.triangleCount(), 12u);
}

}  // namespace
}  // namespace penumbra
