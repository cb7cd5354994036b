// A mesh's edge adjacency, shared by the techniques that find silhouette edges seen from the light
// (plm, smoothies, kirsch: techniques/ribbon/plm.h; parker's outer objects:
// techniques/parker/outer_objects.h), kept in the scene's caches while a mesh's geometry is the same.
//
// Vertices are welded by bit-identical position (-0 and +0 alike; each vertex maps to the first at
// its position, firstVertexAtSamePosition of techniques/silhouette/mesh_topology.h). The triangles
// that can be hit (finite corners, a non-zero finite normal) contribute their three half-edges, less
// any whose two ends weld together; the half-edges are grouped by edge (the pair of welded ends),
// each edge's uses in triangle order (then corner order), the edges ordered by (lower, higher)
// welded end. Which edges are silhouettes depends on the light and is each technique's to decide
// (they differ in which triangles they count and how they orient them).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/mesh_fingerprint.h"
#include "penumbra/scene.h"

namespace penumbra {

struct MeshEdges {
  std::vector<uint32_t> weld;         //!< per mesh vertex: the first vertex at its position
  std::vector<uint32_t> low, high;    //!< per edge: its welded ends, low < high
  std::vector<uint32_t> firstUse;     //!< per edge, and one past the last: its uses below
  std::vector<uint32_t> useTriangle;  //!< per use: the triangle (index into the mesh's triangles)
  std::vector<uint8_t> useCorner;     //!< per use: k, the half-edge from corner k to corner (k + 1) % 3

  size_t edgeCount() const { return low.size(); }
  // The mesh's triangle indices must be in range (the scene loader's check).
  void build(const Mesh& mesh);
};

// The MeshEdges of object `objectIndex` of `scene`, kept in the scene's caches (Scene::caches) and
// shared by every technique prepared on the scene or its copies: built again only where the mesh's
// geometry differs from the one they were built from, proved as the Embree scene's is (by the mesh's
// fingerprint, or by the scene's declared revision: Scene::geometryRevision). Without caches, built
// afresh.
std::shared_ptr<const MeshEdges> sharedMeshEdges(const Scene& scene, size_t objectIndex);

// Per object index, the MeshEdges of the object's mesh for one technique: the scene's shared ones
// (sharedMeshEdges), or, for a scene without caches, its own, built again only where the mesh's
// fingerprint differs from the one they were last built for.
class MeshEdgeCache {
 public:
  MeshEdgeCache();
  ~MeshEdgeCache();
  MeshEdgeCache(const MeshEdgeCache&) = delete;
  MeshEdgeCache& operator=(const MeshEdgeCache&) = delete;

  // Sizes the cache to a scene's objects (entries of objects beyond it are dropped).
  void resize(size_t objectCount);
  // The edges of the mesh of object `objectIndex` of `scene`; `rebuilt` (optional) tells whether they
  // are others than this cache gave for that index last time (built now, by this or another cache).
  const MeshEdges& edges(const Scene& scene, size_t objectIndex, bool* rebuilt = nullptr);
  size_t matchCount() const;  //!< edge sets it was given anew so far (edges() with `rebuilt` true)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace penumbra
