// Mesh topology: welding, edge adjacency, any mesh as a closed oriented occluder surface (solids
// repaired, everything else as doubled shells; our extension of Rouf 2007, Section 1.3) and
// silhouette rings (Section 3.2.3.2). See src/techniques/silhouette/mesh_topology.h for the rule.
#include "techniques/silhouette/mesh_topology.h"

#include <algorithm>
#include <array>
#include <cmath>
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
  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    const size_t count = j - i;
    if (count == 1) {
      ++m.boundaryEdges;
    } else if (count > 2) {
      ++m.nonManifoldEdges;
    } else if (half[i].forward == half[i + 1].forward) {
      ++m.inconsistentEdges;
    } else {
      m.neighbours[half[i].t][half[i].k] = half[i + 1].t;
      m.neighbours[half[i + 1].t][half[i + 1].k] = half[i].t;
    }
    i = j;
  }
}

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
    first[sorted[r].second] =
        (r > 0 && sorted[r].first == sorted[r - 1].first) ? first[sorted[r - 1].second] : sorted[r].second;
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

namespace {

// Welds, drops degenerate triangles and finds whether the rest lie in one plane (no adjacency).
MeshTopology weldAndDrop(const Mesh& mesh) {
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
  m.planar = !m.triangles.empty();
  if (m.planar) {
    const Vec3 n0 = m.faceNormals[0];
    const Vec3 p0 = m.positions[m.triangles[0].x];
    for (size_t t = 0; t < m.triangles.size() && m.planar; ++t) {
      m.planar = std::abs(glm::dot(m.faceNormals[t], n0)) > 1.0f - 1e-5f;
      for (int i = 0; i < 3; ++i)
        m.planar = m.planar && std::abs(glm::dot(m.positions[m.triangles[t][i]] - p0, n0)) <= 1e-5f * scale;
    }
  }
  return m;
}

}  // namespace

MeshTopology buildMeshTopology(const Mesh& mesh) {
  MeshTopology m = weldAndDrop(mesh);
  buildAdjacency(m);
  return m;
}

namespace {

// Undirected edge key of a -> b.
uint64_t edgeKey(uint32_t a, uint32_t b) { return (uint64_t(std::min(a, b)) << 32) | std::max(a, b); }

// Reversed triangle (y, x, z): its edge 0 is y->x (edge 0 of (x, y, z) reversed), edge 1 is x->z
// (edge 2 reversed), edge 2 is z->y (edge 1 reversed).
constexpr uint8_t kReverseOf[3] = {0, 2, 1};

glm::uvec3 reversed(const glm::uvec3& t) { return glm::uvec3(t.y, t.x, t.z); }

std::tuple<uint32_t, uint32_t, uint32_t> sortedCorners(glm::uvec3 c) {
  if (c.x > c.y) std::swap(c.x, c.y);
  if (c.y > c.z) std::swap(c.y, c.z);
  if (c.x > c.y) std::swap(c.x, c.y);
  return {c.x, c.y, c.z};
}

}  // namespace

