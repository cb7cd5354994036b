// Outer objects of Parker, Shirley and Smits 1998, "Single Sample Soft Shadows" (Section 3 and the
// Appendix), and the traversal that lets one shadow ray see every outer object it passes, not only
// the first: a light buffer (Haines and Greenberg 1986) — a grid over the directions leaving the
// light's centre (a cube map; for a directional light, a grid over the plane perpendicular to the
// light) whose every cell lists each outer object that any shadow ray through that cell can touch.
//
// Every outer object is a capsule: the points within R + b of a segment p0 -> p0 + e, with
//  - an analytic sphere: e = 0, R = its radius (the Appendix's sphere test exactly);
//  - a triangle mesh: the edges on its silhouette seen from the light's centre (and its open
//    boundary and non-manifold edges), R = 0. The Appendix's outer object of a triangle is the
//    triangle with rounded corners, offset per side by b in the plane perpendicular to the ray
//    (so by b / cos in the triangle's own plane, "proportional to the cosine of projected triangle
//    normal and the vector v"): the triangle together with its three edge capsules of radius b.
//    For a ray that misses the mesh (a ray that hits it is in the umbra, s = 0, through the inner
//    test) the nearest part of the union of those rounded triangles lies on the mesh's outline as
//    seen along the ray, i.e. on its silhouette edges; edges inside the outline are dropped. This
//    is exact for the min combination up to the variation of b between neighbouring edges.
//
// For a shadow ray o + t v (v unit, towards the light's centre at distance A) and a capsule:
// t0 = ray parameter of the point closest to the capsule's segment, d = that distance. If t0 <= 0
// (the capsule is behind the receiver; the Appendix's "t0 negative") or t0 >= A (beyond the light)
// the capsule does not shadow. Otherwise b = D t0 / A (Appendix; D the light's diameter; for a
// directional light b = D t0 with D the solar disk's diameter at unit distance, the limit A -> inf),
// tau = (d - R) / b, and d < R is the inner object (s = 0).
//
// Combination (Section 3): per object, tau is the smallest over its capsules (the union of its
// triangles' outer objects is the object's outer object, so a smooth mesh does not darken with its
// tessellation); the objects' attenuations s_i = s(tau_i) are combined by min (the paper's
// "thresholding"), product, or sum s = 1 - sum(1 - s_i), which leaves [0, 1] when many objects are
// grazed and is then taken as 0 (fully shadowed).
//
// Cost (one core of the development machine): building the light buffer of `torus` (162
// silhouette edges, 64 x 64 cells a face) takes about 1.5 ms, of `spheres` (5 spheres, the ground's outline) 0.4 ms. Per
// shadow ray that misses every inner object: one cell lookup and, where the cell lists anything
// (`torus` at 1024 x 1024: 4 rays in 10, 14 capsules on average), one pass over the list in
// 8-capsule blocks that the compiler vectorizes (8 lanes where the CPU has AVX2, else 4). In all,
// parker's visibility pass costs 1.48x raytraced-hard's on `torus` and 1.16x on `spheres`
// (bench/parker_bench.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "penumbra/light.h"
#include "penumbra/math.h"
#include "penumbra/scene.h"

namespace penumbra::rt {

enum class OuterFalloff { Bernstein, Sinusoid };  //!< s = 3 tau^2 - 2 tau^3, or (1 + sin(pi tau - pi/2)) / 2
enum class OuterCombine { Min, Product, Sum };

struct OuterObjectOptions {
  float lightDiameter = 1.0f;  //!< D: world units; for a directional light, per unit distance
  bool analyticSpheres = true; //!< objects that remember a true sphere use it instead of their mesh
  // Cells per side of each cube-map face (or of the planar grid), at most: halved while the light
  // buffer would list more than maxGridEntries (cell, capsule) pairs.
  int gridResolution = 64;
  // The light buffer's size limit. Each capsule is listed in every cell its footprint reaches,
  // about (footprint / cell)^2 of them: 10^6 separate tiny triangles (3 x 10^6 open edges, each
  // reaching ~10^2 cells at 64 x 64 a face) would list 1.7 x 10^8 pairs, 8 GB and a minute of
  // page faults. Halving the grid divides that by up to 4 and leaves V unchanged (the lists stay
  // conservative); 2^24 entries are 0.5 GB. A grid of one cell a face is never refused.
  size_t maxGridEntries = size_t{1} << 24;
};

// The attenuation of the Section 3 falloff at tau (s = 0 at tau <= 0, 1 at tau >= 1).
inline float outerFalloff(float tau, OuterFalloff falloff) {
  const float t = std::clamp(tau, 0.0f, 1.0f);
  if (falloff == OuterFalloff::Sinusoid) return 0.5f * (1.0f + std::sin(kPi * t - 0.5f * kPi));
  return t * t * (3.0f - 2.0f * t);
}

class OuterObjects {
 public:
  // Builds the capsules of every object of `scene` (silhouettes seen from light.center(), or along
  // light.direction() for a directional light) and the light buffer. Throws Error for a light
  // diameter that is not finite and > 0.
  OuterObjects(const Scene& scene, const Light& light, const OuterObjectOptions& options);

