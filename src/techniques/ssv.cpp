// `ssv`: soft shadow volumes for convex polygonal lights with a double silhouette (Rouf 2007,
// "Real time soft shadow generation for arbitrary planar lights", Chapters 3 and 4). Software
// implementation, per camera pixel, of the two phases of Section 3.2.1:
//
// Phase 1 (prepare): every facet of every occluder is classified against every light vertex as
// fully lit / partially lit / in shadow (Section 3.2.2); the penumbra silhouette (boundary of the
// fully lit facets) and the umbra silhouette (boundary of the facets in shadow) are split into
// rings (3.2.3.2) from the edge adjacency built once per mesh (src/core/mesh_topology.cpp). For
// every silhouette edge its edge shadow is set up: the direction of the edge shadow, seen from the
// light's centre and quantized to the nearest of the four axis directions of the light (3.2.3.1),
// the corner type at both ends (convex / concave; a straight corner, two equal quantized
// directions, takes the type of the true bend; 3.2.3.4-6) and the edge's box in the light-space
// binning grid (ssv.h). Edges at reflex (concave) mesh edges are kept in their ring for the umbra
// test but give no edge-shadow contribution (end of 3.2.3.2).
//
// Phase 2 (visibility, per pixel p):
//  - Edge shadow: the edge is projected from p onto the light's plane. The front plane is where
//    the projected line touches the light on its visible side (all of the light visible past the
//    edge), the back plane where it touches it on the hidden side; between them the visible
//    fraction t is interpolated linearly in the line's offset across the light (the linear shading
//    assumption of 3.3). Front and back planes are found by walking the light's vertices (O(L),
//    3.4.1). The mid region is where the projected segment spans the whole light along its own
//    direction; in the corner regions (an end of the segment projects inside the light's extent)
//    t is blended linearly, across the corner, towards the value that makes the edge neutral for
//    its neighbour: 0 ("black") at a convex corner, where neighbours are AND-ed, and 1 ("white")
//    at a concave corner, where they are OR-ed (our reading of the outline colouring of 3.2.3.4-5;
//    the figures are missing). This keeps V continuous where an edge shadow ends.
//  - Each contribution is a half-plane of the light mapped to the unit square: the hidden part is
//    the side of a line perpendicular to the edge shadow's quantized direction, at the fraction t
//    (the "rectangular shape intersection problem" of 3.2.3.1; exact for a rect light and edges
//    parallel to its sides, approximate otherwise — the thin-light artifact of Fig. 4-9 comes from
//    here and is not hidden).
//  - Collaborative combination within a ring (3.2.4.1, 3.2.4.3): the contributing edges, in ring
//    order, are folded into the ring's visibility curve: the next edge is AND-ed (its hidden part
//    intersected) when it lies on the hidden side of the previous one (a convex turn), OR-ed
//    otherwise (concave). Competitive combination across rings (3.2.4.2, 3.2.4.4): the hidden
//    parts of the rings are united (visibility AND-ed).
//  - The visible fraction of the combined curves by slicing (3.2.4.4, Fig. 4-8): cut the unit
//    square at every distinct coordinate of the curves (two coordinates within `merge_tolerance`,
//    0.01 in the thesis, count as one) and test one point per cell, weighted by its area; or by
//    fixed 8x8 / 16x16 sampling (`integration`).
//  - Hard shadow (3.2.5): p is in the umbra of an umbra ring when it lies behind all its edges'
//    back planes: the back planes are cut by the plane z = z_p, consecutive lines are intersected
//    and p is tested inside the resulting polygon by its winding (angle sweep); a polygon wound
//    the other way (no umbra exists) contains nothing. Umbra pixels get V = 0.
//
// Other choices and approximations:
//  - Occluder edges are clipped to z < z_p (1 - 1e-4): the part of an edge at or beyond p's depth
//    cannot lie between p and the light; and to the light's plane. Receivers behind the light's
//    plane are handled in the light space of its other face (planar lights emit from both).
//  - An edge seen (nearly) end-on from the light's centre has no direction of its own: it gives no
//    contribution and its corner is classified between its neighbours.
//  - Option edge_visibility=area replaces the linear ramp by the exact fraction of the light past
//    the edge's infinite line (clipping the light polygon, O(L)); the thesis' ramp is the default.
//  - Binning: a light-space grid over directions from the light's centre (ssv.h, which says why).
//  - A two-sided planar sheet (an open planar mesh, e.g. the ground; mesh_topology.h) does not
//    shadow its own pixels.
//  - The silhouettes are computed from the facets only: intermediate edges between the penumbra
//    and umbra silhouettes are ignored (3.3, "the object looks like a prism").
//
// Known weaknesses, measured in tests/techniques/ssv_test.cpp: a convex occluder very close to a
// large light can have every facet partially lit, and then it has no silhouette and casts no
// shadow here; the corner interpolation bends shadow contours (the contour of a tilted cube is not
// convex, Fig. 4-10 is not reproduced); walls of an occluder that face the light can be found in
// its umbra.
//
// Parameters: integration ("slicing" | "8x8" | "16x16"), merge_tolerance (fraction of the light's
// side, [0, 0.25], default 0.01), grid (cells per side of the light-space binning grid, default 64),
// edge_visibility ("linear" | "area").
#include "techniques/ssv.h"

