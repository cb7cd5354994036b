// Outer objects of Parker, Shirley and Smits 1998, "Single Sample Soft Shadows" (Section 3 and the
// Appendix), and the traversal that lets one shadow ray see every outer object it passes, not only
// the first: a bounding-volume hierarchy over the outer objects (the paper's "shadow-ray/bounding-
// volume tests"), walked with the running minimum of tau, so that the ray reads only the outer
// objects that can still lower it.
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
// The hierarchy (outer_objects.cpp): capsules are cut into pieces no longer than 1/64 of the
// scene's radius and grouped by a surface-area heuristic into a tree of 8-wide nodes whose
// children are bounded by capsules, with leaves of up to 8 capsules. A bound gives a lower bound
// of tau for every capsule point in it, so a child is skipped when its bound is not below the
// smallest tau found so far (min; under product and sum, when it is not below 1, where s = 1).
// Rays walk the tree in groups of neighbours (kGroup) that share the bounds, each ray also tested
// on its own before a node's children or a leaf's capsules are read. Only the order of work
// depends on the tree and the groups: V is the minimum (or combination) over exactly the capsules
// the Appendix's formulas give, to the bit.
//
// Cost: building is linear in the triangles for the silhouettes and O(n log n) in the silhouette
// pieces for the tree (bench/parker_bench.cpp: prepare at 10k, 40k and 160k triangles). Per group
// of shadow rays that miss every inner object: per visited node, its 8 children's group bounds in
// one vector pass and 8 rays' own bounds per pass; per visited leaf, the same, then each capsule
// left against 8 rays per pass (8 lanes where the CPU has AVX2, else 4; with AVX-512F the whole
// group of 16 in one pass, for the rays' own bounds too). Where a small occluder
// lies under a wide light every ray is in its penumbra and many of its silhouette edges lie
// within a few per cent of the ray's smallest tau, all of which must be read: about 30 capsule
// evaluations per ray on `teapots` under its 2.4 x 2.4 light, where a light buffer listed all 551.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "penumbra/light.h"
#include "penumbra/math.h"
#include "penumbra/scene.h"
#include "penumbra/techniques/parker.h"
#include "techniques/mesh_edges.h"

namespace penumbra::rt {

using penumbra::OuterCombine;  // include/penumbra/techniques/parker.h
using penumbra::OuterFalloff;

struct OuterObjectOptions {
  float lightDiameter = 1.0f;   //!< D: world units; for a directional light, per unit distance
  bool analyticSpheres = true;  //!< objects that remember a true sphere use it instead of their mesh
};

// The attenuation of the Section 3 falloff at tau (s = 0 at tau <= 0, 1 at tau >= 1).
inline float outerFalloff(float tau, OuterFalloff falloff) {
  const float t = std::clamp(tau, 0.0f, 1.0f);
  if (falloff == OuterFalloff::Sinusoid) return 0.5f * (1.0f + std::sin(kPi * t - 0.5f * kPi));
  return t * t * (3.0f - 2.0f * t);
}

// The meshes' fingerprints (techniques/mesh_edges.h), under the names parker uses.
using penumbra::MeshFingerprint;
using penumbra::meshFingerprint;

class OuterObjects {
 public:
  // The meshes' edge adjacency (techniques/mesh_edges.h, kept in the scene's caches and shared with
  // the ribbon techniques), which depends on the geometry alone: a caller that builds the outer
  // objects again for the same objects under another light passes the same cache, and a mesh whose
  // geometry is unchanged is not matched again.
  using EdgeCache = MeshEdgeCache;

  // Builds the capsules of every object of `scene` (silhouettes seen from light.center(), or along
  // light.direction() for a directional light) and their hierarchy. Throws Error for a light
  // diameter that is not finite and > 0.
  OuterObjects(const Scene& scene, const Light& light, const OuterObjectOptions& options, EdgeCache* cache = nullptr);

  // s for the shadow ray from `origin` along unit `direction` to the light's centre at
  // `distanceToLight` (kInfinity for a directional light). 0 when the ray passes through an
  // analytic sphere (its inner object); meshes' inner objects are the caller's (an occlusion ray).
  float attenuation(const Vec3& origin, const Vec3& direction, float distanceToLight, OuterFalloff falloff,
                    OuterCombine combine) const;
  // Children per node, and capsules per leaf (leaves are padded to it).
  static constexpr int kWidth = 8;
  // Rays that walk the hierarchy together: attenuations() takes its rays in groups of this many,
  // in the order given (the caller groups neighbouring rays: the bounds are shared by a group).
  static constexpr int kGroup = 16;

