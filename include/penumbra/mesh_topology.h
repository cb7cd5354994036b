// Mesh topology for the silhouette-based techniques (soft shadow volumes, Rouf 2007, Sections 1.3,
// 3.2.2 and 4.1.2; penumbra wedges, Assarsson & Akenine-Moeller 2003): welded vertices, the
// neighbour across every triangle edge (built once per mesh, O(f log f) by sorting, answering
// "neighbour across edge k" in constant time), the occluder checks of Rouf Section 1.3 (closed,
// triangulated, manifold, consistently wound) and silhouettes as the boundary of a set of
// triangles, decomposed into oriented rings (Section 3.2.3.2).
//
// Choices:
//  - Vertices are welded when their positions are bit-identical (meshes made by penumbra or loaded
//    from files repeat a corner exactly when it is shared; a tolerance weld could merge distinct
//    features of a small mesh).
//  - Degenerate triangles (two equal corners after welding, or collinear corners) cover no area
//    and cannot block light: they are dropped before the checks. A mesh that relied on one to close
//    itself (a T-junction) then reports a hole.
//  - An open, connected mesh whose triangles all lie in one plane (a ground plane, a card) is accepted as a
//    two-sided sheet: a closed solid of zero thickness made of the triangles and their reversed
//    copies. Its boundary edges join the two faces, so they are silhouette edges whenever the
//    sheet faces the light, as they are for the ray tracer, which sees both sides of a triangle.
//    Any other open, non-manifold or inconsistently wound mesh is refused with an Error naming the
//    object, the defect and an edge where it occurs.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "penumbra/math.h"
#include "penumbra/scene.h"

namespace penumbra {

inline constexpr uint32_t kNoNeighbour = 0xffffffffu;

struct MeshTopology {
  std::vector<Vec3> positions;             //!< welded, world space
  std::vector<glm::uvec3> triangles;       //!< into positions; degenerate ones dropped
  //! neighbours[t][k]: the triangle across edge (triangles[t][k], triangles[t][(k+1)%3]), or kNoNeighbour
  std::vector<std::array<uint32_t, 3>> neighbours;
  std::vector<Vec3> faceNormals;           //!< unit, from the winding
  size_t droppedDegenerate = 0;            //!< degenerate triangles of the input that were dropped
  size_t boundaryEdges = 0;                //!< edges with one triangle (holes)
  size_t nonManifoldEdges = 0;             //!< edges with more than two triangles
  size_t inconsistentEdges = 0;            //!< edges whose two triangles run the same way along it
  Vec3 firstDefectA{0.0f}, firstDefectB{0.0f};  //!< one edge with a defect, for messages
  bool planar = false;                     //!< every triangle lies in one plane
  bool twoSidedSheet = false;              //!< built by twoSidedSheet()

  size_t vertexCount() const { return positions.size(); }
  size_t triangleCount() const { return triangles.size(); }
  bool closed() const { return boundaryEdges == 0 && nonManifoldEdges == 0 && inconsistentEdges == 0; }
  // Edge k of triangle t is convex (the solid's inside angle there is below 180 degrees): the
  // neighbour's far corner lies behind t's plane. Boundary edges count as convex.
  bool convexEdge(uint32_t t, int k) const;
};

// Welds, drops degenerate triangles and builds the adjacency; records the defects, never throws.
MeshTopology buildMeshTopology(const Mesh& mesh);

// Welding by bit-identical position (-0 and +0 alike), by sorting (10^6 vertices in a fraction of a
// second, where a hash map took seconds): first[i] is the smallest index of a vertex at vertex i's
// position.
std::vector<uint32_t> firstVertexAtSamePosition(const std::vector<Vec3>& positions);
// The same as welded ids in order of first occurrence (id[i] indexes `welded`, the distinct positions).
std::vector<uint32_t> weldVertices(const std::vector<Vec3>& positions, std::vector<Vec3>& welded);

// The topology an occluder is used with: `mesh` itself when closed, its two-sided sheet when it is
// open and planar; otherwise throws Error "<technique>: object '<name>': ..." naming the defect.
MeshTopology occluderTopology(const Mesh& mesh, std::string_view objectName, std::string_view technique);

// The closed zero-thickness solid made of a planar open mesh's triangles and their reversed copies
// (triangle t + n is the reverse of t).
MeshTopology twoSidedSheet(const MeshTopology& sheet);

// A directed silhouette edge a -> b, running as in triangle `inner` (inside the set), whose neighbour
// `outer` across it is outside the set.
struct SilhouetteEdge {
  uint32_t a = 0, b = 0;
  uint32_t inner = 0, outer = 0;
  uint8_t k = 0;  //!< edge index in `inner`
};

// The boundary of the triangle set {t : inSet[t] != 0}: every edge between a triangle in the set and
// one outside it, directed as in the inner triangle. Deterministic order (by triangle, then edge).
std::vector<SilhouetteEdge> boundaryEdges(const MeshTopology& topology, const std::vector<uint8_t>& inSet);

// Decomposes boundary edges into closed rings (Rouf 2007, Section 3.2.3.2: in-degree equals
// out-degree at every vertex of the boundary of a face set of a closed oriented mesh, so the edges
// split into cycles). Each ring lists its edges in order, rings[r][i].b == rings[r][i+1].a. Where a
// vertex has several outgoing edges (two rings touching at a vertex) the first unused one in edge
// order is taken: the cycles are valid either way, only their grouping differs.
// Throws Error if the edges do not close (a mesh that is not closed).
std::vector<std::vector<SilhouetteEdge>> silhouetteRings(const MeshTopology& topology,
                                                         const std::vector<SilhouetteEdge>& edges);

}  // namespace penumbra
