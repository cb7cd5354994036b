// Mesh topology for the silhouette-based techniques (soft shadow volumes, Rouf 2007, Sections 1.3,
// 3.2.2 and 4.1.2; penumbra wedges, Assarsson & Akenine-Moeller 2003): welded vertices, the
// neighbour across every triangle edge (built once per mesh, O(f log f) by sorting, answering
// "neighbour across edge k" in constant time), occluders as closed oriented surfaces, and
// silhouettes as the boundary of a set of triangles, decomposed into oriented rings (Section
// 3.2.3.2).
//
// Choices:
//  - Vertices are welded when their positions are bit-identical (meshes made by penumbra or loaded
//    from files repeat a corner exactly when it is shared; a tolerance weld could merge distinct
//    features of a small mesh).
//  - Degenerate triangles (two equal corners after welding, or collinear corners) cover no area
//    and cannot block light: they are dropped. A mesh that relied on one to close itself (a
//    T-junction) then has a hole there, handled as any other hole (below).
//
// Occluders that are not closed 2-manifolds (our extension: Rouf Section 1.3 and penumbra wedges
// assume simple, hole-free solids, while real meshes have holes, inconsistent winding,
// non-manifold edges and repeated triangles). Both techniques need only this of an occluder: a
// closed oriented surface, every half-edge paired with one running the other way. Then the boundary
// of any set of its triangles splits into rings, and the winding number of the boundary projected
// from a receiver counts the set's triangles between the receiver and a point of the light, so the
// facing set's is non-zero exactly where the light is hidden. occluderTopology builds such a
// surface from any triangle mesh and never refuses one:
//  1. Triangles with the same three welded corners (either winding) are one: a copy blocks no more
//     light than the original. Later copies are dropped.
//  2. Orientation repair: triangles are joined into components across edges with exactly two
//     triangles, and each component is wound consistently by propagation from its first triangle
//     (a triangle whose shared edge runs the same way as its neighbour's is flipped).
//  3. A component that is then closed (each of its edges has exactly two of its triangles, running
//     opposite ways; other components may share the edge, as two boxes touching along an edge do)
//     and orientable, with non-zero volume, is a solid: used once, flipped as a whole if its signed
//     volume is negative (normals point outwards).
//  4. Every other component (open, non-orientable, or enclosing no volume) becomes a doubled shell:
//     each triangle, wound as repaired, and its reversed copy (appended after the surface's triangles,
//     MeshTopology::copyOf), a closed surface of zero thickness that blocks light as the ray
//     tracer's two-sided triangles do. At each edge the shell triangles are sorted by angle around
//     it and, for each sector between two consecutive ones, the two sides facing the sector are
//     paired. So a boundary edge joins a triangle's front to its own back (it is a silhouette edge
//     whenever one side of that triangle is lit, as for the ray tracer, which sees both sides); two
//     triangles wound consistently across an edge pair front with front and back with back,
//     inconsistently front with back; at a non-manifold edge each sector is closed by its own two
//     sides. The side running the edge one way always pairs with a side running it the other way
//     whatever the angles (ties, slivers), so rings close on any input.
//  5. An occluder whose triangles all lie in one plane (a ground plane, a card) is a two-sided
//     sheet: all shell, and it cannot shadow any point of itself.
// The cost: a shell has twice the triangles of its surface, and its silhouettes run along its
// boundary edges as well as where the surface turns from the light.
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
  std::vector<Vec3> positions;        //!< welded, world space
  std::vector<glm::uvec3> triangles;  //!< into positions; degenerate ones dropped
  //! neighbours[t][k]: the triangle across edge (triangles[t][k], triangles[t][(k+1)%3]), or kNoNeighbour
  std::vector<std::array<uint32_t, 3>> neighbours;
  std::vector<Vec3> faceNormals;  //!< unit, from the winding
  size_t droppedDegenerate = 0;   //!< degenerate triangles of the input that were dropped
  size_t droppedDuplicates = 0;   //!< occluderTopology: triangles repeating another's corners
  // The surface's defects (buildMeshTopology: of the mesh as given; occluderTopology: after
  // dropping duplicates, before repair).
  size_t boundaryEdges = 0;      //!< edges with one triangle (holes)
  size_t nonManifoldEdges = 0;   //!< edges with more than two triangles
  size_t inconsistentEdges = 0;  //!< edges whose two triangles run the same way along it
  bool planar = false;           //!< every triangle lies in one plane
  // occluderTopology only:
  size_t surfaceTriangles = 0;   //!< triangles [0, surfaceTriangles): the surface, each once
  std::vector<uint32_t> copyOf;  //!< triangle surfaceTriangles + i is the reverse of copyOf[i] (shells)
  size_t flippedTriangles = 0;   //!< surface triangles wound against the input (repaired, or a solid turned outwards)
  size_t solidComponents = 0;    //!< closed components used once
  size_t shellComponents = 0;    //!< components doubled into shells
  bool twoSidedSheet = false;    //!< planar and all shell: cannot shadow itself

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

// The topology an occluder is used with: a closed oriented surface built from any mesh by the rule
// above (solids once, repaired; everything else as doubled shells). Never throws; every half-edge
// has a neighbour, and the neighbour relation is symmetric.
MeshTopology occluderTopology(const Mesh& mesh);

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
// Throws Error if the edges do not close (the boundary of a set of triangles of an occluderTopology
// always closes: it is a sum of closed triangle outlines with paired half-edges cancelling).
std::vector<std::vector<SilhouetteEdge>> silhouetteRings(const MeshTopology& topology,
                                                         const std::vector<SilhouetteEdge>& edges);

}  // namespace penumbra
