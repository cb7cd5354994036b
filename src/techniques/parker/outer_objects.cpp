// Outer objects and their hierarchy (see outer_objects.h for the model and the paper).
//
// Lower bounds of tau. Every bound below is a capsule B (segment p0 -> p0 + e, radius y) that
// holds a set of capsule points (and y covers their capsules' radii R). For a shadow ray o + t v
// (v unit) the distance of a point q in B from the ray's line is at least the distance d_B of the
// line from B's segment minus y, and q's ray parameter t0 = (q - o).v is at most
// max((p0 - o).v, (p0 + e - o).v) + y =: t0max (t0 is linear along the segment). Hence, for
// every capsule whose point nearest the ray's line lies in B,
//     tau = (d - R) / (bScale t0) >= (d_B - y) / (bScale t0max)   when t0 > 0,
// and the capsule does not shadow at all when t0max <= 0 or when the smallest t0 in B is >= A.
// A capsule is cut into pieces, and it is read (whole, by the Appendix's formulas) in the leaf of
// each piece: the piece that holds its nearest point carries the bound of its tau. A node's bound
// holds its children's, so it bounds the whole subtree.
//
// Groups of rays. The caller hands over rays in coherent groups (parker: the open rays of a 4 x 4
// pixel tile). Against an anchor a (the light's centre; for a directional light the mean origin)
// and a unit direction v0 (the mean of the rays'), ray i's line is within rho_i of a and its
// direction at angle theta_i from v0. The projector difference |(I - v_i v_i^T) x - (I - v0 v0^T) x|
// is at most sin(theta_i) |x|, so the distance of q from ray i's line is at least
//     |(I - v0 v0^T)(q - a)| - sin(theta_i) |q - a| - rho_i,
// and t0_i(q) = (q - a).v_i + h_i with h_i = (a - o_i).v_i, (q - a).v_i <= (q - a).v0 + |v_i - v0| |q - a|.
// One bound per node child then serves the whole group (the largest of sin(theta_i), |v_i - v0|,
// rho_i and of bScale_i t0_i over the group): the group walks the tree once.
//
// The walk keeps each ray's smallest tau (starting at 1: tau >= 1 gives s = 1, then lowered by the
// seeds, the capsules that gave the previous group's minima: neighbouring rays' minima come from
// the same few capsules, so the walk starts near its end and skips more) and pushes the children
// whose group bound is below the largest of them, the most promising on top. A node or
// leaf taken from the stack is first tested ray by ray, 8 rays at a time (16 with AVX-512F), against the ball
// around its bound (each ray's own bound: the group's is loose where the rays start near the
// capsules, as on a many-part mesh); a leaf's capsules are then culled by their group bound (a
// capsule bounds itself) and the rest evaluated for the rays of each half of the group one ray of
// which passed (with AVX-512F, for the whole group where one ray passed: a capsule read for a ray
// that did not need it takes that ray's minimum over one more capsule, which changes nothing). A capsule left out has,
// for every ray, tau >= that ray's final minimum, so the minima, and V, are those of reading every capsule. Rounding:
// every bounding radius is enlarged by 1e-6 of itself and of the coordinates' magnitude when built, and by kBoundSlack
// of the coordinates' magnitude when read (the formulas' float rounding is a few 1e-7 of it), and every bound is
// lowered by 1e-5 of itself: bounds err only low, which only adds work.
//
// The tree. Capsules are cut into pieces no longer than 1/64 of the scene's radius; a node holds
// up to kWidth runs of pieces, made by splitting the run of largest area in two until there are
// kWidth (binned surface-area heuristic, 16 bins across the longest axis of the pieces' centres,
// each piece's box grown by the piece length so that long thin runs weigh by their length); a run
// of at most kWidth pieces is a leaf holding its distinct capsules. Each bound is the capsule along
// the principal axis of what it holds. Building takes one pass over a run per split: O(n log n) in
// the number of pieces n, nearly linear at the sizes met (bench/parker_bench.cpp).
//
// Silhouettes. Per mesh, the edge adjacency of techniques/mesh_edges.h (vertices welded by
// position, the half-edges of the triangles that can be hit matched by their welded ends), shared
// with the ribbon techniques and kept while the mesh is unchanged.
//
// The per-ray and per-group loops read 8 capsules, 8 node children or 8 (or 16) rays at a time
// branch-free, so the compiler turns them into vector operations (CMakeLists.txt builds this file
// without errno for sqrt and with selects it may if-convert). Every lane computes exactly the
// scalar formulas and the minimum is exact, so V depends neither on the tree, the groups, nor the
// vector width.
#include "techniques/parker/outer_objects.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <tuple>
#include <utility>

#include <tbb/parallel_for.h>

#include "penumbra/error.h"

// An 8-wide build of the per-ray loop beside the baseline's 4-wide one, chosen at run time, where
// the baseline has no AVX2 of its own.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__AVX2__)
#define PENUMBRA_OUTER_AVX2 1
#else
#define PENUMBRA_OUTER_AVX2 0
#endif