  // The capsules that gave the smallest tau of the last group of rays (min combination): read
  // first for the next group, whose rays are their neighbours, the walk starts near the final
  // minima and skips more. A caller that hands over neighbouring groups one call at a time keeps
  // one per thread. Only the order of work depends on it, not V.
  struct Seeds {
    const OuterObjects* owner = nullptr;  //!< the outer objects the entries index (others: none)
    int count = 0;
    int32_t entry[kGroup] = {};  //!< leaf entries
  };

  // The same for `count` rays at once (rays[i].origin, unit rays[i].direction, distanceToLight[i])
  // into s[i]: the per-call work is shared, and the loop over the rays runs in one function built
  // for the widest vectors the CPU has. `seeds`, when given, carries the capsules of one call's
  // minima to the next.
  void attenuations(const Ray* rays, const float* distanceToLight, int count, OuterFalloff falloff,
                    OuterCombine combine, float* s, Seeds* seeds = nullptr) const;

  // The widest build of the per-ray loop that runs, at most `lanes` wide (16: AVX-512F, 8: AVX2, 4: the
  // baseline; a wider one only where the CPU has it). Every width gives the same bits; tests hold the
  // narrower builds to that on a CPU that would pick the widest.
  void limitLanes(int lanes);

  // Objects whose analytic sphere is used (their meshes are not part of the outer objects; the
  // caller must leave them out of its inner occlusion test too).
  const std::vector<bool>& usesAnalyticSphere() const { return analytic_; }
  // Whether `object` is one of those under `options` (known before building).
  static bool usesAnalyticSphere(const Object& object, const OuterObjectOptions& options) {
    return options.analyticSpheres && object.sphere.has_value();
  }
  size_t analyticSphereCount() const { return analyticCount_; }
  size_t silhouetteEdgeCount() const { return edgeCount_; }
  size_t pieceCount() const { return pieceCount_; }
  size_t nodeCount() const { return nodes_.size(); }
  size_t leafCount() const { return leafCount_; }
  int treeDepth() const { return depth_; }

  // A node of the hierarchy: kWidth children, each bounded by a capsule (segment p0 -> p0 + e,
  // `radius`, which covers the capsule points and the radii R of everything below it), and a
  // reference: >= 0 a node, < 0 the leaf ~child. An unused child has radius -infinity, which no
  // ray reaches.
  struct alignas(32) Node {
    float p0x[kWidth], p0y[kWidth], p0z[kWidth], ex[kWidth], ey[kWidth], ez[kWidth], radius[kWidth];
    int32_t child[kWidth];
  };

 private:
  bool directional_ = false;
  Vec3 lightCenter_{0.0f};
  float diameter_ = 1.0f;
  float sceneMagnitude_ = 0.0f;  //!< the largest coordinate magnitude of the scene's bounds (rounding slack)
  bool avx2_ = false;            //!< the per-ray loop's 8-wide build runs (same values, see outer_objects.cpp)
  bool avx512_ = false;          //!< its 16-wide build runs (a whole group of rays to a vector; same values)

  std::vector<bool> analytic_;
  size_t analyticCount_ = 0, edgeCount_ = 0, pieceCount_ = 0, leafCount_ = 0;
  int depth_ = 0;

  // The tree: nodes_[0] is the root unless root_ < 0 (a single leaf ~root_), or there is no
  // capsule at all (hasCapsules_ false). Leaf k holds capsules kWidth k ... kWidth k + kWidth - 1
  // of the entry arrays (copies of its capsules, contiguous so that the per-ray loop vectorizes),
  // padded with points of radius -infinity that no ray reaches.
  std::vector<Node> nodes_;
  int32_t root_ = 0;
  bool hasCapsules_ = false;
  std::vector<float> entryP0x_, entryP0y_, entryP0z_, entryEx_, entryEy_, entryEz_, entryRadius_;
  std::vector<int32_t> entryObject_;
  // Each leaf's bound (the capsule around its pieces), as in its parent node.
  std::vector<float> leafP0x_, leafP0y_, leafP0z_, leafEx_, leafEy_, leafEz_, leafRadius_;
};

}  // namespace penumbra::rt