  // s for the shadow ray from `origin` along unit `direction` to the light's centre at
  // `distanceToLight` (kInfinity for a directional light). 0 when the ray passes through an
  // analytic sphere (its inner object); meshes' inner objects are the caller's (an occlusion ray).
  float attenuation(const Vec3& origin, const Vec3& direction, float distanceToLight, OuterFalloff falloff,
                    OuterCombine combine) const;
  // The same for `count` rays at once (rays[i].origin, unit rays[i].direction, distanceToLight[i])
  // into s[i]: the per-call work is shared, and under the min combination the loop over the rays
  // runs in one function built for the widest vectors the CPU has.
  void attenuations(const Ray* rays, const float* distanceToLight, int count, OuterFalloff falloff, OuterCombine combine,
                    float* s) const;

  // Objects whose analytic sphere is used (their meshes are not part of the outer objects; the
  // caller must leave them out of its inner occlusion test too).
  const std::vector<bool>& usesAnalyticSphere() const { return analytic_; }
  // Whether `object` is one of those under `options` (known before building).
  static bool usesAnalyticSphere(const Object& object, const OuterObjectOptions& options) {
    return options.analyticSpheres && object.sphere.has_value();
  }
  size_t analyticSphereCount() const { return analyticCount_; }
  size_t silhouetteEdgeCount() const { return edgeCount_; }
  size_t gridEntryCount() const { return entryCount_; }
  int gridResolution() const { return resolution_; }

  // Capsules a cell's list holds in one pass of the per-ray loop; lists are padded to a multiple.
  static constexpr uint32_t kBlock = 8;

 private:
  // Capsules, structure of arrays (one entry per capsule, listed per cell below).
  struct Capsules {
    std::vector<float> p0x, p0y, p0z, ex, ey, ez, radius;
    std::vector<int32_t> object;  //!< index into the scene's objects
    void add(const Vec3& p0, const Vec3& e, float r, int32_t objectIndex);
    size_t size() const { return object.size(); }
  };
  // A piece of a capsule: a ball (centre, radius `reach` = piece radius + R) that bounds it.
  struct Piece {
    Vec3 center;
    float reach;
    int capsule;
  };

  // The (cell, capsule) pairs of the cube map (local light) or of the planar grid (directional)
  // for every piece, by the footprint bound of outer_objects.cpp; per cell in capsule order.
  // insertLocal stops, returning false, once `pairs` holds more than `limit`.
  bool insertLocal(const Bounds3& bounds, float margin, const std::vector<Piece>& pieces, size_t limit,
                   std::vector<std::pair<int, int>>& pairs) const;
  void insertDirectional(const Piece& piece, std::vector<std::pair<int, int>>& pairs) const;

  bool directional_ = false;
  Vec3 lightCenter_{0.0f};
  Frame frame_;             //!< directional: x, y span the grid plane, z = direction to the light
  Vec2 gridLower_{0.0f};    //!< directional: grid origin in (x, y)
  float cellSize_ = 1.0f;   //!< directional: world units per cell
  int resolution_ = 1;
  int faceCount_ = 6;       //!< cube faces (local light) or 1 (directional)
  float maxReceiverDistance_ = 0.0f;  //!< local: A_max, farthest scene point from the light's centre
  float minReceiverDepth_ = 0.0f;     //!< directional: smallest z of a scene point
  float diameter_ = 1.0f;
  bool avx2_ = false;       //!< the per-ray loop's 8-wide build runs (same values, see outer_objects.cpp)

  Capsules capsules_;
  std::vector<bool> analytic_;
  size_t analyticCount_ = 0, edgeCount_ = 0;

  // The light buffer in compressed rows: cell c holds cellCount_[c] entries from cellStart_[c],
  // sorted by object, each a copy of its capsule (contiguous, so the per-ray loop vectorizes), then
  // padding up to a multiple of kBlock that no ray reaches (R = -infinity). One extra cell after
  // the grid's lists every capsule, for an origin outside the grid (not expected: receivers lie in
  // the scene's bounds, which the grid covers with a margin).
  std::vector<uint32_t> cellStart_, cellCount_;
  std::vector<float> entryP0x_, entryP0y_, entryP0z_, entryEx_, entryEy_, entryEz_, entryRadius_;
  std::vector<int32_t> entryObject_;
  size_t entryCount_ = 0;  //!< entries without the padding
};

}  // namespace penumbra::rt