namespace penumbra::rt {
namespace {

constexpr int kWidth = OuterObjects::kWidth;
constexpr int kGroup = OuterObjects::kGroup;
constexpr float kNoTau = std::numeric_limits<float>::max();
// When read, every bounding radius grows by this fraction of the largest coordinate magnitude of
// the rays' origins, the anchor and the scene (float rounding of the formulas is a few 1e-7 of it).
constexpr float kBoundSlack = 1e-5f;
// Every bound is lowered by this fraction of itself (the division's relative rounding).
constexpr float kBoundShrink = 1.0f - 1e-5f;
// Levels a traversal can hold: (kWidth - 1) stacked children per level below the root, plus it.
constexpr int kMaxDepth = 64;
constexpr int kStackSize = kMaxDepth * (kWidth - 1) + 1;

// A shadow ray as the capsule loop reads it.
struct RayQuery {
  float ox, oy, oz, vx, vy, vz;
  float bScale;  //!< b = bScale t0: D / A, or D for a directional light
  float tLimit;  //!< A: capsules at or beyond the light's centre do not shadow
};

// Structure-of-arrays capsules (leaf entries, node children, leaf bounds), as restrict pointers
// so that the loops over them vectorize.
struct CapsuleView {
  const float* __restrict p0x;
  const float* __restrict p0y;
  const float* __restrict p0z;
  const float* __restrict ex;
  const float* __restrict ey;
  const float* __restrict ez;
  const float* __restrict radius;
};

[[gnu::always_inline]] inline CapsuleView capsulesFrom(const CapsuleView& c, size_t first) {
  return {c.p0x + first, c.p0y + first, c.p0z + first, c.ex + first, c.ey + first, c.ez + first, c.radius + first};
}

// tau of the capsule (p0, e, radius) for the ray (o, v, bScale, tLimit); kNoTau where the capsule
// does not shadow. The closest points of the ray's line and the capsule's segment, computed on the
// parts perpendicular to the ray (vectors, not differences of squares, which cancel when the ray
// passes close to a far point). Every operation runs whatever the inputs and the result is
// selected, so that a loop over capsules, or over rays, has no branch and vectorizes; both loops
// run these operations in this order, so a ray's tau of a capsule has the same bits in either.
[[gnu::always_inline]] inline float capsuleTau(float p0x, float p0y, float p0z, float ex, float ey, float ez,
                                               float radius, float ox, float oy, float oz, float vx, float vy, float vz,
                                               float bScale, float tLimit) {
  const float wx = p0x - ox, wy = p0y - oy, wz = p0z - oz;
  const float wv = wx * vx + wy * vy + wz * vz;
  const float ev = ex * vx + ey * vy + ez * vz;
  const float wpx = wx - wv * vx, wpy = wy - wv * vy, wpz = wz - wv * vz;
  const float epx = ex - ev * vx, epy = ey - ev * vy, epz = ez - ev * vz;
  const float ee = epx * epx + epy * epy + epz * epz;
  const float we = wpx * epx + wpy * epy + wpz * epz;
  const float u = std::min(1.0f, std::max(0.0f, -we / std::max(ee, 1e-30f)));
  const float t0 = wv + u * ev;
  const float rx = wpx + u * epx, ry = wpy + u * epy, rz = wpz + u * epz;
  const float d = std::sqrt(rx * rx + ry * ry + rz * rz);
  const float q = (d - radius) / (bScale * t0);
  return ((t0 > 0.0f) & (t0 < tLimit)) ? q : kNoTau;
}

// tau of the kWidth capsules of leaf `leaf` for one ray (capsules in the vector lanes).
[[gnu::always_inline]] inline void leafTau(const CapsuleView& entries, uint32_t leaf, const RayQuery& r,
                                           float* __restrict tau) {
  const CapsuleView c = capsulesFrom(entries, static_cast<size_t>(leaf) * kWidth);
  for (int j = 0; j < kWidth; ++j)
    tau[j] = capsuleTau(c.p0x[j], c.p0y[j], c.p0z[j], c.ex[j], c.ey[j], c.ez[j], c.radius[j], r.ox, r.oy, r.oz, r.vx,
                        r.vy, r.vz, r.bScale, r.tLimit);
}

// A group of rays: each ray's query and, for the bounds, the group's anchor a, direction v0 and
// the largest deviations from them (the top of the file).
struct RayGroup {
  int count;
  alignas(32) float ox[kGroup], oy[kGroup], oz[kGroup], vx[kGroup], vy[kGroup], vz[kGroup];
  alignas(32) float bScale[kGroup], tLimit[kGroup], raySlack[kGroup];
  float ax, ay, az, v0x, v0y, v0z;
  float rho;    //!< largest distance of a ray's line from a
  float kappa;  //!< largest sin(theta_i)
  float mu;     //!< largest |v_i - v0|
  float bsMin, bsMax;
  float h;       //!< largest bScale_i h_i
  float gLimit;  //!< largest tLimit_i - h_i
  float slack;   //!< the group's rounding slack

