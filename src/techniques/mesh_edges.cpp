// A mesh's edge adjacency and its cache (mesh_edges.h).
#include "techniques/mesh_edges.h"

#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>

#include <tbb/parallel_sort.h>

#include "core/scene_caches.h"
#include "penumbra/math.h"
#include "techniques/silhouette/mesh_topology.h"

namespace penumbra {

namespace {

// One half-edge: its edge's welded ends as one key (low << 32 | high) and its place in triangle
// and corner order (3 * triangle + corner), which orders the half-edges totally.
struct HalfEdge {
  uint64_t key;
  uint64_t use;
};

}  // namespace

void MeshEdges::build(const Mesh& mesh) {
  weld = firstVertexAtSamePosition(mesh.positions);
  std::vector<HalfEdge> half;
  half.reserve(3 * mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const glm::uvec3& tri = mesh.triangles[t];
    const Vec3 p0 = mesh.positions[tri.x], p1 = mesh.positions[tri.y], p2 = mesh.positions[tri.z];
    const Vec3 n = glm::cross(p1 - p0, p2 - p0);
    const float n2 = glm::dot(n, n);
    if (!(n2 > 0.0f) || !std::isfinite(n2) || !isFinite(p0) || !isFinite(p1) || !isFinite(p2))
      continue;  // cannot be hit
    const uint32_t v[3] = {tri.x, tri.y, tri.z};
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t wa = weld[v[k]], wb = weld[v[(k + 1) % 3]];
      if (wa == wb) continue;
      half.push_back({uint64_t{std::min(wa, wb)} << 32 | std::max(wa, wb), 3 * uint64_t{t} + k});
    }
  }
  // (key, use) is a total order: a parallel sort gives the one order.
  tbb::parallel_sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key < y.key || (x.key == y.key && x.use < y.use);
  });
  low.clear();
  high.clear();
  firstUse.clear();
  useTriangle.resize(half.size());
  useCorner.resize(half.size());
  for (size_t i = 0; i < half.size(); ++i) {
    if (i == 0 || half[i].key != half[i - 1].key) {
      low.push_back(static_cast<uint32_t>(half[i].key >> 32));
      high.push_back(static_cast<uint32_t>(half[i].key & 0xffffffffu));
      firstUse.push_back(static_cast<uint32_t>(i));
    }
    useTriangle[i] = static_cast<uint32_t>(half[i].use / 3);
    useCorner[i] = static_cast<uint8_t>(half[i].use % 3);
  }
  firstUse.push_back(static_cast<uint32_t>(half.size()));
}

namespace {

// `edges` made the edge adjacency of `mesh`, whose fingerprint is `fingerprint`, unless `builtFrom`
// says they already are; whether they were built now.
template <typename Pointer>
bool keepOrBuild(Pointer& edges, MeshFingerprint& builtFrom, const Mesh& mesh, const MeshFingerprint& fingerprint) {
  if (edges && builtFrom == fingerprint) return false;
  auto built = std::make_shared<MeshEdges>();
  built->build(mesh);
  edges = std::move(built);
  builtFrom = fingerprint;
  return true;
}

}  // namespace

std::shared_ptr<const MeshEdges> sharedMeshEdges(const Scene& scene, size_t objectIndex) {
  const Mesh& mesh = scene.objects.at(objectIndex).mesh;
  if (!scene.caches) {
    auto edges = std::make_shared<MeshEdges>();
    edges->build(mesh);
    return edges;
  }
  SceneCaches& caches = *scene.caches;
  std::lock_guard lock(caches.mutex);
  if (caches.meshEdges.size() < scene.objects.size()) caches.meshEdges.resize(scene.objects.size());
  SceneCaches::MeshEdgesEntry& entry = caches.meshEdges[objectIndex];
  // Declared geometry they were built from (or proved equal to): nothing to hash.
  if (!(entry.edges && scene.geometryRevision != 0 && entry.revision == scene.geometryRevision)) {
    keepOrBuild(entry.edges, entry.fingerprint, mesh, meshFingerprint(mesh));
    entry.revision = scene.geometryRevision;
  }
  return std::static_pointer_cast<const MeshEdges>(entry.edges);
}

struct MeshEdgeCache::Impl {
  struct Entry {
    MeshFingerprint key;                     //!< without scene caches: the geometry `edges` is of
    std::shared_ptr<const MeshEdges> edges;  //!< the edges last given for the index
  };
  std::vector<Entry> entries;  //!< per object index
  size_t matches = 0;
};

MeshEdgeCache::MeshEdgeCache() : impl_(std::make_unique<Impl>()) {}
MeshEdgeCache::~MeshEdgeCache() = default;

void MeshEdgeCache::resize(size_t objectCount) { impl_->entries.resize(objectCount); }

const MeshEdges& MeshEdgeCache::edges(const Scene& scene, size_t objectIndex, bool* rebuilt) {
  if (objectIndex >= impl_->entries.size()) impl_->entries.resize(objectIndex + 1);
  Impl::Entry& entry = impl_->entries[objectIndex];
  if (scene.caches) {
    std::shared_ptr<const MeshEdges> shared = sharedMeshEdges(scene, objectIndex);
    const bool anew = shared != entry.edges;
    impl_->matches += anew ? 1 : 0;
    if (rebuilt) *rebuilt = anew;
    entry.edges = std::move(shared);
    return *entry.edges;
  }
  const Mesh& mesh = scene.objects.at(objectIndex).mesh;
  const bool build = keepOrBuild(entry.edges, entry.key, mesh, meshFingerprint(mesh));
  impl_->matches += build ? 1 : 0;
  if (rebuilt) *rebuilt = build;
  return *entry.edges;
}

size_t MeshEdgeCache::matchCount() const { return impl_->matches; }

}  // namespace penumbra
