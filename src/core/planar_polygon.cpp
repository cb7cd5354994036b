// Simple planar polygons: validation, ear clipping and convex partitions. See
// src/core/planar_polygon.h for the algorithms and the tolerances.
#include "core/planar_polygon.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace penumbra::polygon2d {

namespace {

double cross(const DVec2& a, const DVec2& b) { return a.x * b.y - a.y * b.x; }
// > 0 when a, b, c turn left (counter-clockwise).
double orient(const DVec2& a, const DVec2& b, const DVec2& c) { return cross(b - a, c - a); }

double pointSegmentDistance(const DVec2& q, const DVec2& a, const DVec2& b) {
  const DVec2 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0.0 ? std::clamp(glm::dot(q - a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(q - (a + t * ab));
}

// Segments a-b and c-d cross properly (each one's ends strictly on either side of the other's line).
bool properlyCross(const DVec2& a, const DVec2& b, const DVec2& c, const DVec2& d) {
  const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  return ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0)) && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0));
}

// Segments a-b and c-d share a point, touching included (an end within `tol` of the other segment).
bool segmentsMeet(const DVec2& a, const DVec2& b, const DVec2& c, const DVec2& d, double tol) {
  return properlyCross(a, b, c, d) || pointSegmentDistance(a, c, d) <= tol || pointSegmentDistance(b, c, d) <= tol ||
         pointSegmentDistance(c, a, b) <= tol || pointSegmentDistance(d, a, b) <= tol;
}

// Point q inside or on the boundary of the counter-clockwise triangle a, b, c.
bool inClosedTriangle(const DVec2& q, const DVec2& a, const DVec2& b, const DVec2& c) {
  return orient(a, b, q) >= 0.0 && orient(b, c, q) >= 0.0 && orient(c, a, q) >= 0.0;
}

// The segment from vertex i to vertex j (not neighbours) runs inside the simple counter-clockwise
// polygon: it leaves i into the interior (O'Rourke's InCone, both ends) and meets no edge other than
// those at i and j, nor any vertex on the way (closed test: a diagonal through a vertex is refused).
bool isDiagonal(const std::vector<DVec2>& p, size_t i, size_t j) {
  const size_t n = p.size();
  const auto inCone = [&](size_t a, size_t b) {
    const DVec2 &prev = p[(a + n - 1) % n], &cur = p[a], &next = p[(a + 1) % n];
    if (orient(prev, cur, next) >= 0.0) return orient(cur, p[b], prev) > 0.0 && orient(p[b], cur, next) > 0.0;
    return !(orient(cur, p[b], next) >= 0.0 && orient(p[b], cur, prev) >= 0.0);
  };
  if (!inCone(i, j) || !inCone(j, i)) return false;
  for (size_t k = 0; k < n; ++k) {
    const size_t k1 = (k + 1) % n;
    if (k == i || k == j || k1 == i || k1 == j) continue;
    if (segmentsMeet(p[i], p[j], p[k], p[k1], 0.0)) return false;
  }
  return true;
}

}  // namespace

double twiceSignedArea(const std::vector<DVec2>& p) {
  double a = 0.0;
  for (size_t i = 0; i < p.size(); ++i) a += cross(p[i], p[(i + 1) % p.size()]);
  return a;
}

std::string simplePolygonProblem(const std::vector<DVec2>& p, double tol) {
  const size_t n = p.size();
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      if (glm::length(p[i] - p[j]) <= tol) return fmt::format("vertices {} and {} coincide", i, j);
  for (size_t i = 0; i < n; ++i) {
    const DVec2 &a = p[i], &b = p[(i + 1) % n];
    for (size_t j = i + 1; j < n; ++j) {
      const DVec2 &c = p[j], &d = p[(j + 1) % n];
      if (j == i + 1 || (i == 0 && j == n - 1)) {
        // Consecutive edges share one vertex s; they overlap when the corner at s folds back, the far
        // end of one lying on the other.
        const bool iFirst = j == i + 1;
        const DVec2& s = iFirst ? b : a;
        const DVec2& e0 = iFirst ? a : b;
        const DVec2& e1 = iFirst ? d : c;
        if (pointSegmentDistance(e1, s, e0) <= tol || pointSegmentDistance(e0, s, e1) <= tol)
          return fmt::format("edges {} and {} overlap", i, j);
        continue;
      }
      if (properlyCross(a, b, c, d)) return fmt::format("edges {} and {} cross", i, j);
      if (segmentsMeet(a, b, c, d, tol)) return fmt::format("edges {} and {} touch", i, j);
    }
  }
  return {};
}