#include <algorithm>
#include <array>
#include <memory>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/timer.h"

namespace penumbra {
namespace silhouette {

LightPlane makeLightPlane(const Light& light, const Bounds3& sceneBounds, std::string_view technique, bool back) {
  if (light.shape() != LightShape::Rect && light.shape() != LightShape::Polygon)
    fail("{}: a {} light is not supported; {} needs a planar convex polygonal light: rect or polygon (triangle, quad, hexagon, ...)",
         technique, toString(light.shape()), technique);
  const std::vector<Vec3>& ws = light.vertices();
  if (ws.size() > static_cast<size_t>(kMaxLightVertices))
    fail("{}: the polygon light has {} vertices; at most {} are supported", technique, ws.size(), kMaxLightVertices);
  LightPlane plane;
  plane.wsOrigin = light.center();
  const Vec3 z = back ? -light.lightFrame(sceneBounds).z : light.lightFrame(sceneBounds).z;
  Vec3 x = ws[1] - ws[0];
  x = glm::normalize(x - z * glm::dot(x, z));
  plane.lsFromWs.z = z;
  plane.lsFromWs.x = x;
  plane.lsFromWs.y = glm::cross(z, x);
  for (const Vec3& v : ws) {
    const Vec3 l = plane.toLight(v);
    plane.vertices.push_back(Vec2(l.x, l.y));
  }
  float twiceArea = 0.0f;
  for (size_t i = 0; i < plane.vertices.size(); ++i) {
    const Vec2 &a = plane.vertices[i], &b = plane.vertices[(i + 1) % plane.vertices.size()];
    twiceArea += a.x * b.y - a.y * b.x;
  }
  if (twiceArea < 0.0f) std::reverse(plane.vertices.begin(), plane.vertices.end());
  plane.area = 0.5f * std::abs(twiceArea);
  plane.lower = plane.upper = plane.vertices[0];
  for (const Vec2& v : plane.vertices) {
    plane.extent = std::max(plane.extent, glm::length(v));
    plane.lower = glm::min(plane.lower, v);
    plane.upper = glm::max(plane.upper, v);
  }
  return plane;
}

std::vector<Occluder> makeOccluders(const Scene& scene, std::string_view technique) {
  std::vector<Occluder> occluders;
  for (const Object& object : scene.objects) {
    Occluder o;
    o.objectId = object.id;
    o.name = object.name;
    o.topology = occluderTopology(object.mesh, object.name, technique);
    if (o.topology.triangles.empty()) continue;
    o.sheet = o.topology.twoSidedSheet;
    occluders.push_back(std::move(o));
  }
  return occluders;
}

Occluder toLightSpace(const Occluder& world, const LightPlane& plane) {
  Occluder o = world;
  for (Vec3& p : o.topology.positions) p = plane.toLight(p);
  for (Vec3& n : o.topology.faceNormals) n = plane.lsFromWs.toLocal(n);
  return o;
}

namespace {
// Clips a convex polygon to the half-plane dot(n, x) <= d (Sutherland-Hodgman).
int clipHalfPlane(const Vec2* in, int count, Vec2* out, const Vec2& n, float d) {
  int m = 0;
  for (int i = 0; i < count; ++i) {
    const Vec2 &a = in[i], &b = in[(i + 1) % count];
    const float da = glm::dot(n, a) - d, db = glm::dot(n, b) - d;
    if (da <= 0.0f) out[m++] = a;
    if ((da < 0.0f) != (db < 0.0f) && da != 0.0f && db != 0.0f) out[m++] = a + (b - a) * (da / (da - db));
  }
  return m;
}
}  // namespace

float clippedFanArea(const std::vector<Vec2>& poly, const Vec2& a0, const Vec2& b0) {
  const float cross = a0.x * b0.y - a0.y * b0.x;
  if (cross == 0.0f) return 0.0f;
  const Vec2 a = cross > 0.0f ? a0 : b0, b = cross > 0.0f ? b0 : a0;
  std::array<Vec2, kMaxLightVertices + 4> bufA, bufB;
  int n = static_cast<int>(poly.size());
  std::copy(poly.begin(), poly.end(), bufA.begin());
  // Inside of the counter-clockwise triangle (0, a, b): left of 0->a, a->b, b->0.
  const Vec2 corners[3] = {Vec2(0.0f), a, b};
  Vec2* in = bufA.data();
  Vec2* out = bufB.data();
  for (int e = 0; e < 3 && n > 0; ++e) {
    const Vec2 s = corners[e], t = corners[(e + 1) % 3];
    const Vec2 nOut(t.y - s.y, s.x - t.x);  // right normal: outside
    n = clipHalfPlane(in, n, out, nOut, glm::dot(nOut, s));
    std::swap(in, out);
  }
  float twice = 0.0f;
  for (int i = 0; i < n; ++i) {
    const Vec2 &p = in[i], &q = in[(i + 1) % n];
    twice += p.x * q.y - p.y * q.x;
  }
  return (cross > 0.0f ? 0.5f : -0.5f) * twice;
}

void UGrid::build(const Vec2& lower, const Vec2& upper, int resolution, const std::vector<Vec2>& itemLower,
                  const std::vector<Vec2>& itemUpper) {
  res_ = resolution;
  lower_ = lower;
  const Vec2 size = glm::max(upper - lower, Vec2(1e-20f));
  scale_ = Vec2(static_cast<float>(res_)) / size;
  start_.assign(size_t(res_) * res_ + 1, 0);
  auto range = [&](size_t i, int& x0, int& y0, int& x1, int& y1) {
    const Vec2 lo = (itemLower[i] - lower_) * scale_, hi = (itemUpper[i] - lower_) * scale_;
    if (!(hi.x >= 0.0f && hi.y >= 0.0f && lo.x < res_ && lo.y < res_)) return false;
    x0 = std::max(0, static_cast<int>(lo.x));
    y0 = std::max(0, static_cast<int>(lo.y));
    x1 = std::min(res_ - 1, static_cast<int>(std::min(hi.x, float(res_ - 1))));
    y1 = std::min(res_ - 1, static_cast<int>(std::min(hi.y, float(res_ - 1))));
    return true;
  };
  int x0, y0, x1, y1;
  for (size_t i = 0; i < itemLower.size(); ++i)
    if (range(i, x0, y0, x1, y1))
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) ++start_[size_t(y) * res_ + x + 1];
  for (size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  items_.resize(start_.back());
  std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < itemLower.size(); ++i)
    if (range(i, x0, y0, x1, y1))
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) items_[fill[size_t(y) * res_ + x]++] = static_cast<uint32_t>(i);
}

