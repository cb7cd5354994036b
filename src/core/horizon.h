// The receiver's own surface as a bound on V (HorizonClamp, penumbra/technique.h). Single-sample
// techniques see the light from its centre only: they light facets next to a smooth model's terminator
// that face away from the light's centre while their shading normals still face it (most of the umbra
// leaks the real-mesh corpus counts), where the reference's rays leave from the side the centre lies
// on, inside the solid, and find V = 0.
//  - Facing: V = 0 where the geometric normal faces away from the light's centre (brabec's rule for
//    back-facing receivers; an open sheet seen from its back side is darkened too).
//  - Plane: V at most the share of the light on the side of the receiver's face plane that its
//    geometric normal points to (out of a closed surface): a ray to a point of the light beyond that
//    plane enters the face's own solid, so for a flat closed surface the bound is exact. Against the
//    reference it is too dark on a face turned towards the light's centre whose plane cuts the light:
//    the reference's rays leave from the face's lit side, offset by its epsilon, and pass the face's
//    edge where the faceted surface bends away, as they would over the smooth surface it stands for.
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
#include "penumbra/technique.h"

namespace penumbra {

// The share in [0, 1] of `light` on the side of the plane through p towards which ng points (any
// length; 1 when ng is 0).
float lightAboveHorizon(const Light& light, const Vec3& p, const Vec3& ng);

// The clamp of `bound` at every pixel that sees geometry, from its position and geometric normal, in
// parallel over rows: Facing sets V = 0 where the face turns from the light's centre (the side the
// reference's rays leave from, rt::lightSide, is then inside the solid); Plane sets V to at most
// lightAboveHorizon.
void clampToHorizon(const GBuffer& gbuffer, const HorizonBound& bound, Image<float>& v);

// The same for row y alone, in place (v: the row's V): for a pass that writes V a row at a time and
// clamps each row while the row's G-buffer reads are still in cache, where a pass of its own would read
// the position and normal of every pixel from memory again.
void clampRowToHorizon(const GBuffer& gbuffer, const HorizonBound& bound, int y, float* v);

}  // namespace penumbra