  RayQuery query(int i) const { return {ox[i], oy[i], oz[i], vx[i], vy[i], vz[i], bScale[i], tLimit[i]}; }
};

// For each of the kWidth capsule bounds `c` (a node's children, or a leaf's capsules): the group
// bound of the top of the file where it can hold, for some ray of the group, a capsule with tau
// below `limit`; +infinity where it cannot (or is unused: radius -infinity makes every test false).
[[gnu::always_inline]] inline void childBounds(const CapsuleView& c, const RayGroup& g, float limit,
                                               float* __restrict bound) {
  for (int k = 0; k < kWidth; ++k) {
    const float x0 = c.p0x[k] - g.ax, y0 = c.p0y[k] - g.ay, z0 = c.p0z[k] - g.az;
    const float ex = c.ex[k], ey = c.ey[k], ez = c.ez[k];
    const float xv = x0 * g.v0x + y0 * g.v0y + z0 * g.v0z;
    const float ev = ex * g.v0x + ey * g.v0y + ez * g.v0z;
    const float px = x0 - xv * g.v0x, py = y0 - xv * g.v0y, pz = z0 - xv * g.v0z;
    const float qx = ex - ev * g.v0x, qy = ey - ev * g.v0y, qz = ez - ev * g.v0z;
    const float qq = qx * qx + qy * qy + qz * qz;
    const float pq = px * qx + py * qy + pz * qz;
    const float u = std::min(1.0f, std::max(0.0f, -pq / std::max(qq, 1e-30f)));
    const float rx = px + u * qx, ry = py + u * qy, rz = pz + u * qz;
    const float dPerp = std::sqrt(rx * rx + ry * ry + rz * rz);
    const float x1 = x0 + ex, y1 = y0 + ey, z1 = z0 + ez;
    const float y = c.radius[k] + g.slack;
    const float far = std::sqrt(std::max(x0 * x0 + y0 * y0 + z0 * z0, x1 * x1 + y1 * y1 + z1 * z1)) + y;  // >= |q - a|
    const float along = std::max(xv, xv + ev) + y + g.mu * far;     // >= (q - a).v_i
    const float alongMin = std::min(xv, xv + ev) - y - g.mu * far;  // <= (q - a).v_i
    const float num = dPerp - y - g.rho - g.kappa * far;
    const float den = (along >= 0.0f ? g.bsMax : g.bsMin) * along + g.h;  // >= bScale_i t0_i
    const float b = num / den * kBoundShrink;
    const bool visit = (den > 0.0f) & (alongMin < g.gLimit) & (b < limit);
    bound[k] = visit ? b : kInfinity;
  }
}

// Whether one of the rays [first, first + kLanes) of the group can find, within the bound `c` (its
// first capsule), a capsule with tau below its minimum best[i] (each ray's own bound, the top of
// the file). Rays in the vector lanes.
template <int kLanes>
[[gnu::always_inline]] inline bool someRayReads(const CapsuleView& c, const RayGroup& g, const float* __restrict best,
                                                int first) {
  // The ball around the capsule bound: centre at its middle, radius half its length plus its own.
  const float hx = 0.5f * c.ex[0], hy = 0.5f * c.ey[0], hz = 0.5f * c.ez[0];
  const float cx = c.p0x[0] + hx, cy = c.p0y[0] + hy, cz = c.p0z[0] + hz;
  const float radius = std::sqrt(hx * hx + hy * hy + hz * hz) * (1.0f + 1e-6f) + c.radius[0];
  alignas(64) float reads[kLanes];
  for (int k = 0; k < kLanes; ++k) {
    const int i = first + k;
    const float wx = cx - g.ox[i], wy = cy - g.oy[i], wz = cz - g.oz[i];
    const float wv = wx * g.vx[i] + wy * g.vy[i] + wz * g.vz[i];
    const float px = wx - wv * g.vx[i], py = wy - wv * g.vy[i], pz = wz - wv * g.vz[i];
    const float d = std::sqrt(px * px + py * py + pz * pz);
    const float y = radius + g.raySlack[i];
    const float t0max = wv + y;
    const float b = (d - y) / (g.bScale[i] * t0max) * kBoundShrink;
    reads[k] = ((t0max > 0.0f) & (wv - y < g.tLimit[i]) & (b < best[i])) ? 1.0f : 0.0f;
  }
  float any = 0.0f;
  for (int k = 0; k < kLanes; ++k) any = std::max(any, reads[k]);
  return any > 0.0f;
}

// What the per-ray code reads of the hierarchy, gathered once per call.
struct TreeView {
  const OuterObjects::Node* nodes;
  int32_t root;
  bool empty;
  CapsuleView entries;     //!< kWidth per leaf
  CapsuleView leafBounds;  //!< one per leaf
  const int32_t* entryObject;
  bool directional;
  Vec3 lightCenter;
  float diameter;
  float sceneMagnitude;  //!< the largest coordinate magnitude of the scene's bounds
};

// The group of rays [first, first + count): queries (b = D t0 / A, Appendix; A -> infinity with D
// per unit distance for a directional light) and the group's bound parameters. Unused slots
// repeat the first ray.
[[gnu::always_inline]] inline void makeGroup(const TreeView& view, const Ray* rays, const float* distanceToLight,
                                             int count, RayGroup& g) {
  g.count = count;
  Vec3 directionSum(0.0f), originSum(0.0f);
  for (int i = 0; i < count; ++i) {
    directionSum += rays[i].direction;
    originSum += rays[i].origin;
  }
  const Vec3 anchor = view.directional ? originSum / static_cast<float>(count) : view.lightCenter;
  const float sumLength = glm::length(directionSum);
  const Vec3 v0 = sumLength > 0.0f ? directionSum / sumLength : rays[0].direction;
  g.ax = anchor.x, g.ay = anchor.y, g.az = anchor.z;
  g.v0x = v0.x, g.v0y = v0.y, g.v0z = v0.z;
  for (int i = 0; i < kGroup; ++i) {
    const int k = i < count ? i : 0;
    const Ray& ray = rays[k];
    g.ox[i] = ray.origin.x, g.oy[i] = ray.origin.y, g.oz[i] = ray.origin.z;
    g.vx[i] = ray.direction.x, g.vy[i] = ray.direction.y, g.vz[i] = ray.direction.z;
    g.bScale[i] = view.directional ? view.diameter : view.diameter / distanceToLight[k];
    g.tLimit[i] = view.directional ? kInfinity : distanceToLight[k];
  }
  // Each ray's terms of the bounds, a ray to a vector lane (glm's dot, length and cross written out in
  // their order), then their extremes over the group.
  alignas(64) float rayMagnitude[kGroup], rho[kGroup], kappa[kGroup], mu[kGroup], bh[kGroup], limit[kGroup];
  for (int i = 0; i < kGroup; ++i) {
    rayMagnitude[i] =
        std::max(std::max(view.sceneMagnitude, std::abs(g.ox[i])), std::max(std::abs(g.oy[i]), std::abs(g.oz[i])));
    g.raySlack[i] = kBoundSlack * rayMagnitude[i];
    const float wx = anchor.x - g.ox[i], wy = anchor.y - g.oy[i], wz = anchor.z - g.oz[i];
    const float h = wx * g.vx[i] + wy * g.vy[i] + wz * g.vz[i];
    const float px = wx - h * g.vx[i], py = wy - h * g.vy[i], pz = wz - h * g.vz[i];
    rho[i] = std::sqrt(px * px + py * py + pz * pz);
    const float cx = g.vy[i] * v0.z - v0.y * g.vz[i], cy = g.vz[i] * v0.x - v0.z * g.vx[i],
                cz = g.vx[i] * v0.y - v0.x * g.vy[i];
    kappa[i] = std::sqrt(cx * cx + cy * cy + cz * cz);
    const float dx = g.vx[i] - v0.x, dy = g.vy[i] - v0.y, dz = g.vz[i] - v0.z;
    mu[i] = std::sqrt(dx * dx + dy * dy + dz * dz);
    bh[i] = g.bScale[i] * h;
    limit[i] = g.tLimit[i] - h;
  }
  float magnitude = std::max({view.sceneMagnitude, std::abs(anchor.x), std::abs(anchor.y), std::abs(anchor.z)});
  g.rho = g.kappa = g.mu = 0.0f;
  g.bsMin = kInfinity, g.bsMax = 0.0f, g.h = -kInfinity, g.gLimit = -kInfinity;
  for (int i = 0; i < kGroup; ++i) {
    magnitude = std::max(magnitude, rayMagnitude[i]);
    g.rho = std::max(g.rho, rho[i]);
    g.kappa = std::max(g.kappa, kappa[i]);
    g.mu = std::max(g.mu, mu[i]);
    g.bsMin = std::min(g.bsMin, g.bScale[i]);
    g.bsMax = std::max(g.bsMax, g.bScale[i]);
    g.h = std::max(g.h, bh[i]);
    g.gLimit = std::max(g.gLimit, limit[i]);
  }
  g.slack = kBoundSlack * magnitude;
}

struct StackItem {
  int32_t ref;           //!< >= 0 a node, < 0 the leaf ~ref
  float bound;           //!< the child's bound when it was pushed
  int32_t parent, slot;  //!< where its bound is: child `slot` of node `parent` (-1: the root)
};

// Pushes the children of `node` whose bound is below `limit`, the smallest bound on top (read
// first, so that the rays' minima fall early and prune more).
[[gnu::always_inline]] inline void pushChildren(const OuterObjects::Node& node, int32_t parent, const RayGroup& g,
                                                float limit, StackItem* stack, int& top) {
  alignas(32) float bound[kWidth];
  childBounds({node.p0x, node.p0y, node.p0z, node.ex, node.ey, node.ez, node.radius}, g, limit, bound);
  const int base = top;
  for (int k = 0; k < kWidth; ++k) {
    if (!(bound[k] < kInfinity)) continue;
    const StackItem item{node.child[k], bound[k], parent, k};
    int j = top++;
    while (j > base && stack[j - 1].bound < item.bound) {
      stack[j] = stack[j - 1];
      --j;
    }
    stack[j] = item;
  }
}

// The largest of the group's minima best[i] (unused slots hold -infinity).
[[gnu::always_inline]] inline float largestMinimum(const float* __restrict best) {
  alignas(32) float upper[kGroup / 2];
  for (int i = 0; i < kGroup / 2; ++i) upper[i] = std::max(best[i], best[i + kGroup / 2]);
  for (int width = kGroup / 4; width > 0; width /= 2)
    for (int i = 0; i < width; ++i) upper[i] = std::max(upper[i], upper[i + width]);
  return upper[0];
}

// Ray i's tau of leaf entry `e` lowers best[i] (and sets bestEntry[i] to e where it does), for the
// rays [first, first + kLanes), one to a vector lane.
template <int kLanes>
[[gnu::always_inline]] inline void readEntry(const CapsuleView& entries, int32_t e, const RayGroup& g, int first,
                                             float* __restrict best, int32_t* __restrict bestEntry) {
  const float p0x = entries.p0x[e], p0y = entries.p0y[e], p0z = entries.p0z[e], ex = entries.ex[e], ey = entries.ey[e],
              ez = entries.ez[e], radius = entries.radius[e];
  for (int i = first; i < first + kLanes; ++i) {
    const float tau = capsuleTau(p0x, p0y, p0z, ex, ey, ez, radius, g.ox[i], g.oy[i], g.oz[i], g.vx[i], g.vy[i],
                                 g.vz[i], g.bScale[i], g.tLimit[i]);
    bestEntry[i] = tau < best[i] ? e : bestEntry[i];
    best[i] = tau < best[i] ? tau : best[i];
  }
}

// The rays of a group as the walk reads them: the halves [0, 8) and [8, 16), each read where one of
// its rays passes a bound; or, with kWhole (16-lane vectors) and more than 8 rays, all 16 at once
// wherever one of them passes. Reading a capsule for a ray that did not need it only takes the
// minimum over more capsules, which it already is: the minima are the same either way.
template <bool kWhole>
struct GroupReads {
  const RayGroup& g;
  const bool second = g.count > kGroup / 2;  // the second half holds rays
  const bool whole = kWhole && second;

