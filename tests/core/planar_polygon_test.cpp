// Tests of src/core/planar_polygon.h on an L, a U and seeded random star-shaped polygons:
// the ear triangulation and every convex partition tile the polygon (areas add up, and random
// points inside it fall in exactly one piece), every piece is convex and counter-clockwise; the
// partition along diagonals has as few pieces, and among those as short cuts, as an exhaustive
// search over sets of diagonals finds (written here independently: a set of non-crossing diagonals
// cuts the polygon into convex pieces exactly when it splits every reflex corner into angles of at
// most 180 degrees); cuts that continue an edge split an L into two rectangles and a U into three,
// and never give more pieces; Hertel–Mehlhorn stays within its bounds (at most 2r + 1 pieces, r the
// reflex corners, and at most 4 times the optimum).
#include "core/planar_polygon.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

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
    if ((q[i].y > x.y) != (q[j].y > x.y) && x.x < (q[j].x - q[i].x) * (x.y - q[i].y) / (q[j].y - q[i].y) + q[i].x)
      in = !in;
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
void expectConvexTiling(const Poly& p, const std::vector<Poly>& pieces, uint32_t seed) {
  double total = 0.0;
  for (const Poly& q : pieces) {
    ASSERT_GE(q.size(), 3u);
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
    for (const Poly& q : pieces) in += inside(q, x);
    EXPECT_EQ(in, inside(p, x) ? 1 : 0) << "point (" << x.x << ", " << x.y << ")";
  }
}

void expectConvexTiling(const Poly& p, const std::vector<std::vector<uint32_t>>& pieces, uint32_t seed) {
  std::vector<Poly> polys;
  for (const auto& piece : pieces) {
    for (uint32_t k : piece) ASSERT_LT(k, p.size());
    polys.push_back(piecePolygon(p, piece));
  }
  expectConvexTiling(p, polys, seed);
}

std::vector<Poly> piecePolygons(const Poly& p, const ConvexPartition& partition) {
  std::vector<Poly> out;
  for (const auto& piece : partition.pieces) {
    Poly q;
    for (uint32_t c : piece) q.push_back(partition.corner(p, c));
    out.push_back(q);
  }
  return out;
}

// Total length of the cuts: the pieces' perimeters beyond the polygon's own, halved.
double cutLength(const Poly& p, const std::vector<Poly>& pieces) {
  const auto perimeter = [](const Poly& q) {
    double l = 0.0;
    for (size_t i = 0; i < q.size(); ++i) l += glm::length(q[(i + 1) % q.size()] - q[i]);
    return l;
  };
  double sum = 0.0;
  for (const Poly& q : pieces) sum += perimeter(q);
  return 0.5 * (sum - perimeter(p));
}

