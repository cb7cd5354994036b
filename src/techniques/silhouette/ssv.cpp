// `ssv`: soft shadow volumes for convex polygonal lights with a double silhouette (Rouf 2007,
// "Real time soft shadow generation for arbitrary planar lights", Chapters 3 and 4). Software
// implementation, per camera pixel, of the two phases of Section 3.2.1. A concave polygon light is
// broken up into its fewest convex parts (Section 5.2.5), each run as a light of its own and V
// combined by area (convex_parts.h); everything below is about one convex light.
//
// Phase 1 (prepare): every facet of every occluder is classified against every light vertex as
// fully lit / partially lit / in shadow (Section 3.2.2); the penumbra silhouette (boundary of the
// fully lit facets) and the umbra silhouette (boundary of the facets in shadow) are split into
// rings (3.2.3.2) from the edge adjacency built once per mesh (src/techniques/silhouette/mesh_topology.cpp). Every
// silhouette edge gets the fixed part of its edge shadow: its direction, the edge projected from the
// light's centre and quantized to the nearest of the four axis directions of the light (3.2.3.1),
// and its box in the light-space binning grid.
//
// Phase 2 (visibility, per pixel p): the light is mapped to the unit "light square" (its bounding
// rectangle in light space; x along the polygon's first edge, so a rect light is the square
// itself). Each ring gives one visibility curve (3.2.4.3, Figs. 3-20, 3-21):
//  - an edge of the ring, projected from p, is replaced by its approximant: the line of the light
//    square perpendicular to the edge's quantized direction that leaves the edge shadow's visible
//    fraction t of the square visible. t is interpolated linearly between the front plane (t = 1)
//    and the back plane (t = 0), the planes through the edge that touch the light on either side,
//    found by walking the light's vertices (O(L), 3.2.3.3, 3.4.1; the linear shading assumption of
//    3.3);
//  - consecutive approximants are joined where they meet, which realizes the corner rules: at a
//    convex corner the hidden parts are AND-ed (visibilities OR-ed, 3.2.4.1, Fig. 3-7: two edges
//    each leaving 50 % leave 75 %), at a concave corner OR-ed, and at a straight corner (two equal
//    quantized directions, 3.2.3.6) the two are joined by a step at the projected shared vertex:
//    the cut line both edge shadows agree on;
//  - only the edges whose edge shadows contain p (their projection meets the light square) are
//    drawn as approximants, in chains of consecutive edges; the curve is closed through the
//    projections of the other edges, which lie outside the square and only say which side of the
//    chains is hidden. A point of the square is hidden by the ring when the curve winds around it;
//  - in a corner region (the projected edge ends inside the square) the approximant moves from the
//    ramp's position towards the position of the edge's part inside the square as that part
//    shrinks, so an edge shadow starts where its neighbour's chain left the square and V stays
//    continuous (the role of the corner colouring of 3.2.3.3-5).
// The rings that bound one facet set (one silhouette of one object; an object with a hole has two)
// are one curve: their windings add. Silhouettes compete (3.2.4.2, 3.2.4.4): a point is hidden
// when any of them hides it (visibilities AND-ed).
// The visible fraction is measured by slicing (3.2.4.4, Fig. 3-22): the square is cut at every
// distinct coordinate of the curves (two within `merge_tolerance`, 0.01 in the thesis, count as
// one, Section 4.2.6) and one point per cell is tested, weighted by its area; or by fixed 8x8 /
// 16x16 sampling (`integration`, Fig. 4-8). The points are tested row by row (each piece of a curve
// only on the rows it spans, its crossings by bisection), which gives what testing every piece at
// every point gives. The hard shadow (3.2.5): a ring none of whose edge
// shadows contains p (p behind all its back planes or in front of some front plane) hides the
// whole light when p lies in its shadow, tested in 2D by the angle sweep (winding) of p's
// direction from the light's centre around the ring's projection, which works for concave and
// self-intersecting rings alike (Fig. 3-23).
//
// Choices where the text leaves them open (kept so V stays continuous and exact where the
// thesis' assumptions hold: a rect light and occluder edges parallel to its sides):
//  - The corner areas of Sections 3.2.3.3-6 are not coloured and interpolated separately: joining
//    the approximants of consecutive edges gives the same values on their outlines (black inside
//    the neighbour at a convex corner, white at a concave one) and is exact in the case above.
//  - The umbra test is made only where no edge shadow of the ring contains p, where it is exact;
//    the polygon of intersected back lines is not used, because at a concave corner the umbra is
//    bounded by the corner's own shadow rather than by the meeting point of the two back lines,
//    and for a ring that is not planar the back lines' polygon can wind around points outside
//    the umbra. Elsewhere the curves decide (they give V = 0 where they enclose the square).
//  - Edges at reflex (concave) mesh edges stay in their ring's curve: leaving them out (end of
//    3.2.3.2) would open it.
//  - An object without fully lit facets (a large light close to it) has no penumbra silhouette in
//    the sense of 3.2.2, and its umbra silhouette alone would shrink its shadow to the facets in
//    shadow: the boundary of the facets facing the light's centre ("potentially fully lit", 3.2.2)
//    stands for it. An object without facets in shadow has one silhouette, as has one whose two
//    silhouettes coincide (a plate lit by the whole light).
//  - Rings are clipped as closed polygons to zNear <= z <= z_p (1 - 1e-4) (only occluder parts
//    nearer to the light than p can occlude it), closed along the cut. Where a silhouette's facet
//    set reaches beyond p (p on or beside its object), the closing segments project far outside
//    the light and could pass around it either way; which side of its curves is hidden is then
//    fixed by one ray from p to the light's centre (the offset rule of src/rt/shadow_ray.h; what
//    the hard shadow of a shadow-volume pass gives): the object hides the centre when the first
//    thing the ray meets is the object. The ray sees the object, not one of its silhouettes: the
//    object's outlines (penumbra and umbra silhouettes) are flipped only where together they
//    disagree with it; the straddled walls' silhouette below, and a cut outline with no edge shadow
//    on the light (it hides all of the light or none), follow it alone, except where they leave
//    the centre visible while another silhouette of the object hides it: there rays to points the
//    rest leaves visible decide (SsvTechnique::fixCutSides says why). Elsewhere no ray is
//    traced: the curves and the angle sweep agree with the projection to the last bit, a
//    ray would not.
//  - Receivers behind the light's plane are handled in the light space of its other face (planar
//    lights emit from both). An edge seen (nearly) end-on from the centre has no direction: its
//    curve piece is dropped and its neighbours meet at its projection.
//  - Binning: a light-space grid over directions from the light's centre (stages.h, which says why)
//    lists per cell the rings with an edge whose region of influence reaches a receiver of the
//    cell (bounded with the cell's deepest receiver) and the rings whose hard-shadow box overlaps
//    it; a pixel combines the rings listed in its cell, less those it finds beyond the reach of
//    every edge shadow of an uncut ring with its own direction and depth (beyondEdgeShadows).
//    Within a ring it passes over each chunk of eight edges it finds so (EdgeChunk, stages.h): one
//    edge to the next chunk stands for it, which winds the same around every point of the light
//    square; the slicing then has no cuts at the passed-over vertices, which lie outside the square.
//  - Occluders that are not closed 2-manifolds (our extension; Rouf Section 1.3 assumes simple,
//    hole-free solids): any mesh becomes a closed oriented surface (mesh_topology.h), solids where
//    a component is closed, doubled shells (each triangle and its reversed copy) elsewhere. The
//    rings and windings above need nothing more. One thing a shell changes: a shell triangle whose
//    plane the light straddles has both sides partially lit, both sides are in the umbra
//    silhouette's facet set, and their projections cancel (as a thin solid plate's two faces do in
//    Rouf's method, where the plate's rims carry its shadow): the walls of an open box or a cup,
//    which a large light straddles, would shadow nothing where they alone block the light. A
//    third silhouette, competing with the other two, bounds one side of each such triangle (the
//    side facing the light's centre); its winding counts the walls crossed.
//  - A two-sided planar sheet (an open planar mesh, e.g. the ground; mesh_topology.h) does not
//    shadow its own pixels.
//
// Approximations (Section 3.3), measured in tests/techniques/silhouette/ssv_test.cpp: linear shading across
// an edge shadow and quantized directions (exact for rect lights and axis-parallel edges; for
// tilted edges and other polygons the hidden parts are axis-parallel stand-ins whose area follows
// the ramp, and a thin light shows the artifacts of Fig. 4-9); only the two silhouettes are used, so the
// object looks like a prism between them and the hidden part is the union of the two rings'
// projections, not their hull. Option edge_visibility=area replaces the linear ramp by the exact
// fraction of the light past the edge's line (clipping the light polygon, O(L)).
//
// Parameters: integration ("slicing" | "8x8" | "16x16"), merge_tolerance (fraction of the light's
// side, [0, 0.25], default 0.01), grid (cells per side of the light-space binning grid, default 64),
// edge_visibility ("linear" | "area").
#include "penumbra/techniques/silhouette.h"
#include "techniques/silhouette/stages.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image_fill.h"
#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "rt/ray_scene.h"
#include "rt/shadow_ray.h"
#include "techniques/silhouette/convex_parts.h"