std::pair<const uint32_t*, const uint32_t*> UGrid::cell(const Vec2& u) const {
  const Vec2 g = (u - lower_) * scale_;
  if (!(g.x >= 0.0f && g.y >= 0.0f && g.x <= res_ && g.y <= res_) || res_ == 0) return {nullptr, nullptr};
  const int x = std::min(res_ - 1, static_cast<int>(g.x)), y = std::min(res_ - 1, static_cast<int>(g.y));
  const size_t c = size_t(y) * res_ + x;
  return {items_.data() + start_[c], items_.data() + start_[c + 1]};
}

bool receiverRange(const GBuffer& gbuffer, const LightPlane& plane, float zMin, Vec2& lower, Vec2& upper) {
  lower = Vec2(kInfinity);
  upper = Vec2(-kInfinity);
  for (int y = 0; y < gbuffer.height(); ++y)
    for (int x = 0; x < gbuffer.width(); ++x) {
      if (!gbuffer.hit(x, y)) continue;
      const Vec3 p = plane.toLight(gbuffer.wsPosition(x, y));
      if (!(p.z > zMin)) continue;
      const Vec2 u(p.x / p.z, p.y / p.z);
      lower = glm::min(lower, u);
      upper = glm::max(upper, u);
    }
  return lower.x <= upper.x;
}

}  // namespace silhouette

namespace {

using namespace silhouette;

enum class Integration { Slicing, Fixed8, Fixed16 };

struct SsvOptions {
  Integration integration = Integration::Slicing;
  float mergeTolerance = 0.01f;  //!< slicing: cuts closer than this (fraction of the light's side) merge
  int grid = 64;                 //!< cells per side of the light-space binning grid
  bool areaEdgeVisibility = false;  //!< per edge, the exact light area past its line instead of the linear ramp
};

// One silhouette edge and its edge shadow (light space).
struct Edge {
  Vec3 a, b;            //!< endpoints, clipped to z >= zNear
  Vec3 ringA;           //!< unclipped start (for the umbra polygon)
  Vec2 uMid;            //!< u-space midpoint
  Vec2 uA, uB;          //!< u-space ends
  Vec2 nHidden;         //!< u-space unit normal towards the hidden side (the occluder's side)
  uint8_t axis = 0;     //!< quantized direction of the edge shadow: axis 0 = x, 1 = y ...
  int8_t sign = 1;      //!< ... and sign: the hidden part of the light lies towards +sign
  bool convexA = true, convexB = true;  //!< corner type at a and at b
  bool contributes = true;  //!< false for reflex mesh edges and edges behind the light (umbra polygon only)
  uint32_t ring = 0;
  uint32_t index = 0;   //!< position in the ring
};

struct Ring {
  uint32_t first = 0, count = 0;  //!< edges [first, first + count)
  bool umbra = false;
  bool sheet = false;
  bool crossesLightPlane = false;  //!< some vertex is not in front of the light: no umbra test
  int32_t objectId = 0;
  float orientation = 1.0f;  //!< sign of the ring's area in u-space
  Vec2 uLower{kInfinity}, uUpper{-kInfinity};
  float zMax = 0.0f;
};

// One edge shadow's statement at a pixel: the hidden part of the unit light square is
// {s[axis] > cut} (sign > 0) or {s[axis] < cut} (sign < 0).
struct Contribution {
  uint32_t ring, edge;
  uint8_t axis;
  int8_t sign;
  float cut;
  bool andWithPrevious;
};

// Everything about one face of the light: its light space, silhouettes and edge shadows.
struct Side {
  LightPlane plane;
  std::vector<Edge> edges;
  std::vector<Ring> rings;
  UGrid grid;
  std::vector<uint32_t> gridEdge;  //!< grid item -> edge
  bool binned = false;
};

class SsvTechnique final : public ShadowTechnique {
 public:
  explicit SsvTechnique(const SsvOptions& options) : options_(options) {}
  std::string_view name() const override { return "ssv"; }

