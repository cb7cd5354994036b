// Mesh topology: welding, edge adjacency, the occluder checks of Rouf 2007 (Section 1.3) and
// silhouette rings (Section 3.2.3.2). See include/penumbra/mesh_topology.h for the choices.
#include "penumbra/mesh_topology.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <tuple>

#include "penumbra/error.h"

namespace penumbra {
namespace {

// Exact float bits of a position; +0.0 and -0.0 are the same point.
std::array<uint32_t, 3> positionBits(const Vec3& p) {
  const Vec3 q = p + Vec3(0.0f);
  std::array<uint32_t, 3> bits;
  std::memcpy(bits.data(), &q, sizeof(bits));
  return bits;
}

// One half-edge: triangle t, edge k, running from -> to.
struct HalfEdge {
  uint64_t key;  // undirected: min << 32 | max
  uint32_t t;
  uint8_t k;
  bool forward;  // from < to
};

void buildAdjacency(MeshTopology& m) {
  const size_t n = m.triangles.size();
  m.neighbours.assign(n, {kNoNeighbour, kNoNeighbour, kNoNeighbour});
  std::vector<HalfEdge> half;
  half.reserve(3 * n);
  for (uint32_t t = 0; t < n; ++t)
    for (uint8_t k = 0; k < 3; ++k) {
      const uint32_t a = m.triangles[t][k], b = m.triangles[t][(k + 1) % 3];
      half.push_back({(uint64_t(std::min(a, b)) << 32) | std::max(a, b), t, k, a < b});
    }
  std::sort(half.begin(), half.end(),
            [](const HalfEdge& x, const HalfEdge& y) { return std::tie(x.key, x.t, x.k) < std::tie(y.key, y.t, y.k); });
  m.boundaryEdges = m.nonManifoldEdges = m.inconsistentEdges = 0;
  bool noted = false;
  auto note = [&](uint64_t key) {
    if (noted) return;
    noted = true;
    m.firstDefectA = m.positions[key >> 32];
    m.firstDefectB = m.positions[key & 0xffffffffu];
  };
  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    const size_t count = j - i;
    if (count == 1) {
      ++m.boundaryEdges;
      note(half[i].key);
    } else if (count > 2) {
      ++m.nonManifoldEdges;
      note(half[i].key);
    } else if (half[i].forward == half[i + 1].forward) {
      ++m.inconsistentEdges;
      note(half[i].key);
    } else {
      m.neighbours[half[i].t][half[i].k] = half[i + 1].t;
      m.neighbours[half[i + 1].t][half[i + 1].k] = half[i].t;
    }
    i = j;
  }
}

std::string formatPoint(const Vec3& p) { return fmt::format("({:.4g}, {:.4g}, {:.4g})", p.x, p.y, p.z); }

}  // namespace

bool MeshTopology::convexEdge(uint32_t t, int k) const {
  const uint32_t u = neighbours[t][k];
  if (u == kNoNeighbour) return true;
  const glm::uvec3& tu = triangles[u];
  const uint32_t a = triangles[t][k], b = triangles[t][(k + 1) % 3];
  uint32_t far = tu[0];
  for (int i = 0; i < 3; ++i)
    if (tu[i] != a && tu[i] != b) far = tu[i];
  return glm::dot(faceNormals[t], positions[far] - positions[a]) <= 0.0f;
}

std::vector<uint32_t> firstVertexAtSamePosition(const std::vector<Vec3>& positions) {
  const size_t n = positions.size();
  std::vector<std::pair<std::array<uint32_t, 3>, uint32_t>> sorted(n);
  for (uint32_t i = 0; i < n; ++i) sorted[i] = {positionBits(positions[i]), i};
  std::sort(sorted.begin(), sorted.end());  // by position, then index: each run starts at its first vertex
  std::vector<uint32_t> first(n);
  for (size_t r = 0; r < n; ++r)
    first[sorted[r].second] = (r > 0 && sorted[r].first == sorted[r - 1].first) ? first[sorted[r - 1].second] : sorted[r].second;
  return first;
}

