// Scene::caches: what the techniques build from a scene's geometry alone, shared by the scene's
// copies and by every technique prepared on them (RaySceneCache, src/rt/ray_scene.h, keeps the Embree
// scene here). Core does not know the ray tracer, so the scene is held type-erased.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "core/mesh_fingerprint.h"
#include "penumbra/math.h"
#include "penumbra/scene.h"

namespace penumbra {

struct SceneCaches {
  std::mutex mutex;                      //!< techniques may prepare on one scene from several threads
  std::vector<uint64_t> rayKey;          //!< the geometry rayScene was built from (RaySceneCache's key)
  std::shared_ptr<const void> rayScene;  //!< a RayScene
  Bounds3 rayBounds;                     //!< the bounds of that geometry
  uint64_t rayRevision = 0;              //!< Scene::geometryRevision of that geometry (0: undeclared)
  uint64_t nextRevision = 1;             //!< the next number Scene::declareGeometry gives
  // Per object index, the edge adjacency of its mesh (a MeshEdges of src/techniques/mesh_edges.h,
  // sharedMeshEdges), the mesh's fingerprint and the revision it was built from or proved equal to.
  struct MeshEdgesEntry {
    MeshFingerprint fingerprint;
    uint64_t revision = 0;
    std::shared_ptr<const void> edges;
  };
  std::vector<MeshEdgesEntry> meshEdges;
};

}  // namespace penumbra