  // Which halves pass the bound `c` (both or neither, when whole).
  std::pair<bool, bool> pass(const CapsuleView& c, const float* __restrict best) const {
    if (whole) {
      const bool any = someRayReads<kGroup>(c, g, best, 0);
      return {any, any};
    }
    return {someRayReads<kGroup / 2>(c, g, best, 0), second && someRayReads<kGroup / 2>(c, g, best, kGroup / 2)};
  }
  // Entry e read for the halves that passed.
  void read(const CapsuleView& entries, int32_t e, bool first, bool last, float* __restrict best,
            int32_t* __restrict bestEntry) const {
    if (whole) {
      if (first || last) readEntry<kGroup>(entries, e, g, 0, best, bestEntry);
      return;
    }
    if (first) readEntry<kGroup / 2>(entries, e, g, 0, best, bestEntry);
    if (last && second) readEntry<kGroup / 2>(entries, e, g, kGroup / 2, best, bestEntry);
  }
};

// best[i] = the smallest tau of ray i over every capsule where it is below 1 (else 1): the
// traversal of the top of the file. The leaf entries `seeds` (those that gave the minima of the
// group before, whose rays are neighbours of these) are read first: the minima then start near
// their final values and the walk skips more. Reading an entry twice changes no minimum, so the
// minima do not depend on the seeds. `seeds` is replaced by the entries that gave this group's
// minima.
template <bool kWhole>
[[gnu::always_inline]] inline void groupMinTau(const TreeView& view, const RayGroup& g, float* __restrict best,
                                               OuterObjects::Seeds& seeds) {
  alignas(64) int32_t bestEntry[kGroup];
  for (int i = 0; i < kGroup; ++i) {
    best[i] = i < g.count ? 1.0f : -kInfinity;  // unused slots read nothing
    bestEntry[i] = -1;
  }
  if (view.empty) return;
  const GroupReads<kWhole> reads{g};
  for (int k = 0; k < seeds.count; ++k) reads.read(view.entries, seeds.entry[k], true, true, best, bestEntry);
  float limit = largestMinimum(best);
  const auto keepSeeds = [&] {
    seeds.count = 0;
    for (int i = 0; i < g.count; ++i) {
      if (bestEntry[i] < 0) continue;
      bool known = false;
      for (int k = 0; k < seeds.count; ++k) known = known || seeds.entry[k] == bestEntry[i];
      if (!known) seeds.entry[seeds.count++] = bestEntry[i];
    }
  };
  if (!(limit > 0.0f)) {  // every ray is inside an analytic sphere's inner object
    keepSeeds();
    return;
  }
  StackItem stack[kStackSize];
  int top = 0;
  stack[top++] = {view.root, -kInfinity, -1, 0};
  while (top > 0) {
    const StackItem item = stack[--top];
    if (!(item.bound < limit)) continue;
    if (item.ref >= 0) {
      if (item.parent >= 0) {  // each ray's own bound (the root has none: every ray reads it)
        const OuterObjects::Node& parent = view.nodes[item.parent];
        const CapsuleView bound =
            capsulesFrom({parent.p0x, parent.p0y, parent.p0z, parent.ex, parent.ey, parent.ez, parent.radius},
                         static_cast<size_t>(item.slot));
        const auto [first, last] = reads.pass(bound, best);
        if (!first && !last) continue;
      }
      pushChildren(view.nodes[item.ref], item.ref, g, limit, stack, top);
      continue;
    }
    // The leaf (the top of the file): the halves of the group one ray of which passes its own
    // bound, the capsules that pass their group bound, those against those, 8 or 16 rays to the lanes.
    const uint32_t leaf = static_cast<uint32_t>(~item.ref);
    const CapsuleView bound = capsulesFrom(view.leafBounds, leaf);
    bool first = true, last = true;
    if (item.parent >= 0) {
      std::tie(first, last) = reads.pass(bound, best);
      if (!first && !last) continue;
    }
    const CapsuleView c = capsulesFrom(view.entries, static_cast<size_t>(leaf) * kWidth);
    alignas(32) float capsuleBound[kWidth];
    childBounds(c, g, limit, capsuleBound);
    int listed[kWidth], capsules = 0;
    for (int j = 0; j < kWidth; ++j) {
      listed[capsules] = j;
      capsules += capsuleBound[j] < kInfinity;
    }
    for (int n = 0; n < capsules; ++n)
      reads.read(view.entries, static_cast<int32_t>(leaf * kWidth) + listed[n], first, last, best, bestEntry);
    limit = largestMinimum(best);
    if (!(limit > 0.0f)) break;  // every ray is inside an analytic sphere's inner object
  }
  keepSeeds();
}

// s of each ray under the min combination: the falloff of its smallest tau, group by group.
template <bool kWhole>
[[gnu::always_inline]] inline void minAttenuationsOver(const TreeView& view, const Ray* rays,
                                                       const float* distanceToLight, int count, OuterFalloff falloff,
                                                       float* s, OuterObjects::Seeds& seeds) {
  RayGroup g;
  for (int first = 0; first < count; first += kGroup) {
    const int n = std::min(kGroup, count - first);
    makeGroup(view, rays + first, distanceToLight + first, n, g);
    alignas(32) float best[kGroup];
    groupMinTau<kWhole>(view, g, best, seeds);
    for (int i = 0; i < n; ++i) s[first + i] = best[i] <= 0.0f ? 0.0f : outerFalloff(best[i], falloff);
  }
}

void minAttenuations(const TreeView& view, const Ray* rays, const float* distanceToLight, int count,
                     OuterFalloff falloff, float* s, OuterObjects::Seeds& seeds) {
  minAttenuationsOver<false>(view, rays, distanceToLight, count, falloff, s, seeds);
}

#if PENUMBRA_OUTER_AVX2
// The same compiled for 8-wide vectors, and for 16-wide ones (a whole group of rays to a vector), where
// the CPU has them: the same operations per lane (no multiply-add: CMakeLists.txt builds this file with
// -ffp-contract=off), so the same values.
[[gnu::target("avx2")]] void minAttenuationsAvx2(const TreeView& view, const Ray* rays, const float* distanceToLight,
                                                 int count, OuterFalloff falloff, float* s,
                                                 OuterObjects::Seeds& seeds) {
  minAttenuationsOver<false>(view, rays, distanceToLight, count, falloff, s, seeds);
}
[[gnu::target("avx512f")]] void minAttenuationsAvx512(const TreeView& view, const Ray* rays,
                                                      const float* distanceToLight, int count, OuterFalloff falloff,
                                                      float* s, OuterObjects::Seeds& seeds) {
  minAttenuationsOver<true>(view, rays, distanceToLight, count, falloff, s, seeds);
}
#endif

// s of one ray under the product or sum combination: every capsule with tau below 1 (the others
// give s_i = 1, which changes neither), per object the smallest tau, then the objects' s_i
// combined in the order of the objects. `found` is scratch space.
float combinedAttenuation(const TreeView& view, const Ray& ray, float distanceToLight, OuterFalloff falloff,
                          OuterCombine combine, std::vector<std::pair<int32_t, float>>& found) {
  if (view.empty) return 1.0f;
  RayGroup g;
  makeGroup(view, &ray, &distanceToLight, 1, g);
  const RayQuery r = g.query(0);
  alignas(32) float one[kGroup];
  for (int i = 0; i < kGroup; ++i) one[i] = i == 0 ? 1.0f : -kInfinity;
  found.clear();
  StackItem stack[kStackSize];
  int top = 0;
  stack[top++] = {view.root, -kInfinity, -1, 0};
  while (top > 0) {
    const StackItem item = stack[--top];
    if (item.ref >= 0) {
      pushChildren(view.nodes[item.ref], item.ref, g, 1.0f, stack, top);
      continue;
    }
    const uint32_t leaf = static_cast<uint32_t>(~item.ref);
    if (!someRayReads<kGroup / 2>(capsulesFrom(view.leafBounds, leaf), g, one, 0)) continue;
    alignas(32) float tau[kWidth];
    leafTau(view.entries, leaf, r, tau);
    for (int j = 0; j < kWidth; ++j) {
      if (!(tau[j] < 1.0f)) continue;
      if (tau[j] <= 0.0f) return 0.0f;  // inside an analytic sphere's inner object
      found.emplace_back(view.entryObject[static_cast<size_t>(leaf) * kWidth + static_cast<size_t>(j)], tau[j]);
    }
  }
  std::sort(found.begin(), found.end());  // by object, its smallest tau first
  float s = 1.0f;
  for (size_t i = 0; i < found.size(); ++i) {
    if (i > 0 && found[i].first == found[i - 1].first) continue;
    const float si = outerFalloff(found[i].second, falloff);
    s = combine == OuterCombine::Product ? s * si : s - (1.0f - si);
  }
  return std::max(0.0f, s);
}

// Capsules, structure of arrays, in the order they are found (object by object).
struct Capsules {
  std::vector<float> p0x, p0y, p0z, ex, ey, ez, radius;
  std::vector<int32_t> object;  //!< index into the scene's objects
  void add(const Vec3& p0, const Vec3& e, float r, int32_t objectIndex) {
    p0x.push_back(p0.x);
    p0y.push_back(p0.y);
    p0z.push_back(p0.z);
    ex.push_back(e.x);
    ey.push_back(e.y);
    ez.push_back(e.z);
    radius.push_back(r);
    object.push_back(objectIndex);
  }
  size_t size() const { return object.size(); }
};

// A piece of a capsule: its part of the segment, a -> b, the capsule's radius, and the capsule.
struct Piece {
  Vec3 a, b;
  float radius;
  int32_t capsule;
};

// A ball: centre and radius.
struct Ball {
  Vec3 center;
  float radius;
};

// A capsule bound: segment p0 -> p0 + e, radius.
struct Bound {
  Vec3 p0, e;
  float radius;
};

// The capsule around `balls` along their centres' principal axis (a few power iterations on
// their covariance), just long enough to span their centres' projections; its radius enlarged by
// 1e-6 of itself and of the coordinates' magnitude so that rounding leaves every ball inside.
Bound enclosingBound(const Ball* first, int count, float magnitude) {
  const Ball* last = first + count;
  Vec3 mean(0.0f);
  for (const Ball* b = first; b != last; ++b) mean += b->center;
  mean /= static_cast<float>(count);
  float cxx = 0, cxy = 0, cxz = 0, cyy = 0, cyz = 0, czz = 0;
  for (const Ball& b : std::span(first, last)) {
    const Vec3 d = b.center - mean;
    cxx += d.x * d.x, cxy += d.x * d.y, cxz += d.x * d.z, cyy += d.y * d.y, cyz += d.y * d.z, czz += d.z * d.z;
  }
  Vec3 axis = cxx >= cyy && cxx >= czz ? Vec3(1, 0, 0) : cyy >= czz ? Vec3(0, 1, 0) : Vec3(0, 0, 1);
  for (int iteration = 0; iteration < 8; ++iteration) {
    const Vec3 next(cxx * axis.x + cxy * axis.y + cxz * axis.z, cxy * axis.x + cyy * axis.y + cyz * axis.z,
                    cxz * axis.x + cyz * axis.y + czz * axis.z);
    const float length = glm::length(next);
    if (!(length > 0.0f) || !std::isfinite(length)) break;
    axis = next / length;
  }
  float lo = kInfinity, hi = -kInfinity;
  for (const Ball& b : std::span(first, last)) {
    const float t = glm::dot(b.center - mean, axis);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  const Vec3 p0 = mean + lo * axis, e = (hi - lo) * axis;
  float radius = 0.0f;
  for (const Ball& b : std::span(first, last)) {
    const float t = glm::dot(b.center - mean, axis);
    radius = std::max(radius, glm::length(b.center - (mean + t * axis)) + b.radius);
  }
  return {p0, e, radius * (1.0f + 1e-6f) + 1e-6f * magnitude};
}

// The outputs of the tree build, as the OuterObjects members they fill.
struct TreeOut {
  std::vector<OuterObjects::Node> nodes;
  std::array<std::vector<float>, 7> entries;  //!< p0x p0y p0z ex ey ez radius, kWidth per leaf
  std::vector<int32_t> entryObject;
  std::array<std::vector<float>, 7> leafBounds;  //!< one per leaf
  size_t leaves = 0;
  int depth = 0;
};

// Half the surface area of a box (the binned SAH's cost of a run).
float halfArea(const Bounds3& box) {
  if (box.empty()) return 0.0f;
  const Vec3 d = box.diagonal();
  return d.x * d.y + d.y * d.z + d.z * d.x;
}

// Builds the tree top-down over the pieces (binned surface-area heuristic on the pieces' boxes,
// grown by `margin` so that long thin runs weigh by their length).
class TreeBuilder {
 public:
  TreeBuilder(const std::vector<Piece>& pieces, const Capsules& capsules, float magnitude, float margin)
      : pieces_(pieces),
        capsules_(capsules),
        magnitude_(magnitude),
        order_(pieces.size()),
        centroid_(pieces.size()),
        box_(pieces.size()) {
    for (size_t p = 0; p < pieces.size(); ++p) {
      order_[p] = static_cast<uint32_t>(p);
      centroid_[p] = 0.5f * (pieces[p].a + pieces[p].b);
      const Vec3 grow(pieces[p].radius + margin);
      box_[p].extend(glm::min(pieces[p].a, pieces[p].b) - grow);
      box_[p].extend(glm::max(pieces[p].a, pieces[p].b) + grow);
    }
  }

  // The whole tree into `out` (the root: node 0, or the leaf ~0 for at most kWidth pieces). The
  // root's runs are built at once on the threads there are, each into its own storage, then put
  // one after the other, their references moved accordingly: the same tree on any thread count.
  void buildAll(TreeOut& out) {
    Run all{0, order_.size(), {}};
    for (const Bounds3& b : box_) all.box.extend(b);
    if (all.size() <= static_cast<size_t>(kWidth)) {
      leaf(all.lo, all.hi, out);
      return;
    }
    std::array<Run, kWidth> runs;
    const int count = splitRuns(all, 0, runs);
    newNode(out);
    std::array<TreeOut, kWidth> parts;
    std::array<std::pair<int32_t, Bound>, kWidth> results;
    tbb::parallel_for(0, count, [&](int k) {
      results[static_cast<size_t>(k)] = build(runs[static_cast<size_t>(k)], 1, parts[static_cast<size_t>(k)]);
    });
    for (int k = 0; k < count; ++k) {
      TreeOut& part = parts[static_cast<size_t>(k)];
      const int32_t nodeOffset = static_cast<int32_t>(out.nodes.size()), leafOffset = static_cast<int32_t>(out.leaves);
      const auto moved = [&](int32_t ref) { return ref >= 0 ? ref + nodeOffset : ~(~ref + leafOffset); };
      for (OuterObjects::Node& node : part.nodes)
        for (int c = 0; c < kWidth; ++c)
          if (node.radius[c] > -kInfinity) node.child[c] = moved(node.child[c]);
      out.nodes.insert(out.nodes.end(), part.nodes.begin(), part.nodes.end());
      for (size_t a = 0; a < 7; ++a) {
        out.entries[a].insert(out.entries[a].end(), part.entries[a].begin(), part.entries[a].end());
        out.leafBounds[a].insert(out.leafBounds[a].end(), part.leafBounds[a].begin(), part.leafBounds[a].end());
      }
      out.entryObject.insert(out.entryObject.end(), part.entryObject.begin(), part.entryObject.end());
      out.leaves += part.leaves;
      out.depth = std::max(out.depth, part.depth);
      setChild(out.nodes[0], k, moved(results[static_cast<size_t>(k)].first), results[static_cast<size_t>(k)].second);
    }
  }

 private:
  struct Run {
    size_t lo, hi;
    Bounds3 box;
    size_t size() const { return hi - lo; }
  };

  // A node with every child unused (radius -infinity: no ray reaches it); its index.
  static size_t newNode(TreeOut& out) {
    out.nodes.emplace_back();
    OuterObjects::Node& node = out.nodes.back();
    for (int k = 0; k < kWidth; ++k) {
      node.p0x[k] = node.p0y[k] = node.p0z[k] = node.ex[k] = node.ey[k] = node.ez[k] = 0.0f;
      node.radius[k] = -kInfinity;
      node.child[k] = 0;
    }
    return out.nodes.size() - 1;
  }

  static void setChild(OuterObjects::Node& node, int k, int32_t ref, const Bound& bound) {
    node.p0x[k] = bound.p0.x, node.p0y[k] = bound.p0.y, node.p0z[k] = bound.p0.z;
    node.ex[k] = bound.e.x, node.ey[k] = bound.e.y, node.ez[k] = bound.e.z;
    node.radius[k] = bound.radius;
    node.child[k] = ref;
  }

  // The runs of a node: the run of largest area (of more than kWidth pieces) split in two until
  // there are kWidth. Their number.
  int splitRuns(const Run& run, int depth, std::array<Run, kWidth>& runs) {
    int count = 1;
    runs[0] = run;
    while (count < kWidth) {
      int largest = -1;
      for (int k = 0; k < count; ++k)
        if (runs[k].size() > static_cast<size_t>(kWidth) &&
            (largest < 0 || halfArea(runs[k].box) > halfArea(runs[largest].box)))
          largest = k;
      if (largest < 0) break;
      const auto [left, right] = depth < kSahDepth ? split(runs[largest]) : splitAtMedian(runs[largest]);
      runs[largest] = left;
      runs[count++] = right;
    }
    return count;
  }

  // The child reference (a node >= 0, a leaf < 0, in `out`) and bound of the run's pieces.
  std::pair<int32_t, Bound> build(const Run& run, int depth, TreeOut& out) {
    out.depth = std::max(out.depth, depth);
    if (run.size() <= static_cast<size_t>(kWidth)) return leaf(run.lo, run.hi, out);
    std::array<Run, kWidth> runs;
    const int count = splitRuns(run, depth, runs);
    const size_t index = newNode(out);
    std::array<Ball, 2 * kWidth> ends;
    for (int k = 0; k < count; ++k) {
      const auto [ref, bound] = build(runs[static_cast<size_t>(k)], depth + 1, out);
      setChild(out.nodes[index], k, ref, bound);  // build() may have grown the nodes
      // A capsule is the hull of the balls at its two ends.
      ends[static_cast<size_t>(2 * k)] = {bound.p0, bound.radius};
      ends[static_cast<size_t>(2 * k + 1)] = {bound.p0 + bound.e, bound.radius};
    }
    return {static_cast<int32_t>(index), enclosingBound(ends.data(), 2 * count, magnitude_)};
  }

  // Below kSahDepth levels the runs are halved at their median instead: the heuristic may peel
  // one piece at a time off a run (pieces spaced ever farther apart), and halving keeps the tree
  // within kMaxDepth levels whatever the input.
  static constexpr int kSahDepth = 24;
  std::pair<Run, Run> splitAtMedian(const Run& run) {
    Bounds3 centers;
    for (size_t i = run.lo; i < run.hi; ++i) centers.extend(centroid_[order_[i]]);
    const Vec3 extent = centers.diagonal();
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
    const size_t middle = run.lo + run.size() / 2;
    std::nth_element(order_.begin() + static_cast<std::ptrdiff_t>(run.lo),
                     order_.begin() + static_cast<std::ptrdiff_t>(middle),
                     order_.begin() + static_cast<std::ptrdiff_t>(run.hi),
                     [&](uint32_t a, uint32_t b) { return centroid_[a][axis] < centroid_[b][axis]; });
    Run left{run.lo, middle, {}}, right{middle, run.hi, {}};
    for (size_t i = left.lo; i < left.hi; ++i) left.box.extend(box_[order_[i]]);
    for (size_t i = right.lo; i < right.hi; ++i) right.box.extend(box_[order_[i]]);
    return {left, right};
  }

  // Two runs from one: the plane among 16 bins across the longest axis of the centroids' box with
  // the least sum of area times count; the middle where all centroids coincide.
  std::pair<Run, Run> split(const Run& run) {
    constexpr int kBins = 16;
    Bounds3 centers;
    for (size_t i = run.lo; i < run.hi; ++i) centers.extend(centroid_[order_[i]]);
    const Vec3 extent = centers.diagonal();
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
    Run left{run.lo, run.lo + run.size() / 2, {}}, right{left.hi, run.hi, {}};
    if (!(extent[axis] > 0.0f)) {
      for (size_t i = left.lo; i < left.hi; ++i) left.box.extend(box_[order_[i]]);
      for (size_t i = right.lo; i < right.hi; ++i) right.box.extend(box_[order_[i]]);
      return {left, right};
    }
    const float scale = static_cast<float>(kBins) / extent[axis], lower = centers.lower[axis];
    const auto binOf = [&](uint32_t p) {
      return std::min(kBins - 1, static_cast<int>((centroid_[p][axis] - lower) * scale));
    };
    std::array<Bounds3, kBins> binBox;
    std::array<size_t, kBins> binCount{};
    for (size_t i = run.lo; i < run.hi; ++i) {
      const uint32_t p = order_[i];
      const int bin = binOf(p);
      binBox[static_cast<size_t>(bin)].extend(box_[p]);
      ++binCount[static_cast<size_t>(bin)];
    }
    std::array<Bounds3, kBins> rightBox;  // bins [bin, kBins)
    rightBox[kBins - 1] = binBox[kBins - 1];
    for (int bin = kBins - 2; bin > 0; --bin) {
      rightBox[static_cast<size_t>(bin)] = rightBox[static_cast<size_t>(bin + 1)];
      rightBox[static_cast<size_t>(bin)].extend(binBox[static_cast<size_t>(bin)]);
    }
    Bounds3 leftBox;
    size_t n = 0;
    int bestBin = -1;
    float bestCost = kInfinity;
    Bounds3 bestLeft;
    for (int bin = 0; bin < kBins - 1; ++bin) {
      leftBox.extend(binBox[static_cast<size_t>(bin)]);
      n += binCount[static_cast<size_t>(bin)];
      if (n == 0 || n == run.size()) continue;
      const float cost = halfArea(leftBox) * static_cast<float>(n) +
                         halfArea(rightBox[static_cast<size_t>(bin + 1)]) * static_cast<float>(run.size() - n);
      if (cost < bestCost) {
        bestCost = cost;
        bestBin = bin;
        bestLeft = leftBox;
      }
    }
    const size_t cut = static_cast<size_t>(std::partition(order_.begin() + static_cast<std::ptrdiff_t>(run.lo),
                                                          order_.begin() + static_cast<std::ptrdiff_t>(run.hi),
                                                          [&](uint32_t p) { return binOf(p) <= bestBin; }) -
                                           order_.begin());
    return {{run.lo, cut, bestLeft}, {cut, run.hi, rightBox[static_cast<size_t>(bestBin + 1)]}};
  }

  // A leaf of the distinct capsules of the pieces order_[lo, hi), padded to kWidth.
  std::pair<int32_t, Bound> leaf(size_t lo, size_t hi, TreeOut& out) {
    std::array<int32_t, kWidth> ids;
    int count = 0;
    for (size_t i = lo; i < hi; ++i) ids[static_cast<size_t>(count++)] = pieces_[order_[i]].capsule;
    std::sort(ids.begin(), ids.begin() + count);
    count = static_cast<int>(std::unique(ids.begin(), ids.begin() + count) - ids.begin());
    for (int k = 0; k < kWidth; ++k) {
      const bool used = k < count;
      const size_t c = used ? static_cast<size_t>(ids[static_cast<size_t>(k)]) : 0;
      out.entries[0].push_back(used ? capsules_.p0x[c] : 0.0f);
      out.entries[1].push_back(used ? capsules_.p0y[c] : 0.0f);
      out.entries[2].push_back(used ? capsules_.p0z[c] : 0.0f);
      out.entries[3].push_back(used ? capsules_.ex[c] : 0.0f);
      out.entries[4].push_back(used ? capsules_.ey[c] : 0.0f);
      out.entries[5].push_back(used ? capsules_.ez[c] : 0.0f);
      out.entries[6].push_back(used ? capsules_.radius[c] : -kInfinity);  // padding: tau = +inf for every ray
      out.entryObject.push_back(used ? capsules_.object[c] : -1);
    }
    std::array<Ball, 2 * kWidth> ends;
    for (size_t i = lo; i < hi; ++i) {
      const Piece& piece = pieces_[order_[i]];
      ends[2 * (i - lo)] = {piece.a, piece.radius};
      ends[2 * (i - lo) + 1] = {piece.b, piece.radius};
    }
    const Bound bound = enclosingBound(ends.data(), static_cast<int>(2 * (hi - lo)), magnitude_);
    const float values[7] = {bound.p0.x, bound.p0.y, bound.p0.z, bound.e.x, bound.e.y, bound.e.z, bound.radius};
    for (size_t k = 0; k < 7; ++k) out.leafBounds[k].push_back(values[k]);
    return {~static_cast<int32_t>(out.leaves++), bound};
  }

  const std::vector<Piece>& pieces_;
  const Capsules& capsules_;
  float magnitude_;
  std::vector<uint32_t> order_;
  std::vector<Vec3> centroid_;
  std::vector<Bounds3> box_;
};

// Each capsule cut into pieces of at most `pieceLength` (at most 1e6 pieces per capsule), in capsule
// order.
std::vector<Piece> cutIntoPieces(const Capsules& capsules, float pieceLength) {
  std::vector<Piece> pieces;
  pieces.reserve(capsules.size());
  for (size_t c = 0; c < capsules.size(); ++c) {
    const Vec3 p0(capsules.p0x[c], capsules.p0y[c], capsules.p0z[c]);
    const Vec3 e(capsules.ex[c], capsules.ey[c], capsules.ez[c]);
    const int count = std::max(1, static_cast<int>(std::ceil(std::min(glm::length(e) / pieceLength, 1e6f))));
    for (int k = 0; k < count; ++k)
      pieces.push_back({p0 + e * (static_cast<float>(k) / static_cast<float>(count)),
                        k + 1 == count ? p0 + e : p0 + e * (static_cast<float>(k + 1) / static_cast<float>(count)),
                        capsules.radius[c], static_cast<int32_t>(c)});
  }
  return pieces;
}

// The built tree moved into the arrays the per-ray code reads (OuterObjects' members).
void moveTree(TreeOut& out, std::vector<OuterObjects::Node>& nodes, const std::array<std::vector<float>*, 7>& entries,
              const std::array<std::vector<float>*, 7>& leafBounds, std::vector<int32_t>& entryObject) {
  nodes = std::move(out.nodes);
  for (size_t k = 0; k < 7; ++k) {
    *entries[k] = std::move(out.entries[k]);
    *leafBounds[k] = std::move(out.leafBounds[k]);
  }
  entryObject = std::move(out.entryObject);
}

// Calls keep(a, b) for each kept edge of a mesh (techniques/mesh_edges.h: the edges of its
// triangles that can be hit): an open boundary (one face), a silhouette (two faces, one towards the
// light) or a non-manifold edge (three or more, its outline status ambiguous), with the vertices of
// its first half-edge. `front(p0, n)`: whether the triangle with first vertex p0 and normal n faces
// the light.
template <typename Front, typename Keep>
void forEachKept(const MeshEdges& edges, const Mesh& mesh, Front front, Keep keep) {
  const auto facing = [&](uint32_t t) {
    const glm::uvec3& tri = mesh.triangles[t];
    const Vec3 p0 = mesh.positions[tri.x], p1 = mesh.positions[tri.y], p2 = mesh.positions[tri.z];
    return front(p0, glm::cross(p1 - p0, p2 - p0));
  };
  for (size_t e = 0; e < edges.edgeCount(); ++e) {
    const uint32_t u = edges.firstUse[e], count = edges.firstUse[e + 1] - u;
    if (count != 2 || facing(edges.useTriangle[u]) != facing(edges.useTriangle[u + 1])) {
      const glm::uvec3& tri = mesh.triangles[edges.useTriangle[u]];
      const uint32_t k = edges.useCorner[u];
      keep(tri[static_cast<int>(k)], tri[static_cast<int>((k + 1) % 3)]);
    }
  }
}

}  // namespace

OuterObjects::OuterObjects(const Scene& scene, const Light& light, const OuterObjectOptions& options,
                           EdgeCache* cache) {
  if (!(options.lightDiameter > 0.0f) || !std::isfinite(options.lightDiameter))
    fail("parker: light diameter must be a finite number > 0, got {}", options.lightDiameter);
  directional_ = light.isDirectional();
  lightCenter_ = light.center();
  diameter_ = options.lightDiameter;
#if PENUMBRA_OUTER_AVX2
  avx2_ = __builtin_cpu_supports("avx2");
  avx512_ = __builtin_cpu_supports("avx512f");
#endif

  const Bounds3 bounds = scene.bounds();
  const float sceneRadius = bounds.empty() ? 1.0f : std::max(bounds.radius(), 1e-6f);
  if (!bounds.empty())
    for (int k = 0; k < 3; ++k)
      sceneMagnitude_ = std::max({sceneMagnitude_, std::abs(bounds.lower[k]), std::abs(bounds.upper[k])});

  Capsules capsules;
  // Capsules: analytic spheres, then every mesh's silhouette edges.
  analytic_.assign(scene.objects.size(), false);
  EdgeCache local;
  EdgeCache& edgeCache = cache ? *cache : local;
  edgeCache.resize(scene.objects.size());
  for (size_t objectIndex = 0; objectIndex < scene.objects.size(); ++objectIndex) {
    const Object& object = scene.objects[objectIndex];
    const int32_t index = static_cast<int32_t>(objectIndex);
    if (usesAnalyticSphere(object, options)) {
      capsules.add(object.sphere->center, Vec3(0.0f), object.sphere->radius, index);
      analytic_[objectIndex] = true;
      ++analyticCount_;
      continue;
    }
    const Mesh& mesh = object.mesh;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const glm::uvec3& tri = mesh.triangles[t];
      if (tri.x >= mesh.positions.size() || tri.y >= mesh.positions.size() || tri.z >= mesh.positions.size())
        fail("{}: object '{}' triangle {} uses vertex index {} but the mesh has {} vertices", scene.source, object.name,
             t, std::max({tri.x, tri.y, tri.z}), mesh.positions.size());
    }
    // Per edge (its vertices welded by position: split normals or UV seams make duplicates) the
    // faces that share it, matched again only where the mesh changed since the cache's last use.
    const MeshEdges& edges = edgeCache.edges(scene, objectIndex);
    forEachKept(
        edges, mesh,
        [&](const Vec3& p0, const Vec3& n) {
          return glm::dot(n, directional_ ? light.direction() : lightCenter_ - p0) > 0.0f;
        },
        [&](uint32_t a, uint32_t b) {
          const Vec3 pa = mesh.positions[a];
          capsules.add(pa, mesh.positions[b] - pa, 0.0f, index);
          ++edgeCount_;
        });
  }