std::vector<uint32_t> weldVertices(const std::vector<Vec3>& positions, std::vector<Vec3>& welded) {
  const std::vector<uint32_t> first = firstVertexAtSamePosition(positions);
  std::vector<uint32_t> id(positions.size());
  welded.clear();
  for (size_t i = 0; i < positions.size(); ++i) {
    if (first[i] == i) {
      id[i] = static_cast<uint32_t>(welded.size());
      welded.push_back(positions[i]);
    } else {
      id[i] = id[first[i]];  // first[i] < i: already numbered
    }
  }
  return id;
}

MeshTopology buildMeshTopology(const Mesh& mesh) {
  MeshTopology m;
  const std::vector<uint32_t> remap = weldVertices(mesh.positions, m.positions);
  const Bounds3 bounds = mesh.bounds();
  const float scale = bounds.empty() ? 1.0f : std::max(glm::length(bounds.diagonal()), 1e-30f);
  for (const glm::uvec3& tri : mesh.triangles) {
    if (tri.x >= remap.size() || tri.y >= remap.size() || tri.z >= remap.size()) {
      ++m.droppedDegenerate;  // out of range indices are caught by the scene loader; never index past
      continue;
    }
    const glm::uvec3 w(remap[tri.x], remap[tri.y], remap[tri.z]);
    const Vec3 e1 = m.positions[w.y] - m.positions[w.x], e2 = m.positions[w.z] - m.positions[w.x];
    const Vec3 cross = glm::cross(e1, e2);
    const float len = glm::length(cross);
    // Collinear to float precision: the sine of the corner angle is below 1e-5 (float rounding of
    // collinear corners leaves about 1e-7), or the area is below 1e-12 of the mesh's squared size.
    if (w.x == w.y || w.y == w.z || w.x == w.z || !(len > 1e-5f * glm::length(e1) * glm::length(e2)) ||
        !(len > 1e-12f * scale * scale)) {
      ++m.droppedDegenerate;
      continue;
    }
    m.triangles.push_back(w);
    m.faceNormals.push_back(cross / len);
  }
  buildAdjacency(m);
  m.planar = !m.triangles.empty();
  if (m.planar) {
    const Vec3 n0 = m.faceNormals[0];
    const Vec3 p0 = m.positions[m.triangles[0].x];
    for (size_t t = 0; t < m.triangles.size() && m.planar; ++t) {
      m.planar = std::abs(glm::dot(m.faceNormals[t], n0)) > 1.0f - 1e-5f;
      for (int i = 0; i < 3; ++i) m.planar = m.planar && std::abs(glm::dot(m.positions[m.triangles[t][i]] - p0, n0)) <= 1e-5f * scale;
    }
  }
  return m;
}

MeshTopology twoSidedSheet(const MeshTopology& sheet) {
  MeshTopology m;
  const auto n = static_cast<uint32_t>(sheet.triangles.size());
  m.positions = sheet.positions;
  m.triangles = sheet.triangles;
  m.faceNormals = sheet.faceNormals;
  m.neighbours = sheet.neighbours;
  m.triangles.reserve(2 * n);
  for (uint32_t t = 0; t < n; ++t) {
    const glm::uvec3& tri = sheet.triangles[t];
    m.triangles.push_back(glm::uvec3(tri.y, tri.x, tri.z));  // reversed
    m.faceNormals.push_back(-sheet.faceNormals[t]);
  }
  m.neighbours.resize(2 * n);
  // Reversed triangle (y, x, z): its edge 0 is y->x (edge 0 of t reversed), edge 1 is x->z (edge 2
  // of t), edge 2 is z->y (edge 1 of t).
  constexpr int kReverseOf[3] = {0, 2, 1};
  for (uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t front = sheet.neighbours[t][k];
      // Across a boundary edge the front face continues as the back face.
      if (front == kNoNeighbour) m.neighbours[t][k] = n + t;
      m.neighbours[n + t][kReverseOf[k]] = front == kNoNeighbour ? t : n + front;
    }
  m.droppedDegenerate = sheet.droppedDegenerate;
  m.planar = true;
  m.twoSidedSheet = true;
  return m;
}