namespace penumbra {

namespace {

using namespace silhouette;

using Integration = SsvIntegration;  // include/penumbra/techniques/silhouette.h

constexpr int32_t kClosure = -1;     //!< a clipped ring's edge along the clipping plane (no silhouette edge)
constexpr int32_t kPassedOver = -2;  //!< a ring's edge that stands for a chunk of its edges (EdgeChunk)

// One silhouette edge and the fixed part of its edge shadow (light space).
struct Edge {
  Vec3 a, b;                //!< endpoints, light space (b is the next edge's a)
  Vec2 uA, uB;              //!< directions from the light's centre
  uint8_t axis = 0;         //!< quantized direction (3.2.3.1): the light-square axis (0: x, 1: y) nearest to its normal
  bool degenerate = false;  //!< seen end-on from the centre: no direction of its own
  bool inFront = true;      //!< some part lies in front of the light's plane
  uint32_t ring = 0;
};

struct Ring {
  uint32_t first = 0, count = 0;  //!< edges [first, first + count)
  uint32_t firstChunk = 0;        //!< chunks [firstChunk, firstChunk + ceil(count / kChunkEdges)) of Side::chunks
  bool umbra = false;
  bool sheet = false;
  bool crossesLightPlane = false;  //!< some vertex is not in front of the light
  int32_t objectId = 0;
  uint32_t group = 0;  //!< index into Side::groups
  Vec2 uLower{kInfinity},
      uUpper{-kInfinity};  //!< u-space box of the ring (its hard shadow from the centre lies inside)
  float zMin = kInfinity, zMax = 0.0f;
};

// The rings that bound one facet set (one silhouette of one object, e.g. the outline and the hole
// of a ring-shaped object): their windings add.
struct Group {
  int32_t objectId = 0;
  bool straddled = false;  //!< the straddled shell triangles' silhouette (walls crossed), not an outline
  bool sheet = false;
  bool crossesLightPlane = false;
  float zMin = kInfinity, zMax = 0.0f;
};

// A piece of a visibility curve in light-square coordinates, directed a -> b.
struct Piece {
  Vec2 a, b;
  uint32_t group;  //!< the ring's group
};

// One edge's approximant in a visibility curve: the line s[axis] = cut of the light square, and the
// projected edge it stands for.
struct Approximant {
  uint8_t axis;
  float cut;
  Vec2 start, end;   //!< the projected edge
  bool contributes;  //!< its edge shadow contains p: the projected edge meets the square
};

// One group's pieces at one pixel (Scratch::pieces[firstPiece, endPiece)) and what fixes its hidden
// side.
struct GroupRun {
  uint32_t group;
  int32_t objectId;
  size_t firstPiece, endPiece;
  int centreWinding;       //!< of its rings' projections around the light's centre
  bool cut;                //!< its facet set reaches beyond p or behind the light's plane
  bool undecided = false;  //!< fixCutSides' scratch: hides all of the light or none, the centre's ray cannot tell
};

// Per-thread buffers of the per-pixel pass.
struct Scratch {
  std::vector<GroupRun> runs;
  std::vector<size_t> undecided;  //!< runs whose hidden side the centre's ray cannot tell (fixCutSides)
  std::vector<Vec3> loop, tmp;
  std::vector<int32_t> loopEdge, tmpEdge;
  std::vector<Approximant> approximants;
  std::vector<Vec2> curve;
  std::vector<Piece> pieces;
  std::vector<uint32_t> rings;
  std::vector<float> xs, ys;
  // Integration: cell centres, pieces per row, per-row winding events and marks, the result.
  std::vector<float> cx, cy;
  std::vector<uint32_t> rowStart, rowFill, rowPieces;
  std::vector<std::pair<uint32_t, uint32_t>> pieceRows;  //!< the rows [first, second) each piece spans
  std::vector<std::pair<uint32_t, int>> events;
  std::vector<int> diff;
  std::vector<uint8_t> hidden;
  std::vector<float> sortedCuts;  //!< sortCuts' scratch
  std::vector<uint32_t> cutCounts;
};

// std::lower_bound of x in the sorted, non-empty v, without branches on the comparisons.
uint32_t firstNotBelow(const std::vector<float>& v, float x) {
  const float* base = v.data();
  size_t count = v.size();
  while (count > 1) {
    const size_t half = count / 2;
    base = base[half] < x ? base + half : base;
    count -= half;
  }
  return static_cast<uint32_t>(base - v.data()) + (*base < x ? 1u : 0u);
}

// Sorts cuts in [0, 1] into increasing order, the sequence std::sort gives, in O(n) for the spread-out
// cuts of a pixel's curves: a counting sort by bucket floor(c n) (monotone in c, so buckets keep
// the order), then an insertion sort, which moves each cut only within its bucket.
void sortCuts(std::vector<float>& cuts, std::vector<float>& sorted, std::vector<uint32_t>& counts) {
  const size_t n = cuts.size();
  const float scale = static_cast<float>(n);
  auto bucket = [&](float c) { return std::min(n - 1, static_cast<size_t>(c * scale)); };
  counts.assign(n + 1, 0);
  for (const float c : cuts) ++counts[bucket(c) + 1];
  for (size_t b = 1; b <= n; ++b) counts[b] += counts[b - 1];
  sorted.resize(n);
  for (const float c : cuts) sorted[counts[bucket(c)]++] = c;
  for (size_t i = 1; i < n; ++i) {
    const float c = sorted[i];
    size_t j = i;
    for (; j > 0 && sorted[j - 1] > c; --j) sorted[j] = sorted[j - 1];
    sorted[j] = c;
  }
  cuts.swap(sorted);
}

// Everything about one face of the light: its light space, silhouettes and edge shadows.
struct Side {
  LightPlane plane;
  Vec2 squareScale{1.0f};  //!< light plane (x, y) -> light square [0, 1]^2: (q - plane.lower) * squareScale
  std::vector<Edge> edges;
  std::vector<EdgeChunk> chunks;
  std::vector<Ring> rings;
  std::vector<Group> groups;
  UGrid edgeGrid;  //!< per cell: the rings with an edge whose region of influence reaches it
  UGrid ringGrid;  //!< per cell: the rings whose u-space box (hard shadow) overlaps it
  bool binned = false;
};

// What the per-pixel pass asks the ray tracer: the object that first meets the ray from the pixel
// to the light's centre (traced once if asked), and to a given point of the light.
template <typename Centre, typename Toward>
struct Blockers {
  Centre centre;
  Toward toward;
};
template <typename Centre, typename Toward>
Blockers(Centre, Toward) -> Blockers<Centre, Toward>;

class SsvTechnique final : public ShadowTechnique {
 public:
  // `occluders`: shared by the instances that run the parts of one concave light (convex_parts.h).
  SsvTechnique(const SsvOptions& options, std::shared_ptr<OccluderCache> occluders)
      : options_(options), occluderCache_(std::move(occluders)) {}
  std::string_view name() const override { return "ssv"; }