MeshTopology occluderTopology(const Mesh& mesh) {
  MeshTopology in = weldAndDrop(mesh);
  MeshTopology m;
  m.positions = std::move(in.positions);
  m.droppedDegenerate = in.droppedDegenerate;
  m.planar = in.planar;
  if (in.triangles.empty()) return m;

  // 1. One triangle per set of three corners: the first in input order is kept.
  std::vector<uint32_t> tris;  // the kept triangles (indices into in.triangles), in input order
  {
    std::vector<std::pair<std::tuple<uint32_t, uint32_t, uint32_t>, uint32_t>> order(in.triangles.size());
    for (uint32_t t = 0; t < order.size(); ++t) order[t] = {sortedCorners(in.triangles[t]), t};
    std::sort(order.begin(), order.end());
    std::vector<uint8_t> keep(in.triangles.size(), 1);
    for (size_t i = 1; i < order.size(); ++i)
      if (order[i].first == order[i - 1].first) keep[order[i].second] = 0;
    for (uint32_t t = 0; t < keep.size(); ++t)
      if (keep[t]) tris.push_back(t);
    m.droppedDuplicates = in.triangles.size() - tris.size();
  }
  const auto n = static_cast<uint32_t>(tris.size());
  auto input = [&](uint32_t i) { return in.triangles[tris[i]]; };

  // Half-edges of the kept triangles, grouped by undirected edge.
  std::vector<HalfEdge> half;
  half.reserve(3 * size_t(n));
  for (uint32_t i = 0; i < n; ++i)
    for (uint8_t k = 0; k < 3; ++k) {
      const uint32_t a = input(i)[k], b = input(i)[(k + 1) % 3];
      half.push_back({edgeKey(a, b), i, k, a < b});
    }
  std::sort(half.begin(), half.end(),
            [](const HalfEdge& x, const HalfEdge& y) { return std::tie(x.key, x.t, x.k) < std::tie(y.key, y.t, y.k); });
  std::vector<size_t> groupStart;  // half-edges [groupStart[g], groupStart[g + 1]) share an edge
  for (size_t i = 0; i < half.size(); ++i)
    if (i == 0 || half[i].key != half[i - 1].key) groupStart.push_back(i);
  groupStart.push_back(half.size());
  const size_t groups = groupStart.size() - 1;

  // 2. Orientation repair across the edges with exactly two triangles: flip[i] makes each such edge
  // run opposite ways in its two triangles, where the component allows it.
  std::vector<std::array<uint32_t, 3>> across(n, {kNoNeighbour, kNoNeighbour, kNoNeighbour});
  std::vector<std::array<uint8_t, 3>> sameWay(n, {0, 0, 0});
  for (size_t g = 0; g < groups; ++g) {
    const size_t i = groupStart[g];
    const size_t count = groupStart[g + 1] - i;
    if (count == 1) ++m.boundaryEdges;
    if (count > 2) ++m.nonManifoldEdges;
    if (count != 2) continue;
    const HalfEdge &x = half[i], &y = half[i + 1];
    m.inconsistentEdges += x.forward == y.forward;
    across[x.t][x.k] = y.t;
    across[y.t][y.k] = x.t;
    sameWay[x.t][x.k] = sameWay[y.t][y.k] = x.forward == y.forward;
  }
  constexpr uint32_t kUnset = 0xffffffffu;
  std::vector<uint32_t> component(n, kUnset);
  std::vector<uint8_t> flip(n, 0);
  std::vector<uint8_t> closedComponent;  // per component: orientable and closed (so far)
  {
    std::vector<uint32_t> stack;
    for (uint32_t seed = 0; seed < n; ++seed) {
      if (component[seed] != kUnset) continue;
      const auto c = static_cast<uint32_t>(closedComponent.size());
      closedComponent.push_back(1);
      component[seed] = c;
      stack.push_back(seed);
      while (!stack.empty()) {
        const uint32_t t = stack.back();
        stack.pop_back();
        for (int k = 0; k < 3; ++k) {
          const uint32_t u = across[t][k];
          if (u == kNoNeighbour) continue;
          const uint8_t want = flip[t] ^ sameWay[t][k];
          if (component[u] == kUnset) {
            component[u] = c;
            flip[u] = want;
            stack.push_back(u);
          } else if (flip[u] != want) {
            closedComponent[c] = 0;  // not orientable (a Moebius strip): a shell
          }
        }
      }
    }
  }
  const size_t components = closedComponent.size();
  // Whether half-edge h runs from the smaller vertex id to the larger once its triangle is flipped.
  auto forwardAfterFlip = [&](const HalfEdge& h) -> uint8_t { return h.forward != (flip[h.t] != 0); };

  // 3. Closed components: at every edge each component has no triangle or exactly two, running
  // opposite ways.
  {
    std::vector<std::pair<uint32_t, uint8_t>> at;  // (component, forward after flip) of one edge's half-edges
    for (size_t g = 0; g < groups; ++g) {
      at.clear();
      for (size_t i = groupStart[g]; i < groupStart[g + 1]; ++i)
        at.push_back({component[half[i].t], forwardAfterFlip(half[i])});
      std::sort(at.begin(), at.end());
      for (size_t i = 0; i < at.size();) {
        size_t j = i;
        while (j < at.size() && at[j].first == at[i].first) ++j;
        if (j - i != 2 || at[i].second == at[i + 1].second) closedComponent[at[i].first] = 0;
        i = j;
      }
    }
  }
  // Signed volumes (divergence theorem, about each component's first corner, in double) and sizes.
  std::vector<double> volume(components, 0.0);
  std::vector<Bounds3> box(components);
  std::vector<Vec3> origin(components);
  for (uint32_t i = n; i-- > 0;) origin[component[i]] = m.positions[input(i).x];
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t c = component[i];
    const glm::uvec3 t = flip[i] ? reversed(input(i)) : input(i);
    const glm::dvec3 o(origin[c]);
    const glm::dvec3 p0 = glm::dvec3(m.positions[t.x]) - o, p1 = glm::dvec3(m.positions[t.y]) - o,
                     p2 = glm::dvec3(m.positions[t.z]) - o;
    volume[c] += glm::dot(p0, glm::cross(p1, p2)) / 6.0;
    for (int k = 0; k < 3; ++k) box[c].extend(m.positions[t[k]]);
  }
  // solid[c]: 0 a shell, 1 a solid as propagated, 2 a solid flipped as a whole.
  std::vector<uint8_t> solid(components, 0);
  for (size_t c = 0; c < components; ++c) {
    if (!closedComponent[c] || m.planar) continue;
    // A closed surface enclosing (almost) no volume has no outside for its normals to point to;
    // as a shell it blocks the same light whatever its winding.
    const double size = glm::length(glm::dvec3(box[c].diagonal()));
    if (!(std::abs(volume[c]) > 1e-9 * size * size * size)) continue;
    solid[c] = volume[c] > 0.0 ? 1 : 2;
  }
  for (size_t c = 0; c < components; ++c) {
    m.solidComponents += solid[c] != 0;
    m.shellComponents += solid[c] == 0;
  }

  // 4. The surface, wound as repaired (solids turned outwards); then the reversed copies of the
  // shells' triangles. reversedOut[i]: surface triangle i runs against the input; copy[i]: its copy.
  std::vector<uint8_t> reversedOut(n, 0);
  std::vector<uint32_t> copy(n, kNoNeighbour);
  m.triangles.reserve(2 * size_t(n));
  for (uint32_t i = 0; i < n; ++i) {
    const uint8_t s = solid[component[i]];
    reversedOut[i] = uint8_t(flip[i] ^ (s == 2 ? 1 : 0));
    m.flippedTriangles += reversedOut[i];
    m.triangles.push_back(reversedOut[i] ? reversed(input(i)) : input(i));
  }
  m.surfaceTriangles = n;
  for (uint32_t i = 0; i < n; ++i)
    if (solid[component[i]] == 0) {
      copy[i] = static_cast<uint32_t>(m.triangles.size());
      m.copyOf.push_back(i);
      m.triangles.push_back(reversed(m.triangles[i]));
    }
  m.faceNormals.resize(m.triangles.size());
  for (uint32_t i = 0; i < n; ++i) {
    const Vec3 normal = reversedOut[i] ? -in.faceNormals[tris[i]] : in.faceNormals[tris[i]];
    m.faceNormals[i] = normal;
    if (copy[i] != kNoNeighbour) m.faceNormals[copy[i]] = -normal;
  }
  m.twoSidedSheet = m.planar;  // every component of a planar mesh is a shell (no volume)

  // 5. Pairing, edge by edge.
  m.neighbours.assign(m.triangles.size(), {kNoNeighbour, kNoNeighbour, kNoNeighbour});
  auto link = [&](uint32_t t, uint8_t k, uint32_t u, uint8_t j) {
    m.neighbours[t][k] = u;
    m.neighbours[u][j] = t;
  };
  struct ShellSide {
    double angle;
    uint32_t i;  // surface triangle
    uint8_t k;   // its edge, as given
    bool forward;
  };
  std::vector<ShellSide> shell;
  std::vector<std::pair<uint32_t, size_t>> solidAt;  // (component, half-edge)
  for (size_t g = 0; g < groups; ++g) {
    shell.clear();
    solidAt.clear();
    for (size_t h = groupStart[g]; h < groupStart[g + 1]; ++h) {
      const HalfEdge& e = half[h];
      if (solid[component[e.t]])
        solidAt.push_back({component[e.t], h});
      else
        shell.push_back({0.0, e.t, e.k, e.forward});
    }
    // Solids: each component's two half-edges here, which run opposite ways (step 3).
    std::sort(solidAt.begin(), solidAt.end());
    for (size_t s = 0; s + 1 < solidAt.size(); s += 2) {
      const HalfEdge &x = half[solidAt[s].second], &y = half[solidAt[s + 1].second];
      link(x.t, reversedOut[x.t] ? kReverseOf[x.k] : x.k, y.t, reversedOut[y.t] ? kReverseOf[y.k] : y.k);
    }
    if (shell.empty()) continue;
    if (shell.size() > 2) {
      // Radial order around the edge u -> v (u the smaller vertex id), from the first triangle's
      // far corner. One or two triangles need no order: either way round pairs the same sides.
      const auto u = static_cast<uint32_t>(half[groupStart[g]].key >> 32);
      const auto v = static_cast<uint32_t>(half[groupStart[g]].key & 0xffffffffu);
      const glm::dvec3 pu(m.positions[u]);
      const glm::dvec3 axis = glm::normalize(glm::dvec3(m.positions[v]) - pu);
      glm::dvec3 e1(0.0), e2(0.0);
      for (size_t s = 0; s < shell.size(); ++s) {
        const uint32_t far = input(shell[s].i)[(shell[s].k + 2) % 3];
        glm::dvec3 r = glm::dvec3(m.positions[far]) - pu;
        r -= axis * glm::dot(r, axis);
        if (s == 0) {
          e1 = glm::normalize(r);
          e2 = glm::cross(axis, e1);
        }
        const double angle = std::atan2(glm::dot(r, e2), glm::dot(r, e1));
        shell[s].angle = std::isfinite(angle) ? angle : 0.0;
      }
      std::sort(shell.begin(), shell.end(), [](const ShellSide& x, const ShellSide& y) {
        return std::tie(x.angle, x.i, x.k) < std::tie(y.angle, y.i, y.k);
      });
    }
    // The sector from shell[s] to shell[s + 1] (increasing angle, turning about u -> v) is faced by
    // the side of shell[s] that runs u -> v and the side of shell[s + 1] that runs v -> u. A
    // surface triangle runs u -> v when its half-edge (as given) is forward and it was not
    // reversed, or the other way round; its copy runs the other way.
    auto side = [&](const ShellSide& e, bool uToV) -> std::pair<uint32_t, uint8_t> {
      const bool surfaceUToV = e.forward != (reversedOut[e.i] != 0);
      if (surfaceUToV == uToV) return {e.i, reversedOut[e.i] ? kReverseOf[e.k] : e.k};
      return {copy[e.i], reversedOut[e.i] ? e.k : kReverseOf[e.k]};
    };
    const size_t count = shell.size();
    for (size_t s = 0; s < count; ++s) {
      const auto [xt, xk] = side(shell[s], true);
      const auto [yt, yk] = side(shell[(s + 1) % count], false);
      link(xt, xk, yt, yk);
    }
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
        fail(
            "silhouette: the boundary does not close at vertex {} ({:.4g}, {:.4g}, {:.4g}): the topology is not a "
            "closed "
            "oriented surface (build it with occluderTopology)",
            v, topology.positions[v].x, topology.positions[v].y, topology.positions[v].z);
      current = out[c];
    }
    rings.push_back(std::move(ring));
  }
  return rings;
}

}  // namespace penumbra
