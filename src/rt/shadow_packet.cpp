// buildShadowRays of shadow_packet.h. Each shape's loop is written for the vectorizer: straight-line
// code over the lanes, selects instead of branches, restrict pointers so that writing the packet
// cannot be taken to change the lanes.
#include "shadow_packet.h"

#include <cmath>
#include <cstdint>
#include <limits>

#include "core/target_clones.h"
#include "rt/shadow_ray.h"

namespace penumbra::rt {
namespace {

// The lane loops below are also compiled for AVX2 and AVX-512F (core/target_clones.h): 8 or 16 lanes
// a step instead of 4, so one packet's rays are one or two steps, bit-identical on every CPU.
#define PENUMBRA_LANE_CLONES PENUMBRA_CLONES_AVX512

// The lane-invariant values of a light, hoisted out of the lane loops.
struct LightConstants {
  Vec3 center, u, v, a, ab, direction;
  Frame frame;
  float radius = 0.0f, r2 = 0.0f, tanHalf = 0.0f;
  bool limbDarkened = false;
};

inline void sinCosPoly(float a, float& s, float& c) {
  const float a2 = a * a;
  s = a + a * a2 * (-1.6666654611e-1f + a2 * (8.3321608736e-3f + a2 * -1.9515295891e-4f));
  c = 1.0f - 0.5f * a2 + a2 * a2 * (4.166664568298827e-2f + a2 * (-1.388731625493765e-3f + a2 * 2.443315711809948e-5f));
}

// concentricDisk (sampling.h) without its branches: the wedge's angle is at most pi/4 from an axis.
inline void concentric(float ux, float uy, float& qx, float& qy) {
  const float ox = 2.0f * ux - 1.0f, oy = 2.0f * uy - 1.0f;
  const bool alongX = std::fabs(ox) > std::fabs(oy);
  const float r = alongX ? ox : oy;
  const float across = alongX ? oy : ox;
  // r == 0 only at the centre, where across is 0 too and the point is the disk's centre.
  const float a = (kPi / 4.0f) * (across / (r != 0.0f ? r : 1.0f));
  float s, c;
  sinCosPoly(a, s, c);
  qx = r * (alongX ? c : s);
  qy = r * (alongX ? s : c);
}

// The ray from origin o to light point x, as rt::shadowRay; flags the lanes rt::shadowRay treats
// apart (a zero or overflowing length).
inline void segmentTo(float xx, float xy, float xz, float ox, float oy, float oz, float epsilon, float& dx, float& dy,
                      float& dz, float& tMax, int32_t& fix) {
  const float ex = xx - ox, ey = xy - oy, ez = xz - oz;
  const float len2 = ex * ex + ey * ey + ez * ez;
  const float len = std::sqrt(len2);
  const float inv = 1.0f / len;
  dx = ex * inv;
  dy = ey * inv;
  dz = ez * inv;
  tMax = std::max(0.0f, len - epsilon);
  fix |= static_cast<int32_t>(!(len2 > 0.0f) | !(len2 < kInfinity));
}

// A lane loop's outputs: they come into the cloned functions as restrict parameters
// (PENUMBRA_LANE_OUTPUTS; core/target_clones.h says why) and are gathered here inside the loop's own
// function.
struct Out {
  float* dirX;
  float* dirY;
  float* dirZ;
  float* tMax;
  float* weight;
  int32_t* fix;
};
#define PENUMBRA_LANE_OUTPUTS                                                                     \
  float* __restrict dirX, float* __restrict dirY, float* __restrict dirZ, float* __restrict tMax, \
      float* __restrict weight, int32_t* __restrict fix
#define PENUMBRA_LANE_OUT \
  Out { dirX, dirY, dirZ, tMax, weight, fix }

// rt::offsetOrigin for one lane: the point moved epsilon along its geometric normal, to the side of the
// light's centre (Light::directionToCenter: towards the centre, unit, or +z from the centre itself;
// a directional light's direction), with selects for the branches.
template <bool kDirectional>
inline __attribute__((always_inline)) void laneOrigin(const LightConstants& k, float epsilon, float px, float py,
                                                      float pz, float nx, float ny, float nz, float& ox, float& oy,
                                                      float& oz) {
  float ux = k.direction.x, uy = k.direction.y, uz = k.direction.z;
  if constexpr (!kDirectional) {
    const float dx = k.center.x - px, dy = k.center.y - py, dz = k.center.z - pz;
    const float len = std::sqrt((dx * dx + dy * dy) + dz * dz);
    const bool positive = len > 0.0f;
    ux = positive ? dx / len : 0.0f;
    uy = positive ? dy / len : 0.0f;
    uz = positive ? dz / len : 1.0f;
  }
  const float side = (nx * ux + ny * uy) + nz * uz >= 0.0f ? 1.0f : -1.0f;
  const float offset = side * epsilon;
  ox = px + offset * nx;
  oy = py + offset * ny;
  oz = pz + offset * nz;
}

// Light::sample's set-up for a sphere light at P: the silhouette disk seen from P and its frame
// around P -> centre. The same operations whether made per lane (sphereKernel) or once for lanes that
// share P (onePointSphereKernel), so the rays are the same to the bit.
struct SphereView {
  float tx, ty, tz, d2;                //!< centre - P and its squared length
  float wx, wy, wz;                    //!< unit P -> centre
  float fxx, fxy, fxz, fyx, fyy, fyz;  //!< the disk's frame
  float h2, diskRadius, axial;         //!< d2 - r2, the disk's radius, the distance to its plane
};
inline __attribute__((always_inline)) SphereView sphereView(const LightConstants& k, float px, float py, float pz) {
  SphereView s;
  s.tx = k.center.x - px;
  s.ty = k.center.y - py;
  s.tz = k.center.z - pz;
  s.d2 = s.tx * s.tx + s.ty * s.ty + s.tz * s.tz;
  const float invD = 1.0f / std::sqrt(s.d2);
  s.wx = s.tx * invD;
  s.wy = s.ty * invD;
  s.wz = s.tz * invD;
  const float sign = std::copysign(1.0f, s.wz);
  const float fa = -1.0f / (sign + s.wz);
  const float fb = s.wx * s.wy * fa;
  s.fxx = 1.0f + sign * s.wx * s.wx * fa;
  s.fxy = sign * fb;
  s.fxz = -sign * s.wx;
  s.fyx = fb;
  s.fyy = sign + s.wy * s.wy * fa;
  s.fyz = -s.wy;
  s.h2 = s.d2 - k.r2;
  s.diskRadius = k.radius * std::sqrt(s.h2) * invD;
  s.axial = s.h2 * invD;
  return s;
}

// A point of the disk (u in [0,1)^2), the direction to it, the sphere's front surface, and the ray
// from the origin O to that point. Flags the lanes the scalar path takes (P inside the light, or a
// degenerate ray).
inline __attribute__((always_inline)) void sphereRay(const LightConstants& k, const SphereView& v, float ux, float uy,
                                                     float px, float py, float pz, float ox, float oy, float oz,
                                                     float epsilon, float& dirX, float& dirY, float& dirZ, float& tMax,
                                                     int32_t& fixOut) {
  float qx, qy;
  concentric(ux, uy, qx, qy);
  qx *= v.diskRadius;
  qy *= v.diskRadius;
  float sx = v.axial * v.wx + qx * v.fxx + qy * v.fyx;
  float sy = v.axial * v.wy + qx * v.fxy + qy * v.fyy;
  float sz = v.axial * v.wz + qx * v.fxz + qy * v.fyz;
  const float sInv = 1.0f / std::sqrt(sx * sx + sy * sy + sz * sz);
  sx *= sInv;
  sy *= sInv;
  sz *= sInv;
  const float b = sx * v.tx + sy * v.ty + sz * v.tz;
  const float t = b - std::sqrt(std::max(0.0f, b * b - v.h2));
  int32_t fix = !(v.d2 > k.r2);  // P inside the light (or not finite): the scalar path's special case
  segmentTo(px + t * sx, py + t * sy, pz + t * sz, ox, oy, oz, epsilon, dirX, dirY, dirZ, tMax, fix);
  fixOut = fix;
}

inline __attribute__((always_inline)) void sphereKernel(const LightConstants& k, const ShadowLanes& __restrict in,
                                                        int count, float epsilon, const Out out) {
  for (int i = 0; i < count; ++i) {
    const SphereView v = sphereView(k, in.px[i], in.py[i], in.pz[i]);
    sphereRay(k, v, in.ux[i], in.uy[i], in.px[i], in.py[i], in.pz[i], in.ox[i], in.oy[i], in.oz[i], epsilon,
              out.dirX[i], out.dirY[i], out.dirZ[i], out.tMax[i], out.fix[i]);
    out.weight[i] = 1.0f;
  }
}

// Lanes that share one point P and origin O (lane 0's): the view made once, by the caller.
inline __attribute__((always_inline)) void onePointSphereKernel(const LightConstants& k, const SphereView& v,
                                                                const ShadowLanes& __restrict in, int count,
                                                                float epsilon, const Out out) {
  const float px = in.px[0], py = in.py[0], pz = in.pz[0], ox = in.ox[0], oy = in.oy[0], oz = in.oz[0];
  for (int i = 0; i < count; ++i) {
    sphereRay(k, v, in.ux[i], in.uy[i], px, py, pz, ox, oy, oz, epsilon, out.dirX[i], out.dirY[i], out.dirZ[i],
              out.tMax[i], out.fix[i]);
    out.weight[i] = 1.0f;
  }
}

// sphereKernel with each lane's origin made on the way (laneOrigin, whose length to the centre is the
// view's sqrt(d2), the same expression, which the compiler computes once): one pass over the lanes
// instead of two. Writes the origins to the packet.
inline __attribute__((always_inline)) void sphereWithOriginsKernel(const LightConstants& k,
                                                                   const ShadowLanes& __restrict in, int count,
                                                                   float epsilon, const Out out, float* __restrict orgX,
                                                                   float* __restrict orgY, float* __restrict orgZ) {
  for (int i = 0; i < count; ++i) {
    const float px = in.px[i], py = in.py[i], pz = in.pz[i];
    const SphereView v = sphereView(k, px, py, pz);
    float ox, oy, oz;
    laneOrigin<false>(k, epsilon, px, py, pz, in.nx[i], in.ny[i], in.nz[i], ox, oy, oz);
    orgX[i] = ox;
    orgY[i] = oy;
    orgZ[i] = oz;
    sphereRay(k, v, in.ux[i], in.uy[i], px, py, pz, ox, oy, oz, epsilon, out.dirX[i], out.dirY[i], out.dirZ[i],
              out.tMax[i], out.fix[i]);
    out.weight[i] = 1.0f;
  }
}

// Disk, rect and segment lights: the light point does not depend on P.
template <LightShape kShape>
inline __attribute__((always_inline)) void planarKernel(const LightConstants& k, const ShadowLanes& __restrict in,
                                                        int count, float epsilon, const Out out) {
  for (int i = 0; i < count; ++i) {
    float xx, xy, xz;
    if constexpr (kShape == LightShape::Disk) {
      float qx, qy;
      concentric(in.ux[i], in.uy[i], qx, qy);
      qx *= k.radius;
      qy *= k.radius;
      xx = k.center.x + qx * k.frame.x.x + qy * k.frame.y.x;
      xy = k.center.y + qx * k.frame.x.y + qy * k.frame.y.y;
      xz = k.center.z + qx * k.frame.x.z + qy * k.frame.y.z;
    } else if constexpr (kShape == LightShape::Rect) {
      const float su = 2.0f * in.ux[i] - 1.0f, sv = 2.0f * in.uy[i] - 1.0f;
      xx = k.center.x + su * k.u.x + sv * k.v.x;
      xy = k.center.y + su * k.u.y + sv * k.v.y;
      xz = k.center.z + su * k.u.z + sv * k.v.z;
    } else {
      static_assert(kShape == LightShape::Segment);
      xx = k.a.x + in.ux[i] * k.ab.x;
      xy = k.a.y + in.ux[i] * k.ab.y;
      xz = k.a.z + in.ux[i] * k.ab.z;
    }
    // Light::sample falls back to the centre's direction when the light point is P itself.
    const float ex = xx - in.px[i], ey = xy - in.py[i], ez = xz - in.pz[i];
    int32_t fix = !(ex * ex + ey * ey + ez * ez > 0.0f);
    segmentTo(xx, xy, xz, in.ox[i], in.oy[i], in.oz[i], epsilon, out.dirX[i], out.dirY[i], out.dirZ[i], out.tMax[i],
              fix);
    out.fix[i] = fix;
    out.weight[i] = 1.0f;
  }
}

inline __attribute__((always_inline)) void directionalKernel(const LightConstants& k, const ShadowLanes& __restrict in,
                                                             int count, const Out out) {
  // The limb-darkening law's coefficient, 0 for a uniform disk (whose weights are then 1 exactly), and
  // the weights' normalization, the law's mean over the disk: floats, not a bool select, so that the
  // loop vectorizes.
  const float u = k.limbDarkened ? kLimbDarkeningU : 0.0f;
  const float lawMean = 1.0f - u / 3.0f;
  for (int i = 0; i < count; ++i) {
    float qx, qy;
    concentric(in.ux[i], in.uy[i], qx, qy);
    const float sx = k.direction.x + k.tanHalf * (qx * k.frame.x.x + qy * k.frame.y.x);
    const float sy = k.direction.y + k.tanHalf * (qx * k.frame.x.y + qy * k.frame.y.y);
    const float sz = k.direction.z + k.tanHalf * (qx * k.frame.x.z + qy * k.frame.y.z);
    const float inv = 1.0f / std::sqrt(sx * sx + sy * sy + sz * sz);
    out.dirX[i] = sx * inv;
    out.dirY[i] = sy * inv;
    out.dirZ[i] = sz * inv;
    out.tMax[i] = kInfinity;
    const float mu = std::sqrt(std::max(0.0f, 1.0f - (qx * qx + qy * qy)));
    out.weight[i] = (1.0f - u * (1.0f - mu)) / lawMean;
    out.fix[i] = 0;
  }
}

// The kernels, each compiled for every target of PENUMBRA_LANE_CLONES.
PENUMBRA_LANE_CLONES void sphereLanes(const LightConstants& k, const ShadowLanes& __restrict in, int count,
                                      float epsilon, PENUMBRA_LANE_OUTPUTS) {
  sphereKernel(k, in, count, epsilon, PENUMBRA_LANE_OUT);
}
PENUMBRA_LANE_CLONES void onePointSphereLanes(const LightConstants& k, const SphereView& v,
                                              const ShadowLanes& __restrict in, int count, float epsilon,
                                              PENUMBRA_LANE_OUTPUTS) {
  onePointSphereKernel(k, v, in, count, epsilon, PENUMBRA_LANE_OUT);
}
PENUMBRA_LANE_CLONES void sphereWithOriginsLanes(const LightConstants& k, const ShadowLanes& __restrict in, int count,
                                                 float epsilon, float* __restrict orgX, float* __restrict orgY,
                                                 float* __restrict orgZ, PENUMBRA_LANE_OUTPUTS) {
  sphereWithOriginsKernel(k, in, count, epsilon, PENUMBRA_LANE_OUT, orgX, orgY, orgZ);
}
PENUMBRA_LANE_CLONES void diskLanes(const LightConstants& k, const ShadowLanes& __restrict in, int count, float epsilon,
                                    PENUMBRA_LANE_OUTPUTS) {
  planarKernel<LightShape::Disk>(k, in, count, epsilon, PENUMBRA_LANE_OUT);
}
PENUMBRA_LANE_CLONES void rectLanes(const LightConstants& k, const ShadowLanes& __restrict in, int count, float epsilon,
                                    PENUMBRA_LANE_OUTPUTS) {
  planarKernel<LightShape::Rect>(k, in, count, epsilon, PENUMBRA_LANE_OUT);
}
PENUMBRA_LANE_CLONES void segmentLanes(const LightConstants& k, const ShadowLanes& __restrict in, int count,
                                       float epsilon, PENUMBRA_LANE_OUTPUTS) {
  planarKernel<LightShape::Segment>(k, in, count, epsilon, PENUMBRA_LANE_OUT);
}
PENUMBRA_LANE_CLONES void directionalLanes(const LightConstants& k, const ShadowLanes& __restrict in, int count,
                                           PENUMBRA_LANE_OUTPUTS) {
  directionalKernel(k, in, count, PENUMBRA_LANE_OUT);
}
#undef PENUMBRA_LANE_OUTPUTS
#undef PENUMBRA_LANE_OUT

// rt::offsetOrigin per lane (laneOrigin), over the lanes.
template <bool kDirectional>
inline __attribute__((always_inline)) void originKernel(const LightConstants& k, float epsilon, int count,
                                                        const float* __restrict px, const float* __restrict py,
                                                        const float* __restrict pz, const float* __restrict nx,
                                                        const float* __restrict ny, const float* __restrict nz,
                                                        float* __restrict ox, float* __restrict oy,
                                                        float* __restrict oz) {
  for (int i = 0; i < count; ++i)
    laneOrigin<kDirectional>(k, epsilon, px[i], py[i], pz[i], nx[i], ny[i], nz[i], ox[i], oy[i], oz[i]);
}
#define PENUMBRA_ORIGIN_PARAMETERS                                                                                    \
  const LightConstants &k, float epsilon, int count, const float *__restrict px, const float *__restrict py,          \
      const float *__restrict pz, const float *__restrict nx, const float *__restrict ny, const float *__restrict nz, \
      float *__restrict ox, float *__restrict oy, float *__restrict oz
PENUMBRA_LANE_CLONES void localOrigins(PENUMBRA_ORIGIN_PARAMETERS) {
  originKernel<false>(k, epsilon, count, px, py, pz, nx, ny, nz, ox, oy, oz);
}
PENUMBRA_LANE_CLONES void directionalOrigins(PENUMBRA_ORIGIN_PARAMETERS) {
  originKernel<true>(k, epsilon, count, px, py, pz, nx, ny, nz, ox, oy, oz);
}
#undef PENUMBRA_ORIGIN_PARAMETERS

// The ray to the light's centre per lane (buildCenterRays): Light::directionToCenter and
// distanceToCenter (one length serves both, as glm::length computes it), the origin offset to the
// centre's side, then rt::shadowRay's re-aimed segment, its divisions as glm's vector-by-scalar
// division makes them. Flags the lanes rt::shadowRay treats apart (a length that overflows, a zero one).
template <bool kDirectional>
inline __attribute__((always_inline)) void centerRayKernel(const LightConstants& k, const ShadowLanes& __restrict in,
                                                           int count, float epsilon, const Out out,
                                                           float* __restrict orgX, float* __restrict orgY,
                                                           float* __restrict orgZ, float* __restrict facing) {
  for (int i = 0; i < count; ++i) {
    float ux = k.direction.x, uy = k.direction.y, uz = k.direction.z, distance = 0.0f;
    if constexpr (!kDirectional) {
      const float dx = k.center.x - in.px[i], dy = k.center.y - in.py[i], dz = k.center.z - in.pz[i];
      distance = std::sqrt((dx * dx + dy * dy) + dz * dz);
      const bool positive = distance > 0.0f;
      ux = positive ? dx / distance : 0.0f;
      uy = positive ? dy / distance : 0.0f;
      uz = positive ? dz / distance : 1.0f;
    }
    const float f = (in.nx[i] * ux + in.ny[i] * uy) + in.nz[i] * uz;
    facing[i] = f;
    const float offset = (f >= 0.0f ? 1.0f : -1.0f) * epsilon;
    const float ox = in.px[i] + offset * in.nx[i], oy = in.py[i] + offset * in.ny[i], oz = in.pz[i] + offset * in.nz[i];
    orgX[i] = ox;
    orgY[i] = oy;
    orgZ[i] = oz;
    if constexpr (kDirectional) {
      out.dirX[i] = ux;
      out.dirY[i] = uy;
      out.dirZ[i] = uz;
      out.tMax[i] = kInfinity;
      out.fix[i] = 0;
    } else {
      const float ex = (in.px[i] + distance * ux) - ox, ey = (in.py[i] + distance * uy) - oy,
                  ez = (in.pz[i] + distance * uz) - oz;
      const float len = std::sqrt((ex * ex + ey * ey) + ez * ez);
      out.dirX[i] = ex / len;
      out.dirY[i] = ey / len;
      out.dirZ[i] = ez / len;
      out.tMax[i] = std::max(0.0f, len - epsilon);
      out.fix[i] = static_cast<int32_t>(!(distance < kInfinity) | !(len < kInfinity) | !(len > 0.0f));
    }
  }
}
#define PENUMBRA_CENTER_PARAMETERS                                                                             \
  const LightConstants &k, const ShadowLanes &__restrict in, int count, float epsilon, float *__restrict orgX, \
      float *__restrict orgY, float *__restrict orgZ, float *__restrict facing, float *__restrict dirX,        \
      float *__restrict dirY, float *__restrict dirZ, float *__restrict tMax, int32_t *__restrict fix
PENUMBRA_LANE_CLONES void localCenterRays(PENUMBRA_CENTER_PARAMETERS) {
  centerRayKernel<false>(k, in, count, epsilon, Out{dirX, dirY, dirZ, tMax, nullptr, fix}, orgX, orgY, orgZ, facing);
}
PENUMBRA_LANE_CLONES void directionalCenterRays(PENUMBRA_CENTER_PARAMETERS) {
  centerRayKernel<true>(k, in, count, epsilon, Out{dirX, dirY, dirZ, tMax, nullptr, fix}, orgX, orgY, orgZ, facing);
}
#undef PENUMBRA_CENTER_PARAMETERS

}  // namespace

void buildCenterRays(const Light& light, const ShadowLanes& lanes, int count, float epsilon, RayPacket16& packet,
                     float* facing) {
  alignas(64) int32_t fix[16];
  LightConstants k;
  const bool directional = light.isDirectional();
  if (directional) {
    k.direction = light.direction();
    directionalCenterRays(k, lanes, count, epsilon, packet.orgX, packet.orgY, packet.orgZ, facing, packet.dirX,
                          packet.dirY, packet.dirZ, packet.tMax, fix);
  } else {
    k.center = light.center();
    localCenterRays(k, lanes, count, epsilon, packet.orgX, packet.orgY, packet.orgZ, facing, packet.dirX, packet.dirY,
                    packet.dirZ, packet.tMax, fix);
  }
  for (int i = 0; i < count; ++i) {
    packet.tMin[i] = 0.0f;
    if (!fix[i]) continue;
    const Vec3 wsP(lanes.px[i], lanes.py[i], lanes.pz[i]);
    const Ray ray = shadowRay(wsP, Vec3(packet.orgX[i], packet.orgY[i], packet.orgZ[i]), light.directionToCenter(wsP),
                              light.distanceToCenter(wsP), epsilon);
    packet.dirX[i] = ray.direction.x;
    packet.dirY[i] = ray.direction.y;
    packet.dirZ[i] = ray.direction.z;
    packet.tMax[i] = ray.tMax;
  }
}

void sinCosQuarterPi(float a, float& s, float& c) { sinCosPoly(a, s, c); }

void offsetOrigins(const Light& light, float epsilon, int count, ShadowLanes& lanes) {
  LightConstants k;
  if (light.isDirectional()) {
    k.direction = light.direction();
    directionalOrigins(k, epsilon, count, lanes.px, lanes.py, lanes.pz, lanes.nx, lanes.ny, lanes.nz, lanes.ox,
                       lanes.oy, lanes.oz);
  } else {
    k.center = light.center();
    localOrigins(k, epsilon, count, lanes.px, lanes.py, lanes.pz, lanes.nx, lanes.ny, lanes.nz, lanes.ox, lanes.oy,
                 lanes.oz);
  }
}

namespace {

// The lanes the vector kernels flagged (fix[i]), and every lane of a polygon light (scalar): the
// scalar path, rt::shadowRay on Light::sample from the packet's origins.
void scalarLanes(const Light& light, const ShadowLanes& lanes, int count, float epsilon, const int32_t* fix,
                 bool scalar, RayPacket16& packet, float* weight) {
  for (int i = 0; i < count; ++i) {
    if (!scalar && !fix[i]) continue;
    const Vec3 wsP(lanes.px[i], lanes.py[i], lanes.pz[i]);
    const LightSample s = light.sample(wsP, Vec2(lanes.ux[i], lanes.uy[i]));
    const Ray ray =
        shadowRay(wsP, Vec3(packet.orgX[i], packet.orgY[i], packet.orgZ[i]), s.wsDirection, s.distance, epsilon);
    packet.dirX[i] = ray.direction.x;
    packet.dirY[i] = ray.direction.y;
    packet.dirZ[i] = ray.direction.z;
    packet.tMax[i] = ray.tMax;
    weight[i] = s.weight;
  }
}

void copyOrigins(const ShadowLanes& lanes, int count, RayPacket16& packet) {
  for (int i = 0; i < count; ++i) {
    packet.orgX[i] = lanes.ox[i];
    packet.orgY[i] = lanes.oy[i];
    packet.orgZ[i] = lanes.oz[i];
    packet.tMin[i] = 0.0f;
  }
}

// A light's centre and radius (a sphere's whole set-up), the start of every shape's constants.
LightConstants centreAndRadius(const Light& light) {
  LightConstants k;
  k.center = light.center();
  k.radius = light.radius();
  k.r2 = k.radius * k.radius;
  return k;
}

}  // namespace

void buildShadowRays(const Light& light, const ShadowLanes& lanes, int count, float epsilon, RayPacket16& packet,
                     float* weight) {
  alignas(64) int32_t fix[16];
  copyOrigins(lanes, count, packet);
  LightConstants k = centreAndRadius(light);
  bool scalar = false;
  switch (light.shape()) {
    case LightShape::Sphere:
      sphereLanes(k, lanes, count, epsilon, packet.dirX, packet.dirY, packet.dirZ, packet.tMax, weight, fix);
      break;
    case LightShape::Disk:
      k.frame = Frame::fromZ(light.normal());
      diskLanes(k, lanes, count, epsilon, packet.dirX, packet.dirY, packet.dirZ, packet.tMax, weight, fix);
      break;
    case LightShape::Rect:
      k.u = light.u();
      k.v = light.v();
      rectLanes(k, lanes, count, epsilon, packet.dirX, packet.dirY, packet.dirZ, packet.tMax, weight, fix);
      break;
    case LightShape::Segment:
      k.a = light.a();
      k.ab = light.b() - light.a();
      segmentLanes(k, lanes, count, epsilon, packet.dirX, packet.dirY, packet.dirZ, packet.tMax, weight, fix);
      break;
    case LightShape::Directional:
      k.direction = light.direction();
      k.frame = Frame::fromZ(k.direction);
      k.tanHalf = std::tan(0.5f * light.angularDiameter());
      k.limbDarkened = light.profile() == LightProfile::LimbDarkened;
      directionalLanes(k, lanes, count, packet.dirX, packet.dirY, packet.dirZ, packet.tMax, weight, fix);
      break;
    case LightShape::Polygon:
      scalar = true;  // a triangle picked by area per sample: not worth a vector form
      break;
  }
  scalarLanes(light, lanes, count, epsilon, fix, scalar, packet, weight);
}

void buildShadowRaysFromOnePoint(const Light& light, const ShadowLanes& lanes, int count, float epsilon,
                                 RayPacket16& packet, float* weight) {
  if (light.shape() != LightShape::Sphere) {
    buildShadowRays(light, lanes, count, epsilon, packet, weight);
    return;
  }
  alignas(64) int32_t fix[16];
  copyOrigins(lanes, count, packet);
  const LightConstants k = centreAndRadius(light);
  const SphereView view = sphereView(k, lanes.px[0], lanes.py[0], lanes.pz[0]);
  onePointSphereLanes(k, view, lanes, count, epsilon, packet.dirX, packet.dirY, packet.dirZ, packet.tMax, weight, fix);
  scalarLanes(light, lanes, count, epsilon, fix, false, packet, weight);
}

void buildShadowRaysAndOrigins(const Light& light, ShadowLanes& lanes, int count, float epsilon, RayPacket16& packet,
                               float* weight) {
  // Other shapes take the two steps.
  if (light.shape() != LightShape::Sphere) {
    offsetOrigins(light, epsilon, count, lanes);
    buildShadowRays(light, lanes, count, epsilon, packet, weight);
    return;
  }
  alignas(64) int32_t fix[16];
  const LightConstants k = centreAndRadius(light);
  sphereWithOriginsLanes(k, lanes, count, epsilon, packet.orgX, packet.orgY, packet.orgZ, packet.dirX, packet.dirY,
                         packet.dirZ, packet.tMax, weight, fix);
  for (int i = 0; i < count; ++i) packet.tMin[i] = 0.0f;
  scalarLanes(light, lanes, count, epsilon, fix, false, packet, weight);
}

}  // namespace penumbra::rt