 private:
  void prepareImpl(const Scene& scene, const Light& light) override {
    prepared_ = false;
    const Bounds3 bounds = scene.bounds();
    sides_[0] = Side{};
    sides_[1] = Side{};
    sides_[0].plane = makeLightPlane(light, bounds, "ssv");
    sides_[1].plane = makeLightPlane(light, bounds, "ssv", true);
    occluders_ = &occluderCache_->get(scene);  // made again only when the geometry changed
    rays_ = nullptr;
    rays_ = &raysCache_.get(scene);  // built when the geometry changed, else kept
    light_ = light;
    epsilon_ = shadowRayEpsilon(bounds);
    zNear_ = 1e-4f * std::max(bounds.radius(), 1e-6f);
    facets_ = 0;
    for (const Occluder& o : *occluders_) facets_ += o.topology.surfaceTriangles;
    // The other face of the light is built when a receiver lies behind the light's plane.
    buildSide(sides_[0]);
    backBuilt_ = false;
    prepared_ = true;
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (!prepared_) fail("ssv: visibility() called before prepare(); call prepare(scene, light) first");
    const int width = gbuffer.width(), height = gbuffer.height();
    resetInParallel(v, width, height, 1.0f);
    if (!backBuilt_ && anyReceiverBehind(gbuffer, sides_[0].plane)) {
      buildSide(sides_[1]);
      backBuilt_ = true;
      endPass("back face silhouettes");
    }
    for (Side& side : sides_) bin(side, gbuffer);
    endPass("binning");
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
      Scratch scratch;
      for (int y = range.begin(); y < range.end(); ++y)
        for (int x = 0; x < width; ++x) {
          if (!gbuffer.hit(x, y)) continue;
          const Vec3 wsP = gbuffer.wsPosition(x, y);
          // Receivers behind the light's plane see its other face.
          const Vec3 front = sides_[0].plane.lsFromWs(wsP);
          const Side& side = sides_[front.z > 0.0f ? 0 : 1];
          const Vec3 p = front.z > 0.0f ? front : side.plane.lsFromWs(wsP);
          // The object that hides the light's centre from p (kNoObject: none), traced once if needed,
          // and the one that hides a given point of the light (world space).
          std::optional<int32_t> centreBlocker;
          Blockers blockers{[&]() {
                              if (!centreBlocker)
                                centreBlocker = silhouette::centreBlockerAt(*rays_, *light_, gbuffer, x, y, epsilon_);
                              return *centreBlocker;
                            },
                            [&](const Vec3& wsLightPoint) {
                              return silhouette::blockerToward(*rays_, *light_, gbuffer, x, y, wsLightPoint, epsilon_);
                            }};
          v(x, y) = visibilityAt(side, p, gbuffer.objectId(x, y), scratch, blockers);
        }
    });
  }

 public:
  std::vector<std::pair<std::string, double>> stats() const override {
    size_t umbraRings = 0, umbraEdges = 0;
    for (const Ring& r : sides_[0].rings) {
      umbraRings += r.umbra;
      umbraEdges += r.umbra ? r.count : 0;
    }
    return {{"facets", double(facets_)},
            {"silhouette_edges", double(sides_[0].edges.size())},
            {"penumbra_silhouette_edges", double(sides_[0].edges.size() - umbraEdges)},
            {"umbra_silhouette_edges", double(umbraEdges)},
            {"rings", double(sides_[0].rings.size())},
            {"umbra_rings", double(umbraRings)}};
  }

 private:
  void bin(Side& side, const GBuffer& gbuffer) const {
    side.binned = false;
    Vec2 lower, upper;
    if (side.rings.empty() || !receiverRange(gbuffer, side.plane, zNear_, lower, upper)) return;
    const std::vector<float> cellFar = receiverCellFar(gbuffer, side.plane, zNear_, lower, upper, options_.grid);
    std::vector<Vec2> lo, hi;
    std::vector<float> near;
    std::vector<uint32_t> ring;
    for (const Edge& e : side.edges) {
      if (!e.inFront) continue;
      lo.push_back(glm::min(e.uA, e.uB));
      hi.push_back(glm::max(e.uA, e.uB));
      near.push_back(side.plane.extent / std::max(std::min(e.a.z, e.b.z), zNear_));
      ring.push_back(e.ring);
    }
    // Each cell lists the rings (once, in order) with an edge whose region of influence reaches it.
    side.edgeGrid.buildInfluence(lower, upper, options_.grid, lo, hi, near, cellFar, ring);
    lo.clear();
    hi.clear();
    for (const Ring& r : side.rings) {
      lo.push_back(r.uLower);
      hi.push_back(r.uUpper);
    }
    side.ringGrid.build(lower, upper, options_.grid, lo, hi);
    side.binned = true;
  }

  void buildSide(Side& side) const {
    side.squareScale = Vec2(1.0f) / glm::max(side.plane.upper - side.plane.lower, Vec2(1e-30f));
    for (const Occluder& o : *occluders_) buildRings(side, o, toLightSpace(o, side.plane));
  }

  void buildRings(Side& side, const Occluder& o, const LightSpaceGeometry& ls) const {
    const MeshTopology& m = o.topology;
    const size_t n = m.triangles.size();
    // Section 3.2.2: fully lit (every light vertex in front of the facet's plane), in shadow (none
    // in front), partially lit otherwise. The penumbra silhouette bounds the fully lit facets, the
    // umbra silhouette the facets in shadow (= the boundary of those not in shadow).
    std::vector<uint8_t> lit(n), notShadow(n), facing(n);
    size_t litCount = 0, notShadowCount = 0;
    for (size_t t = 0; t < n; ++t) {
      const Vec3 p0 = ls.positions[m.triangles[t].x];
      int front = 0;
      for (const Vec2& l : side.plane.vertices) front += glm::dot(ls.normals[t], Vec3(l, 0.0f) - p0) > 0.0f;
      lit[t] = front == static_cast<int>(side.plane.vertices.size());
      notShadow[t] = front > 0;
      facing[t] = glm::dot(ls.normals[t], -p0) > 0.0f;
      litCount += lit[t];
      notShadowCount += notShadow[t];
    }
    // A side of an object with no fully lit facet (a large light close to it) has no penumbra
    // silhouette in the sense of Section 3.2.2, and the umbra silhouette alone would shrink its
    // shadow to the facets in shadow. The facets facing the light's centre, "potentially fully lit"
    // in the words of 3.2.2 (and the fully lit ones whenever the light is small), bound it instead.
    if (litCount == 0) lit = facing;
    const bool noUmbra = notShadowCount == n;
    if (lit == notShadow || noUmbra) {
      // One silhouette is both (e.g. a sheet, or a thin plate seen by the whole light), or there is
      // no facet in shadow (an object against the light): one set of rings.
      addRings(side, o, ls, silhouetteRings(m, boundaryEdges(m, lit)), true);
    } else {
      addRings(side, o, ls, silhouetteRings(m, boundaryEdges(m, lit)), false);
      addRings(side, o, ls, silhouetteRings(m, boundaryEdges(m, notShadow)), true);
    }
    // The straddled shell triangles' silhouette (header): one side of each, the one facing the
    // light's centre.
    std::vector<uint8_t> straddled(n, 0);
    bool anyStraddled = false;
    for (size_t i = 0; i < m.copyOf.size(); ++i) {
      const uint32_t front = m.copyOf[i], back = static_cast<uint32_t>(m.surfaceTriangles + i);
      if (!notShadow[front] || !notShadow[back]) continue;
      straddled[facing[back] && !facing[front] ? back : front] = 1;
      anyStraddled = true;
    }
    if (anyStraddled) addRings(side, o, ls, silhouetteRings(m, boundaryEdges(m, straddled)), true, true);
  }