  void prepare(const Scene& scene, const Light& light) override {
    timings_ = {};
    prepared_ = false;
    Timer timer;
    const Bounds3 bounds = scene.bounds();
    sides_[0] = Side{};
    sides_[1] = Side{};
    sides_[0].plane = makeLightPlane(light, bounds, "ssv");
    sides_[1].plane = makeLightPlane(light, bounds, "ssv", true);
    const std::vector<Occluder> occluders = makeOccluders(scene, "ssv");
    zNear_ = 1e-4f * std::max(bounds.radius(), 1e-6f);
    facets_ = 0;
    for (const Occluder& o : occluders) facets_ += o.sheet ? o.topology.triangleCount() / 2 : o.topology.triangleCount();
    for (Side& side : sides_)
      for (const Occluder& o : occluders) buildRings(side, toLightSpace(o, side.plane));
    timings_.add("silhouettes+edge shadows", timer.elapsedMs());
    prepared_ = true;
  }

  void visibility(const GBuffer& gbuffer, Image<float>& v) override {
    if (!prepared_) fail("ssv: visibility() called before prepare(); call prepare(scene, light) first");
    timings_.passes.erase(std::remove_if(timings_.passes.begin(), timings_.passes.end(),
                                         [](const auto& p) { return p.first != "silhouettes+edge shadows"; }),
                          timings_.passes.end());
    Timer timer;
    const int width = gbuffer.width(), height = gbuffer.height();
    v = Image<float>(width, height, 1.0f);
    for (Side& side : sides_) bin(side, gbuffer);
    timings_.add("binning", timer.elapsedMs());
    Timer pixelTimer;
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
      std::vector<Contribution> contributions;
      std::vector<float> xs, ys;
      for (int y = range.begin(); y < range.end(); ++y)
        for (int x = 0; x < width; ++x) {
          if (!gbuffer.hit(x, y)) continue;
          const Vec3 wsP = gbuffer.wsPosition(x, y);
          // Receivers behind the light's plane see its other face.
          const Vec3 front = sides_[0].plane.toLight(wsP);
          const Side& side = sides_[front.z > 0.0f ? 0 : 1];
          const Vec3 p = front.z > 0.0f ? front : side.plane.toLight(wsP);
          v(x, y) = visibilityAt(side, p, gbuffer.objectId(x, y), contributions, xs, ys);
        }
    });
    timings_.add("visibility", pixelTimer.elapsedMs());
  }

  PassTimings timings() const override { return timings_; }

  std::vector<std::pair<std::string, double>> stats() const override {
    size_t contributing = 0, umbraRings = 0;
    for (const Edge& e : sides_[0].edges) contributing += e.contributes;
    for (const Ring& r : sides_[0].rings) umbraRings += r.umbra;
    return {{"facets", double(facets_)},
            {"silhouette_edges", double(sides_[0].edges.size())},
            {"contributing_edges", double(contributing)},
            {"rings", double(sides_[0].rings.size())},
            {"umbra_rings", double(umbraRings)}};
  }

 private:
  void bin(Side& side, const GBuffer& gbuffer) const {
    side.binned = false;
    Vec2 lower, upper;
    if (side.edges.empty() || !receiverRange(gbuffer, side.plane, zNear_, lower, upper)) return;
    std::vector<Vec2> lo, hi;
    side.gridEdge.clear();
    for (uint32_t i = 0; i < side.edges.size(); ++i) {
      const Edge& e = side.edges[i];
      if (!e.contributes) continue;
      const float grow = side.plane.extent / std::min(e.a.z, e.b.z);
      lo.push_back(glm::min(e.uA, e.uB) - grow);
      hi.push_back(glm::max(e.uA, e.uB) + grow);
      side.gridEdge.push_back(i);
    }
    side.grid.build(lower, upper, options_.grid, lo, hi);
    side.binned = true;
  }

  void buildRings(Side& side, const Occluder& o) const {
    const MeshTopology& m = o.topology;
    const size_t n = m.triangles.size();
    // Section 3.2.2: fully lit (every light vertex in front of the facet), in shadow (none in
    // front), partially lit otherwise.
    std::vector<uint8_t> lit(n), notShadow(n);
    for (size_t t = 0; t < n; ++t) {
      const Vec3 p0 = m.positions[m.triangles[t].x];
      int front = 0;
      for (const Vec2& l : side.plane.vertices) front += glm::dot(m.faceNormals[t], Vec3(l, 0.0f) - p0) > 0.0f;
      lit[t] = front == static_cast<int>(side.plane.vertices.size());
      notShadow[t] = front > 0;
    }
    addRings(side, o, silhouetteRings(m, boundaryEdges(m, lit)), false);
    addRings(side, o, silhouetteRings(m, boundaryEdges(m, notShadow)), true);
  }

  void addRings(Side& side, const Occluder& o, const std::vector<std::vector<SilhouetteEdge>>& rings, bool umbra) const {
    const MeshTopology& m = o.topology;
    auto uOf = [&](const Vec3& p) {
      const float z = std::max(p.z, zNear_);
      return Vec2(p.x / z, p.y / z);
    };
    for (const auto& ringEdges : rings) {
      Ring ring;
      ring.first = static_cast<uint32_t>(side.edges.size());
      ring.count = static_cast<uint32_t>(ringEdges.size());
      ring.umbra = umbra;
      ring.sheet = o.sheet;
      ring.objectId = o.objectId;
      const auto ringId = static_cast<uint32_t>(side.rings.size());
      float area2 = 0.0f;
      for (uint32_t i = 0; i < ringEdges.size(); ++i) {
        const SilhouetteEdge& s = ringEdges[i];
        Edge e;
        e.ringA = m.positions[s.a];
        e.a = m.positions[s.a];
        e.b = m.positions[s.b];
        ring.crossesLightPlane = ring.crossesLightPlane || e.a.z < zNear_;
        // Only the part in front of the light's plane can occlude a receiver in front of it.
        const bool inFront = clipToSlab(e.a, e.b, zNear_, kInfinity);
        e.ring = ringId;
        e.index = i;
        e.contributes = inFront && m.convexEdge(s.inner, s.k);
        e.uA = uOf(e.a);
        e.uB = uOf(e.b);
        e.uMid = 0.5f * (e.uA + e.uB);
        // The hidden side: where the solid lies next to the edge, seen from the centre. A point
        // just inside a convex edge: the midpoint pushed against both faces' normals.
        const Vec3 mid = 0.5f * (e.a + e.b);
        const float len = glm::length(e.b - e.a);
        const Vec3 inside = mid - 1e-3f * len * (m.faceNormals[s.inner] + m.faceNormals[s.outer]);
        const Vec2 d = e.uB - e.uA;
        Vec2 nrm(-d.y, d.x);
        const float nl = glm::length(nrm);
        nrm = nl > 0.0f ? nrm / nl : Vec2(1.0f, 0.0f);
        if (glm::dot(uOf(inside) - e.uA, nrm) < 0.0f) nrm = -nrm;
        e.nHidden = nrm;
        e.axis = std::abs(nrm.x) >= std::abs(nrm.y) ? 0 : 1;  // Section 3.2.3.1: nearest multiple of 90 degrees
        e.sign = nrm[e.axis] >= 0.0f ? 1 : -1;
        area2 += e.uA.x * e.uB.y - e.uA.y * e.uB.x;
        ring.uLower = glm::min(ring.uLower, glm::min(e.uA, e.uB));
        ring.uUpper = glm::max(ring.uUpper, glm::max(e.uA, e.uB));
        ring.zMax = std::max({ring.zMax, e.a.z, e.b.z});
        side.edges.push_back(e);
      }
      ring.orientation = area2 >= 0.0f ? 1.0f : -1.0f;
      // An edge seen (nearly) end-on from the centre, e.g. a vertical edge of a box under the
      // light, has no direction of its own: it gives no contribution and the corner it sits in is
      // classified between its neighbours.
      const float uDiagonal = glm::length(ring.uUpper - ring.uLower);
      auto degenerate = [&](const Edge& e) { return !(glm::length(e.uB - e.uA) > 1e-3f * uDiagonal); };
      for (uint32_t i = 0; i < ring.count; ++i) {
        Edge& e = side.edges[ring.first + i];
        if (degenerate(e)) e.contributes = false;
      }
      // Corner types (Sections 3.2.3.4-6): convex when the neighbour lies on the hidden side.
      for (uint32_t i = 0; i < ring.count; ++i) {
        Edge& e = side.edges[ring.first + i];
        uint32_t next = (i + 1) % ring.count, prev = (i + ring.count - 1) % ring.count;
        for (uint32_t k = 0; k < ring.count && degenerate(side.edges[ring.first + next]); ++k) next = (next + 1) % ring.count;
        for (uint32_t k = 0; k < ring.count && degenerate(side.edges[ring.first + prev]); ++k) prev = (prev + ring.count - 1) % ring.count;
        e.convexB = glm::dot(side.edges[ring.first + next].uMid - e.uA, e.nHidden) > 0.0f;
        e.convexA = glm::dot(side.edges[ring.first + prev].uMid - e.uA, e.nHidden) > 0.0f;
      }
      side.rings.push_back(ring);
    }
  }

  // Section 3.2.5: p behind every back plane of umbra ring r (winding of p around the polygon of
  // consecutive back-line intersections in the plane z = z_p).
  static bool inUmbra(const Side& side, const Ring& r, const Vec3& p) {
    if (r.crossesLightPlane || p.z <= r.zMax * (1.0f + 1e-4f)) return false;
    const Vec2 u(p.x / p.z, p.y / p.z);
    if (u.x < r.uLower.x || u.y < r.uLower.y || u.x > r.uUpper.x || u.y > r.uUpper.y) return false;
    // Back line of each edge in the slice: the edge projected from the light vertex that is the
    // last one it hides, found by walking the light's vertices (O(L), Section 3.4.1).
    auto backLine = [&](uint32_t i, Vec2& s0, Vec2& s1) {
      const Edge& e = side.edges[r.first + i];
      const Vec3 b3 = side.edges[r.first + (i + 1) % r.count].ringA;
      const Vec2 a = projectFrom(p, e.ringA), b = projectFrom(p, b3);
      Vec2 m(-(b - a).y, (b - a).x);
      if (glm::dot(m, e.nHidden) < 0.0f) m = -m;
      Vec2 best = side.plane.vertices[0];
      for (const Vec2& l : side.plane.vertices)
        if (glm::dot(l, m) < glm::dot(best, m)) best = l;
      const Vec3 l3(best, 0.0f);
      s0 = Vec2(l3 + (e.ringA - l3) * (p.z / e.ringA.z));
      s1 = Vec2(l3 + (b3 - l3) * (p.z / b3.z));
    };
    int winding = 0;
    Vec2 firstVertex(0.0f), prevVertex(0.0f);
    Vec2 p0, p1, q0, q1;
    backLine(0, p0, p1);
    const Vec2 start0 = p0, start1 = p1;
    const Vec2 q(p);
    for (uint32_t i = 0; i < r.count; ++i) {
      if (i + 1 < r.count) {
        backLine(i + 1, q0, q1);
      } else {
        q0 = start0;
        q1 = start1;
      }
      const Vec2 d1 = p1 - p0, d2 = q1 - q0;
      const float den = d1.x * d2.y - d1.y * d2.x;
      Vec2 vtx;
      if (std::abs(den) > 1e-6f * glm::length(d1) * glm::length(d2)) {
        const Vec2 w = q0 - p0;
        vtx = p0 + d1 * ((w.x * d2.y - w.y * d2.x) / den);
      } else {
        vtx = 0.5f * (p1 + q0);
      }
      if (i == 0) firstVertex = vtx;
      else winding += crossing(prevVertex, vtx, q);
      prevVertex = vtx;
      p0 = q0;
      p1 = q1;
    }
    winding += crossing(prevVertex, firstVertex, q);
    return winding != 0 && (winding > 0) == (r.orientation > 0.0f);
  }

  // Signed crossing of edge a-b with the ray from q towards +x (winding number, Sunday 2001).
  static int crossing(const Vec2& a, const Vec2& b, const Vec2& q) {
    const float side = (b.x - a.x) * (q.y - a.y) - (q.x - a.x) * (b.y - a.y);
    if (a.y <= q.y) return (b.y > q.y && side > 0.0f) ? 1 : 0;
    return (b.y <= q.y && side < 0.0f) ? -1 : 0;
  }

  float visibilityAt(const Side& side, const Vec3& p, int32_t objectId, std::vector<Contribution>& cs, std::vector<float>& xs,
                     std::vector<float>& ys) const {
    if (!side.binned || !(p.z > zNear_)) return 1.0f;
    for (const Ring& r : side.rings)
      if (r.umbra && !(r.sheet && r.objectId == objectId) && inUmbra(side, r, p)) return 0.0f;
    const Vec2 u(p.x / p.z, p.y / p.z);
    const auto [begin, end] = side.grid.cell(u);
    cs.clear();
    const float zMax = p.z * (1.0f - 1e-4f);
    for (const uint32_t* it = begin; it != end; ++it) {
      const uint32_t id = side.gridEdge[*it];
      const Edge& e = side.edges[id];
      const Ring& r = side.rings[e.ring];
      if (r.sheet && r.objectId == objectId) continue;
      Vec3 a = e.a, b = e.b;
      if (!clipToSlab(a, b, zNear_, zMax)) continue;
      const Vec2 pa = projectFrom(p, a), pb = projectFrom(p, b);
      const Vec2 d = pb - pa;
      const float len = glm::length(d);
      if (!(len > 1e-12f)) continue;
      const Vec2 dir = d / len;
      Vec2 m(-dir.y, dir.x);
      if (glm::dot(m, e.nHidden) < 0.0f) m = -m;
      float hLo, hHi, sLo, sHi;
      side.plane.support(m, hLo, hHi);
      side.plane.support(dir, sLo, sHi);
      // Lateral: the projected segment must overlap the light along its own direction.
      const float sa = glm::dot(pa, dir), sb = glm::dot(pb, dir);
      if (sb <= sLo || sa >= sHi) continue;
      // Front plane: the line at hHi (nothing hidden, t = 1); back plane: at hLo (all hidden, t = 0).
      float t = std::clamp((glm::dot(pa, m) - hLo) / (hHi - hLo), 0.0f, 1.0f);
      if (options_.areaEdgeVisibility && t > 0.0f && t < 1.0f) t = visibleBeyondLine(side.plane, m, glm::dot(pa, m));
      // Corner regions: w, the fraction of the light's extent along the edge that the projected
      // segment covers, is 1 in the mid region and falls to 0 where the segment leaves the light.
      // Towards w = 0 the value goes to the one neutral for the neighbour at the end that lies
      // inside (3.2.3.4-5): at a convex corner (neighbours AND-ed) black, except on the front
      // outline, which stays white; at a concave corner (OR-ed) white, except on the back outline,
      // which stays black. te = t w / (1 - t (1 - w)) has exactly these edges: te(t, 1) = t,
      // te(1, w) = 1, te(t < 1, 0) = 0; the concave case is its mirror in t. An edge with both ends
      // inside and corners of both kinds blends linearly to 1/2. A short edge (seen nearly end-on
      // from the centre) covers little and so says little.
      const float w = std::clamp((std::min(sb, sHi) - std::max(sa, sLo)) / (sHi - sLo), 0.0f, 1.0f);
      const bool insideA = sa > sLo, insideB = sb < sHi;
      const bool convexEnds = (!insideA || e.convexA) && (!insideB || e.convexB);
      const bool concaveEnds = (!insideA || !e.convexA) && (!insideB || !e.convexB);
      float te = t;
      if (!insideA && !insideB) te = t;
      else if (convexEnds) te = t * w / std::max(1.0f - t * (1.0f - w), 1e-12f);
      else if (concaveEnds) te = 1.0f - (1.0f - t) * w / std::max(1.0f - (1.0f - t) * (1.0f - w), 1e-12f);
      else te = w * t + (1.0f - w) * 0.5f;
      te = std::clamp(te, 0.0f, 1.0f);
      cs.push_back({e.ring, id, e.axis, e.sign, e.sign > 0 ? te : 1.0f - te, false});
    }
    if (cs.empty()) return 1.0f;
    // Within a ring: ring order starting after a gap, and the AND / OR of each neighbour pair.
    std::sort(cs.begin(), cs.end(), [](const Contribution& x, const Contribution& y) {
      return x.ring != y.ring ? x.ring < y.ring : x.edge < y.edge;
    });
    for (size_t i = 0; i < cs.size();) {
      size_t j = i;
      while (j < cs.size() && cs[j].ring == cs[i].ring) ++j;
      const Ring& r = side.rings[cs[i].ring];
      // Rotate so the fold starts at an edge whose predecessor in the ring does not contribute.
      size_t startAt = i;
      for (size_t k = i; k < j && j - i > 1; ++k) {
        const uint32_t prevIdx = (side.edges[cs[k].edge].index + r.count - 1) % r.count;
        const size_t pk = k == i ? j - 1 : k - 1;
        if (side.edges[cs[pk].edge].index != prevIdx) {
          startAt = k;
          break;
        }
      }
      std::rotate(cs.begin() + i, cs.begin() + startAt, cs.begin() + j);
      for (size_t k = i + 1; k < j; ++k) {
        const Edge& prev = side.edges[cs[k - 1].edge];
        const Edge& cur = side.edges[cs[k].edge];
        cs[k].andWithPrevious = glm::dot(cur.uMid - prev.uA, prev.nHidden) > 0.0f;
      }
      i = j;
    }
    // Hidden: the union over rings (competitive) of each ring's folded curve (collaborative).
    auto hiddenAt = [&](float sx, float sy) {
      for (size_t i = 0; i < cs.size();) {
        bool h = false;
        size_t j = i;
        for (; j < cs.size() && cs[j].ring == cs[i].ring; ++j) {
          const Contribution& c = cs[j];
          const float s = c.axis == 0 ? sx : sy;
          const bool hj = c.sign > 0 ? s > c.cut : s < c.cut;
          h = j == i ? hj : (c.andWithPrevious ? (h && hj) : (h || hj));
        }
        if (h) return true;
        i = j;
      }
      return false;
    };
    double visible = 0.0;
    if (options_.integration == Integration::Slicing) {
      xs.assign({0.0f, 1.0f});
      ys.assign({0.0f, 1.0f});
      for (const Contribution& c : cs) (c.axis == 0 ? xs : ys).push_back(std::clamp(c.cut, 0.0f, 1.0f));
      const float tolerance = options_.mergeTolerance;
      auto merge = [tolerance](std::vector<float>& cuts) {
        std::sort(cuts.begin(), cuts.end());
        size_t n = 1;
        for (size_t i = 1; i < cuts.size(); ++i)
          if (cuts[i] - cuts[n - 1] > tolerance) cuts[n++] = cuts[i];
        cuts.resize(n);
        if (cuts.back() < 1.0f) {
          if (n > 1 && 1.0f - cuts.back() <= tolerance) cuts.back() = 1.0f;
          else cuts.push_back(1.0f);
        }
      };
      merge(xs);
      merge(ys);
      for (size_t iy = 0; iy + 1 < ys.size(); ++iy)
        for (size_t ix = 0; ix + 1 < xs.size(); ++ix) {
          const float w = (xs[ix + 1] - xs[ix]) * (ys[iy + 1] - ys[iy]);
          if (w > 0.0f && !hiddenAt(0.5f * (xs[ix] + xs[ix + 1]), 0.5f * (ys[iy] + ys[iy + 1]))) visible += w;
        }
    } else {
      const int n = options_.integration == Integration::Fixed8 ? 8 : 16;
      int count = 0;
      for (int iy = 0; iy < n; ++iy)
        for (int ix = 0; ix < n; ++ix) count += !hiddenAt((ix + 0.5f) / n, (iy + 0.5f) / n);
      visible = double(count) / (n * n);
    }
    return std::clamp(static_cast<float>(visible), 0.0f, 1.0f);
  }

  // The fraction of the light's area on the visible side of the line dot(x, m) = offset (the exact
  // visibility past one infinite edge), by clipping the polygon: O(L).
  static float visibleBeyondLine(const LightPlane& plane, const Vec2& m, float offset) {
    std::array<Vec2, kMaxLightVertices + 2> clipped;
    const int n = clipHalfPlane(plane.vertices.data(), static_cast<int>(plane.vertices.size()), clipped.data(), m, offset);
    float twice = 0.0f;
    for (int i = 0; i < n; ++i) {
      const Vec2 &a = clipped[i], &b = clipped[(i + 1) % n];
      twice += a.x * b.y - a.y * b.x;
    }
    return std::clamp(0.5f * twice / plane.area, 0.0f, 1.0f);
  }

  SsvOptions options_;
  Side sides_[2];  //!< [0]: the face towards the scene's centre; [1]: the other face
  float zNear_ = 0.0f;
  size_t facets_ = 0;
  bool prepared_ = false;
  PassTimings timings_;
};

}  // namespace