bool isConvex(const std::vector<DVec2>& p, double turnTolerance) {
  const size_t n = p.size();
  for (size_t i = 0; i < n; ++i)
    if (cross(p[(i + 1) % n] - p[i], p[(i + 2) % n] - p[(i + 1) % n]) < -turnTolerance) return false;
  return true;
}

std::vector<std::array<uint32_t, 3>> earClip(const std::vector<DVec2>& p) {
  std::vector<uint32_t> ring(p.size());
  for (size_t i = 0; i < p.size(); ++i) ring[i] = static_cast<uint32_t>(i);
  std::vector<std::array<uint32_t, 3>> triangles;
  size_t start = 0;
  while (ring.size() > 3) {
    const size_t m = ring.size();
    // Only a corner that does not turn left can lie in an ear (any other vertex inside would be
    // reached by a reflex one first), so those are the vertices to test.
    std::vector<uint32_t> blockers;
    for (size_t k = 0; k < m; ++k)
      if (orient(p[ring[(k + m - 1) % m]], p[ring[k]], p[ring[(k + 1) % m]]) <= 0.0) blockers.push_back(ring[k]);
    size_t ear = m, straightest = 0;
    double bestTurn = -std::numeric_limits<double>::infinity();
    for (size_t s = 0; s < m && ear == m; ++s) {
      const size_t k = (start + s) % m;
      const uint32_t a = ring[(k + m - 1) % m], b = ring[k], c = ring[(k + 1) % m];
      const double turn = orient(p[a], p[b], p[c]);
      if (turn > bestTurn) {
        bestTurn = turn;
        straightest = k;
      }
      if (!(turn > 0.0)) continue;
      bool free = true;
      for (uint32_t r : blockers)
        if (r != a && r != b && r != c && inClosedTriangle(p[r], p[a], p[b], p[c])) {
          free = false;
          break;
        }
      if (free) ear = k;
    }
    // A simple polygon always has an ear (Meisters); rounding in a nearly degenerate one can hide it,
    // and then the corner that turns most is cut, so the loop ends whatever the input.
    if (ear == m) ear = straightest;
    triangles.push_back({ring[(ear + m - 1) % m], ring[ear], ring[(ear + 1) % m]});
    ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(ear));
    start = ear % ring.size();
  }
  if (ring.size() == 3) triangles.push_back({ring[0], ring[1], ring[2]});
  return triangles;
}