  void addRings(Side& side, const Occluder& o, const LightSpaceGeometry& ls,
                const std::vector<std::vector<SilhouetteEdge>>& rings, bool umbra, bool straddled = false) const {
    auto uOf = [&](const Vec3& p) {
      const float z = std::max(p.z, zNear_);
      return Vec2(p.x / z, p.y / z);
    };
    const auto group = static_cast<uint32_t>(side.groups.size());
    Group g;
    g.objectId = o.objectId;
    g.sheet = o.sheet;
    g.straddled = straddled;
    for (const auto& ringEdges : rings) {
      Ring ring;
      ring.group = group;
      ring.first = static_cast<uint32_t>(side.edges.size());
      ring.count = static_cast<uint32_t>(ringEdges.size());
      ring.umbra = umbra;
      ring.sheet = o.sheet;
      ring.objectId = o.objectId;
      const auto ringId = static_cast<uint32_t>(side.rings.size());
      for (const SilhouetteEdge& s : ringEdges) {
        Edge e;
        e.a = ls.positions[s.a];
        e.b = ls.positions[s.b];
        e.ring = ringId;
        ring.crossesLightPlane = ring.crossesLightPlane || e.a.z < zNear_;
        Vec3 ca = e.a, cb = e.b;
        e.inFront = clipToSlab(ca, cb, zNear_, kInfinity);
        e.uA = uOf(e.a);
        e.uB = uOf(e.b);
        // Section 3.2.3.1: the direction of the edge shadow is the edge's projection from the
        // light's centre, quantized to the nearest multiple of 90 degrees (light-square axes): its
        // approximants cut the axis its normal is nearest to. (Which side it hides follows from
        // the curve it is part of.)
        const Vec2 d = e.uB - e.uA;
        e.axis = std::abs(d.y) >= std::abs(d.x) ? 0 : 1;
        ring.uLower = glm::min(ring.uLower, glm::min(e.uA, e.uB));
        ring.uUpper = glm::max(ring.uUpper, glm::max(e.uA, e.uB));
        ring.zMin = std::min({ring.zMin, e.a.z, e.b.z});
        ring.zMax = std::max({ring.zMax, e.a.z, e.b.z});
        side.edges.push_back(e);
      }
      // An edge seen (nearly) end-on from the centre, e.g. a vertical edge of a box under the
      // light, has no direction of its own: its curve piece is dropped and its neighbours meet
      // at its projection.
      const float uDiagonal = glm::length(ring.uUpper - ring.uLower);
      for (uint32_t i = 0; i < ring.count; ++i) {
        Edge& e = side.edges[ring.first + i];
        e.degenerate = !(glm::length(e.uB - e.uA) > 1e-3f * uDiagonal);
      }
      ring.firstChunk = static_cast<uint32_t>(side.chunks.size());
      for (uint32_t i = 0; i < ring.count; i += kChunkEdges) {
        EdgeChunk c;
        for (uint32_t j = i; j < std::min(i + kChunkEdges, ring.count); ++j) {
          const Edge& e = side.edges[ring.first + j];
          c.add(e.uA, e.a.z);
          c.add(e.uB, e.b.z);
        }
        side.chunks.push_back(c);
      }
      g.crossesLightPlane = g.crossesLightPlane || ring.crossesLightPlane;
      g.zMin = std::min(g.zMin, ring.zMin);
      g.zMax = std::max(g.zMax, ring.zMax);
      side.rings.push_back(ring);
    }
    if (!rings.empty()) side.groups.push_back(g);
  }

  // Signed crossing of edge a-b with the ray from q towards +x (winding number, Sunday 2001).
  static int crossing(const Vec2& a, const Vec2& b, const Vec2& q) {
    const float side = (b.x - a.x) * (q.y - a.y) - (q.x - a.x) * (b.y - a.y);
    if (a.y <= q.y) return (b.y > q.y && side > 0.0f) ? 1 : 0;
    return (b.y <= q.y && side < 0.0f) ? -1 : 0;
  }

  // The position of an edge shadow's approximant (Sections 3.2.3.1, 3.2.3.3): the projected edge
  // q0-q1 leaves the fraction t of the light visible, linear between the front plane (t = 1, the
  // line touches the light on its hidden side) and the back plane (t = 0); the approximant is the
  // line of the light square across `axis` that leaves the same fraction: s[axis] = t measured
  // from the side the edge's normal (taken towards +axis) points away from (which side is hidden
  // does not change the line: t and 1 - t measured from opposite sides).
  float approximantCut(const Side& side, const Vec2& q0, const Vec2& q1, uint8_t axis) const {
    const Vec2 d = q1 - q0;
    Vec2 m(-d.y, d.x);
    const float len = glm::length(m);
    if (!(len > 0.0f)) {
      // A point: the approximant passes through it.
      return (q0[axis] - side.plane.lower[axis]) * side.squareScale[axis];
    }
    m /= len;
    if (m[axis] < 0.0f) m = -m;
    float hLo, hHi;
    side.plane.support(m, hLo, hHi);
    const float offset = glm::dot(q0, m);
    if (options_.areaEdgeVisibility && offset > hLo && offset < hHi) return visibleBeyondLine(side.plane, m, offset);
    return (offset - hLo) / (hHi - hLo);
  }

  // Liang-Barsky: the part [t0, t1] of segment a-b inside the light square [0, 1]^2; false if none.
  static bool clipToSquare(const Vec2& a, const Vec2& b, float& t0, float& t1) {
    t0 = 0.0f;
    t1 = 1.0f;
    const Vec2 d = b - a;
    for (int k = 0; k < 2; ++k) {
      for (const float bound : {0.0f, 1.0f}) {
        const float num = bound == 0.0f ? a[k] : 1.0f - a[k];  // distance inside this side
        const float den = bound == 0.0f ? -d[k] : d[k];        // rate of leaving through it
        if (den == 0.0f) {
          if (num < 0.0f) return false;
        } else {
          const float t = num / den;
          if (den > 0.0f)
            t1 = std::min(t1, t);
          else
            t0 = std::max(t0, t);
        }
      }
    }
    return t0 <= t1;
  }

  // A loop around the light square adds `winding` to every winding inside it; only its right side
  // can cross a ray towards +x.
  static Piece loopPiece(int winding, uint32_t group) {
    return {Vec2(2.0f, winding > 0 ? -1.0f : 2.0f), Vec2(2.0f, winding > 0 ? 2.0f : -1.0f), group};
  }
  static void loopAround(Scratch& s, int winding, uint32_t group) {
    for (int i = 0; i < std::abs(winding); ++i) s.pieces.push_back(loopPiece(winding, group));
  }

  // Whether a run's pieces are only loops around the square: its winding is the same at every
  // point of the light.
  static bool onlyLoops(const Scratch& s, const GroupRun& run) {
    for (size_t k = run.firstPiece; k < run.endPiece; ++k)
      if (!(s.pieces[k].a.x == 2.0f && s.pieces[k].b.x == 2.0f)) return false;
    return true;
  }

