// Tests of the shared edge adjacency (src/techniques/mesh_edges.h), used by plm, smoothies, kirsch
// and parker's outer objects: welding by exact position (-0 as +0), which triangles count, the
// order of edges and uses, and the cache's reuse. Against edge lists written out by hand for small
// meshes, and on a closed sphere against the property that every edge has two opposite uses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "penumbra/primitives.h"
#include "techniques/mesh_edges.h"

namespace penumbra {
namespace {

// Two triangles over a unit square, the shared diagonal's vertices repeated (a split-normal seam),
// one repeat written with -0.
Mesh seamSquare() {
  Mesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 0, 1), Vec3(-0.0f, 0, 0), Vec3(1, 0, 1), Vec3(0, 0, 1)};
  m.triangles = {glm::uvec3(0, 1, 2), glm::uvec3(3, 4, 5)};
  return m;
}

TEST(MeshEdges, WeldsByPositionAndMatchesTheSharedEdge) {
  const Mesh m = seamSquare();
  MeshEdges e;
  e.build(m);
  EXPECT_EQ(e.weld, (std::vector<uint32_t>{0, 1, 2, 0, 2, 5}));  // -0 as +0
  // Five edges, by (low, high): (0,1) (0,2) (0,5) (1,2) (2,5); the diagonal (0,2) used by both.
  EXPECT_EQ(e.low, (std::vector<uint32_t>{0, 0, 0, 1, 2}));
  EXPECT_EQ(e.high, (std::vector<uint32_t>{1, 2, 5, 2, 5}));
  EXPECT_EQ(e.firstUse, (std::vector<uint32_t>{0, 1, 3, 4, 5, 6}));
  // The diagonal's uses in triangle order: triangle 0's corner 2 (2 -> 0), triangle 1's corner 0 (3 -> 4).
  EXPECT_EQ(e.useTriangle[1], 0u);
  EXPECT_EQ(e.useCorner[1], 2u);
  EXPECT_EQ(e.useTriangle[2], 1u);
  EXPECT_EQ(e.useCorner[2], 0u);
}

TEST(MeshEdges, LeavesOutTrianglesThatCannotBeHitAndCollapsedHalfEdges) {
  Mesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1),
                 Vec3(2, 0, 0), Vec3(1, 0, 0), Vec3(std::numeric_limits<float>::infinity(), 0, 0)};
  m.triangles = {glm::uvec3(0, 1, 3),   // collinear: zero area
                 glm::uvec3(0, 5, 2),   // a non-finite corner
                 glm::uvec3(0, 1, 4),   // corners 1 and 4 weld: zero area, dropped
                 glm::uvec3(0, 1, 2)};  // the only one kept
  MeshEdges e;
  e.build(m);
  EXPECT_EQ(e.edgeCount(), 3u);
  for (size_t u = 0; u < e.useTriangle.size(); ++u) EXPECT_EQ(e.useTriangle[u], 3u);
}

// Every edge of a closed mesh is used exactly twice, once in each direction; edges by (low, high).
TEST(MeshEdges, ClosedMeshEdgesAreUsedTwiceInOppositeDirections) {
  const Mesh m = makeTorus(1.0f, 0.3f, 12, 8);
  MeshEdges e;
  e.build(m);
  ASSERT_GT(e.edgeCount(), 0u);
  for (size_t k = 0; k < e.edgeCount(); ++k) {
    ASSERT_LT(e.low[k], e.high[k]);
    if (k > 0) {
      EXPECT_TRUE(std::pair(e.low[k - 1], e.high[k - 1]) < std::pair(e.low[k], e.high[k]));
    }
    ASSERT_EQ(e.firstUse[k + 1] - e.firstUse[k], 2u);
    const auto from = [&](uint32_t u) { return e.weld[m.triangles[e.useTriangle[u]][e.useCorner[u]]]; };
    EXPECT_NE(from(e.firstUse[k]), from(e.firstUse[k] + 1));
    EXPECT_LT(e.useTriangle[e.firstUse[k]], e.useTriangle[e.firstUse[k] + 1]);
  }
}

