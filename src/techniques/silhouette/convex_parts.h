// Techniques built for convex polygonal lights (ssv, wedges) on any simple polygon light, as Rouf
// 2007, Section 5.2.5 proposes: "In case of concave planar light sources, we suggest breaking up
// the light source into a minimal number of convex polygons". The light is cut into
// Light::convexParts (the fewest convex pieces bounded by its edges and diagonals:
// penumbra/planar_polygon.h says how and why), one instance of the technique is prepared per piece,
// each piece a polygon light of its own (its centroid its centre sample, its own silhouettes and
// edge shadows; the instances of ssv and wedges share the scene's occluders, stages.h's
// OccluderCache), and their visibilities are combined by area:
//     V = sum_i A_i V_i / sum_i A_i,
// exact whenever each V_i is, because V is the visible fraction of the emitting area and the pieces
// tile it without overlap. A pixel every piece leaves fully lit (or fully hidden) keeps V = 1 (0)
// exactly. The cost is the technique's times the number of pieces (2 for an L, 3 for a U).
//
// A convex light, and a light of any other shape, goes to one instance unchanged: V, timings and
// stats are the technique's own, bit for bit. With several pieces the timings of passes with the
// same name add up, the stats add up (the work done over all pieces) and a stat "light_parts"
// gives the number of pieces.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "penumbra/technique.h"

namespace penumbra {

// `make` builds one instance of the technique (called once per piece, as needed).
std::unique_ptr<ShadowTechnique> overConvexParts(std::string name,
                                                 std::function<std::unique_ptr<ShadowTechnique>()> make);

}  // namespace penumbra