  // The hidden side of the cut silhouettes of one object (runs [begin, end) of s.runs). A facet set
  // reaching beyond p (p on or beside its object) or behind the light's plane is cut there and
  // closed along the cut: the closing segments project far outside the light and could pass around
  // it either way, which adds or removes one winding everywhere on the square. Which side is hidden
  // is then fixed by whether the object hides the light's centre from p: one ray, what the hard
  // shadow of a shadow-volume pass gives. A silhouette that disagrees with it is flipped:
  //  - the straddled walls' silhouette (header), which counts walls rather than outlining the
  //    object, and a cut outline whose winding is the same over the whole square (only loops: no
  //    edge shadow contains p, so it hides all of the light or none) follow the ray where it sees
  //    the centre. Where the ray meets the object and they leave the centre visible, the ray tells
  //    nothing about them if another silhouette of the object hides the centre itself (p on the
  //    ground beside a box standing on it: the cut umbra silhouette, or a shell's straddled walls,
  //    leave the centre visible while the penumbra silhouette hides part of the light, the centre
  //    included). They are then flipped only if rays to points the rest leaves visible meet the
  //    object (visibilityAt, undecidedHide); otherwise they follow the ray. Following it there hid
  //    the whole light along the foot of every flat-based model fitted onto the ground;
  //  - the object's outlines (its penumbra and umbra silhouettes) are flipped only where together
  //    they disagree with the ray. The ray sees the object, not one outline: outlines compete, and
  //    in a penumbra on the object one may leave the centre visible (its curve cutting the square
  //    elsewhere) while the other hides it; flipping the first would hide nearly the whole light
  //    on single pixels. Where none hides the centre but the straddled walls' silhouette does (the
  //    walls of a box open at the top), the ray is explained and they are undecided as above.
  // Whether a silhouette hides the centre is its rings' projections' winding, not its curve's: an
  // approximant may pass the centre on the other side than its projected edge, in the penumbra.
  template <typename Blockers>
  static void fixCutSides(const Side& side, Scratch& s, size_t begin, size_t end, Blockers& blockers) {
    bool anyCut = false, anyOutline = false;
    for (size_t k = begin; k < end; ++k) {
      anyCut = anyCut || s.runs[k].cut;
      anyOutline = anyOutline || !side.groups[s.runs[k].group].straddled;
    }
    if (!anyCut) return;
    const bool hidesCentre = blockers.centre() == s.runs[begin].objectId;
    auto flip = [&](size_t k) { flipRun(s, k, hidesCentre); };
    auto disagrees = [&](size_t k) { return s.runs[k].cut && (s.runs[k].centreWinding != 0) != hidesCentre; };
    auto outline = [&](size_t k) { return anyOutline && !side.groups[s.runs[k].group].straddled; };
    // A cut outline with only loops, or the straddled walls' silhouette, that leaves the centre
    // visible where the ray meets the object waits until the rest is decided.
    for (size_t k = begin; k < end; ++k)
      s.runs[k].undecided = hidesCentre && disagrees(k) && (!outline(k) || onlyLoops(s, s.runs[k]));
    bool outlinesHide = false;
    for (size_t k = begin; k < end; ++k) {
      if (!s.runs[k].undecided && disagrees(k) && (!outline(k) || onlyLoops(s, s.runs[k]))) flip(k);
      if (outline(k)) outlinesHide = outlinesHide || s.runs[k].centreWinding != 0;
    }
    // Where another silhouette of the object hides the centre, the ray is explained and cannot tell
    // an undecided one's hidden side (p on the ground beside a box standing on it: the cut umbra
    // silhouette, or a shell's straddled walls, leave the centre visible while the penumbra
    // silhouette hides part of the light, the centre included; or the straddled walls of a box open
    // at the top hide the centre while its outlines leave it visible): rays to points the rest leaves
    // visible decide (visibilityAt, undecidedHide). Where none does, it follows the ray.
    auto othersHide = [&]() {
      for (size_t k = begin; k < end; ++k)
        if (!s.runs[k].undecided && s.runs[k].centreWinding != 0) return true;
      return false;
    };
    if (outlinesHide != hidesCentre) {
      // No outline hides the centre the ray sees hidden: they are flipped together, unless the
      // straddled walls hide it, which leaves them undecided.
      const bool othersExplain = hidesCentre && othersHide();
      for (size_t k = begin; k < end; ++k)
        if (outline(k) && disagrees(k)) {
          if (othersExplain) {
            s.runs[k].undecided = true;
          } else {
            flip(k);
            s.runs[k].undecided = false;
          }
        }
    }
    const bool explained = othersHide();
    for (size_t k = begin; k < end; ++k) {
      if (!s.runs[k].undecided) continue;
      if (explained)
        s.undecided.push_back(k);
      else
        flip(k);
    }
  }

  // Flips run k's hidden side: a loop around the square, right after the run's pieces (a group's
  // pieces stay consecutive for hiddenCells), moving those of the runs after it.
  static void flipRun(Scratch& s, size_t k, bool hidesCentre) {
    GroupRun& run = s.runs[k];
    const int loop = hidesCentre ? 1 : -run.centreWinding;
    const size_t count = static_cast<size_t>(std::abs(loop));
    s.pieces.insert(s.pieces.begin() + static_cast<std::ptrdiff_t>(run.endPiece), count, loopPiece(loop, run.group));
    for (size_t later = k; later < s.runs.size(); ++later) {
      if (later > k) s.runs[later].firstPiece += count;
      s.runs[later].endPiece += count;
    }
    run.centreWinding = hidesCentre ? 1 : 0;
  }

  // Ring r as a closed polygon clipped to zNear <= z <= zMax in s.loop (Sutherland-Hodgman against
  // both depth bounds; each vertex keeps in s.loopEdge the edge that leaves it, kClosure along a
  // cut); whether it was cut. In a ring that is not cut, a chunk of edges beyond every edge shadow
  // of p is one edge to the next chunk (kPassedOver; EdgeChunk, stages.h, says why the curve stays the same).
  bool clipRing(const Side& side, const Ring& r, const Vec3& p, float zMax, Scratch& s) const {
    s.loop.clear();
    s.loopEdge.clear();
    const bool uncut = !r.crossesLightPlane && r.zMax <= zMax;
    const Vec2 u(p.x / p.z, p.y / p.z);
    for (uint32_t i = 0, k = r.firstChunk; i < r.count; i += kChunkEdges, ++k) {
      if (uncut && side.chunks[k].beyond(side.plane, u, p.z)) {
        s.loop.push_back(side.edges[r.first + i].a);
        s.loopEdge.push_back(kPassedOver);
        continue;
      }
      for (uint32_t j = i; j < std::min(i + kChunkEdges, r.count); ++j) {
        s.loop.push_back(side.edges[r.first + j].a);
        s.loopEdge.push_back(static_cast<int32_t>(r.first + j));
      }
    }
    bool cut = false;
    for (const float bound : {zNear_, zMax}) {
      const bool low = bound == zNear_;
      // Whether every vertex lies within the bound, from the ring's own depths: the first clip keeps
      // the deepest vertex (deeper than zMax > zNear) and adds points at zNear only.
      const bool allIn = low ? !r.crossesLightPlane : r.zMax <= bound;
      if (allIn) continue;
      cut = true;
      s.tmp.clear();
      s.tmpEdge.clear();
      const size_t n = s.loop.size();
      for (size_t i = 0; i < n; ++i) {
        const Vec3 &a = s.loop[i], &b = s.loop[i + 1 < n ? i + 1 : 0];
        const bool inA = low ? a.z >= bound : a.z <= bound, inB = low ? b.z >= bound : b.z <= bound;
        if (inA) {
          s.tmp.push_back(a);
          s.tmpEdge.push_back(s.loopEdge[i]);
        }
        if (inA != inB) {
          const Vec3 c = a + (b - a) * ((bound - a.z) / (b.z - a.z));
          s.tmp.push_back(Vec3(c.x, c.y, bound));
          s.tmpEdge.push_back(inA ? kClosure : s.loopEdge[i]);
        }
      }
      s.loop.swap(s.tmp);
      s.loopEdge.swap(s.tmpEdge);
    }
    return cut;
  }

