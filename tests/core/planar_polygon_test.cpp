// Tests of include/penumbra/planar_polygon.h on an L, a U and seeded random star-shaped polygons:
// the ear triangulation and both convex partitions tile the polygon (areas add up, and random
// points inside it fall in exactly one piece), every piece is convex and counter-clockwise, the
// optimal partition has as few pieces as an exhaustive search over sets of diagonals finds (written
// here independently: a set of non-crossing diagonals cuts the polygon into convex pieces exactly
// when it splits every reflex corner into angles of at most 180 degrees), and Hertel–Mehlhorn stays
// within its bounds (at most 2r + 1 pieces, r the reflex corners, and at most 4 times the optimum).
#include "penumbra/planar_polygon.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "penumbra/sampling.h"
#include "penumbra/timer.h"

namespace penumbra::polygon2d {
namespace {

using Poly = std::vector<DVec2>;
constexpr double kPiD = 3.14159265358979323846;

double unitRandom(uint32_t seed, uint32_t i) { return hashCombine(seed, i) * (1.0 / 4294967296.0); }

// n vertices at sorted random angles and random radii in [0.25, 1] around the origin: simple, and
// concave at many corners.
Poly starPolygon(uint32_t seed, int n) {
  std::vector<double> angles;
  for (int i = 0; i < n; ++i) angles.push_back(2.0 * kPiD * (i + 0.8 * unitRandom(seed, 2 * i)) / n);
  Poly p;
  for (int i = 0; i < n; ++i) {
    const double r = 0.25 + 0.75 * unitRandom(seed, 2 * i + 1);
    p.push_back(r * DVec2(std::cos(angles[i]), std::sin(angles[i])));
  }
  return p;
}

double cross(const DVec2& a, const DVec2& b) { return a.x * b.y - a.y * b.x; }

bool inside(const Poly& q, const DVec2& x) {
  bool in = false;
  for (size_t i = 0, j = q.size() - 1; i < q.size(); j = i++)
    if ((q[i].y > x.y) != (q[j].y > x.y) && x.x < (q[j].x - q[i].x) * (x.y - q[i].y) / (q[j].y - q[i].y) + q[i].x) in = !in;
  return in;
}

int reflexCorners(const Poly& p) {
  int r = 0;
  for (size_t i = 0; i < p.size(); ++i)
    r += cross(p[(i + 1) % p.size()] - p[i], p[(i + 2) % p.size()] - p[(i + 1) % p.size()]) < 0.0;
  return r;
}

Poly piecePolygon(const Poly& p, const std::vector<uint32_t>& piece) {
  Poly q;
  for (uint32_t k : piece) q.push_back(p[k]);
  return q;
}

// Checks that `pieces` tile `p` with convex counter-clockwise pieces.
void expectConvexTiling(const Poly& p, const std::vector<std::vector<uint32_t>>& pieces, uint32_t seed) {
  double total = 0.0;
  for (const auto& piece : pieces) {
    ASSERT_GE(piece.size(), 3u);
    for (uint32_t k : piece) ASSERT_LT(k, p.size());
    const Poly q = piecePolygon(p, piece);
    EXPECT_GT(twiceSignedArea(q), 0.0) << "a piece runs clockwise";
    EXPECT_TRUE(isConvex(q, 1e-12)) << "a piece is not convex";
    total += 0.5 * twiceSignedArea(q);
  }
  EXPECT_NEAR(total, 0.5 * twiceSignedArea(p), 1e-9);
  DVec2 lo(1e30), hi(-1e30);
  for (const DVec2& v : p) {
    lo = glm::min(lo, v);
    hi = glm::max(hi, v);
  }
  for (uint32_t i = 0; i < 400; ++i) {
    const DVec2 x = lo + (hi - lo) * DVec2(unitRandom(seed + 7, 2 * i), unitRandom(seed + 7, 2 * i + 1));
    int in = 0;
    for (const auto& piece : pieces) in += inside(piecePolygon(p, piece), x);
    EXPECT_EQ(in, inside(p, x) ? 1 : 0) << "point (" << x.x << ", " << x.y << ")";
  }
}

// --- The exhaustive search, independent of the library's code. ---

bool properCross(const DVec2& a, const DVec2& b, const DVec2& c, const DVec2& d) {
  const double o1 = cross(b - a, c - a), o2 = cross(b - a, d - a), o3 = cross(d - c, a - c), o4 = cross(d - c, b - c);
  return o1 * o2 < 0.0 && o3 * o4 < 0.0;
}

bool validDiagonal(const Poly& p, size_t i, size_t j) {
  const size_t n = p.size();
  if ((i + 1) % n == j || (j + 1) % n == i) return false;
  for (size_t k = 0; k < n; ++k)
    if (properCross(p[i], p[j], p[k], p[(k + 1) % n])) return false;
  return inside(p, 0.5 * (p[i] + p[j]));  // general position: no vertex lies on another's diagonal
}

// Angle of direction d measured counter-clockwise from direction `from`, in [0, 2 pi).
double ccwAngle(const DVec2& from, const DVec2& d) {
  double a = std::atan2(cross(from, d), glm::dot(from, d));
  return a < 0.0 ? a + 2.0 * kPiD : a;
}

bool splitsEveryReflexCorner(const Poly& p, const std::vector<std::pair<size_t, size_t>>& chosen) {
  const size_t n = p.size();
  for (size_t v = 0; v < n; ++v) {
    const DVec2 toNext = p[(v + 1) % n] - p[v], toPrev = p[(v + n - 1) % n] - p[v];
    const double interior = ccwAngle(toNext, toPrev);  // the polygon's inside lies counter-clockwise from toNext
    if (interior <= kPiD) continue;
    std::vector<double> cuts = {0.0, interior};
    for (const auto& [a, b] : chosen)
      if (a == v || b == v) cuts.push_back(ccwAngle(toNext, p[a == v ? b : a] - p[v]));
    std::sort(cuts.begin(), cuts.end());
    for (size_t k = 0; k + 1 < cuts.size(); ++k)
      if (cuts[k + 1] - cuts[k] > kPiD) return false;
  }
  return true;
}

size_t exhaustiveMinimum(const Poly& p) {
  std::vector<std::pair<size_t, size_t>> diagonals;
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = i + 1; j < p.size(); ++j)
      if (validDiagonal(p, i, j)) diagonals.emplace_back(i, j);
  std::vector<std::pair<size_t, size_t>> chosen;
  std::function<bool(size_t, size_t)> search = [&](size_t from, size_t left) {
    if (left == 0) return splitsEveryReflexCorner(p, chosen);
    for (size_t k = from; k < diagonals.size(); ++k) {
      bool crosses = false;
      for (const auto& c : chosen) crosses = crosses || properCross(p[c.first], p[c.second], p[diagonals[k].first], p[diagonals[k].second]);
      if (crosses) continue;
      chosen.push_back(diagonals[k]);
      const bool found = search(k + 1, left - 1);
      chosen.pop_back();
      if (found) return true;
    }
    return false;
  };
  for (size_t s = 0;; ++s)
    if (search(0, s)) return s + 1;
}

// --- Tests. ---

const Poly kL = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
const Poly kU = {{0, 0}, {3, 0}, {3, 2}, {2, 2}, {2, 0.5}, {1, 0.5}, {1, 2}, {0, 2}};

TEST(PlanarPolygon, EarClippingTilesThePolygon) {
  std::vector<Poly> polys = {kL, kU};
  for (uint32_t seed = 0; seed < 20; ++seed) polys.push_back(starPolygon(seed, 5 + seed % 30));
  for (size_t k = 0; k < polys.size(); ++k) {
    SCOPED_TRACE(::testing::Message() << "polygon " << k);
    const Poly& p = polys[k];
    const auto triangles = earClip(p);
    ASSERT_EQ(triangles.size(), p.size() - 2);
    std::vector<std::vector<uint32_t>> pieces;
    for (const auto& t : triangles) pieces.push_back({t[0], t[1], t[2]});
    expectConvexTiling(p, pieces, static_cast<uint32_t>(k));
  }
}

TEST(PlanarPolygon, OptimalPartitionHasTheFewestPieces) {
  const auto l = optimalConvexPartition(kL, 1e-9);
  EXPECT_EQ(l.size(), 2u);
  expectConvexTiling(kL, l, 1);
  const auto u = optimalConvexPartition(kU, 1e-9);
  // Above the bound ceil(r / 2) + 1 = 2 (each diagonal resolves at most two reflex corners): the
  // notch's two reflex corners share an edge, so no diagonal resolves both.
  EXPECT_EQ(u.size(), 3u);
  EXPECT_EQ(exhaustiveMinimum(kU), 3u);
  expectConvexTiling(kU, u, 2);
  // A convex polygon is its own partition, straight corners and all.
  const Poly square = {{0, 0}, {1, 0}, {2, 0}, {2, 1}, {0, 1}};
  EXPECT_EQ(optimalConvexPartition(square, 1e-9), (std::vector<std::vector<uint32_t>>{{0, 1, 2, 3, 4}}));
  for (uint32_t seed = 100; seed < 140; ++seed) {
    const Poly p = starPolygon(seed, 5 + seed % 5);
    SCOPED_TRACE(::testing::Message() << "seed " << seed << ", " << p.size() << " vertices");
    const auto pieces = optimalConvexPartition(p, 1e-12);
    expectConvexTiling(p, pieces, seed);
    EXPECT_EQ(pieces.size(), exhaustiveMinimum(p));
    EXPECT_GE(pieces.size(), static_cast<size_t>(reflexCorners(p) + 1) / 2 + 1);
  }
}

TEST(PlanarPolygon, HertelMehlhornStaysWithinItsBounds) {
  for (uint32_t seed = 200; seed < 230; ++seed) {
    const Poly p = starPolygon(seed, 5 + seed % 40);
    SCOPED_TRACE(::testing::Message() << "seed " << seed << ", " << p.size() << " vertices");
    const auto pieces = hertelMehlhorn(p, 1e-12);
    expectConvexTiling(p, pieces, seed);
    const auto optimal = optimalConvexPartition(p, 1e-12);
    EXPECT_GE(pieces.size(), optimal.size());
    EXPECT_LE(pieces.size(), 4 * optimal.size());
    EXPECT_LE(pieces.size(), static_cast<size_t>(2 * reflexCorners(p) + 1));
  }
  // Above kOptimalPartitionMaxVertices the partition is Hertel–Mehlhorn's.
  const Poly big = starPolygon(7, 200);
  const auto pieces = convexPartition(big, 1e-12);
  expectConvexTiling(big, pieces, 7);
  EXPECT_EQ(pieces, hertelMehlhorn(big, 1e-12));
}

TEST(PlanarPolygon, OptimalPartitionOfTheLargestPolygonIsQuick) {
  // The dynamic programme is O(n^5 / 120) when most chords are diagonals, as in a regular polygon
  // with one corner pushed in: at kOptimalPartitionMaxVertices about 9 million steps.
  const size_t n = kOptimalPartitionMaxVertices;
  Poly p;
  for (size_t i = 0; i < n; ++i) p.push_back((i == 0 ? 0.9 : 1.0) * DVec2(std::cos(2.0 * kPiD * i / n), std::sin(2.0 * kPiD * i / n)));
  Timer timer;
  const auto pieces = convexPartition(p, 1e-12);
  const double ms = timer.elapsedMs();
  expectConvexTiling(p, pieces, 3);
  EXPECT_EQ(pieces.size(), 2u);  // one reflex corner: one diagonal
  EXPECT_LT(ms, 2000.0);
}

TEST(PlanarPolygon, SimplePolygonProblemsNameVerticesAndEdges) {
  EXPECT_EQ(simplePolygonProblem(kL, 1e-9), "");
  EXPECT_EQ(simplePolygonProblem(starPolygon(5, 40), 1e-9), "");
  EXPECT_EQ(simplePolygonProblem({{0, 0}, {1, 1}, {1, 0}, {0, 1}}, 1e-9), "edges 0 and 2 cross");
  EXPECT_EQ(simplePolygonProblem({{0, 0}, {2, 0}, {2, 2}, {1, 0}, {0, 2}}, 1e-9), "edges 0 and 2 touch");
  EXPECT_EQ(simplePolygonProblem({{0, 0}, {2, 0}, {1, 0}, {1, 1}}, 1e-9), "edges 0 and 1 overlap");
  EXPECT_EQ(simplePolygonProblem({{0, 0}, {1, 0}, {1, 1}, {0, 1}, {1, 0}}, 1e-9), "vertices 1 and 4 coincide");
  // The closing edge (n - 1 -> 0) counts: the L with its last vertex pushed across its first edge.
  Poly bad = kL;
  bad.back() = DVec2(1.5, -1.0);
  EXPECT_EQ(simplePolygonProblem(bad, 1e-9), "edges 0 and 4 cross");
}

}  // namespace
}  // namespace penumbra::polygon2d
