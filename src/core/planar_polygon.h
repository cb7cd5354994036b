// Simple polygons in their own plane (2D, double precision): the geometry behind polygon lights
// that are not convex (Rouf 2007, Section 5.2.5: "In case of concave planar light sources, we
// suggest breaking up the light source into a minimal number of convex polygons").
//
//  - simplePolygonProblem: what keeps a polygon from being simple (two vertices that coincide, two
//    edges that cross or touch, two consecutive edges that fold back onto each other), or nothing.
//  - earClip: a triangulation by ear clipping (Meisters 1975; O(n r) per ear, r the reflex vertices),
//    for uniform sampling by area.
//  - optimalConvexPartition: the fewest convex pieces whose corners are the polygon's own vertices
//    (pieces bounded by its edges and diagonals), by the dynamic programme over diagonals of Greene
//    (1983, "The decomposition of polygons into convex parts"): the piece on the diagonal (i, j) is
//    a convex chain i < v1 < ... < j, the rest are the sub-polygons its chords cut off; O(n^5 / 120)
//    steps. Among partitions with the fewest pieces it takes one whose cuts are shortest in total
//    (compact pieces rather than slivers).
//  - convexPartition: what polygon lights use. The same programme, run on the polygon with points
//    added where the extension of an edge beyond a reflex corner first meets the boundary, so a cut
//    may also continue an edge (an L splits into two rectangles, not two trapezoids; a U into three
//    rectangles). Its count is never above optimalConvexPartition's (every diagonal is still
//    available) and is what Rouf asks for: the fewest pieces, among cuts along diagonals and edge
//    extensions. Silhouette techniques gain from it: ssv is exact for a rect light whose sides are
//    parallel to the occluder's edges, and a rectangle piece stays one. Above
//    kOptimalPartitionMaxVertices corners (after the added points) the programme runs on the
//    polygon alone, and above that many vertices Hertel & Mehlhorn (1983) take over: the ear
//    triangulation with every diagonal removed whose removal leaves both of its ends convex, at
//    most 4 times the optimum, O(n^2). Partitions with Steiner points anywhere (Chazelle 1980) can
//    have fewer pieces still; no technique here needs them.
//
// Tolerances: `turnTolerance` is in squared length units (the cross product of two consecutive
// edges, |e1||e2| sin(turn)); a corner whose turn is >= -turnTolerance counts as convex, so a
// polygon with (nearly) collinear vertices stays one convex piece. `lengthTolerance` is the distance
// below which two vertices coincide or a vertex touches an edge.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace penumbra::polygon2d {

using DVec2 = glm::dvec2;

inline constexpr size_t kOptimalPartitionMaxVertices = 64;

// Twice the signed area (positive when counter-clockwise).
double twiceSignedArea(const std::vector<DVec2>& p);

// Empty when `p` is simple; otherwise what is wrong, naming vertices and edges by index (edge i runs
// from vertex i to vertex i + 1): "vertices 2 and 5 coincide", "edges 1 and 4 cross", "edges 0 and 2
// touch", "edges 3 and 4 overlap". O(n^2).
std::string simplePolygonProblem(const std::vector<DVec2>& p, double lengthTolerance);

// Every corner of the counter-clockwise polygon `p` turns left (or straight, within the tolerance).
bool isConvex(const std::vector<DVec2>& p, double turnTolerance);

// Triangles (vertex indices, counter-clockwise) covering the simple counter-clockwise polygon `p`.
std::vector<std::array<uint32_t, 3>> earClip(const std::vector<DVec2>& p);

// Convex pieces (vertex indices, counter-clockwise, each starting at its lowest index) of the simple
// counter-clockwise polygon `p`, cut along diagonals only. A piece keeps the polygon's straight
// corners (turn within the tolerance) that lie on it.
std::vector<std::vector<uint32_t>> optimalConvexPartition(const std::vector<DVec2>& p, double turnTolerance);
std::vector<std::vector<uint32_t>> hertelMehlhorn(const std::vector<DVec2>& p, double turnTolerance);

// A partition whose pieces may also have corners on the polygon's edges.
struct ConvexPartition {
  struct EdgePoint {
    uint32_t edge = 0;  //!< the edge from vertex `edge` to vertex `edge` + 1 (mod n)
    double t = 0.0;     //!< in (0, 1), from its first vertex
  };
  std::vector<EdgePoint> added;               //!< corner n + k of a piece is added[k]
  std::vector<std::vector<uint32_t>> pieces;  //!< corners, counter-clockwise

  // The corner's position in the polygon's plane.
  DVec2 corner(const std::vector<DVec2>& p, uint32_t id) const {
    if (id < p.size()) return p[id];
    const EdgePoint& e = added[id - p.size()];
    return p[e.edge] + e.t * (p[(e.edge + 1) % p.size()] - p[e.edge]);
  }
};
ConvexPartition convexPartition(const std::vector<DVec2>& p, double turnTolerance);

}  // namespace penumbra::polygon2d