  // The clipped ring's edges (s.loop) projected from p onto the light square, each as its
  // approximant in s.approximants (a degenerate edge has none); whether some edge shadow contains p.
  bool makeApproximants(const Side& side, const Vec3& p, Scratch& s) const {
    const size_t n = s.loop.size();
    auto toSquare = [&](const Vec3& q) { return (projectFrom(p, q) - side.plane.lower) * side.squareScale; };
    s.approximants.clear();
    bool anyContribution = false;
    const Vec2 first = toSquare(s.loop[0]);
    Vec2 a = first;
    for (size_t i = 0; i < n; ++i) {
      const Vec2 b = i + 1 < n ? toSquare(s.loop[i + 1]) : first;
      const int32_t id = s.loopEdge[i];
      if (id == kClosure || id == kPassedOver) {
        // Along the clipping plane (its points are at p's depth and project far outside the
        // light), or standing for a chunk that projects outside it: it never contributes, it only
        // separates chains.
        s.approximants.push_back({0, 0.0f, a, b, false});
      } else if (!side.edges[id].degenerate) {
        const Edge& e = side.edges[id];
        float t0, t1;
        const bool contributes = clipToSquare(a, b, t0, t1);
        anyContribution = anyContribution || contributes;
        float cut = 0.0f;  // only a contributing edge is drawn as its approximant
        if (contributes) {
          // The cut from the light-plane points (the square is an axis-wise affine image of the
          // light plane, so the ramp measured in either is the same).
          const Vec2 qa = side.plane.lower + a / side.squareScale, qb = side.plane.lower + b / side.squareScale;
          cut = approximantCut(side, qa, qb, e.axis);
          // Corner regions (3.2.3.3-5): where the projected edge ends inside the square it covers
          // only the fraction w of the square along its approximant, and the cut moves from the
          // ramp's value (mid region, w = 1) to the position of the edge's part inside the square
          // (w -> 0). So an edge whose end enters the square starts on the square's edge, where
          // its neighbour's chain left it, and V stays continuous as edge shadows begin and end.
          const Vec2 p0 = a + (b - a) * t0, p1 = a + (b - a) * t1;
          const float w = std::min(std::abs(p1[1 - e.axis] - p0[1 - e.axis]), 1.0f);
          cut = w * std::clamp(cut, 0.0f, 1.0f) + (1.0f - w) * 0.5f * (p0[e.axis] + p1[e.axis]);
        }
        s.approximants.push_back({e.axis, cut, a, b, contributes});
      }
      a = b;
    }
    return anyContribution;
  }

  // The curve of s.approximants (some contributing) in s.curve: every contributing edge as its
  // approximant, joined to the next one, and the others as their projected edges.
  static void traceCurve(Scratch& s) {
    const size_t k = s.approximants.size();
    // The join of approximant e with the next one, f.
    auto join = [&](const Approximant& e, const Approximant& f) {
      Vec2 w;
      if (e.axis != f.axis) {
        w[e.axis] = e.cut;
        w[f.axis] = f.cut;
        s.curve.push_back(w);
      } else {
        const int other = 1 - e.axis;
        w[other] = f.start[other];
        w[e.axis] = e.cut;
        s.curve.push_back(w);
        w[e.axis] = f.cut;
        s.curve.push_back(w);
      }
    };
    size_t gap = k;
    for (size_t i = 0; i < k; ++i)
      if (!s.approximants[i].contributes) {
        gap = i;
        break;
      }
    s.curve.clear();
    if (gap == k) {
      // Every edge shadow contains p: one closed curve of approximants.
      for (size_t i = 0; i < k; ++i) join(s.approximants[i], s.approximants[i + 1 < k ? i + 1 : 0]);
    } else {
      // Once around the ring from a gap: the projected edges outside the square as they are, each
      // chain of contributing edges as its approximants, entered and left on the approximant at
      // the position (along it) of the projected edge's outer end, clamped to the square.
      for (size_t step = 1, i = gap; step <= k; ++step) {
        i = i + 1 < k ? i + 1 : 0;  // (gap + step) mod k
        const Approximant& e = s.approximants[i];
        if (!e.contributes) {
          s.curve.push_back(e.start);
          s.curve.push_back(e.end);
          continue;
        }
        const int other = 1 - e.axis;
        if (!s.approximants[i > 0 ? i - 1 : k - 1].contributes) {
          s.curve.push_back(e.start);
          Vec2 entry;
          entry[e.axis] = e.cut;
          entry[other] = std::clamp(e.start[other], 0.0f, 1.0f);
          s.curve.push_back(entry);
        }
        const Approximant& next = s.approximants[i + 1 < k ? i + 1 : 0];
        if (next.contributes) {
          join(e, next);
        } else {
          Vec2 exit;
          exit[e.axis] = e.cut;
          exit[other] = std::clamp(e.end[other], 0.0f, 1.0f);
          s.curve.push_back(exit);
          s.curve.push_back(e.end);
        }
      }
    }
  }

  // The visibility curve of ring r at p (Sections 3.2.4.1-3), appended to s.pieces; returns the
  // winding of the ring's projection around the light's centre.
  //
  // The ring is clipped to the depths that can lie between p and the light (zNear <= z <=
  // z_p (1 - 1e-4), closed along the cut) and projected from p onto the light square. The edges
  // whose edge shadows contain p (their projection meets the square) form chains of consecutive
  // edges, and in a chain every edge is replaced by its approximant, an axis-parallel line
  // (approximantCut); consecutive approximants are joined where they meet: perpendicular ones at
  // their crossing, which makes the corner's hidden part the AND of the two at a convex corner and
  // the OR at a concave one (3.2.3.4-5, Fig. 3-7), parallel ones (a straight corner, 3.2.3.6) by a
  // step at the projected shared vertex, the cut line both edge shadows agree on. A chain is
  // entered and left on its first and last approximants at the position of the projected edges'
  // outer ends, clamped to the square, and the curve is closed through the projections of the
  // edges whose edge shadows do not contain p: they lie outside the square and only say which side
  // of the chains is hidden, whichever way the ring is seen from p. A ring none of whose edge
  // shadows contain p hides all of the light or none of it (3.2.5): beyond the ring, as p's
  // direction from the light's centre lies inside the ring or not (an angle sweep).
  int appendCurve(const Side& side, uint32_t ringId, const Vec3& p, Scratch& s) const {
    const Ring& r = side.rings[ringId];
    const float zMax = p.z * (1.0f - 1e-4f);
    const bool cut = clipRing(side, r, p, zMax, s);
    // Also a loop of passed-over chunks left with fewer vertices: it winds around no point of the square.
    if (s.loop.size() < 3) return 0;
    const bool anyContribution = makeApproximants(side, p, s);
    // A ring cut at p's depth (p on or beside its object) or at the light's plane is closed along
    // the cut, and that closing segment, projected from p, runs far outside the light and could
    // pass around it either way: the ring's hidden side is then fixed by whether its object hides
    // the light's centre from p (one ray, what a shadow-volume pass gives).
    // The winding of the ring's projection around the light's centre.
    int centreWinding = 0;
    if (cut || anyContribution) {
      const Vec2 centre = -side.plane.lower * side.squareScale;
      for (const Approximant& e : s.approximants) centreWinding += crossing(e.start, e.end, centre);
    }
    if (!anyContribution) {
      // No edge shadow contains p: the ring hides all of the light or none of it, as it hides the
      // centre or not. Beyond an uncut ring that is the umbra test (3.2.5): the angle sweep of p's
      // direction from the centre around the ring.
      if (!cut) {
        const Vec2 u(p.x / p.z, p.y / p.z);
        if (u.x < r.uLower.x || u.y < r.uLower.y || u.x > r.uUpper.x || u.y > r.uUpper.y) return 0;
        for (uint32_t i = 0; i < r.count; ++i) {
          const Edge& e = side.edges[r.first + i];
          centreWinding += crossing(e.uA, e.uB, u);
        }
      }
      loopAround(s, centreWinding, r.group);
      return centreWinding;
    }
    traceCurve(s);
    // The pieces that can cross a ray from a point of the square towards +x.
    const size_t c = s.curve.size();
    for (size_t i = 0; i < c; ++i) {
      const Vec2 &u = s.curve[i], &v = s.curve[i + 1 < c ? i + 1 : 0];
      if (u.y == v.y || std::max(u.x, v.x) <= 0.0f || std::max(u.y, v.y) <= 0.0f || std::min(u.y, v.y) >= 1.0f)
        continue;
      s.pieces.push_back({u, v, r.group});
    }
    return centreWinding;
  }