std::vector<std::vector<uint32_t>> optimalConvexPartition(const std::vector<DVec2>& p, double turnTolerance) {
  const size_t n = p.size();
  if (n <= 3 || isConvex(p, turnTolerance)) {
    std::vector<uint32_t> all(n);
    for (size_t i = 0; i < n; ++i) all[i] = static_cast<uint32_t>(i);
    return {all};
  }
  const auto at = [n](size_t i, size_t j) { return i * n + j; };
  const auto convexCorner = [&](size_t a, size_t b, size_t c) { return orient(p[a], p[b], p[c]) >= -turnTolerance; };
  // chord[i, j], i < j: a polygon edge or a diagonal; cut[i, j]: its length when it is a diagonal.
  std::vector<uint8_t> chord(n * n, 0);
  std::vector<double> cut(n * n, 0.0);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      const bool edge = j == i + 1 || (i == 0 && j == n - 1);
      chord[at(i, j)] = edge || isDiagonal(p, i, j);
      if (!edge) cut[at(i, j)] = glm::length(p[j] - p[i]);
    }
  // Costs are (pieces, total cut length), compared in that order.
  struct Cost {
    int pieces = std::numeric_limits<int>::max();
    double length = 0.0;
    bool valid() const { return pieces != std::numeric_limits<int>::max(); }
    bool operator<(const Cost& o) const { return pieces != o.pieces ? pieces < o.pieces : length < o.length; }
    Cost operator+(const Cost& o) const { return {pieces + o.pieces, length + o.length}; }
  };
  // best[i, j]: the sub-polygon i, i+1, ..., j closed by the chord (j, i), cut into the fewest convex
  // pieces (the chord itself not counted as a cut); inner[i, j]: the vertices strictly between i and
  // j of the piece that holds the chord.
  std::vector<Cost> best(n * n);
  std::vector<std::vector<uint32_t>> inner(n * n);
  for (size_t i = 0; i + 1 < n; ++i) best[at(i, i + 1)] = {0, 0.0};
  // What the chord (b, d) of a piece brings: the sub-polygon it cuts off, and itself as a cut.
  const auto beyond = [&](size_t b, size_t d) { return best[at(b, d)] + Cost{0, cut[at(b, d)]}; };
  // chain[a, b]: the cheapest chain i = v0 < ... < a < b built so far (convex at every corner from
  // v0 to a), counting what its chords cut off; from[a, b]: the vertex before a on it.
  std::vector<Cost> chain(n * n);
  std::vector<uint32_t> from(n * n);
  for (size_t len = 2; len < n; ++len)
    for (size_t i = 0; i + len < n; ++i) {
      const size_t j = i + len;
      if (!chord[at(i, j)]) continue;
      std::fill(chain.begin(), chain.end(), Cost{});
      for (size_t b = i + 1; b < j; ++b)
        if (chord[at(i, b)] && best[at(i, b)].valid() && convexCorner(j, i, b)) {
          chain[at(i, b)] = beyond(i, b);
          from[at(i, b)] = static_cast<uint32_t>(i);
        }
      for (size_t b = i + 1; b < j; ++b)
        for (size_t a = i; a < b; ++a) {
          if (!chain[at(a, b)].valid()) continue;
          for (size_t d = b + 1; d <= j; ++d) {
            if (!chord[at(b, d)] || !best[at(b, d)].valid() || !convexCorner(a, b, d)) continue;
            const Cost c = chain[at(a, b)] + beyond(b, d);
            if (c < chain[at(b, d)]) {
              chain[at(b, d)] = c;
              from[at(b, d)] = static_cast<uint32_t>(a);
            }
          }
        }
      Cost cheapest;
      size_t last = 0;
      for (size_t a = i + 1; a < j; ++a)
        if (chain[at(a, j)] < cheapest && convexCorner(a, j, i)) {
          cheapest = chain[at(a, j)];
          last = a;
        }
      if (!cheapest.valid()) continue;
      best[at(i, j)] = cheapest + Cost{1, 0.0};
      std::vector<uint32_t> piece;
      for (size_t a = last, b = j; a != i;) {
        piece.push_back(static_cast<uint32_t>(a));
        const size_t prev = from[at(a, b)];
        b = a;
        a = prev;
      }
      std::reverse(piece.begin(), piece.end());
      inner[at(i, j)] = std::move(piece);
    }
  // Unfold: the piece on chord (i, j), then the sub-polygons cut off by its chords.
  std::vector<std::vector<uint32_t>> out;
  std::vector<std::pair<size_t, size_t>> todo = {{0, n - 1}};
  while (!todo.empty()) {
    const auto [i, j] = todo.back();
    todo.pop_back();
    if (j == i + 1) continue;
    std::vector<uint32_t> piece = {static_cast<uint32_t>(i)};
    piece.insert(piece.end(), inner[at(i, j)].begin(), inner[at(i, j)].end());
    piece.push_back(static_cast<uint32_t>(j));
    for (size_t k = 0; k + 1 < piece.size(); ++k) todo.emplace_back(piece[k], piece[k + 1]);
    out.push_back(std::move(piece));
  }
  return out;
}

std::vector<std::vector<uint32_t>> hertelMehlhorn(const std::vector<DVec2>& p, double turnTolerance) {
  const size_t n = p.size();
  std::vector<std::vector<uint32_t>> pieces;
  for (const auto& t : earClip(p)) pieces.push_back({t[0], t[1], t[2]});
  // The triangulation's diagonals, each once, in the order the ears were cut.
  std::vector<std::pair<uint32_t, uint32_t>> diagonals;
  for (const auto& t : pieces)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      if ((a + 1) % n == b || (b + 1) % n == a) continue;  // a polygon edge
      if (a < b) diagonals.emplace_back(a, b);
    }
  const auto findEdge = [&](uint32_t a, uint32_t b, size_t& piece, size_t& pos) {
    for (piece = 0; piece < pieces.size(); ++piece) {
      const std::vector<uint32_t>& q = pieces[piece];
      for (pos = 0; pos < q.size(); ++pos)
        if (q[pos] == a && q[(pos + 1) % q.size()] == b) return true;
    }
    return false;
  };
  for (const auto& [a, b] : diagonals) {
    size_t pi, pa, qi, qb;
    if (!findEdge(a, b, pi, pa) || !findEdge(b, a, qi, qb) || pi == qi) continue;
    // P holds a -> b, Q holds b -> a. The union runs b .. (around P) .. a, then a .. (around Q) .. b.
    const std::vector<uint32_t>& P = pieces[pi];
    const std::vector<uint32_t>& Q = pieces[qi];
    std::vector<uint32_t> merged;
    for (size_t k = 1; k <= P.size(); ++k) merged.push_back(P[(pa + k) % P.size()]);  // b ... a
    for (size_t k = 2; k < Q.size(); ++k) merged.push_back(Q[(qb + k) % Q.size()]);   // after a ... before b
    const size_t m = merged.size();
    const auto corner = [&](size_t k) {
      return orient(p[merged[(k + m - 1) % m]], p[merged[k]], p[merged[(k + 1) % m]]) >= -turnTolerance;
    };
    // Only the corners at a (index P.size() - 1) and b (index 0) change.
    if (!corner(0) || !corner(P.size() - 1)) continue;
    pieces[pi] = std::move(merged);
    pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(qi));
  }
  for (std::vector<uint32_t>& q : pieces) std::rotate(q.begin(), std::min_element(q.begin(), q.end()), q.end());
  return pieces;
}