  // Pieces of at most sceneRadius / 64 along each capsule.
  const float pieceLength = sceneRadius / 64.0f;
  const std::vector<Piece> pieces = cutIntoPieces(capsules, pieceLength);
  pieceCount_ = pieces.size();
  if (pieces.empty()) return;
  if (pieces.size() > static_cast<size_t>(std::numeric_limits<int32_t>::max() / kWidth))
    fail("parker: {} outer-object pieces are more than the hierarchy holds", pieces.size());

  TreeOut out;
  TreeBuilder(pieces, capsules, sceneMagnitude_, pieceLength).buildAll(out);
  root_ = out.nodes.empty() ? ~0 : 0;
  moveTree(out, nodes_, {&entryP0x_, &entryP0y_, &entryP0z_, &entryEx_, &entryEy_, &entryEz_, &entryRadius_},
           {&leafP0x_, &leafP0y_, &leafP0z_, &leafEx_, &leafEy_, &leafEz_, &leafRadius_}, entryObject_);
  depth_ = out.depth;
  leafCount_ = out.leaves;
  hasCapsules_ = true;
  if (depth_ >= kMaxDepth)
    fail("parker: the outer objects' hierarchy is {} levels deep, more than {}", depth_ + 1, kMaxDepth);
}

void OuterObjects::attenuations(const Ray* rays, const float* distanceToLight, int count, OuterFalloff falloff,
                                OuterCombine combine, float* s, Seeds* seeds) const {
  TreeView view;
  view.nodes = nodes_.data();
  view.root = root_;
  view.empty = !hasCapsules_;
  view.entries = {entryP0x_.data(), entryP0y_.data(), entryP0z_.data(),   entryEx_.data(),
                  entryEy_.data(),  entryEz_.data(),  entryRadius_.data()};
  view.leafBounds = {leafP0x_.data(), leafP0y_.data(), leafP0z_.data(),   leafEx_.data(),
                     leafEy_.data(),  leafEz_.data(),  leafRadius_.data()};
  view.entryObject = entryObject_.data();
  view.directional = directional_;
  view.lightCenter = lightCenter_;
  view.diameter = diameter_;
  view.sceneMagnitude = sceneMagnitude_;
  if (combine == OuterCombine::Min) {
    // Seeds of other outer objects (or of ones rebuilt at this address) are dropped: an entry must
    // be one of these leaves'.
    Seeds none{this};
    Seeds& use = seeds ? *seeds : none;
    bool valid = use.owner == this && use.count >= 0 && use.count <= kGroup;
    for (int k = 0; valid && k < use.count; ++k)
      valid = use.entry[k] >= 0 && static_cast<size_t>(use.entry[k]) < entryP0x_.size();
    if (!valid) use = Seeds{this};
#if PENUMBRA_OUTER_AVX2
    if (avx512_) {
      minAttenuationsAvx512(view, rays, distanceToLight, count, falloff, s, use);
      return;
    }
    if (avx2_) {
      minAttenuationsAvx2(view, rays, distanceToLight, count, falloff, s, use);
      return;
    }
#endif
    minAttenuations(view, rays, distanceToLight, count, falloff, s, use);
    return;
  }
  std::vector<std::pair<int32_t, float>> found;
  for (int i = 0; i < count; ++i)
    s[i] = combinedAttenuation(view, rays[i], distanceToLight[i], falloff, combine, found);
}

void OuterObjects::limitLanes(int lanes) {
  avx512_ = avx512_ && lanes >= 16;
  avx2_ = avx2_ && lanes >= 8;
}

float OuterObjects::attenuation(const Vec3& origin, const Vec3& direction, float distanceToLight, OuterFalloff falloff,
                                OuterCombine combine) const {
  Ray ray;
  ray.origin = origin;
  ray.direction = direction;
  float s = 1.0f;
  attenuations(&ray, &distanceToLight, 1, falloff, combine, &s);
  return s;
}

}  // namespace penumbra::rt
