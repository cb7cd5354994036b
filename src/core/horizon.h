// The light above a receiver's horizon: the share of the light on the side of the receiver's tangent
// plane that its geometric normal points to (as its triangle is wound: out of a closed surface). A ray
// from the surface to a point of the light beyond that plane enters the surface's own solid, so V
// cannot exceed this share; and where the normal faces away from the light's centre (a back-facing
// facet next to a smooth model's terminator, whose shading normal still faces the light), the
// reference's rays start inside the solid and V is 0. Single-sample techniques see the light from its
// centre only: near a terminator they light what the receiver's own surface half hides, and they light
// back-facing facets outright (most of the umbra leaks the corpus counts). Clamping V to the share
// gives back what the surface's own horizon hides, exactly for a locally flat closed surface. An open
// sheet seen from its back side is darkened by it, as brabec's rule for back-facing receivers does.
//
// The share is measured as Light::sample distributes its points, each in closed form:
//  - rect and polygon: the area of the polygon clipped to the side (one half-plane clip, exact for a
//    concave polygon too);
//  - disk: the circular segment on that side;
//  - sphere: the same for its silhouette disk seen from p, which Light::sample fills uniformly;
//  - directional: the same for its disk of directions at unit distance (a limb-darkened profile is
//    taken as uniform: an approximation);
//  - segment: the length on that side.
#pragma once

#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/light.h"

namespace penumbra {

// The share in [0, 1] of `light` on the side of the plane through p towards which ng points (any
// length; 1 when ng is 0).
float lightAboveHorizon(const Light& light, const Vec3& p, const Vec3& ng);

// v = min(v, lightAboveHorizon) at every pixel that sees geometry, from its position and geometric
// normal; in parallel over rows.
void clampToHorizon(const GBuffer& gbuffer, const Light& light, Image<float>& v);

// The same for row y alone, in place (v: the row's V): for a pass that writes V a row at a time and
// clamps each row while the row's G-buffer reads are still in cache, where a pass of its own would read
// the position and normal of every pixel from memory again.
void clampRowToHorizon(const GBuffer& gbuffer, const Light& light, int y, float* v);

}  // namespace penumbra
