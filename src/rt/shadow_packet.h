// Shadow rays built sixteen at a time, straight into an Embree packet: the ray-generation half of
// the reference's and the few-ray techniques' inner loops (rays to light samples), and of
// raytraced-hard's and parker's (rays to the light's centre).
//
// Lane i is the ray rt::shadowRay builds from the shaded point P_i, with origin O_i (P_i offset off
// its surface, rt::offsetOrigin), towards the light point Light::sample(P_i, u_i): the same points,
// the same offset and the same clipping, to float rounding. The difference is the form: every step
// is one loop over the sixteen lanes, structure of arrays, without calls or branches, which the
// compiler turns into vector code; per-lane scalar code spent more time making a ray than Embree
// spent tracing it. The sphere's per-point set-up (its silhouette disk as seen from P) is redone
// per lane, which in vector form costs less than gathering a per-pixel set-up into the lanes.
//
// Approximation: the concentric map's sine and cosine are minimax polynomials on [-pi/4, pi/4]
// (Cephes' single-precision coefficients, a few ulp from libm's), so a point moves by about 1e-7 of
// the light's size. Lanes whose ray is degenerate (P inside a sphere light, a light point on P, a
// length that overflows) and polygon lights go through the scalar path, exactly as before.
#pragma once

#include "penumbra/light.h"
#include "rt/ray_scene.h"

namespace penumbra::rt {

// Per lane: the shaded point P, the geometric normal Ng there, the ray origin O and the light-sample
// coordinates u in [0,1)^2.
struct alignas(64) ShadowLanes {
  float px[16], py[16], pz[16];
  float nx[16], ny[16], nz[16];  //!< read by offsetOrigins only
  float ox[16], oy[16], oz[16];
  float ux[16], uy[16];

  // P and Ng, for offsetOrigins to make O.
  void setSurface(int lane, const Vec3& wsP, const Vec3& wsNg) {
    px[lane] = wsP.x;
    py[lane] = wsP.y;
    pz[lane] = wsP.z;
    nx[lane] = wsNg.x;
    ny[lane] = wsNg.y;
    nz[lane] = wsNg.z;
  }
};

// Sets the ray origins of lanes [0, count) (ox, oy, oz) from their points and geometric normals:
// rt::offsetOrigin(light, P, Ng, epsilon) for each lane, operation for operation
// (Light::directionToCenter's too), in one vector loop.
void offsetOrigins(const Light& light, float epsilon, int count, ShadowLanes& lanes);

// Writes lanes [0, count) of `packet` (origin, direction, tMin, tMax; the rest as the packet holds
// them) and weight[i], the light's profile weight of lane i's sample. `epsilon` as rt::shadowRay.
void buildShadowRays(const Light& light, const ShadowLanes& lanes, int count, float epsilon, RayPacket16& packet,
                     float* weight);

// offsetOrigins and then buildShadowRays, in one pass over the lanes for a sphere light (the origin's
// direction to the centre shares the silhouette disk's set-up): the same origins, rays and weights to
// the bit. Reads the lanes' P, Ng and u; the origins go to the packet (and, for other shapes, to the
// lanes too).
void buildShadowRaysAndOrigins(const Light& light, ShadowLanes& lanes, int count, float epsilon, RayPacket16& packet,
                               float* weight);

// buildShadowRays for lanes that all hold lane 0's P, Ng and O (many samples of one point): the
// light's per-point set-up (a sphere's silhouette disk seen from P) is made once instead of per
// lane. The same rays and weights to the bit.
void buildShadowRaysFromOnePoint(const Light& light, const ShadowLanes& lanes, int count, float epsilon,
                                 RayPacket16& packet, float* weight);

// Writes lanes [0, count) of `packet` with the ray from each lane's point to the light's centre
// (origin, direction, tMin, tMax; the rest as the packet holds them), the ray raytraced-hard and parker
// trace: rt::shadowRay(P, rt::offsetOrigin(P, Ng, side, epsilon), d, Light::distanceToCenter(P),
// epsilon) with d = Light::directionToCenter(P), operation for operation, and facing[i] = Ng . d,
// whose sign is the side. Reads the lanes' P and Ng only (not O or u).
void buildCenterRays(const Light& light, const ShadowLanes& lanes, int count, float epsilon, RayPacket16& packet,
                     float* facing);

// sin and cos of a in [-pi/4, pi/4] by the polynomials above (exposed for its test).
void sinCosQuarterPi(float a, float& s, float& c);

}  // namespace penumbra::rt
