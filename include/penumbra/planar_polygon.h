// Simple polygons in their own plane (2D, double precision): the geometry behind polygon lights
// that are not convex (Rouf 2007, Section 5.2.5: "In case of concave planar light sources, we
// suggest breaking up the light source into a minimal number of convex polygons").
//
//  - simplePolygonProblem: what keeps a polygon from being simple (two vertices that coincide, two
//    edges that cross or touch, two consecutive edges that fold back onto each other), or nothing.
//  - earClip: a triangulation by ear clipping (Meisters 1975; O(n r) per ear, r the reflex vertices),
//    for uniform sampling by area.
//  - convexPartition: a partition into convex polygons whose corners are the polygon's own vertices
//    (its pieces are bounded by the polygon's edges and by diagonals). Up to
//    kOptimalPartitionMaxVertices vertices it is optimal: the fewest pieces of any such partition,
//    by the dynamic programme over diagonals of Greene (1983, "The decomposition of polygons into
//    convex parts"; the piece on the diagonal (i, j) is a convex chain i < v1 < ... < j, the rest are
//    the sub-polygons cut off by its chords), O(n^5 / 120) steps: what Rouf asks for, and cheap for
//    the few vertices of a real window or panel. Above that, Hertel & Mehlhorn (1983): the ear
//    triangulation with every diagonal removed whose removal leaves both of its ends convex, at
//    most 4 times the optimum, O(n^2). Partitions with Steiner points (corners inside the polygon)
//    can have fewer pieces (Chazelle 1980); no technique here needs them.
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
// counter-clockwise polygon `p`: optimal up to kOptimalPartitionMaxVertices vertices, Hertel–Mehlhorn
// above. A piece keeps the polygon's straight corners (turn within the tolerance) that lie on it.
std::vector<std::vector<uint32_t>> convexPartition(const std::vector<DVec2>& p, double turnTolerance);
std::vector<std::vector<uint32_t>> optimalConvexPartition(const std::vector<DVec2>& p, double turnTolerance);
std::vector<std::vector<uint32_t>> hertelMehlhorn(const std::vector<DVec2>& p, double turnTolerance);

}  // namespace penumbra::polygon2d