ConvexPartition convexPartition(const std::vector<DVec2>& p, double turnTolerance) {
  const size_t n = p.size();
  ConvexPartition out;
  if (isConvex(p, turnTolerance) || n > kOptimalPartitionMaxVertices) {
    out.pieces =
        n > kOptimalPartitionMaxVertices ? hertelMehlhorn(p, turnTolerance) : optimalConvexPartition(p, turnTolerance);
    return out;
  }
  double size = 0.0;
  for (const DVec2& v : p) size = std::max(size, glm::length(v - p[0]));
  const double tiny = 1e-9 * size;
  // Where each edge at a reflex corner, continued beyond it, first meets the boundary.
  std::vector<std::vector<std::pair<double, uint32_t>>> onEdge(n);  // per edge: (t, index into out.added)
  for (size_t r = 0; r < n; ++r) {
    const size_t prev = (r + n - 1) % n, next = (r + 1) % n;
    if (orient(p[prev], p[r], p[next]) >= -turnTolerance) continue;
    for (const size_t from : {prev, next}) {
      const DVec2 d = glm::normalize(p[r] - p[from]);
      double nearest = std::numeric_limits<double>::infinity(), hitT = 0.0;
      size_t hitEdge = n;
      for (size_t e = 0; e < n; ++e) {
        const size_t e1 = (e + 1) % n;
        if (e == r || e1 == r) continue;
        const DVec2 ab = p[e1] - p[e];
        const double denom = cross(d, ab);
        if (std::abs(denom) <= 1e-12 * glm::length(ab)) continue;  // parallel
        const DVec2 ar = p[e] - p[r];
        const double s = cross(ar, ab) / denom, t = cross(ar, d) / denom;
        if (s > tiny && t >= 0.0 && t <= 1.0 && s < nearest) {
          nearest = s;
          hitEdge = e;
          hitT = t;
        }
      }
      if (hitEdge == n) continue;
      const double len = glm::length(p[(hitEdge + 1) % n] - p[hitEdge]);
      if (hitT * len <= tiny || (1.0 - hitT) * len <= tiny) continue;  // a vertex: a diagonal reaches it
      bool known = false;
      for (const auto& [t, k] : onEdge[hitEdge]) known = known || std::abs(t - hitT) * len <= tiny;
      if (known) continue;
      onEdge[hitEdge].emplace_back(hitT, static_cast<uint32_t>(out.added.size()));
      out.added.push_back({static_cast<uint32_t>(hitEdge), hitT});
    }
  }
  // The polygon with the added points in place along their edges; ids maps its corners back.
  std::vector<DVec2> refined;
  std::vector<uint32_t> ids;
  for (size_t e = 0; e < n; ++e) {
    refined.push_back(p[e]);
    ids.push_back(static_cast<uint32_t>(e));
    std::sort(onEdge[e].begin(), onEdge[e].end());
    for (const auto& [t, k] : onEdge[e]) {
      refined.push_back(out.corner(p, static_cast<uint32_t>(n + k)));
      ids.push_back(static_cast<uint32_t>(n + k));
    }
  }
  if (refined.size() > kOptimalPartitionMaxVertices) {
    out.added.clear();
    out.pieces = optimalConvexPartition(p, turnTolerance);
    return out;
  }
  for (std::vector<uint32_t>& piece : optimalConvexPartition(refined, turnTolerance)) {
    for (uint32_t& c : piece) c = ids[c];
    out.pieces.push_back(std::move(piece));
  }
  return out;
}

}  // namespace penumbra::polygon2d