// A scene of the two meshes, objects 0 and 1.
Scene twoMeshScene(const Mesh& a, const Mesh& b) {
  Scene scene;
  scene.objects.push_back(Object{});
  scene.objects.back().id = 1;
  scene.objects.back().mesh = a;
  scene.objects.push_back(Object{});
  scene.objects.back().id = 2;
  scene.objects.back().mesh = b;
  return scene;
}

// A scene without caches: the technique's own edges, built again only where a mesh changed.
TEST(MeshEdgeCache, BuildsAMeshAgainOnlyWhenItChanged) {
  Scene scene = twoMeshScene(seamSquare(), makeBox(Vec3(1.0f, 2.0f, 3.0f)));
  scene.caches = nullptr;
  MeshEdgeCache cache;
  cache.resize(2);
  bool rebuilt = false;
  cache.edges(scene, 0, &rebuilt);
  EXPECT_TRUE(rebuilt);
  cache.edges(scene, 1, &rebuilt);
  EXPECT_TRUE(rebuilt);
  const MeshEdges& again = cache.edges(scene, 0, &rebuilt);
  EXPECT_FALSE(rebuilt);
  EXPECT_EQ(again.edgeCount(), 5u);
  EXPECT_EQ(cache.matchCount(), 2u);
  scene.objects[0].mesh.positions[5].x = 0.5f;  // moved: built again
  cache.edges(scene, 0, &rebuilt);
  EXPECT_TRUE(rebuilt);
  EXPECT_EQ(cache.matchCount(), 3u);
  EXPECT_FALSE(meshFingerprint(scene.objects[0].mesh) == meshFingerprint(seamSquare()));
  EXPECT_TRUE(meshFingerprint(scene.objects[1].mesh) == meshFingerprint(makeBox(Vec3(1.0f, 2.0f, 3.0f))));
}

// With the scene's caches: one build per mesh for every technique on the scene or its copies; a
// changed mesh built again, found by its fingerprint, or, declared, by the revision alone (a change
// not declared again is not seen: the owner's promise is taken).
TEST(MeshEdgeCache, TechniquesOnOneSceneShareTheEdgesOfItsCaches) {
  Scene scene = twoMeshScene(seamSquare(), makeBox(Vec3(1.0f, 2.0f, 3.0f)));
  MeshEdgeCache first, second;
  bool rebuilt = false;
  const MeshEdges& a = first.edges(scene, 0, &rebuilt);
  EXPECT_TRUE(rebuilt);
  const Scene copy = scene;
  const MeshEdges& b = second.edges(copy, 0, &rebuilt);
  EXPECT_TRUE(rebuilt) << "new to this cache";
  EXPECT_EQ(&a, &b) << "built twice";
  first.edges(scene, 0, &rebuilt);
  EXPECT_FALSE(rebuilt);
  EXPECT_EQ(first.matchCount(), 1u);
  EXPECT_EQ(second.matchCount(), 1u);
  scene.objects[0].mesh.positions[5].x = 0.5f;
  const MeshEdges& moved = first.edges(scene, 0, &rebuilt);
  EXPECT_TRUE(rebuilt);
  EXPECT_NE(&moved, &a);
  scene.declareGeometry();
  const MeshEdges& declared = first.edges(scene, 0, &rebuilt);
  EXPECT_FALSE(rebuilt) << "proved equal, now under the revision";
  EXPECT_EQ(&declared, &moved);
  scene.objects[0].mesh.positions[5].x = 0.25f;
  EXPECT_EQ(&first.edges(scene, 0, &rebuilt), &moved) << "a declared revision is not proved again";
  EXPECT_FALSE(rebuilt);
  scene.declareGeometry();
  EXPECT_NE(&first.edges(scene, 0, &rebuilt), &moved);
  EXPECT_TRUE(rebuilt);
  EXPECT_EQ(sharedMeshEdges(scene, 1)->edgeCount(), 18u);  // a box, its 8 corners welded: 12 triangles, 18 edges
}

}  // namespace
}  // namespace penumbra