// Corners of a piece that are not straight (a rectangle has 4).
size_t realCorners(const Poly& q) {
  size_t c = 0;
  for (size_t i = 0; i < q.size(); ++i)
    c += std::abs(cross(q[(i + 1) % q.size()] - q[i], q[(i + 2) % q.size()] - q[(i + 1) % q.size()])) > 1e-12;
  return c;
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

// The fewest pieces of any partition along diagonals, and the shortest total cut among those.
std::pair<size_t, double> exhaustiveMinimum(const Poly& p) {
  std::vector<std::pair<size_t, size_t>> diagonals;
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = i + 1; j < p.size(); ++j)
      if (validDiagonal(p, i, j)) diagonals.emplace_back(i, j);
  std::vector<std::pair<size_t, size_t>> chosen;
  double shortest = std::numeric_limits<double>::infinity();
  std::function<void(size_t, size_t)> search = [&](size_t from, size_t left) {
    if (left == 0) {
      if (!splitsEveryReflexCorner(p, chosen)) return;
      double length = 0.0;
      for (const auto& [a, b] : chosen) length += glm::length(p[a] - p[b]);
      shortest = std::min(shortest, length);
      return;
    }
    for (size_t k = from; k < diagonals.size(); ++k) {
      bool crosses = false;
      for (const auto& c : chosen)
        crosses = crosses || properCross(p[c.first], p[c.second], p[diagonals[k].first], p[diagonals[k].second]);
      if (crosses) continue;
      chosen.push_back(diagonals[k]);
      search(k + 1, left - 1);
      chosen.pop_back();
    }
  };
  for (size_t s = 0;; ++s) {
    search(0, s);
    if (shortest < std::numeric_limits<double>::infinity()) return {s + 1, shortest};
  }
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

TEST(PlanarPolygon, OptimalPartitionHasTheFewestPiecesAndTheShortestCuts) {
  const auto l = optimalConvexPartition(kL, 1e-9);
  EXPECT_EQ(l.size(), 2u);
  expectConvexTiling(kL, l, 1);
  const auto u = optimalConvexPartition(kU, 1e-9);
  // Above the bound ceil(r / 2) + 1 = 2 (each diagonal resolves at most two reflex corners): the
  // notch's two reflex corners share an edge, so no diagonal resolves both.
  EXPECT_EQ(u.size(), 3u);
  EXPECT_EQ(exhaustiveMinimum(kU).first, 3u);
  expectConvexTiling(kU, u, 2);
  // A convex polygon is its own partition, straight corners and all.
  const Poly square = {{0, 0}, {1, 0}, {2, 0}, {2, 1}, {0, 1}};
  EXPECT_EQ(optimalConvexPartition(square, 1e-9), (std::vector<std::vector<uint32_t>>{{0, 1, 2, 3, 4}}));
  for (uint32_t seed = 100; seed < 140; ++seed) {
    const Poly p = starPolygon(seed, 5 + seed % 5);
    SCOPED_TRACE(::testing::Message() << "seed " << seed << ", " << p.size() << " vertices");
    const auto pieces = optimalConvexPartition(p, 1e-12);
    expectConvexTiling(p, pieces, seed);
    const auto [fewest, shortest] = exhaustiveMinimum(p);
    EXPECT_EQ(pieces.size(), fewest);
    std::vector<Poly> polys;
    for (const auto& piece : pieces) polys.push_back(piecePolygon(p, piece));
    EXPECT_NEAR(cutLength(p, polys), shortest, 1e-9);
    EXPECT_GE(pieces.size(), static_cast<size_t>(reflexCorners(p) + 1) / 2 + 1);
  }
}

TEST(PlanarPolygon, CutsMayContinueAnEdge) {
  // The L: two rectangles (cut 1 long), not two trapezoids along the diagonal (1.41).
  const ConvexPartition l = convexPartition(kL, 1e-9);
  const std::vector<Poly> lPieces = piecePolygons(kL, l);
  ASSERT_EQ(lPieces.size(), 2u);
  expectConvexTiling(kL, lPieces, 3);
  for (const Poly& q : lPieces) EXPECT_EQ(realCorners(q), 4u);
  EXPECT_NEAR(cutLength(kL, lPieces), 1.0, 1e-12);
  // The U: three rectangles, the two short vertical cuts (0.5 each) below the notch rather than the
  // two horizontal ones (1 each).
  const ConvexPartition u = convexPartition(kU, 1e-9);
  const std::vector<Poly> uPieces = piecePolygons(kU, u);
  ASSERT_EQ(uPieces.size(), 3u);
  expectConvexTiling(kU, uPieces, 4);
  for (const Poly& q : uPieces) EXPECT_EQ(realCorners(q), 4u);
  EXPECT_NEAR(cutLength(kU, uPieces), 1.0, 1e-12);
  // Never more pieces than along diagonals alone, and always a tiling.
  for (uint32_t seed = 300; seed < 330; ++seed) {
    const Poly p = starPolygon(seed, 5 + seed % 25);
    SCOPED_TRACE(::testing::Message() << "seed " << seed << ", " << p.size() << " vertices");
    const ConvexPartition partition = convexPartition(p, 1e-12);
    expectConvexTiling(p, piecePolygons(p, partition), seed);
    EXPECT_LE(partition.pieces.size(), optimalConvexPartition(p, 1e-12).size());
    for (const auto& e : partition.added) {
      EXPECT_LT(e.edge, p.size());
      EXPECT_GT(e.t, 0.0);
      EXPECT_LT(e.t, 1.0);
    }
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
  const ConvexPartition partition = convexPartition(big, 1e-12);
  expectConvexTiling(big, partition.pieces, 7);
  EXPECT_TRUE(partition.added.empty());
  EXPECT_EQ(partition.pieces, hertelMehlhorn(big, 1e-12));
}

TEST(PlanarPolygon, OptimalPartitionOfTheLargestPolygonIsQuick) {
  // The dynamic programme is O(n^5 / 120) when most chords are diagonals, as in a regular polygon
  // with one corner pushed in: at kOptimalPartitionMaxVertices about 9 million steps.
  const size_t n = kOptimalPartitionMaxVertices;
  Poly p;
  for (size_t i = 0; i < n; ++i)
    p.push_back((i == 0 ? 0.9 : 1.0) * DVec2(std::cos(2.0 * kPiD * i / n), std::sin(2.0 * kPiD * i / n)));
  Timer timer;
  const auto pieces = optimalConvexPartition(p, 1e-12);
  const double ms = timer.elapsedMs();
  expectConvexTiling(p, pieces, 3);
  EXPECT_EQ(pieces.size(), 2u);  // one reflex corner: one diagonal
  EXPECT_LT(ms, 2000.0);
  // convexPartition adds the two points where the edges at that corner, continued, meet the
  // boundary: 66 corners, over the limit, so it partitions the polygon alone.
  EXPECT_EQ(convexPartition(p, 1e-12).pieces, pieces);
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