  // s.hidden[iy * nx + ix]: whether the point (cx[ix], cy[iy]) of the light square is hidden, i.e.
  // some group's pieces (runs of equal group in s.pieces) wind around it, exactly as summing
  // crossing() over every piece would say. Row by row: a piece crosses the ray from (x, cy)
  // towards +x only on the rows within its y-range, and there for a prefix of the columns
  // (crossing()'s side test, in float, is monotone in x), found by bisection. O(pieces x rows
  // spanned x log columns + rows x columns) instead of O(pieces x rows x columns).
  static void hiddenCells(Scratch& s) {
    const size_t nx = s.cx.size(), ny = s.cy.size();
    s.hidden.assign(nx * ny, 0);
    // Pieces per row, in piece order (counting sort): rows with min(a.y, b.y) <= cy < max(a.y, b.y).
    s.rowStart.assign(ny + 1, 0);
    s.pieceRows.resize(s.pieces.size());
    for (size_t i = 0; i < s.pieces.size(); ++i) {
      const Piece& piece = s.pieces[i];
      const float lo = std::min(piece.a.y, piece.b.y), hi = std::max(piece.a.y, piece.b.y);
      const uint32_t r0 = firstNotBelow(s.cy, lo), r1 = firstNotBelow(s.cy, hi);
      s.pieceRows[i] = {r0, r1};
      for (uint32_t r = r0; r < r1; ++r) ++s.rowStart[r + 1];
    }
    for (size_t r = 1; r <= ny; ++r) s.rowStart[r] += s.rowStart[r - 1];
    s.rowPieces.resize(s.rowStart[ny]);
    s.rowFill.assign(s.rowStart.begin(), s.rowStart.end() - 1);
    for (uint32_t i = 0; i < s.pieces.size(); ++i)
      for (uint32_t r = s.pieceRows[i].first; r < s.pieceRows[i].second; ++r) s.rowPieces[s.rowFill[r]++] = i;
    s.diff.resize(nx + 1);
    for (size_t iy = 0; iy < ny; ++iy) {
      const float y = s.cy[iy];
      std::fill(s.diff.begin(), s.diff.end(), 0);
      auto flush = [&]() {
        // The group's winding is constant between consecutive prefix ends: mark where it is not 0.
        std::sort(s.events.begin(), s.events.end());
        int winding = 0;
        for (const auto& e : s.events) winding += e.second;
        size_t column = 0;
        for (size_t i = 0; i < s.events.size();) {
          const uint32_t end = s.events[i].first;
          if (winding != 0 && end > column) {
            ++s.diff[column];
            --s.diff[end];
          }
          for (; i < s.events.size() && s.events[i].first == end; ++i) winding -= s.events[i].second;
          column = end;
        }
        s.events.clear();
      };
      uint32_t group = 0;
      bool any = false;
      for (size_t k = s.rowStart[iy]; k < s.rowStart[iy + 1]; ++k) {
        const Piece& piece = s.pieces[s.rowPieces[k]];
        if (any && piece.group != group) flush();
        group = piece.group;
        any = true;
        auto crosses = [&](size_t column) { return crossing(piece.a, piece.b, Vec2(s.cx[column], y)) != 0; };
        // A piece right of every column (a projected edge beyond the square's right side) is crossed by
        // every column's ray when it is by the last one's (the crossed columns are a prefix).
        if (std::min(piece.a.x, piece.b.x) > s.cx[nx - 1] && crosses(nx - 1)) {
          s.events.push_back({static_cast<uint32_t>(nx), piece.a.y <= y ? 1 : -1});
        } else if (crosses(0)) {
          // Bisection for the first column whose point the piece does not cross, in [1, nx]
          // (branch-free: which half holds it is a coin toss for the branch predictor).
          size_t base = 1, count = nx - 1;
          if (count > 0) {
            while (count > 1) {
              const size_t half = count / 2;
              base = crosses(base + half - 1) ? base + half : base;
              count -= half;
            }
            base += crosses(base) ? 1 : 0;
          }
          s.events.push_back({static_cast<uint32_t>(base), piece.a.y <= y ? 1 : -1});
        }
      }
      if (any) flush();
      int open = 0;
      for (size_t ix = 0; ix < nx; ++ix) {
        open += s.diff[ix];
        s.hidden[iy * nx + ix] = open > 0;
      }
    }
  }

  template <typename Blockers>
  float visibilityAt(const Side& side, const Vec3& p, int32_t objectId, Scratch& s, Blockers& blockers) const {
    if (!side.binned || !(p.z > zNear_)) return 1.0f;
    const Vec2 u(p.x / p.z, p.y / p.z);
    // The rings to combine: those with an edge shadow that may contain p (the edge grid), and
    // those whose hard shadow may (the ring grid; their edge shadows may all miss p while the ring
    // hides the whole light).
    s.rings.clear();
    {
      // Both cells list ring ids in increasing order: merged, each ring once, in order (the rings
      // of a group are consecutive).
      const auto [begin, end] = side.edgeGrid.cell(u);
      const auto [rBegin, rEnd] = side.ringGrid.cell(u);
      const uint32_t* e = begin;
      for (const uint32_t* it = rBegin; it != rEnd; ++it) {
        const Ring& r = side.rings[*it];
        if (!(u.x >= r.uLower.x && u.y >= r.uLower.y && u.x <= r.uUpper.x && u.y <= r.uUpper.y)) continue;
        for (; e != end && *e < *it; ++e) s.rings.push_back(*e);
        if (e != end && *e == *it) ++e;
        s.rings.push_back(*it);
      }
      for (; e != end; ++e) s.rings.push_back(*e);
    }
    if (s.rings.empty()) return 1.0f;
    s.pieces.clear();
    const float zMax = p.z * (1.0f - 1e-4f);
    s.runs.clear();
    s.undecided.clear();
    for (size_t i = 0; i < s.rings.size();) {
      // The rings of one group bound one facet set: their windings add.
      const uint32_t group = side.rings[s.rings[i]].group;
      const Group& g = side.groups[group];
      const size_t firstPiece = s.pieces.size();
      int centreWinding = 0;
      for (; i < s.rings.size() && side.rings[s.rings[i]].group == group; ++i) {
        const Ring& r = side.rings[s.rings[i]];
        if ((r.sheet && r.objectId == objectId) || !(r.zMin < p.z)) continue;
        // An uncut ring none of whose edge shadows can contain p, with p's direction outside its
        // box, adds nothing (appendCurve's umbra test would give 0).
        if (!r.crossesLightPlane && r.zMax <= zMax && beyondEdgeShadows(side.plane, r.uLower, r.uUpper, r.zMin, u, p.z))
          continue;
        centreWinding += appendCurve(side, s.rings[i], p, s);
      }
      if (g.sheet && g.objectId == objectId) continue;
      const bool cut = (g.zMax > zMax || g.crossesLightPlane) && g.zMin < p.z;
      s.runs.push_back({group, g.objectId, firstPiece, s.pieces.size(), centreWinding, cut});
    }
    // Per object (its groups are consecutive).
    for (size_t begin = 0; begin < s.runs.size();) {
      size_t end = begin + 1;
      while (end < s.runs.size() && s.runs[end].objectId == s.runs[begin].objectId) ++end;
      fixCutSides(side, s, begin, end, blockers);
      begin = end;
    }
    const float v = visibleFraction(s);
    if (v > 0.0f && !s.undecided.empty() && undecidedHide(side, s, blockers)) {
      for (const size_t k : s.undecided) flipRun(s, k, true);
      return visibleFraction(s);
    }
    return v;
  }