MeshTopology occluderTopology(const Mesh& mesh, std::string_view objectName, std::string_view technique) {
  MeshTopology m = buildMeshTopology(mesh);
  if (m.triangles.empty()) return m;
  const std::string where = fmt::format("{}: object '{}'", technique, objectName);
  const std::string rule = "occluders must be closed, manifold, consistently wound triangle meshes (Rouf 2007, Section 1.3), or open meshes lying in one plane in one connected piece (treated as two-sided sheets)";
  if (m.nonManifoldEdges > 0)
    fail("{}: {} non-manifold edge(s) shared by more than two triangles (e.g. the edge {} - {}); {}: split the mesh into separate objects",
         where, m.nonManifoldEdges, formatPoint(m.firstDefectA), formatPoint(m.firstDefectB), rule);
  if (m.inconsistentEdges > 0)
    fail("{}: inconsistent winding: {} edge(s) run the same way in both of their triangles (e.g. the edge {} - {}); {}: flip the reversed triangles",
         where, m.inconsistentEdges, formatPoint(m.firstDefectA), formatPoint(m.firstDefectB), rule);
  if (m.boundaryEdges > 0) {
    // A sheet is one connected piece (a ground plane, a card); a soup of separate planar pieces
    // would make every piece's outline a silhouette ring of its own.
    std::vector<uint32_t> parent(m.triangles.size());
    for (uint32_t t = 0; t < parent.size(); ++t) parent[t] = t;
    auto find = [&](uint32_t t) {
      while (parent[t] != t) t = parent[t] = parent[parent[t]];
      return t;
    };
    size_t pieces = m.triangles.size();
    for (uint32_t t = 0; t < m.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = m.neighbours[t][k];
        if (u == kNoNeighbour) continue;
        const uint32_t a = find(t), b = find(u);
        if (a != b) {
          parent[a] = b;
          --pieces;
        }
      }
    if (m.planar && pieces == 1) return twoSidedSheet(m);
    if (m.planar)
      fail("{}: the mesh is open and lies in one plane but falls into {} separate pieces; {}: make each piece its own object, or close the mesh",
           where, pieces, rule);
    fail("{}: the mesh is not closed: {} boundary edge(s) with a triangle on one side only (a hole, e.g. at the edge {} - {}); {}: close the hole",
         where, m.boundaryEdges, formatPoint(m.firstDefectA), formatPoint(m.firstDefectB), rule);
  }
  return m;
}

std::vector<SilhouetteEdge> boundaryEdges(const MeshTopology& topology, const std::vector<uint8_t>& inSet) {
  std::vector<SilhouetteEdge> edges;
  for (uint32_t t = 0; t < topology.triangles.size(); ++t) {
    if (!inSet[t]) continue;
    for (uint8_t k = 0; k < 3; ++k) {
      const uint32_t u = topology.neighbours[t][k];
      if (u == kNoNeighbour || inSet[u]) continue;
      edges.push_back({topology.triangles[t][k], topology.triangles[t][(k + 1) % 3], t, u, k});
    }
  }
  return edges;
}

std::vector<std::vector<SilhouetteEdge>> silhouetteRings(const MeshTopology& topology,
                                                         const std::vector<SilhouetteEdge>& edges) {
  // Outgoing edges per vertex, in edge order (counting sort by start vertex).
  std::vector<uint32_t> start(topology.positions.size() + 1, 0);
  for (const SilhouetteEdge& e : edges) ++start[e.a + 1];
  for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  std::vector<uint32_t> out(edges.size());
  std::vector<uint32_t> fill(start.begin(), start.end() - 1);
  for (uint32_t i = 0; i < edges.size(); ++i) out[fill[edges[i].a]++] = i;
  std::vector<uint8_t> used(edges.size(), 0);
  std::vector<uint32_t> cursor(start.begin(), start.end() - 1);  // first possibly unused out-edge
  std::vector<std::vector<SilhouetteEdge>> rings;
  for (uint32_t first = 0; first < edges.size(); ++first) {
    if (used[first]) continue;
    std::vector<SilhouetteEdge> ring;
    uint32_t current = first;
    for (;;) {
      used[current] = 1;
      ring.push_back(edges[current]);
      const uint32_t v = edges[current].b;
      if (v == edges[first].a) break;
      uint32_t& c = cursor[v];
      while (c < start[v + 1] && used[out[c]]) ++c;
      if (c == start[v + 1])
        fail("silhouette: the boundary does not close at vertex {} ({:.4g}, {:.4g}, {:.4g}): the mesh is not closed", v,
             topology.positions[v].x, topology.positions[v].y, topology.positions[v].z);
      current = out[c];
    }
    rings.push_back(std::move(ring));
  }
  return rings;
}

}  // namespace penumbra