TechniqueInfo ssvTechniqueInfo() {
  TechniqueInfo info;
  info.name = "ssv";
  info.summary = "soft shadow volumes with a double (penumbra + umbra) silhouette, for convex polygonal lights";
  info.source = "Rouf 2007, Soft shadows for arbitrary planar lights, Chapters 3-4";
  ParamSpec integration;
  integration.name = "integration";
  integration.type = ParamType::String;
  integration.defaultValue = std::string("slicing");
  integration.choices = {"slicing", "8x8", "16x16"};
  integration.help = "visible fraction from the visibility curves: slicing (variable quantization, Section 3.2.4.4) or fixed 8x8 / 16x16 sampling (Fig. 4-8)";
  ParamSpec merge;
  merge.name = "merge_tolerance";
  merge.type = ParamType::Float;
  merge.defaultValue = 0.01;
  merge.min = 0.0;
  merge.max = 0.25;
  merge.unit = "fraction of the light's side";
  merge.help = "slicing: two cut coordinates closer than this count as one (0.01 in the thesis, Section 4.2.6)";
  ParamSpec grid;
  grid.name = "grid";
  grid.type = ParamType::Int;
  grid.defaultValue = int64_t{64};
  grid.min = 1;
  grid.max = 1024;
  grid.unit = "cells per side";
  grid.help = "resolution of the light-space (direction from the light's centre) grid that bins the edge shadows";
  ParamSpec edge;
  edge.name = "edge_visibility";
  edge.type = ParamType::String;
  edge.defaultValue = std::string("linear");
  edge.choices = {"linear", "area"};
  edge.help = "visible fraction past one edge shadow: linear between its front and back planes (the thesis, Section 3.3) or the exact area of the light past the edge's line";
  info.params = {integration, merge, grid, edge};
  info.create = [](const Params& p) -> std::unique_ptr<ShadowTechnique> {
    SsvOptions o;
    const std::string& mode = p.getString("integration");
    o.integration = mode == "8x8" ? Integration::Fixed8 : mode == "16x16" ? Integration::Fixed16 : Integration::Slicing;
    o.mergeTolerance = static_cast<float>(p.getFloat("merge_tolerance"));
    o.grid = static_cast<int>(p.getInt("grid"));
    o.areaEdgeVisibility = p.getString("edge_visibility") == "area";
    return std::make_unique<SsvTechnique>(o);
  };
  return info;
}

}  // namespace penumbra