  // The visible fraction of the light square under s.runs' pieces; s.hidden, s.cx and s.cy say
  // which cells are hidden (none when no piece meets the square).
  float visibleFraction(Scratch& s) const {
    s.hidden.clear();
    // A silhouette none of whose edge shadows contains p and that winds around the square hides
    // all of the light (the umbra): nothing else can change V.
    for (const GroupRun& run : s.runs)
      if (run.centreWinding != 0 && run.endPiece > run.firstPiece && onlyLoops(s, run)) return 0.0f;
    if (s.pieces.empty()) return 1.0f;
    // Competitive combination (3.2.4.2, 3.2.4.4): a point of the light square is hidden when any
    // ring's curve winds around it (the visibilities AND-ed).
    double visible = 0.0;
    if (options_.integration == Integration::Slicing) {
      // Slicing (3.2.4.4, Fig. 3-22): the light square cut at every distinct coordinate of the
      // curves, one test per cell, weighted by its area.
      s.xs.assign({0.0f, 1.0f});
      s.ys.assign({0.0f, 1.0f});
      auto addCuts = [&](const Vec2& q) {
        if (q.x > 0.0f && q.x < 1.0f) s.xs.push_back(q.x);
        if (q.y > 0.0f && q.y < 1.0f) s.ys.push_back(q.y);
      };
      // A piece's end that the next piece starts from is that piece's (an equal cut merges away).
      for (size_t k = 0; k < s.pieces.size(); ++k) {
        addCuts(s.pieces[k].a);
        if (k + 1 == s.pieces.size() || s.pieces[k + 1].a != s.pieces[k].b) addCuts(s.pieces[k].b);
      }
      const float tolerance = options_.mergeTolerance;
      auto merge = [tolerance, &s](std::vector<float>& cuts) {
        sortCuts(cuts, s.sortedCuts, s.cutCounts);
        size_t n = 1;
        for (size_t i = 1; i < cuts.size(); ++i)
          if (cuts[i] - cuts[n - 1] > tolerance) cuts[n++] = cuts[i];
        cuts.resize(n);
        if (cuts.back() < 1.0f) {
          if (n > 1 && 1.0f - cuts.back() <= tolerance)
            cuts.back() = 1.0f;
          else
            cuts.push_back(1.0f);
        }
      };
      merge(s.xs);
      merge(s.ys);
      s.cx.resize(s.xs.size() - 1);
      s.cy.resize(s.ys.size() - 1);
      for (size_t ix = 0; ix < s.cx.size(); ++ix) s.cx[ix] = 0.5f * (s.xs[ix] + s.xs[ix + 1]);
      for (size_t iy = 0; iy < s.cy.size(); ++iy) s.cy[iy] = 0.5f * (s.ys[iy] + s.ys[iy + 1]);
      hiddenCells(s);
      for (size_t iy = 0; iy < s.cy.size(); ++iy)
        for (size_t ix = 0; ix < s.cx.size(); ++ix) {
          const float w = (s.xs[ix + 1] - s.xs[ix]) * (s.ys[iy + 1] - s.ys[iy]);
          if (w > 0.0f && !s.hidden[iy * s.cx.size() + ix]) visible += w;
        }
    } else {
      const int n = options_.integration == Integration::Fixed8 ? 8 : 16;
      s.cx.resize(size_t(n));
      for (int i = 0; i < n; ++i) s.cx[size_t(i)] = (static_cast<float>(i) + 0.5f) / static_cast<float>(n);
      s.cy = s.cx;
      hiddenCells(s);
      int count = 0;
      for (const uint8_t h : s.hidden) count += !h;
      visible = double(count) / (n * n);
    }
    return std::clamp(static_cast<float>(visible), 0.0f, 1.0f);
  }

  // Whether the undecided runs of fixCutSides are to be flipped: whether their objects hide from p
  // the visible cells (s.hidden) farthest along each axis of the light square, one ray each, as
  // they would hide them flipped. One blocked point alone is not enough: near the curves the rest's
  // approximants may be off by a little (a corner of a box whose face the rest does not outline).
  template <typename Blockers>
  static bool undecidedHide(const Side& side, const Scratch& s, Blockers& blockers) {
    const size_t nx = s.cx.size();
    if (s.hidden.empty() || nx == 0) return false;
    size_t extreme[4] = {SIZE_MAX, SIZE_MAX, SIZE_MAX, SIZE_MAX};  // least and greatest x, least and greatest y
    for (size_t i = 0; i < s.hidden.size(); ++i) {
      if (s.hidden[i]) continue;
      const size_t ix = i % nx, iy = i / nx;
      if (extreme[0] == SIZE_MAX || ix < extreme[0] % nx) extreme[0] = i;
      if (extreme[1] == SIZE_MAX || ix > extreme[1] % nx) extreme[1] = i;
      if (extreme[2] == SIZE_MAX || iy < extreme[2] / nx) extreme[2] = i;
      if (extreme[3] == SIZE_MAX || iy > extreme[3] / nx) extreme[3] = i;
    }
    for (int k = 0; k < 4; ++k) {
      const size_t i = extreme[k];
      if (i == SIZE_MAX) return false;
      if (std::find(extreme, extreme + k, i) != extreme + k) continue;  // tested already
      const Vec2 q = side.plane.lower + Vec2(s.cx[i % nx], s.cy[i / nx]) / side.squareScale;
      const int32_t hit = blockers.toward(side.plane.wsOrigin + side.plane.lsFrame.fromLocal(Vec3(q, 0.0f)));
      const bool byUndecided =
          std::any_of(s.undecided.begin(), s.undecided.end(), [&](size_t run) { return s.runs[run].objectId == hit; });
      if (!byUndecided) return false;
    }
    return true;
  }

  // The fraction of the light's area on the visible side of the line dot(x, m) = offset (the exact
  // visibility past one infinite edge), by clipping the polygon: O(L).
  static float visibleBeyondLine(const LightPlane& plane, const Vec2& m, float offset) {
    std::array<Vec2, kMaxLightVertices + 2> clipped;
    const int n =
        clipHalfPlane(plane.vertices.data(), static_cast<int>(plane.vertices.size()), clipped.data(), m, offset);
    float twice = 0.0f;
    for (int i = 0; i < n; ++i) {
      const Vec2 &a = clipped[i], &b = clipped[(i + 1) % n];
      twice += a.x * b.y - a.y * b.x;
    }
    return std::clamp(0.5f * twice / plane.area, 0.0f, 1.0f);
  }

  SsvOptions options_;
  std::shared_ptr<OccluderCache> occluderCache_;
  const std::vector<Occluder>* occluders_ = nullptr;  //!< occluderCache_'s
  bool backBuilt_ = false;
  RaySceneCache raysCache_;
  const RayScene* rays_ = nullptr;  //!< the light's centre seen from receivers beside an occluder
  std::optional<Light> light_;
  float epsilon_ = 0.0f;
  Side sides_[2];  //!< [0]: the face towards the scene's centre; [1]: the other face
  float zNear_ = 0.0f;
  size_t facets_ = 0;
  bool prepared_ = false;
};

}  // namespace

std::unique_ptr<ShadowTechnique> makeTechnique(const SsvOptions& o) {
  validateOptions("ssv", o);

  // A concave light runs as its convex parts, V combined by area (Section 5.2.5; convex_parts.h).
  return overConvexParts("ssv", [o, occluders = std::make_shared<OccluderCache>()] {
    return std::make_unique<SsvTechnique>(o, occluders);
  });
}

TechniqueInfo ssvTechniqueInfo() {
  TechniqueInfo info;
  info.name = "ssv";
  info.summary =
      "soft shadow volumes with a double (penumbra + umbra) silhouette, for polygonal lights (a concave one in its "
      "fewest convex parts)";
  info.source = "Rouf 2007, Soft shadows for arbitrary planar lights, Chapters 3-4";
  info.tracesRays = true;
  info.setOptions<SsvOptions>([](const SsvOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
