// `plm`: penumbra limit maps (Lawlor 2006, "Interpolation-friendly soft shadow maps", CGVR;
// docs/papers.md), and the silhouette-ribbon stages of plm.h shared with `smoothies` and `kirsch`.
//
// The map (Sec. 2, 2.1) holds four quantities per texel, all in PLM space's zeta (plm.h):
//  c   the depth of the occluder edge casting the texel's soft shadow (none: zetaNone),
//  g   the geometry upper limit: the topmost surface, raised on the outer side of a ribbon so that it
//      does not clip the outer penumbra away (Sec. 3.1 step 2). Deviation: raised to the outer limit
//      of a point `margin` texels nearer the edge, c + max(w - margin, 0) s r, rather than to the
//      texel's own limit c + p_i. Both give the same l_g (Equation 1 saturates to 1 above the outer
//      limit), but with the limit itself in g the receiver's depth bias cut the outermost part of the
//      penumbra to 1 (measured 3.3/255 on a straight edge at 32^2); and at the ribbon's border g
//      still meets the depth of the map's far end, so the interpolation into texels without a ribbon
//      (c = zetaNone) happens where every receiver lies above g,
//  b   the geometry lower limit: below it the receivers are in shadow whatever the ribbon says
//      ("when below deeper geometry, we must clamp to black", Sec. 2.1). Deviation: Sec. 3.1 step 3
//      renders the back faces below c, "but throw away geometry above or near the occluder depth c
//      to prevent a surface from occluding its own soft shadow". Which back face is "near" cannot be
//      told from depth alone: the far side of a sphere lies up to its diameter below its outline and
//      must not cut its inner penumbra, while the underside of a body below an arm lying on it (one
//      closed mesh, no surface in between) must cut the arm's. We fit b instead, as Sec. 3 names
//      the most reliable approach ("first calculate the true shadow profile (e.g., by dense sampling
//      along each shadow ray) and then choose shadowing-function parameters to best fit this known
//      shadow profile"), sparsely: along the texel's light ray below c, every surface that faces the
//      light (a receiver) and lies below the one the map sees is probed with 16 rays to the light
//      (in stages, neighbouring receivers sharing packets, each stopping once the samples traced
//      settle its answer: the sixteen's answer),
//      and b is put just above the first one that sees less than half of what Equation 1 predicts
//      for it, by at least 2 of the 16 (findLowerLimits). A receiver the map sees is lit from the
//      light's centre, so in no umbra, and is not probed,
//  p_i the signed penumbra limit w s r (Sec. 3), + outside the silhouette, 0 where no ribbon.
// Generation (Sec. 3.1): g is the light map of the light's centre sample (renderLightMap: the
// topmost surface, which faces the light); the silhouette ribbons of plm.h give c and p_i with
// "highest penumbra limit wins", taken only where a surface lies below the edge (plm.h's
// farthestZeta) and, on an edge's inner side, only where the light map sees the edge's object
// (the inner side of one edge's line must not reach past a thin occluder's other edges). Deviation
// (the clamp of Fig. 7 C, applied before the priority): a ribbon whose shadow is hidden from the
// light's centre does not compete for the texel — on its outer side (or its inner side over another
// object) where the topmost surface of the texel lies above the edge (a higher occluder hides what
// lies below it), and wherever the topmost surface 1.5 texels beyond the edge lies above it (the edge
// is not on the outline seen from the light: a contour behind the object's own front, or a fold of a
// tessellated silhouette, whose outer side faces into the occluder). The texel goes to the best
// remaining ribbon, or to none. Clamped after the priority instead, a texel whose winner was hidden
// fell to the hard compare, which drew black spikes across the inner penumbra of every tessellated
// curved occluder.
// Evaluation, per pixel: the bilinear interpolation of the four channels at the pixel's map position
// (the paper's single bilinear fetch) and Equation 2,
//     l_g = sat(sat(1/2 + 1/2 p_i / (z - c)) + 4 (z < g) - 2 (z < c) + (z < b) - 1),
// with the compare with g made at the receiver's depth moved towards the light by the slope-scaled
// bias of shadow_map.h (a receiver must not shadow itself through its own depth; where the map holds
// another object, a receiver below c is moved no higher than c), and Equation 1
// and the compares with c and b at its true depth (neither is the receiver's own surface); a
// receiver facing away from the light's centre gets no bias (the map never holds it); where no ribbon
// touches the four texels Equation 2 reduces to the compare with g, which is taken directly; then
// V = f(l_g) through the visibility-to-illumination table of Appendix A (penumbra/light_profile.h)
// when `illumination_table` is on. Deviation (Fig. 7 B, "at the transition between the small and
// large objects' penumbras, the penumbra limit depth p_i crosses over the occluder depth c, which
// results in a highly visible erroneous shadow transition"): where the four texels do not hold one
// ribbon (edges that are neither the same nor neighbours on one silhouette, a texel without a ribbon,
// or b at some of them only or jumping), their parameters are not interpolated; Equation 2 is evaluated at each of
// them, with the compares of shadow_map.h (the receiver's tangent plane at the texel centre), and the four values are
// interpolated. Interpolating c and p_i across such a jump drew the white lines across umbrae and the ragged outlines
// of an interpolated b; the paper's remedy, clamping g and b together at the transition (Fig. 7 C), leaves a hard edge
// there. Approximations: exact along one straight edge under a disk light (up to float rounding, the depth
// rasterization and the bias); one occluder per shadow-map ray (the first penumbra wins, Sec. 3);
// corners are rounded (the ribbon of a segment ends in a half disk); where an occluder is thinner
// than a texel (a sharp corner) the map sees what lies under it and the shadow there is lost; near a
// contact with the receiver the depth bias lights the shadow, as in every shadow map. Lights: directional disks (an
// orthographic map, as the paper) and sphere, disk, rect and polygon lights through the perspective
// transform of plm.h; segment lights are rejected.
// Cost: the fit of b traces rays (on `engine`, 121k triangles, about a third of prepare); the scene's
// BVH for it is kept between prepares while every mesh's geometry is the same to the bit.
// Parameters: map_size (texels), bias_constant (texels) and bias_slope (shadow_map.h), margin
// (texels added to every ribbon's half-width), illumination_table (bool), fit_lower_limit (bool: off
// leaves b at zetaNone everywhere, the map of steps 1 and 2 alone).
#include "techniques/ribbon/plm.h"
#include "penumbra/techniques/ribbon.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <memory>
#include <optional>

#if defined(__SSE4_1__)
#include <smmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define PENUMBRA_RIBBON_AVX512 1  // ribbonSpanAvx512, picked at run time where the CPU has AVX-512F
#endif

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "core/image_fill.h"
#include "core/light_profile.h"
#include "core/target_clones.h"
#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "raster/rasterizer.h"
#include "rt/ray_scene.h"
#include "techniques/mesh_edges.h"
#include "techniques/shadow_map/shadow_map.h"

namespace penumbra {
namespace plm {

float emitterRadius(const Light& light, const char* technique) {
  switch (light.shape()) {
    case LightShape::Sphere:
    case LightShape::Disk:
      return light.radius();
    case LightShape::Directional:
      return std::tan(0.5f * light.angularDiameter());
    case LightShape::Rect:
    case LightShape::Polygon: {
      // The disk of equal area: Newell's area of the (planar, convex) polygon.
      const std::vector<Vec3>& v = light.vertices();
      Vec3 n(0.0f);
      for (size_t i = 0; i < v.size(); ++i) n += glm::cross(v[i], v[(i + 1) % v.size()]);
      return std::sqrt(0.5f * glm::length(n) / kPi);
    }
    case LightShape::Segment:
      break;
  }
  fail(
      "{}: a {} light is not supported (it has no width across its axis, so no disk stands for it); supported: "
      "sphere, disk, rect, polygon, directional",
      technique, toString(light.shape()));
}

Space makeSpace(const LightMap& map, const Light& light, const char* technique, bool sphereAcrossEdges) {
  Space space;
  const float radius = emitterRadius(light, technique);
  space.orthographic = map.orthographic;
  const float zNear = std::max(map.zNear, 1e-6f * std::max(map.zFar, 1e-6f));
  const float zFar = std::max(map.zFar, zNear * (1.0f + 1e-4f));
  space.zetaNear = space.zeta(zNear);
  space.zetaFar = space.zeta(zFar);
  // Deeper than anything, with the scale of the map's range (a finite value: it is interpolated).
  space.zetaNone = space.zetaFar + 4.0f * (space.zetaFar - space.zetaNear);
  const float texelSize = 2.0f * (map.orthographic ? map.halfWidth : map.tanHalfFov) / static_cast<float>(map.size);
  space.ratePerTexel = texelSize / radius;
  space.sphere = sphereAcrossEdges && !map.orthographic && light.shape() == LightShape::Sphere;
  return space;
}

float edgeRate(const Space& space, const LightMap& map, const Edge& e) {
  if (!space.sphere) return space.ratePerTexel;
  // The edge's middle as u = (x / z, y / z) (LightMap::projectLightSpace inverted; t runs down), and
  // its normal in u (the same scale, t flipped).
  const Vec2 mid = 0.5f * (e.a + e.b);
  const float half = 0.5f * static_cast<float>(map.size);
  const float texelU = 2.0f * map.tanHalfFov / static_cast<float>(map.size);
  const Vec2 u((mid.x / half - 1.0f + map.windowOffset.x) * half * texelU,
               (1.0f - mid.y / half + map.windowOffset.y) * half * texelU);
  const float across = e.outward.x * u.x - e.outward.y * u.y;
  return space.ratePerTexel / std::sqrt(1.0f + across * across);
}

// One mesh's silhouette candidates, which depend on its geometry alone, taken from its edge
// adjacency (techniques/mesh_edges.h): the triangles kept (no two welded corners alike, a
// non-degenerate normal) with their normal and centroid, and each edge's uses by those triangles in
// triangle order, the edges in order of first use (edges no kept triangle uses are left out).
// Vertex ids are the adjacency's welded ids (the first vertex at a position).
struct SilhouetteMesh {
  std::vector<Vec3> normals, centroids;  //!< per kept triangle
  std::vector<uint32_t> a, b;            //!< per edge: welded end points, a < b
  std::vector<uint32_t> firstUse;        //!< per edge, and one past the last: its uses in the two arrays below
  std::vector<uint32_t> useTriangle, useOpposite;  //!< per use: the kept triangle, its third (welded) vertex

  void build(const Mesh& mesh, const MeshEdges& edges) {
    const std::vector<uint32_t>& weld = edges.weld;
    constexpr uint32_t kDropped = 0xffffffffu;
    std::vector<uint32_t> kept(mesh.triangles.size(), kDropped);  // per triangle: its index among the kept
    normals.clear();
    centroids.clear();
    for (size_t ti = 0; ti < mesh.triangles.size(); ++ti) {
      const glm::uvec3& tri = mesh.triangles[ti];
      const uint32_t v[3] = {weld[tri.x], weld[tri.y], weld[tri.z]};
      if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;
      const Vec3 n = mesh.faceNormal(ti);
      if (!(glm::dot(n, n) > 0.0f)) continue;  // degenerate
      kept[ti] = static_cast<uint32_t>(normals.size());
      normals.push_back(n);
      centroids.push_back((mesh.positions[v[0]] + mesh.positions[v[1]] + mesh.positions[v[2]]) / 3.0f);
    }
    // The edges in order of their first use by a kept triangle (3 * triangle + corner: distinct, so one order).
    std::vector<std::pair<uint64_t, uint32_t>> order;
    for (size_t e = 0; e < edges.edgeCount(); ++e)
      for (uint32_t u = edges.firstUse[e]; u < edges.firstUse[e + 1]; ++u)
        if (kept[edges.useTriangle[u]] != kDropped) {
          order.emplace_back(3 * uint64_t{edges.useTriangle[u]} + edges.useCorner[u], static_cast<uint32_t>(e));
          break;
        }
    tbb::parallel_sort(order.begin(), order.end());
    a.clear();
    b.clear();
    firstUse.clear();
    useTriangle.clear();
    useOpposite.clear();
    for (const auto& [first, e] : order) {
      a.push_back(edges.low[e]);
      b.push_back(edges.high[e]);
      firstUse.push_back(static_cast<uint32_t>(useTriangle.size()));
      for (uint32_t u = edges.firstUse[e]; u < edges.firstUse[e + 1]; ++u) {
        const uint32_t t = edges.useTriangle[u];
        if (kept[t] == kDropped) continue;
        useTriangle.push_back(kept[t]);
        useOpposite.push_back(weld[mesh.triangles[t][static_cast<int>((edges.useCorner[u] + 2) % 3)]]);
      }
    }
    firstUse.push_back(static_cast<uint32_t>(useTriangle.size()));
  }
};

struct EdgeCache::Impl {
  MeshEdgeCache adjacency;                            //!< per object index, the mesh's edge adjacency
  std::vector<std::optional<SilhouetteMesh>> meshes;  //!< per object index, built from it
  // silhouetteEdges' working storage, kept so that the next light refills it rather than faulting
  // in fresh pages: per kept triangle whether it faces the light; per edge its Edge, if a silhouette.
  std::vector<uint8_t> front, isSilhouette;
  std::vector<Edge> candidates;
  // Per welded vertex: how many silhouette ends meet there (up to 3), and the first two of them;
  // zero again after each object, so that a call touches only the vertices that end an edge.
  std::vector<uint8_t> endCount;
  std::vector<uint32_t> endsAt;
};

EdgeCache::EdgeCache() : impl_(std::make_unique<Impl>()) {}
EdgeCache::~EdgeCache() = default;

std::vector<Edge> silhouetteEdges(const Scene& scene, const Light& light, const LightMap& map, const Space& space,
                                  EdgeCache* cache) {
  EdgeCache local;
  EdgeCache& edgeCache = cache ? *cache : local;
  edgeCache.impl_->meshes.resize(scene.objects.size());
  edgeCache.impl_->adjacency.resize(scene.objects.size());
  std::vector<Edge> edges;
  std::vector<uint8_t>& front = edgeCache.impl_->front;
  std::vector<uint8_t>& isSilhouette = edgeCache.impl_->isSilhouette;
  std::vector<Edge>& candidates = edgeCache.impl_->candidates;
  for (size_t objectIndex = 0; objectIndex < scene.objects.size(); ++objectIndex) {
    const Object& object = scene.objects[objectIndex];
    const size_t firstEdge = edges.size();
    std::vector<std::pair<uint32_t, uint32_t>> ends;  // welded vertex ids of each edge's a and b
    std::optional<SilhouetteMesh>& cached = edgeCache.impl_->meshes[objectIndex];
    bool rebuilt = false;
    const MeshEdges& adjacency = edgeCache.impl_->adjacency.edges(scene, objectIndex, &rebuilt);
    if (!cached || rebuilt) {
      cached.emplace();
      cached->build(object.mesh, adjacency);
    }
    const SilhouetteMesh& topology = *cached;
    const std::vector<Vec3>& positions = object.mesh.positions;  // at the welded ids: the welded positions
    // A triangle faces the light when its normal points to the light's centre (directional: along its direction).
    front.resize(topology.normals.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, front.size(), 4096), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t t = range.begin(); t < range.end(); ++t) {
        const Vec3 toLight = light.isDirectional() ? light.direction() : light.center() - topology.centroids[t];
        front[t] = glm::dot(topology.normals[t], toLight) > 0.0f ? 1 : 0;
      }
    });
    const size_t edgeCount = topology.a.size();
    candidates.resize(edgeCount);
    isSilhouette.assign(edgeCount, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, edgeCount, 1024), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t k = range.begin(); k < range.end(); ++k) {
        const uint32_t u0 = topology.firstUse[k], u1 = topology.firstUse[k + 1];
        const int count = static_cast<int>(u1 - u0);
        int frontCount = 0;
        for (uint32_t u = u0; u < u1; ++u) frontCount += front[topology.useTriangle[u]];
        if (!(count == 1 || (frontCount > 0 && frontCount < count))) continue;
        // The third vertices of the edge's first two triangles, and which of the two (0, 1) faces the light.
        const int slots = std::min(count, 2);
        int firstFront = -1;
        for (int slot = 0; slot < slots && firstFront < 0; ++slot)
          if (front[topology.useTriangle[u0 + static_cast<uint32_t>(slot)]]) firstFront = slot;
        const Vec3& pa = positions[topology.a[k]];
        const Vec3& pb = positions[topology.b[k]];
        const Vec3 sa = map.project(pa), sb = map.project(pb);
        if (!map.orthographic && !(sa.z > 0.0f && sb.z > 0.0f)) continue;  // behind a local light
        Edge e;
        e.a = Vec2(sa.x, sa.y);
        e.b = Vec2(sb.x, sb.y);
        const Vec2 d = e.b - e.a;
        const float length = glm::length(d);
        if (!(length > 1e-6f) || !std::isfinite(length)) continue;  // seen end-on
        Vec2 normal(-d.y / length, d.x / length);
        // The inner side holds the (front-facing) triangle's third vertex.
        int order[2], orderCount = 0;
        if (firstFront >= 0) order[orderCount++] = firstFront;
        for (int slot = 0; slot < slots; ++slot)
          if (slot != firstFront) order[orderCount++] = slot;
        float side = 0.0f;
        for (int q = 0; q < orderCount && !(std::abs(side) > 1e-6f * length); ++q) {
          const Vec3 so = map.project(positions[topology.useOpposite[u0 + static_cast<uint32_t>(order[q])]]);
          if (!map.orthographic && !(so.z > 0.0f)) continue;
          side = glm::dot(Vec2(so.x, so.y) - e.a, normal);
        }
        if (!(std::abs(side) > 1e-6f * length)) continue;  // the triangles are seen edge-on
        e.outward = side > 0.0f ? -normal : normal;
        e.rate = edgeRate(space, map, e);
        e.zetaA = space.zeta(sa.z);
        e.zetaB = space.zeta(sb.z);
        e.objectId = object.id;
        candidates[k] = e;
        isSilhouette[k] = 1;
      }
    });
    const size_t silhouettes = static_cast<size_t>(std::count(isSilhouette.begin(), isSilhouette.end(), 1));
    edges.reserve(edges.size() + silhouettes);
    ends.reserve(silhouettes);
    for (size_t k = 0; k < edgeCount; ++k)
      if (isSilhouette[k]) {
        edges.push_back(candidates[k]);
        ends.emplace_back(topology.a[k], topology.b[k]);
      }
    // Corners: where exactly two silhouette edges of the object meet, the corner is convex when the
    // other edge leaves towards this edge's inner side. Each end is 2 * edge + (0: a, 1: b).
    std::vector<uint8_t>& endCount = edgeCache.impl_->endCount;
    std::vector<uint32_t>& endsAt = edgeCache.impl_->endsAt;
    if (endCount.size() < positions.size()) {
      endCount.resize(positions.size(), 0);
      endsAt.resize(2 * positions.size());
    }
    const auto vertexOf = [&](uint32_t end) { return (end & 1) ? ends[end / 2].second : ends[end / 2].first; };
    const uint32_t endTotal = static_cast<uint32_t>(2 * ends.size());
    for (uint32_t end = 0; end < endTotal; ++end) {
      const uint32_t v = vertexOf(end);
      const uint8_t count = endCount[v];
      if (count < 2) endsAt[2 * v + count] = end;
      if (count < 3) endCount[v] = static_cast<uint8_t>(count + 1);
    }
    for (uint32_t mine = 0; mine < endTotal; ++mine) {
      const uint32_t v = vertexOf(mine);
      if (endCount[v] != 2) continue;
      const uint32_t other = endsAt[2 * v] == mine ? endsAt[2 * v + 1] : endsAt[2 * v];
      Edge& e = edges[firstEdge + mine / 2];
      const Edge& o = edges[firstEdge + other / 2];
      const Vec2 corner = (mine & 1) ? e.b : e.a;
      const Vec2 away = (other & 1) ? o.a : o.b;  // the other edge's far end
      const float side = glm::dot(away - corner, e.outward) < 0.0f ? 1.0f : -1.0f;
      ((mine & 1) ? e.endSideB : e.endSideA) = side;
      ((mine & 1) ? e.neighbourB : e.neighbourA) = static_cast<int32_t>(firstEdge + other / 2);
    }
    for (uint32_t end = 0; end < endTotal; ++end) endCount[vertexOf(end)] = 0;
  }
  return edges;
}

void reserveRibbons(int mapSize, RibbonImage& ribbons) {
  resetInParallel(ribbons.texels, mapSize, mapSize, kNoRibbon);
  const int tiles = ribbonTilesPerRow(mapSize);
  ribbons.mayHoldRibbon.assign(static_cast<size_t>(tiles) * tiles, 0);
}

namespace {

// Texels [from, count) of the span, one at a time: the definition the vector passes below follow
// operation for operation, so that every path gives the same values to the bit.
void ribbonSpanScalar(const RibbonSpan& s, int from, int count, RibbonSpanTexels& out) {
  for (int m = from; m < count; ++m) {
    const float qx = static_cast<float>(s.first + m) + 0.5f;
    const float aqx = qx - s.ax;
    const float along = (aqx * s.dx + s.aqy * s.dy) * s.invLength2;
    const float u = std::min(std::max(along, 0.0f), 1.0f);
    // Beyond an end, the distance to the end point itself: bit-identical for both edges of a
    // corner, so they tie there.
    const bool beforeA = along <= 0.0f, beyondB = along >= 1.0f;
    const float ox = beforeA ? aqx : (beyondB ? qx - s.bx : aqx - u * s.dx);
    const float oy = beforeA ? s.aqy : (beyondB ? s.by : s.aqy - u * s.dy);
    const float distance = std::sqrt(ox * ox + oy * oy);
    const float endSide = beforeA ? s.endSideA : (beyondB ? s.endSideB : 0.0f);
    const bool outer = endSide != 0.0f ? endSide > 0.0f : aqx * s.outX + s.aqy * s.outY >= 0.0f;
    const float c = beforeA ? s.zetaA : (beyondB ? s.zetaB : s.zetaA + u * (s.zetaB - s.zetaA));
    const float p = c + distance * s.rate;
    // The texel's own filters: on the inner side only where the map sees the edge's own
    // object; only where a surface lies below the edge; not where the texel's topmost surface
    // lies above the edge (tested on the outer side only: an inner candidate left here is
    // over its own object, which does not hide its shadow).
    const bool ownObject = !s.coverage || s.coverage[m] == s.objectId;
    // Space::zeta of the depth
    const auto above = [&](float depth) {
      return std::isfinite(depth) && (s.orthographic ? depth : -1.0f / depth) < c;
    };
    const bool kept =
        (outer || ownObject) && s.far[m] > c + kBelowEdge * std::abs(c) && !(s.top && outer && above(s.top[m]));
    const bool take = !(distance > s.halfWidth) && (s.bothSides || outer == s.wantOuter) &&
                      (p < s.priority[m] || (s.ties && p == s.priority[m])) && kept;
    out.u[m] = u;
    out.c[m] = c;
    out.distance[m] = distance;
    out.p[m] = take ? p : kInfinity;
    out.outer |= static_cast<uint32_t>(outer) << m;
    out.taken |= static_cast<uint32_t>(take) << m;
  }
}

#if defined(__SSE4_1__)
// Four texels to an SSE vector, the scalar pass's operations in its order, without branches; returns
// how many texels it did (a multiple of 4; ribbonSpanScalar does the rest).
int ribbonSpanSse(const RibbonSpan& s, int count, RibbonSpanTexels& out) {
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f), half = _mm_set1_ps(0.5f);
  const __m128 ax = _mm_set1_ps(s.ax), bx = _mm_set1_ps(s.bx), dx = _mm_set1_ps(s.dx), dy = _mm_set1_ps(s.dy);
  const __m128 vAqy = _mm_set1_ps(s.aqy), vBy = _mm_set1_ps(s.by), vInvLength2 = _mm_set1_ps(s.invLength2);
  const __m128 outX = _mm_set1_ps(s.outX), outY = _mm_set1_ps(s.outY);
  const __m128 endA = _mm_set1_ps(s.endSideA), endB = _mm_set1_ps(s.endSideB);
  const __m128 zetaA = _mm_set1_ps(s.zetaA), zetaB = _mm_set1_ps(s.zetaB), dZeta = _mm_set1_ps(s.zetaB - s.zetaA);
  const __m128 rate = _mm_set1_ps(s.rate), vH = _mm_set1_ps(s.halfWidth), inf = _mm_set1_ps(kInfinity);
  const __m128 allSides = _mm_castsi128_ps(_mm_set1_epi32(s.bothSides ? -1 : 0));
  const __m128 outerWanted = _mm_castsi128_ps(_mm_set1_epi32(s.wantOuter ? -1 : 0));
  const __m128 allOnes = _mm_castsi128_ps(_mm_set1_epi32(-1)), signBit = _mm_set1_ps(-0.0f);
  const __m128 belowEdge = _mm_set1_ps(kBelowEdge), minusOne = _mm_set1_ps(-1.0f);
  const __m128 orthographic = _mm_castsi128_ps(_mm_set1_epi32(s.orthographic ? -1 : 0));
  const __m128i objectId = _mm_set1_epi32(s.objectId);
  const __m128 tiesWanted = _mm_castsi128_ps(_mm_set1_epi32(s.ties ? -1 : 0));
  int m = 0;
  for (; m + 4 <= count; m += 4) {
    const __m128 qx =
        _mm_add_ps(_mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(s.first + m), _mm_setr_epi32(0, 1, 2, 3))), half);
    const __m128 aqx = _mm_sub_ps(qx, ax);
    const __m128 along = _mm_mul_ps(_mm_add_ps(_mm_mul_ps(aqx, dx), _mm_mul_ps(vAqy, dy)), vInvLength2);
    const __m128 u = _mm_min_ps(one, _mm_max_ps(zero, along));  // std::min(std::max(along, 0), 1), NaN and -0 included
    const __m128 beforeA = _mm_cmple_ps(along, zero), beyondB = _mm_cmpge_ps(along, one);
    const __m128 sx = _mm_sub_ps(aqx, _mm_mul_ps(u, dx)), sy = _mm_sub_ps(vAqy, _mm_mul_ps(u, dy));
    const __m128 ox = _mm_blendv_ps(_mm_blendv_ps(sx, _mm_sub_ps(qx, bx), beyondB), aqx, beforeA);
    const __m128 oy = _mm_blendv_ps(_mm_blendv_ps(sy, vBy, beyondB), vAqy, beforeA);
    const __m128 distance = _mm_sqrt_ps(_mm_add_ps(_mm_mul_ps(ox, ox), _mm_mul_ps(oy, oy)));
    const __m128 endSide = _mm_blendv_ps(_mm_blendv_ps(zero, endB, beyondB), endA, beforeA);
    const __m128 across = _mm_add_ps(_mm_mul_ps(aqx, outX), _mm_mul_ps(vAqy, outY));
    const __m128 outer =
        _mm_or_ps(_mm_cmpgt_ps(endSide, zero), _mm_and_ps(_mm_cmpeq_ps(endSide, zero), _mm_cmpge_ps(across, zero)));
    const __m128 cMid = _mm_add_ps(zetaA, _mm_mul_ps(u, dZeta));
    const __m128 c = _mm_blendv_ps(_mm_blendv_ps(cMid, zetaB, beyondB), zetaA, beforeA);
    const __m128 p = _mm_add_ps(c, _mm_mul_ps(distance, rate));
    // both sides, or the side wanted (outer == wantOuter)
    const __m128 sideWanted = _mm_or_ps(allSides, _mm_xor_ps(outer, _mm_xor_ps(outerWanted, allOnes)));
    const __m128 ownObject = s.coverage
                                 ? _mm_castsi128_ps(_mm_cmpeq_epi32(
                                       _mm_loadu_si128(reinterpret_cast<const __m128i*>(s.coverage + m)), objectId))
                                 : allOnes;
    const __m128 outerOrOwn = _mm_or_ps(outer, ownObject);
    const __m128 somethingBelow =
        _mm_cmpgt_ps(_mm_loadu_ps(s.far + m), _mm_add_ps(c, _mm_mul_ps(belowEdge, _mm_andnot_ps(signBit, c))));
    __m128 kept = _mm_and_ps(outerOrOwn, somethingBelow);
    if (s.top) {
      const __m128 top = _mm_loadu_ps(s.top + m);
      const __m128 finite = _mm_cmplt_ps(_mm_andnot_ps(signBit, top), inf);
      const __m128 topZeta = _mm_blendv_ps(_mm_div_ps(minusOne, top), top, orthographic);
      const __m128 above = _mm_and_ps(finite, _mm_cmplt_ps(topZeta, c));
      kept = _mm_andnot_ps(_mm_and_ps(outer, above), kept);
    }
    const __m128 prio = _mm_loadu_ps(s.priority + m);
    const __m128 take =
        _mm_and_ps(_mm_and_ps(_mm_and_ps(_mm_cmpngt_ps(distance, vH), sideWanted),
                              _mm_or_ps(_mm_cmplt_ps(p, prio), _mm_and_ps(tiesWanted, _mm_cmpeq_ps(p, prio)))),
                   kept);
    _mm_storeu_ps(out.u + m, u);
    _mm_storeu_ps(out.c + m, c);
    _mm_storeu_ps(out.distance + m, distance);
    _mm_storeu_ps(out.p + m, _mm_blendv_ps(inf, p, take));
    out.outer |= static_cast<uint32_t>(_mm_movemask_ps(outer)) << m;
    out.taken |= static_cast<uint32_t>(_mm_movemask_ps(take)) << m;
  }
  return m;
}
#endif

#if PENUMBRA_RIBBON_AVX512
// GCC 12's AVX-512 intrinsics start from a deliberately undefined vector (_mm512_undefined_*), which
// its own -Wuninitialized reports at every inlined use.
#if !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
// Sixteen texels to an AVX-512 vector, the scalar pass's operations in its order (the file is built
// without fused multiply-add, and each compare keeps the SSE one's treatment of NaN); the span's end
// masked, so a span of up to 32 texels takes at most two steps and no scalar tail.
[[gnu::target("avx512f")]] void ribbonSpanAvx512(const RibbonSpan& s, int count, RibbonSpanTexels& out) {
  const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f), half = _mm512_set1_ps(0.5f);
  const __m512 ax = _mm512_set1_ps(s.ax), bx = _mm512_set1_ps(s.bx), dx = _mm512_set1_ps(s.dx),
               dy = _mm512_set1_ps(s.dy);
  const __m512 vAqy = _mm512_set1_ps(s.aqy), vBy = _mm512_set1_ps(s.by), vInvLength2 = _mm512_set1_ps(s.invLength2);
  const __m512 outX = _mm512_set1_ps(s.outX), outY = _mm512_set1_ps(s.outY);
  const __m512 endA = _mm512_set1_ps(s.endSideA), endB = _mm512_set1_ps(s.endSideB);
  const __m512 zetaA = _mm512_set1_ps(s.zetaA), zetaB = _mm512_set1_ps(s.zetaB),
               dZeta = _mm512_set1_ps(s.zetaB - s.zetaA);
  const __m512 rate = _mm512_set1_ps(s.rate), vH = _mm512_set1_ps(s.halfWidth), inf = _mm512_set1_ps(kInfinity);
  const __m512 belowEdge = _mm512_set1_ps(kBelowEdge), minusOne = _mm512_set1_ps(-1.0f);
  const __m512i objectId = _mm512_set1_epi32(s.objectId);
  const __m512i lanes = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  for (int m = 0; m < count; m += 16) {
    const __mmask16 valid = static_cast<__mmask16>(count - m >= 16 ? 0xffff : (1u << (count - m)) - 1u);
    const __m512 qx = _mm512_add_ps(_mm512_cvtepi32_ps(_mm512_add_epi32(_mm512_set1_epi32(s.first + m), lanes)), half);
    const __m512 aqx = _mm512_sub_ps(qx, ax);
    const __m512 along = _mm512_mul_ps(_mm512_add_ps(_mm512_mul_ps(aqx, dx), _mm512_mul_ps(vAqy, dy)), vInvLength2);
    const __m512 u = _mm512_min_ps(one, _mm512_max_ps(zero, along));
    const __mmask16 beforeA = _mm512_cmp_ps_mask(along, zero, _CMP_LE_OS),
                    beyondB = _mm512_cmp_ps_mask(along, one, _CMP_GE_OS);
    const __m512 sx = _mm512_sub_ps(aqx, _mm512_mul_ps(u, dx)), sy = _mm512_sub_ps(vAqy, _mm512_mul_ps(u, dy));
    const __m512 ox = _mm512_mask_blend_ps(beforeA, _mm512_mask_blend_ps(beyondB, sx, _mm512_sub_ps(qx, bx)), aqx);
    const __m512 oy = _mm512_mask_blend_ps(beforeA, _mm512_mask_blend_ps(beyondB, sy, vBy), vAqy);
    const __m512 distance = _mm512_sqrt_ps(_mm512_add_ps(_mm512_mul_ps(ox, ox), _mm512_mul_ps(oy, oy)));
    const __m512 endSide = _mm512_mask_blend_ps(beforeA, _mm512_mask_blend_ps(beyondB, zero, endB), endA);
    const __m512 across = _mm512_add_ps(_mm512_mul_ps(aqx, outX), _mm512_mul_ps(vAqy, outY));
    const __mmask16 outer =
        _mm512_cmp_ps_mask(endSide, zero, _CMP_GT_OS) |
        (_mm512_cmp_ps_mask(endSide, zero, _CMP_EQ_OQ) & _mm512_cmp_ps_mask(across, zero, _CMP_GE_OS));
    const __m512 cMid = _mm512_add_ps(zetaA, _mm512_mul_ps(u, dZeta));
    const __m512 c = _mm512_mask_blend_ps(beforeA, _mm512_mask_blend_ps(beyondB, cMid, zetaB), zetaA);
    const __m512 p = _mm512_add_ps(c, _mm512_mul_ps(distance, rate));
    const __mmask16 sideWanted =
        s.bothSides ? static_cast<__mmask16>(0xffff) : static_cast<__mmask16>(s.wantOuter ? outer : ~outer);
    const __mmask16 ownObject = s.coverage
                                    ? _mm512_cmpeq_epi32_mask(_mm512_maskz_loadu_epi32(valid, s.coverage + m), objectId)
                                    : static_cast<__mmask16>(0xffff);
    const __m512 far = _mm512_maskz_loadu_ps(valid, s.far + m);
    __mmask16 kept = (outer | ownObject) &
                     _mm512_cmp_ps_mask(far, _mm512_add_ps(c, _mm512_mul_ps(belowEdge, _mm512_abs_ps(c))), _CMP_GT_OS);
    if (s.top) {
      const __m512 top = _mm512_maskz_loadu_ps(valid, s.top + m);
      const __mmask16 finite = _mm512_cmp_ps_mask(_mm512_abs_ps(top), inf, _CMP_LT_OS);
      const __m512 topZeta = s.orthographic ? top : _mm512_div_ps(minusOne, top);
      const __mmask16 above = finite & _mm512_cmp_ps_mask(topZeta, c, _CMP_LT_OS);
      kept = static_cast<__mmask16>(kept & ~(outer & above));
    }
    const __m512 prio = _mm512_maskz_loadu_ps(valid, s.priority + m);
    const __mmask16 better = _mm512_cmp_ps_mask(p, prio, _CMP_LT_OS) |
                             (s.ties ? _mm512_cmp_ps_mask(p, prio, _CMP_EQ_OQ) : static_cast<__mmask16>(0));
    const __mmask16 take = _mm512_cmp_ps_mask(distance, vH, _CMP_NGT_US) & sideWanted & better & kept;
    _mm512_mask_storeu_ps(out.u + m, valid, u);
    _mm512_mask_storeu_ps(out.c + m, valid, c);
    _mm512_mask_storeu_ps(out.distance + m, valid, distance);
    _mm512_mask_storeu_ps(out.p + m, valid, _mm512_mask_blend_ps(take, inf, p));
    out.outer |= static_cast<uint32_t>(outer & valid) << m;
    out.taken |= static_cast<uint32_t>(take & valid) << m;
  }
}
#if !defined(__clang__)
#pragma GCC diagnostic pop
#endif
#endif

}  // namespace

bool spanPathAvailable(SpanPath path) {
  switch (path) {
    case SpanPath::Scalar:
      return true;
    case SpanPath::Sse:
#if defined(__SSE4_1__)
      return true;
#else
      return false;
#endif
    case SpanPath::Avx512:
#if PENUMBRA_RIBBON_AVX512
      return __builtin_cpu_supports("avx512f");
#else
      return false;
#endif
  }
  return false;
}

namespace {

// ribbonSpan without its check of the path (rasterizeRibbons picks an available one once).
inline void spanPass(SpanPath path, const RibbonSpan& s, int count, RibbonSpanTexels& out) {
  out.outer = 0;
  out.taken = 0;
  int done = 0;
#if PENUMBRA_RIBBON_AVX512
  if (path == SpanPath::Avx512) {
    ribbonSpanAvx512(s, count, out);
    done = count;
  }
#endif
#if defined(__SSE4_1__)
  if (path == SpanPath::Sse) done = ribbonSpanSse(s, count, out);
#endif
  ribbonSpanScalar(s, done, count, out);
}

}  // namespace

void ribbonSpan(SpanPath path, const RibbonSpan& s, int count, RibbonSpanTexels& out) {
  if (!spanPathAvailable(path)) fail("ribbonSpan: this CPU or build has no such vector path");
  spanPass(path, s, count, out);
}

float penumbraTexels(const Edge& e, float zetaDeepest, float zetaFrom) {
  return std::max(0.0f, zetaDeepest - std::min({e.zetaA, e.zetaB, zetaFrom})) / e.rate;
}

RibbonBox ribbonBox(const Edge& e, float width, int mapSize, float marginTexels) {
  // Capped at the map's size: a ribbon wider than the map covers all of it anyway.
  const float half = std::min(width + marginTexels + kRibbonBorderTexels, 2.0f * static_cast<float>(mapSize));
  const Vec2 lo = glm::min(e.a, e.b) - half, hi = glm::max(e.a, e.b) + half;
  return RibbonBox{std::max(0, static_cast<int>(std::floor(lo.x))), std::max(0, static_cast<int>(std::floor(lo.y))),
                   std::min(mapSize - 1, static_cast<int>(std::floor(hi.x))),
                   std::min(mapSize - 1, static_cast<int>(std::floor(hi.y))), half};
}

namespace {

#if defined(__SSE4_1__)
// isSurface on four depths: all bits set in the lanes that hold a surface.
inline __m128 surfaceLanes(const LightMap& map, __m128 lsDepth) {
  const __m128 finite = _mm_cmplt_ps(lsDepth, _mm_set1_ps(kInfinity));
  return map.orthographic ? finite : _mm_and_ps(finite, _mm_cmpgt_ps(lsDepth, _mm_setzero_ps()));
}
#endif

// The greatest surface depth of `count` texels of a far-layer row, and the least of a nearest-layer
// row (`top`, when given), into `deepest` and `shallowest` (isSurface; texels without a surface leave
// them as they are).
void surfaceDepthRange(const LightMap& map, const float* far, const float* top, int count, float& deepest,
                       float& shallowest) {
  int i = 0;
#if defined(__SSE4_1__)
  const __m128 infinity = _mm_set1_ps(kInfinity), minusInfinity = _mm_set1_ps(-kInfinity);
  __m128 deep = minusInfinity, shallow = infinity;
  for (; i + 4 <= count; i += 4) {
    const __m128 f = _mm_loadu_ps(far + i);
    deep = _mm_max_ps(deep, _mm_blendv_ps(minusInfinity, f, surfaceLanes(map, f)));
    if (top) {
      const __m128 t = _mm_loadu_ps(top + i);
      shallow = _mm_min_ps(shallow, _mm_blendv_ps(infinity, t, surfaceLanes(map, t)));
    }
  }
  float lanes[4];
  _mm_storeu_ps(lanes, deep);
  deepest = std::max({deepest, lanes[0], lanes[1], lanes[2], lanes[3]});
  _mm_storeu_ps(lanes, shallow);
  shallowest = std::min({shallowest, lanes[0], lanes[1], lanes[2], lanes[3]});
#endif
  for (; i < count; ++i) {
    if (isSurface(map, far[i])) deepest = std::max(deepest, far[i]);
    if (top && isSurface(map, top[i])) shallowest = std::min(shallowest, top[i]);
  }
}

}  // namespace

void farthestZetaRow(const LightMap& map, const Space& space, const float* lsFar, int count, float* out) {
  int i = 0;
#if defined(__SSE4_1__)
  // Space::zeta on four texels, every lane's computed and the surface test picking it.
  const __m128 minusOne = _mm_set1_ps(-1.0f), none = _mm_set1_ps(space.zetaNone);
  for (; i + 4 <= count; i += 4) {
    const __m128 z = _mm_loadu_ps(lsFar + i);
    const __m128 zeta = space.orthographic ? z : _mm_div_ps(minusOne, z);
    _mm_storeu_ps(out + i, _mm_blendv_ps(none, zeta, surfaceLanes(map, z)));
  }
#endif
  for (; i < count; ++i) out[i] = isSurface(map, lsFar[i]) ? space.zeta(lsFar[i]) : space.zetaNone;
}

bool ribbonOneSided(const Edge& e, RibbonSides sides) {
  const float wanted = sides == RibbonSides::Outer ? 1.0f : -1.0f;
  return sides != RibbonSides::Both && e.endSideA * wanted <= 0.0f && e.endSideB * wanted <= 0.0f;
}

namespace {

// ribbonMayTake's test of a one-sided ribbon, set up once per edge: the signed distance across the
// edge's line towards the wanted side is linear, so over a rectangle it is greatest at the corner the
// signs of the wanted normal pick (float rounding keeps each term's order, so no other corner's value
// is greater).
struct WantedSide {
  Vec2 a, normal;  // normal: the outward normal turned to the wanted side
  explicit WantedSide(const Edge& e, RibbonSides sides)
      : a(e.a), normal(sides == RibbonSides::Outer ? e.outward : -e.outward) {}
  bool reaches(Vec2 lo, Vec2 hi) const {
    constexpr float kSlack = 1.0f;  // texels; far beyond the rounding of the per-texel side test
    const float x = normal.x >= 0.0f ? hi.x : lo.x, y = normal.y >= 0.0f ? hi.y : lo.y;
    return (x - a.x) * normal.x + (y - a.y) * normal.y >= -kSlack;
  }
};

// Calls f(tile index) for each `tileSize` tile of a mapSize map that the box reaches and where the
// edge's ribbon may take a texel on the wanted sides (ribbonMayTake).
template <typename F>
void forEachRibbonTile(const Edge& e, const RibbonBox& box, RibbonSides sides, int mapSize, int tileSize, const F& f) {
  if (box.i0 > box.i1 || box.j0 > box.j1) return;
  const int tiles = (mapSize + tileSize - 1) / tileSize;
  const int ti0 = box.i0 / tileSize, ti1 = box.i1 / tileSize, tj0 = box.j0 / tileSize, tj1 = box.j1 / tileSize;
  if (!ribbonOneSided(e, sides)) {
    for (int tj = tj0; tj <= tj1; ++tj)
      for (int ti = ti0; ti <= ti1; ++ti) f(static_cast<size_t>(tj) * tiles + ti);
    return;
  }
  const WantedSide side(e, sides);
  for (int tj = tj0; tj <= tj1; ++tj)
    for (int ti = ti0; ti <= ti1; ++ti) {
      // The tile's texel centres.
      const Vec2 lo(static_cast<float>(ti * tileSize) + 0.5f, static_cast<float>(tj * tileSize) + 0.5f);
      const Vec2 hi(static_cast<float>(std::min(mapSize, (ti + 1) * tileSize)) - 0.5f,
                    static_cast<float>(std::min(mapSize, (tj + 1) * tileSize)) - 0.5f);
      if (side.reaches(lo, hi)) f(static_cast<size_t>(tj) * tiles + ti);
    }
}

}  // namespace

bool ribbonMayTake(const Edge& e, RibbonSides sides, Vec2 lo, Vec2 hi) {
  return !ribbonOneSided(e, sides) || WantedSide(e, sides).reaches(lo, hi);
}

void farTilesForRibbons(const std::vector<Edge>& edges, const Space& space, int mapSize, float marginTexels,
                        RibbonSides sides, std::vector<uint8_t>& tiles) {
  const int n = (mapSize + kFarLayerTile - 1) / kFarLayerTile;
  tiles.assign(static_cast<size_t>(n) * n, 0);
  for (const Edge& e : edges)
    forEachRibbonTile(e, mapRangeRibbonBox(e, space, mapSize, marginTexels), sides, mapSize, kFarLayerTile,
                      [&](size_t tile) { tiles[tile] = 1; });
}

void rasterizeRibbons(const std::vector<Edge>& edges, const Space& space, const LightMap& map, RibbonSides sides,
                      float marginTexels, const RibbonFilter& filter, RibbonImage& out, RibbonReach reach) {
  const int mapSize = map.size;
  if (map.lsFarDepth.width() != mapSize || map.lsFarDepth.height() != mapSize)
    fail(
        "rasterizeRibbons: the light map was rendered without its far layer (LightMapLayers::NearestAndFarthest or "
        "NearestDepthAndFarthest)");
  // Every texel lies in one tile below, which writes it once: no serial pass over the whole image.
  constexpr int kTile = kRibbonTile;
  const int tiles = ribbonTilesPerRow(mapSize);
  const size_t tileCount = static_cast<size_t>(tiles) * tiles;
  if (out.texels.width() != mapSize || out.texels.height() != mapSize || out.mayHoldRibbon.size() != tileCount) {
    out.texels.resizeForOverwrite(mapSize, mapSize);
    out.mayHoldRibbon.assign(tileCount, 1);  // storage of unknown content: every tile is written
  }
  std::vector<RibbonBox> boxes(edges.size());
  std::vector<std::vector<uint32_t>> bins(tileCount);
  // Whether `holds(x, y)` at every texel that the per-texel tests below may probe kHiddenProbeTexels
  // beyond the edge (false where one lies outside the map): the edge is sampled at quarter-texel
  // steps, each sample with the 3 x 3 texels around it, which hold every probe texel of the points
  // between samples.
  const auto everyProbeTexel = [&](const Edge& e, const auto& holds) {
    const Vec2 d = e.b - e.a;
    const int steps = std::max(1, static_cast<int>(std::ceil(4.0f * glm::length(d))));
    if (steps > 4 * mapSize) return false;
    for (int q = 0; q <= steps; ++q) {
      const float u = static_cast<float>(q) / static_cast<float>(steps);
      const Vec2 probe = e.a + u * d + kHiddenProbeTexels * e.outward;
      const int pi = static_cast<int>(std::floor(probe.x)), pj = static_cast<int>(std::floor(probe.y));
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          const int x = pi + di, y = pj + dj;
          if (x < 0 || y < 0 || x >= mapSize || y >= mapSize || !holds(x, y)) return false;
        }
    }
    return true;
  };
  // An edge whose every candidate the hidden-shadow test drops (below) is not rasterized: where the
  // topmost surface kHiddenProbeTexels beyond each point of the edge lies above the edge's nearest
  // end (a contour behind the object's own front, most silhouettes of a dense model), against the
  // edge's least depth, so that a skipped edge is one the per-texel test would have dropped everywhere.
  const auto hidden = [&](const Edge& e) {
    const Image<float>* top = filter.topDepth;
    if (!top) return false;
    const float cMin = std::min(e.zetaA, e.zetaB);
    const float cBound = cMin - 1e-5f * std::abs(cMin);  // below every c of the edge, rounding included
    return everyProbeTexel(e, [&](int x, int y) {
      const float depth = (*top)(x, y);
      return std::isfinite(depth) && space.zeta(depth) < cBound;
    });
  };
  // With only the inner side wanted and only footprint borders taken (kirsch), neither is an edge
  // inside its object's footprint: where the map sees the edge's own object beyond each point of
  // the edge, the footprint test drops every candidate of the edge.
  const bool wantOuter = sides != RibbonSides::Inner, wantInner = sides != RibbonSides::Outer;
  const auto insideFootprint = [&](const Edge& e) {
    const Image<int32_t>* coverage = filter.coverage;
    if (!coverage || !filter.footprintBorderOnly || wantOuter) return false;
    return everyProbeTexel(e, [&](int x, int y) { return (*coverage)(x, y) == e.objectId; });
  };
  static const SpanPath widest = spanPathAvailable(SpanPath::Avx512) ? SpanPath::Avx512
                                 : spanPathAvailable(SpanPath::Sse)  ? SpanPath::Sse
                                                                     : SpanPath::Scalar;
  std::vector<uint8_t> skip(edges.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, edges.size(), 256), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t k = range.begin(); k < range.end(); ++k)
      skip[k] = hidden(edges[k]) || insideFootprint(edges[k]) ? 1 : 0;
  });
  // Each ribbon first as wide as the widest penumbra the map's depth range allows (ribbonBox at
  // zetaFar); narrowed (RibbonReach), then only as wide as the widest one on the surfaces there are:
  // down to the deepest surface the far layer holds in the tiles the first box reaches (capped at
  // zetaFar), from the edge or (SurfacesInRange) from the shallowest surface the map sees there.
  // The tiles of the box where the edge may take a texel on the wanted sides (ribbonMayTake).
  const auto forEachTile = [&](size_t k, const auto& f) {
    forEachRibbonTile(edges[k], boxes[k], sides, mapSize, kTile, f);
  };
  const auto empty = [](const RibbonBox& box) { return box.i0 > box.i1 || box.j0 > box.j1; };
  std::vector<uint8_t> reached(tileCount, 0);
  for (size_t k = 0; k < edges.size(); ++k) {
    if (skip[k]) continue;
    boxes[k] = mapRangeRibbonBox(edges[k], space, mapSize, marginTexels);
    forEachTile(k, [&](size_t tile) { reached[tile] = 1; });
  }
  // The far layer where a ribbon may reach (a map rasterized with farTilesForRibbons' tiles has it there).
  static_assert(kFarLayerTile % kTile == 0, "a ribbon tile lies in one far-layer tile");
  if (!map.farTiles.empty()) {
    const int farTilesPerRow = (mapSize + kFarLayerTile - 1) / kFarLayerTile;
    for (int tile = 0; tile < tiles * tiles; ++tile)
      if (reached[static_cast<size_t>(tile)] &&
          !map.farTiles[static_cast<size_t>((tile / tiles) * kTile / kFarLayerTile) * farTilesPerRow +
                        static_cast<size_t>((tile % tiles) * kTile / kFarLayerTile)])
        fail(
            "rasterizeRibbons: a ribbon reaches texel ({}, {}), where the light map has no far layer (rasterize it "
            "with farTilesForRibbons' tiles)",
            (tile % tiles) * kTile, (tile / tiles) * kTile);
  }
  const bool narrowed = reach != RibbonReach::MapDepthRange, fromTop = reach == RibbonReach::SurfacesInRange;
  // Per reached tile, the zeta of its deepest surface (-infinity: none) and of its shallowest one.
  std::vector<float> deepest(narrowed ? tileCount : 0, -kInfinity), shallowest(fromTop ? tileCount : 0, kInfinity);
  if (narrowed)
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles * tiles), [&](const tbb::blocked_range<int>& range) {
      for (int tile = range.begin(); tile < range.end(); ++tile) {
        if (!reached[static_cast<size_t>(tile)]) continue;
        const int ti = tile % tiles, tj = tile / tiles;
        // The deepest and shallowest surface depths, then their zeta: zeta rises with depth (and its
        // rounding never reverses an order), so this is the greatest and least zeta of the surfaces.
        float deep = -kInfinity, shallow = kInfinity;
        for (int j = tj * kTile; j < std::min(mapSize, tj * kTile + kTile); ++j)
          surfaceDepthRange(map, map.lsFarDepth.row(j) + ti * kTile,
                            fromTop ? map.lsDepth.row(j) + ti * kTile : nullptr, std::min(mapSize - ti * kTile, kTile),
                            deep, shallow);
        deepest[static_cast<size_t>(tile)] = deep > -kInfinity ? space.zeta(deep) : -kInfinity;
        if (fromTop) shallowest[static_cast<size_t>(tile)] = shallow < kInfinity ? space.zeta(shallow) : kInfinity;
      }
    });
  for (size_t k = 0; k < edges.size(); ++k) {
    if (skip[k] || empty(boxes[k])) continue;
    if (narrowed) {
      float below = -kInfinity, from = kInfinity;
      forEachTile(k, [&](size_t tile) {
        below = std::max(below, deepest[tile]);
        if (fromTop) from = std::min(from, shallowest[tile]);
      });
      if (below == -kInfinity) continue;  // no surface anywhere the ribbon could fall
      // Never wider than the map's range allows: the far layer is there only in the first box's tiles.
      const float width = std::min(penumbraTexels(edges[k], space.zetaFar),
                                   penumbraTexels(edges[k], std::min(below, space.zetaFar), from));
      boxes[k] = ribbonBox(edges[k], width, mapSize, marginTexels);
    }
    forEachTile(k, [&](size_t tile) { bins[tile].push_back(static_cast<uint32_t>(k)); });
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles * tiles), [&](const tbb::blocked_range<int>& range) {
    // The tile's priorities and winners (texels are the tile's alone: no other task writes them),
    // copied out once when the tile is done, and one span's geometry.
    float priority[kTile * kTile];
    RibbonTexel winners[kTile * kTile];
    float far[kTile * kTile];  // the tile's far layer in zeta, taken where a ribbon reaches only
    RibbonSpanTexels span;
    // Each row's greatest priority (never below it: priorities only fall) and the tile's.
    float rowMax[kTile];
    std::vector<std::pair<float, uint32_t>> order;
    for (int tile = range.begin(); tile < range.end(); ++tile) {
      const int ti = tile % tiles, tj = tile / tiles;
      const int tileWidth = std::min(kTile, mapSize - ti * kTile), tileHeight = std::min(kTile, mapSize - tj * kTile);
      const std::vector<uint32_t>& bin = bins[static_cast<size_t>(tile)];
      uint8_t& mayHoldRibbon = out.mayHoldRibbon[static_cast<size_t>(tile)];
      if (bin.empty()) {  // no ribbon reaches the tile (most of a map): emptied where it may hold one
        if (mayHoldRibbon)
          for (int j = tj * kTile; j < tj * kTile + tileHeight; ++j)
            std::fill_n(out.texels.row(j) + ti * kTile, tileWidth, kNoRibbon);
        mayHoldRibbon = 0;
        continue;
      }
      bool tileTook = false;
      for (int j = 0; j < tileHeight; ++j)
        farthestZetaRow(map, space, map.lsFarDepth.row(tj * kTile + j) + ti * kTile, tileWidth, far + j * kTile);
      std::fill(priority, priority + kTile * kTile, kInfinity);
      std::fill(winners, winners + kTile * kTile, kNoRibbon);
      std::fill(rowMax, rowMax + kTile, kInfinity);
      float tileMax = kInfinity;
      bool tileMaxStale = false;
      // Where outer sides are wanted the tile's edges go in the order of the least priority each
      // can give in it (c at least its lesser end's, the distance at least the tile's texel centres'
      // to the segment's bounding box, lowered by least()'s margins below), so that the nearest
      // ribbons claim the texels first and the spans of the rest are trimmed to little or nothing;
      // once every texel is won more cheaply than the next edge can give, the tile is done. Inner
      // sides alone (kirsch) leave most of a tile unclaimed, outside the footprints, and there the
      // order and its upkeep cost more than they saved: those edges go in index order. Which edge
      // wins a texel does not depend on the order: the least priority, then the lowest index (the
      // compares below).
      const bool ordered = wantOuter;
      if (ordered) {
        order.clear();
        const float x0 = static_cast<float>(ti * kTile) + 0.5f, x1 = x0 + static_cast<float>(tileWidth - 1);
        const float y0 = static_cast<float>(tj * kTile) + 0.5f, y1 = y0 + static_cast<float>(tileHeight - 1);
        for (uint32_t k : bin) {
          const Edge& e = edges[k];
          const float rateFloor = e.rate * (1.0f - 1e-5f);
          const float dx = std::max({0.0f, std::min(e.a.x, e.b.x) - x1, x0 - std::max(e.a.x, e.b.x)});
          const float dy = std::max({0.0f, std::min(e.a.y, e.b.y) - y1, y0 - std::max(e.a.y, e.b.y)});
          const float distance = std::sqrt(dx * dx + dy * dy);
          const float cLeast = std::min(e.zetaA, e.zetaB);
          const float cFloor = cLeast - 1e-5f * std::abs(cLeast);
          order.emplace_back(cFloor + std::max(distance - 0.01f - 1e-5f * distance, 0.0f) * rateFloor, k);
        }
        std::sort(order.begin(), order.end());
      }
      for (size_t q = 0; q < bin.size(); ++q) {
        const uint32_t k = ordered ? order[q].second : bin[q];
        if (ordered) {
          if (tileMaxStale) {
            tileMax = *std::max_element(rowMax, rowMax + tileHeight);
            tileMaxStale = false;
          }
          if (tileMax <= order[q].first) break;  // nothing left in the tile that this edge or a later one can take
        }
        const Edge& e = edges[k];
        const RibbonBox& box = boxes[k];
        const Vec2 d = e.b - e.a;
        const float invLength2 = 1.0f / glm::dot(d, d);
        const int i0 = std::max(box.i0, ti * kTile), i1 = std::min(box.i1, ti * kTile + kTile - 1);
        const int j0 = std::max(box.j0, tj * kTile), j1 = std::min(box.j1, tj * kTile + kTile - 1);
        const float xLo = std::min(e.a.x, e.b.x), xHi = std::max(e.a.x, e.b.x);
        const float yLo = std::min(e.a.y, e.b.y), yHi = std::max(e.a.y, e.b.y);
        const float h = box.halfWidth;
        // Each row's span is trimmed at both ends to the texels this edge may still take: a texel
        // whose winner's priority is at most the least this edge can give there (c at least its
        // lesser end's, the distance at least the row's to the segment's box and the texel's to its
        // line, lowered by a margin well beyond the rounding of the per-texel values) is one the
        // per-texel compare p < priority rejects anyway.
        const float cLeast = std::min(e.zetaA, e.zetaB);
        const float cFloor = cLeast - 1e-5f * std::abs(cLeast);
        const float rateFloor = e.rate * (1.0f - 1e-5f);
        const auto least = [&](float dy, float across) {
          const float distance = std::max(dy, std::abs(across));
          return cFloor + std::max(distance - 0.01f - 1e-5f * distance, 0.0f) * rateFloor;
        };
        // The span pass's view of the edge; each row adds its own (RibbonSpan).
        const RibbonSpan edgeSpan{.ax = e.a.x,
                                  .bx = e.b.x,
                                  .dx = d.x,
                                  .dy = d.y,
                                  .invLength2 = invLength2,
                                  .outX = e.outward.x,
                                  .outY = e.outward.y,
                                  .endSideA = e.endSideA,
                                  .endSideB = e.endSideB,
                                  .zetaA = e.zetaA,
                                  .zetaB = e.zetaB,
                                  .rate = e.rate,
                                  .halfWidth = h,
                                  .objectId = e.objectId,
                                  .bothSides = wantOuter && wantInner,
                                  .wantOuter = wantOuter,
                                  .ties = ordered,
                                  .orthographic = space.orthographic};
        // The texels of the edge's line it may take lie within h of the line on either side; with one
        // side wanted and neither end's corner putting the texels beyond it on that side (kirsch's inner
        // sides at convex corners, smoothies' outer ones at concave corners), on that side alone: the
        // others are the pass's to reject, so they are not visited.
        const bool oneSide = ribbonOneSided(e, sides);
        const float acrossLo = oneSide && wantOuter ? 0.0f : -h, acrossHi = oneSide && !wantOuter ? 0.0f : h;
        for (int j = j0; j <= j1; ++j) {
          // The texels of the row within h of the segment lie within h of its bounding box and
          // within h of its line: only that span is visited (widened by a texel against rounding;
          // the exact test below decides).
          const float y = static_cast<float>(j) + 0.5f;
          const float dy = std::max({0.0f, yLo - y, y - yHi});
          if (dy > h + 1.0f) continue;
          if (ordered && rowMax[j - tj * kTile] <= least(dy, 0.0f)) continue;  // the row is won more cheaply
          const float reach = std::sqrt(std::max(h * h - dy * dy, 0.0f));
          float spanLo = xLo - reach, spanHi = xHi + reach;
          if (std::abs(e.outward.x) > 1e-3f) {
            // (q - a) . n within [acrossLo, acrossHi] along the row, solved for q.x.
            const float across = (y - e.a.y) * e.outward.y;
            const float x0 = e.a.x + (acrossLo - across) / e.outward.x, x1 = e.a.x + (acrossHi - across) / e.outward.x;
            spanLo = std::max(spanLo, std::min(x0, x1));
            spanHi = std::min(spanHi, std::max(x0, x1));
          }
          int si0 = std::max(i0, static_cast<int>(std::floor(spanLo - 0.5f)) - 1);
          const int si1 = std::min(i1, static_cast<int>(std::ceil(spanHi - 0.5f)) + 1);
          RibbonTexel* row = winners + (j - tj * kTile) * kTile;
          // Two passes over the span: the geometry of every texel and the filters that read the
          // texel's own row of other images, in vectors (below); then the candidates that beat the
          // texel's current winner through the filters that read the texel 1.5 texels beyond the
          // edge. Every filter only drops candidates.
          int count = si1 - si0 + 1;
          if (count <= 0) continue;
          // Trimmed for the narrower paths; the AVX-512 pass takes a whole span in at most two steps,
          // where trimming cost more than the texels it saved (what it drops, p >= priority, the pass
          // rejects anyway).
          if (widest != SpanPath::Avx512) {
            const float* rowPriority = priority + (j - tj * kTile) * kTile + (si0 - ti * kTile);
            const float across0 = (static_cast<float>(si0) + 0.5f - e.a.x) * e.outward.x + (y - e.a.y) * e.outward.y;
            int lo = 0, hi = count - 1;
#if defined(__SSE4_1__)
            {
              // Four texels at a time from each end (on a dense model most of a span is already won
              // by nearer edges), least() lane by lane in the same operations and order.
              const __m128 zero = _mm_setzero_ps(), vDy = _mm_set1_ps(dy), vAcross0 = _mm_set1_ps(across0),
                           vOutX = _mm_set1_ps(e.outward.x), vFloor = _mm_set1_ps(cFloor),
                           vRate = _mm_set1_ps(rateFloor), signBit = _mm_set1_ps(-0.0f);
              const auto rejected4 = [&](int at) {  // bit l: texel at + l is one the edge cannot take
                const __m128 index = _mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(at), _mm_setr_epi32(0, 1, 2, 3)));
                const __m128 across = _mm_andnot_ps(signBit, _mm_add_ps(vAcross0, _mm_mul_ps(index, vOutX)));
                const __m128 distance = _mm_blendv_ps(vDy, across, _mm_cmplt_ps(vDy, across));
                const __m128 reach =
                    _mm_sub_ps(_mm_sub_ps(distance, _mm_set1_ps(0.01f)), _mm_mul_ps(_mm_set1_ps(1e-5f), distance));
                const __m128 bound =
                    _mm_add_ps(vFloor, _mm_mul_ps(_mm_blendv_ps(reach, zero, _mm_cmplt_ps(reach, zero)), vRate));
                return _mm_movemask_ps(_mm_cmple_ps(_mm_loadu_ps(rowPriority + at), bound));
              };
              while (hi - lo >= 3) {
                const int bits = rejected4(lo);
                if (bits != 0xf) {
                  lo += __builtin_ctz(~bits);
                  break;
                }
                lo += 4;
              }
              while (hi - lo >= 3) {
                const int bits = rejected4(hi - 3);
                if (bits != 0xf) {
                  hi -= __builtin_clz(static_cast<unsigned>(~bits & 0xf)) - 28;
                  break;
                }
                hi -= 4;
              }
            }
#endif
            while (lo <= hi && rowPriority[lo] <= least(dy, across0 + static_cast<float>(lo) * e.outward.x)) ++lo;
            while (hi >= lo && rowPriority[hi] <= least(dy, across0 + static_cast<float>(hi) * e.outward.x)) --hi;
            if (hi < lo) continue;
            si0 += lo;
            count = hi - lo + 1;
          }
          float* prio = priority + (j - tj * kTile) * kTile + (si0 - ti * kTile);
          // The geometry of every texel of the span and the filters that read the texel's own row of
          // other images (the object the map sees, the far layer, the topmost surface), without branches,
          // 16 or 4 texels to a vector (ribbonSpanScalar says how; the same values at every width).
          RibbonSpan input = edgeSpan;
          input.aqy = y - e.a.y;
          input.by = y - e.b.y;
          input.first = si0;
          input.far = far + (j - tj * kTile) * kTile + (si0 - ti * kTile);
          input.coverage = filter.coverage ? filter.coverage->row(j) + si0 : nullptr;
          input.top = filter.topDepth ? filter.topDepth->row(j) + si0 : nullptr;
          input.priority = prio;
          spanPass(widest, input, count, span);
          bool took = false;
          for (uint32_t candidates = span.taken; candidates != 0; candidates &= candidates - 1) {
            const int m = __builtin_ctz(candidates), i = si0 + m;
            // A tie goes to the lower index, as in index order, where the first to come keeps it.
            if (span.p[m] == prio[m] && static_cast<int32_t>(k) > row[i - ti * kTile].edge) continue;
            const float u = span.u[m], c = span.c[m], distance = span.distance[m], p = span.p[m];
            const bool outer = (span.outer >> m) & 1u;
            const Image<int32_t>* coverage = filter.coverage;
            // The texel kHiddenProbeTexels beyond the edge's nearest point; outside the map nothing is seen.
            const Vec2 probe = e.a + u * d + kHiddenProbeTexels * e.outward;
            const int pi = static_cast<int>(std::floor(probe.x)), pj = static_cast<int>(std::floor(probe.y));
            const bool probeInMap = pi >= 0 && pj >= 0 && pi < mapSize && pj < mapSize;
            if (!outer && coverage && filter.footprintBorderOnly && probeInMap && (*coverage)(pi, pj) == e.objectId)
              continue;
            if (const Image<float>* top = filter.topDepth; top && probeInMap) {
              // Depths as zeta; an empty texel (infinite depth) lies below everything.
              const float depth = (*top)(pi, pj);
              if (std::isfinite(depth) && space.zeta(depth) < c) continue;
            }
            prio[m] = p;
            row[i - ti * kTile] = RibbonTexel{c, outer ? distance : -distance, static_cast<int32_t>(k)};
            took = true;
            tileTook = true;
          }
          if (ordered && took) {
            const float* rowPriority = priority + (j - tj * kTile) * kTile;
            rowMax[j - tj * kTile] = *std::max_element(rowPriority, rowPriority + tileWidth);
            tileMaxStale = true;
          }
        }
      }
      for (int j = tj * kTile; j < std::min(mapSize, tj * kTile + kTile); ++j) {
        const RibbonTexel* from = winners + (j - tj * kTile) * kTile;
        RibbonTexel* to = out.texels.row(j) + ti * kTile;
        std::copy_n(from, tileWidth, to);
      }
      mayHoldRibbon = tileTook ? 1 : 0;
    }
  });
}

}  // namespace plm

namespace {

// The lower limit's fit (findLowerLimits): rays per probed receiver (a 4 x 4 grid over the light's
// parameter square, one packet), the share of Equation 1's prediction below which a receiver is
// taken as shadowed by more than the ribbon's edge, and how many receivers along a texel's ray are
// probed.
constexpr int kProfileGrid = 4;
constexpr int kProfileSamples = kProfileGrid * kProfileGrid;
constexpr float kProfileFraction = 0.5f;
constexpr int kMaxProbes = 16;
// Fewer samples than Equation 1 predicts by at least this many (2/16 of the light): a prediction
// below it cannot be told from no light by 16 samples, and is left alone.
constexpr float kProfileMinDeficit = 2.0f;
// Receivers whose probes start within this many texels (of the map, at their depth) of each other
// share the first stage's packets (PlmTechnique::probe).
constexpr float kPairedProbeTexels = 4.0f;
// The cells of the 4 x 4 grid (row-major indices) in the order a probe's stages trace them, and where
// each stage ends: a checkerboard, then the other one in two quarters of one cell per row and column.
constexpr int kProbeOrder[kProfileSamples] = {0, 2, 5, 7, 8, 10, 13, 15, 1, 4, 11, 14, 3, 6, 9, 12};
constexpr int kProbeStages = 3;
constexpr int kProbeStageEnd[kProbeStages] = {8, 12, 16};
static_assert(kProbeStageEnd[kProbeStages - 1] == kProfileSamples &&
                  16 % (kProbeStageEnd[1] - kProbeStageEnd[0]) == 0 &&
                  16 % (kProbeStageEnd[2] - kProbeStageEnd[1]) == 0 && 16 % kProbeStageEnd[0] == 0,
              "every sample traced once; a stage's packet holds whole jobs");
static_assert(kProfileSamples <= 16, "one Embree packet (RayScene::occluded16)");

// PlmTechnique::ribbonAt_'s bits: a ribbon holds the texel (limits_ is written there); its c lies below
// zetaNone.
constexpr uint8_t kRibbonHere = 1, kRibbonBelowNone = 2;

// Classes of the 2x2 footprint of a bilinear fetch (PlmTechnique::footprint2x2_).
constexpr uint8_t kFootprintMixed = 0, kFootprintRibbonFree = 1, kFootprintOneRibbon = 2;

// What fetchSetUp reads besides the pixels: the light's centre (or direction, for a directional
// light: then fromPoint is 0, so that towardLight - fromPoint P is exact either way), the map's size.
struct FetchConstants {
  float towardX, towardY, towardZ, fromPoint;
  int mapSize;
};

// The set-up of a run of pixels' fetches in plm's visibility pass, arithmetic alone: the receiver's
// bias (none where it faces away from the light's centre), the bilinear weights and the four texel
// indices of its fetch, and its biased depth in zeta. Restrict-qualified arrays and selects only, so
// that the loop vectorizes (a conditional load of the bias kept it scalar).
template <bool kOrtho>
inline __attribute__((always_inline)) void fetchSetUpKernel(
    const FetchConstants k, int count, const float* __restrict position, const float* __restrict normal,
    const float* __restrict s, const float* __restrict t, const float* __restrict lsDepth,
    const float* __restrict receiverBias, float* __restrict ws, float* __restrict wt, float* __restrict zc,
    float* __restrict bias, int32_t* __restrict i0, int32_t* __restrict i1, int32_t* __restrict j0,
    int32_t* __restrict j1) {
  const float lastIndex = static_cast<float>(k.mapSize);
  const int last = k.mapSize - 1;
  for (int x = 0; x < count; ++x) {
    // A surface that faces away from the light's centre is never the one the map holds at its texel
    // (the map sees the surfaces that face the centre), so it cannot shadow itself through the
    // compare: the bias would only lift it above the surface that covers it.
    const float dx = k.towardX - k.fromPoint * position[3 * x], dy = k.towardY - k.fromPoint * position[3 * x + 1],
                dz = k.towardZ - k.fromPoint * position[3 * x + 2];
    const bool facesAway = normal[3 * x] * dx + normal[3 * x + 1] * dy + normal[3 * x + 2] * dz < 0.0f;  // glm::dot
    const float loaded = receiverBias[x];  // at every pixel: a conditional load would not vectorize
    const float b = facesAway ? 0.0f : loaded;
    bias[x] = b;
    // One bilinear fetch of (c, g, b, p_i), clamped to the map's border texels (the position is
    // limited to [-1, size] first, which the clamps below make no difference to, so that a pixel
    // outside the map, whose result is not used, converts no out-of-range float).
    const float fs = s[x] - 0.5f, ft = t[x] - 0.5f;
    const float is = std::floor(fs), it = std::floor(ft);
    ws[x] = fs - is;
    wt[x] = ft - it;
    const int si = static_cast<int>(!(is >= -1.0f) ? -1.0f : std::min(is, lastIndex));
    const int ti = static_cast<int>(!(it >= -1.0f) ? -1.0f : std::min(it, lastIndex));
    i0[x] = std::clamp(si, 0, last);
    i1[x] = std::clamp(si + 1, 0, last);
    j0[x] = std::clamp(ti, 0, last);
    j1[x] = std::clamp(ti + 1, 0, last);
    const float biased = lsDepth[x] - b;
    // Space::zeta, without a branch; behind a local light, below every g.
    zc[x] = kOrtho ? biased : (biased > 0.0f ? -1.0f / biased : -kInfinity);
  }
}

#define PENUMBRA_FETCH_SET_UP_PARAMETERS                                                                      \
  const FetchConstants k, int count, const float *__restrict position, const float *__restrict normal,        \
      const float *__restrict s, const float *__restrict t, const float *__restrict lsDepth,                  \
      const float *__restrict receiverBias, float *__restrict ws, float *__restrict wt, float *__restrict zc, \
      float *__restrict bias, int32_t *__restrict i0, int32_t *__restrict i1, int32_t *__restrict j0,         \
      int32_t *__restrict j1
PENUMBRA_CLONES_AVX512 void fetchSetUpOrtho(PENUMBRA_FETCH_SET_UP_PARAMETERS) {
  fetchSetUpKernel<true>(k, count, position, normal, s, t, lsDepth, receiverBias, ws, wt, zc, bias, i0, i1, j0, j1);
}
PENUMBRA_CLONES_AVX512 void fetchSetUpPerspective(PENUMBRA_FETCH_SET_UP_PARAMETERS) {
  fetchSetUpKernel<false>(k, count, position, normal, s, t, lsDepth, receiverBias, ws, wt, zc, bias, i0, i1, j0, j1);
}
#undef PENUMBRA_FETCH_SET_UP_PARAMETERS

// Beyond this spread of b over the four texels of a fetch, relative to the receiver's distance to
// it, the texels' b are not interpolated (oneRibbon).
constexpr float kTransitionSpread = 1.0f / 16.0f;

// One texel of the penumbra limit map (Sec. 2.2 stores the same four in RGBA).
struct PlmTexel {
  float c, g, b, pi;
  int32_t edge;  //!< the ribbon's edge (index into edges_); -1 where no ribbon
};

class PlmTechnique final : public ShadowTechnique {
 public:
  explicit PlmTechnique(const PlmOptions& options) : options_(options) {}

  std::string_view name() const override { return "plm"; }

 private:
  static constexpr LightMapLayers kLayers = LightMapLayers::NearestAndFarthest;

  void reserveImpl(int, int) override {
    const int n = options_.lightMap.size;
    reserveShadowMap(options_.lightMap, map_, kLayers);
    plm::reserveRibbons(n, ribbons_);
    resetInParallel(limits_, n, n, PlmTexel{});
    resetInParallel(g_, n, n, 0.0f);
    resetInParallel(ribbonAt_, n, n, uint8_t{0});
    resetInParallel(footprint2x2_, n, n, uint8_t{0});
  }

  void prepareImpl(const Scene& scene, const Light& sceneLight) override {
    plm::emitterRadius(sceneLight, "plm");  // rejects unsupported shapes before any work
    // The silhouettes come from the map's projection alone, and the far layer is kept only where
    // their ribbons can reach (the fit of b reads it at ribbon texels only): the map is fitted first
    // and rasterized once they are known.
    fitShadowMap(scene, sceneLight, options_.lightMap, map_);
    light_ = lightAtMapOrigin(sceneLight, map_);  // silhouettes and b's rays look from the map's origin
    const Light& light = *light_;
    setHorizonClamp(options_.lightMap.horizon, light);
    space_ = plm::makeSpace(map_, light, "plm", true);
    table_ = VisibilityToIllumination::forLight(light);
    edges_ = plm::silhouetteEdges(scene, light, map_, space_, &edgeCache_);
    const std::vector<plm::Edge>& edges = edges_;
    plm::farTilesForRibbons(edges, space_, map_.size, options_.marginTexels, plm::RibbonSides::Both, farTiles_);
    rasterizeLightMap(scene, map_, kLayers, farTiles_);
    plm::rasterizeRibbons(edges, space_, map_, plm::RibbonSides::Both, options_.marginTexels,
                          plm::RibbonFilter{&map_.objectId, &map_.lsDepth, false}, ribbons_);
    const Image<plm::RibbonTexel>& ribbons = ribbons_.texels;
    const int n = map_.size;
    limits_.resizeForOverwrite(n, n);
    // Texels whose ribbon needs the lower limit b, row by row as the parallel pass finds them, then
    // in row-major order.
    std::vector<int>& needLower = needLower_;
    needLower.clear();
    coveredInRow_.resize(static_cast<size_t>(n));
    g_.resizeForOverwrite(n, n);
    ribbonAt_.resizeForOverwrite(n, n);
    const plm::Space space = space_;
    const int tiles = plm::ribbonTilesPerRow(n);
    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j) {
        std::vector<int>& covered = coveredInRow_[static_cast<size_t>(j)];
        covered.clear();
        // g of the light map first, in one branch-free loop the compiler vectorizes (Space::zeta).
        const float* depthRow = map_.lsDepth.row(j);
        float* gRow = g_.row(j);
        for (int i = 0; i < n; ++i) {
          const float depth = depthRow[i];
          const float zeta = space.orthographic ? depth : -1.0f / depth;
          gRow[i] = std::isfinite(depth) ? zeta : space.zetaNone;
        }
        const plm::RibbonTexel* ribbonRow = ribbons.row(j);
        PlmTexel* out = limits_.row(j);
        uint8_t* ribbonAt = ribbonAt_.row(j);
        // A texel without a ribbon is not written: texelAt makes it from g. A tile that holds no ribbon
        // texel (rasterizeRibbons' mayHoldRibbon, most of a map) is passed over without reading it.
        const uint8_t* tileHolds = ribbons_.mayHoldRibbon.data() + static_cast<size_t>(j / plm::kRibbonTile) * tiles;
        for (int i = 0; i < n; ++i) {
          if (!tileHolds[i / plm::kRibbonTile]) {
            const int end = std::min(n, (i / plm::kRibbonTile + 1) * plm::kRibbonTile);
            std::fill(ribbonAt + i, ribbonAt + end, uint8_t{0});
            i = end - 1;
            continue;
          }
          const plm::RibbonTexel& r = ribbonRow[i];
          if (!r.covered()) {
            ribbonAt[i] = 0;
            continue;
          }
          const float rate = edges[static_cast<size_t>(r.edge)].rate;
          PlmTexel texel{r.c, gRow[i], space.zetaNone, r.w * rate, r.edge};
          if (r.w > 0.0f) {  // raise g (step 2; see the file comment)
            texel.g = std::min(texel.g, r.c + std::max(r.w - options_.marginTexels, 0.0f) * rate);
            gRow[i] = texel.g;
          }
          covered.push_back(j * n + i);
          out[i] = texel;
          ribbonAt[i] = kRibbonHere | (texel.c < space.zetaNone ? kRibbonBelowNone : 0);
        }
      }
    });
    for (const std::vector<int>& covered : coveredInRow_)
      needLower.insert(needLower.end(), covered.begin(), covered.end());
    if (options_.fitLowerLimit && !needLower.empty()) findLowerLimits(scene, light, needLower);
    // The lit fast path of visibility() reads g alone (g_, filled with limits_ above, a quarter of its
    // size), and a class per texel of the 2x2 footprint of a bilinear fetch whose top-left texel it is
    // (clamped at the border as there): no ribbon in it, or one continuous ribbon (oneRibbon without
    // the depth test of b, which needs the receiver), or neither.
    footprint2x2_.resizeForOverwrite(n, n);
    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j) {
        const int j1 = std::min(j + 1, n - 1);
        const uint8_t *ribbonAt0 = ribbonAt_.row(j), *ribbonAt1 = ribbonAt_.row(j1);
        uint8_t* footprint = footprint2x2_.row(j);
        // No texel's c below zetaNone: the ribbon-free class, without reading the texels, in a loop the
        // compiler vectorizes (the last column's right neighbours are itself, clamped as in the fetch);
        // the rest are classed below, in the few rows and runs that have them.
        const int last = n - 1;
        uint8_t anyRibbon = 0;
        for (int i = 0; i < last; ++i) {
          const uint8_t below = (ribbonAt0[i] | ribbonAt0[i + 1] | ribbonAt1[i] | ribbonAt1[i + 1]) & kRibbonBelowNone;
          footprint[i] = below ? kFootprintMixed : kFootprintRibbonFree;
          anyRibbon |= below;
        }
        const uint8_t belowLast = (ribbonAt0[last] | ribbonAt1[last]) & kRibbonBelowNone;
        footprint[last] = belowLast ? kFootprintMixed : kFootprintRibbonFree;
        if (!(anyRibbon | belowLast)) continue;
        for (int i = 0; i < n; ++i) {
          if (footprint[i] == kFootprintRibbonFree) continue;
          const int i1 = std::min(i + 1, last);
          footprint[i] = continuousRibbon(texelAt(i, j), texelAt(i1, j), texelAt(i, j1), texelAt(i1, j1))
                             ? kFootprintOneRibbon
                             : kFootprintMixed;
        }
      }
    });
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (map_.size == 0) fail("plm: visibility() called before prepare()");
    const int n = map_.size, width = gbuffer.width();
    const bool directional = light_->isDirectional();
    const Vec3 towardLight = directional ? light_->direction() : light_->center();
    const plm::Space space = space_;
    const float* gTexels = g_.data();
    const uint8_t* footprints = footprint2x2_.data();
    const FetchConstants constants{towardLight.x, towardLight.y, towardLight.z, directional ? 0.0f : 1.0f, n};
    v.resizeForOverwrite(width, gbuffer.height());  // every pixel written below, in parallel
    const HorizonBound horizon = horizonForRows();
    forEachReceiverRow(gbuffer, map_, options_.bias, [&](int y, const ReceiverRow& row) {
      float* out = v.row(y);
      const int32_t* ids = gbuffer.objectId.row(y);
      static_assert(sizeof(Vec3) == 3 * sizeof(float));
      const auto* positions = reinterpret_cast<const float*>(gbuffer.wsPosition.row(y));
      const auto* normals = reinterpret_cast<const float*>(gbuffer.wsGeometricNormal.row(y));
      // A run of pixels in two passes: the fetch's set-up, arithmetic alone (fetchSetUp, vectorized),
      // then the fetch and Equation 2 per pixel, where most pixels take the ribbon-free compare.
      constexpr int kRun = 256;
      alignas(64) float ws[kRun], wt[kRun], zc[kRun], bias[kRun];
      alignas(64) int32_t i0[kRun], i1[kRun], j0[kRun], j1[kRun];
      for (int first = 0; first < width; first += kRun) {
        const int count = std::min(kRun, width - first);
        (space.orthographic ? fetchSetUpOrtho : fetchSetUpPerspective)(
            constants, count, positions + 3 * first, normals + 3 * first, row.s.data() + first, row.t.data() + first,
            row.lsDepth.data() + first, row.bias.data() + first, ws, wt, zc, bias, i0, i1, j0, j1);
        for (int k = 0; k < count; ++k) {
          const int x = first + k;
          if (ids[x] == kNoObject || !row.inMap[x]) {
            out[x] = 1.0f;
            continue;
          }
          const float* g0 = gTexels + static_cast<size_t>(j0[k]) * n;
          const float* g1 = gTexels + static_cast<size_t>(j1[k]) * n;
          const float g = lerp2(ws[k], wt[k], g0[i0[k]], g0[i1[k]], g1[i0[k]], g1[i1[k]]);
          // No ribbon under any of the four texels: Equation 2 reduces to the compare with g (c and b
          // interpolate to zetaNone exactly, p_i to 0), the same value without the division. The
          // flag's 2x2 texels hold the clamped footprint's (at the map's border they are a superset).
          const uint8_t footprint = footprints[static_cast<size_t>(j0[k]) * n + i0[k]];
          if (footprint == kFootprintRibbonFree) {
            out[x] = zc[k] < g ? 1.0f : 0.0f;
            continue;
          }
          ShadowReceiver r = row[x];
          r.bias = bias[k];
          out[x] = ribbonPixel(r, ids[x], footprint, i0[k], i1[k], j0[k], j1[k], ws[k], wt[k], g, zc[k]);
        }
      }
      clampRowToHorizon(gbuffer, horizon, y, out);
    });
  }

  // Texel (i, j) of the limits: as prepare() wrote it where a ribbon holds it, else no ribbon (c and b
  // at zetaNone, p_i 0) over the light map's g.
  PlmTexel texelAt(int i, int j) const {
    if (ribbonAt_(i, j) & kRibbonHere) return limits_(i, j);
    return {space_.zetaNone, g_(i, j), space_.zetaNone, 0.0f, -1};
  }

  // The bilinear interpolation of a fetch's four texels (weights ws along s, wt along t).
  static float lerp2(float ws, float wt, float a00, float a10, float a01, float a11) {
    const float top = a00 + ws * (a10 - a00), bottom = a01 + ws * (a11 - a01);
    return top + wt * (bottom - top);
  }

  // A pixel whose fetch has a ribbon under some texel: Equation 2 on the interpolated texel, or per
  // texel across an occluder transition. g and zc as visibilityImpl computed them.
  float ribbonPixel(const ShadowReceiver& r, int32_t receiver, uint8_t footprint, int i0, int i1, int j0, int j1,
                    float ws, float wt, float g, float zc) const {
    const PlmTexel t00 = texelAt(i0, j0), t10 = texelAt(i1, j0), t01 = texelAt(i0, j1), t11 = texelAt(i1, j1);
    if (std::min(std::min(t00.c, t10.c), std::min(t01.c, t11.c)) >= space_.zetaNone) return zc < g ? 1.0f : 0.0f;
    const float z = space_.zeta(r.lsDepth);
    if (!(footprint == kFootprintOneRibbon && bContinuous(t00, t10, t01, t11, z))) {
      // An occluder transition (Fig. 7 B): Equation 2 per texel, with the compares of shadow_map.h
      // (the receiver's tangent plane at the texel's centre), and the four values interpolated.
      const PlmTexel* texels[4] = {&t00, &t10, &t01, &t11};
      const int is[4] = {i0, i1, i0, i1}, js[4] = {j0, j0, j1, j1};
      const float weights[4] = {(1.0f - ws) * (1.0f - wt), ws * (1.0f - wt), (1.0f - ws) * wt, ws * wt};
      float sum = 0.0f;
      for (int k = 0; k < 4; ++k) {
        const float biasedPlane = blockerThreshold(r, is[k], js[k]), plane = biasedPlane + r.bias;
        const float zk = space_.orthographic || plane > 0.0f ? space_.zeta(plane) : -kInfinity;
        const float zck = space_.orthographic || biasedPlane > 0.0f ? space_.zeta(biasedPlane) : -kInfinity;
        const float lg = equation2(*texels[k], zk, zck, map_.objectId(is[k], js[k]) != receiver);
        sum += weights[k] * (options_.illuminationTable ? table_(lg) : lg);
      }
      return sum;
    }
    const PlmTexel texel{lerp2(ws, wt, t00.c, t10.c, t01.c, t11.c), g, lerp2(ws, wt, t00.b, t10.b, t01.b, t11.b),
                         lerp2(ws, wt, t00.pi, t10.pi, t01.pi, t11.pi), t00.edge};
    const bool otherObject = map_.objectId(i0, j0) != receiver && map_.objectId(i1, j0) != receiver &&
                             map_.objectId(i0, j1) != receiver && map_.objectId(i1, j1) != receiver;
    const float lg = equation2(texel, z, zc, otherObject);
    return options_.illuminationTable ? table_(lg) : lg;
  }

  // Equation 1, then Equation 2's three compares (the sat keeps the division's sign harmless), for a
  // receiver at depth z. The compare with g is made at zc, z moved towards the light by the bias;
  // those with c and b at z itself: the bias keeps a surface from shadowing itself through its own
  // depth in g, and neither the edge nor the lower limit is the receiver's surface (biased, a
  // receiver just under a part of the occluder rose above the b that clamps it). Where the map holds
  // another object than the receiver's (otherObject), g is not the receiver's surface, so a receiver
  // below the edge is lifted no higher than c: a bias larger than its distance to the occluder above
  // it (slope-scaled on a grazing receiver, several texels) lit it through g in the ribbon's umbra. A
  // texel without a ribbon gives the compare with g (c and b are zetaNone, p_i 0: the same value).
  float equation2(const PlmTexel& t, float z, float zc, bool otherObject) const {
    if (t.c >= space_.zetaNone) return zc < t.g ? 1.0f : 0.0f;
    const float l = std::clamp(0.5f + 0.5f * t.pi / std::max(z - t.c, 1e-30f), 0.0f, 1.0f);
    const float zg = otherObject && z > t.c ? std::max(zc, t.c) : zc;
    return std::clamp(l + 4.0f * (zg < t.g) - 2.0f * (z < t.c) + (z < t.b) - 1.0f, 0.0f, 1.0f);
  }

  // Whether the four texels of a bilinear fetch hold one continuous ribbon, whose parameters may be
  // interpolated (the paper's fetch): every texel's edge is the same as, or shares an end with, every
  // other's (c and p_i are continuous along a silhouette polyline), and b is absent at all four or
  // present at all four; and, for a receiver at z, bContinuous.
  bool continuousRibbon(const PlmTexel& t00, const PlmTexel& t10, const PlmTexel& t01, const PlmTexel& t11) const {
    const PlmTexel* t[4] = {&t00, &t10, &t01, &t11};
    for (int k = 0; k < 4; ++k) {
      if (t[k]->edge < 0) return false;
      const plm::Edge& e = edges_[static_cast<size_t>(t[k]->edge)];
      for (int m = k + 1; m < 4; ++m)
        if (t[m]->edge != t[k]->edge && t[m]->edge != e.neighbourA && t[m]->edge != e.neighbourB) return false;
    }
    const bool anyB = std::min(std::min(t00.b, t10.b), std::min(t01.b, t11.b)) < space_.zetaNone;
    const bool allB = std::max(std::max(t00.b, t10.b), std::max(t01.b, t11.b)) < space_.zetaNone;
    return anyB == allB;
  }

  // b, where present, spreads over at most kTransitionSpread of the receiver's distance to it: the
  // fitted b jumps where the receivers below change, and interpolated across the jump it put the
  // receiver on either side of it by the sub-texel position alone.
  bool bContinuous(const PlmTexel& t00, const PlmTexel& t10, const PlmTexel& t01, const PlmTexel& t11, float z) const {
    const float bMin = std::min(std::min(t00.b, t10.b), std::min(t01.b, t11.b));
    if (bMin >= space_.zetaNone) return true;
    const float bMax = std::max(std::max(t00.b, t10.b), std::max(t01.b, t11.b));
    return bMax - bMin <= kTransitionSpread * std::abs(z - bMin);
  }

  // b (step 3) for the listed texels, fitted to the shadow along the texel's light ray: from a
  // texel's size below c down, each surface that faces the light is a receiver of this texel's
  // shadow. Its visibility is measured just above it with kProfileSamples rays to the light
  // (stratified over the emitter, one packet), and b is put there at the first one that sees less
  // than kProfileFraction of what Equation 1 predicts for it: below that depth another occluder, or
  // more of this one than its edge accounts for, shadows the receivers (see the file comment).
  // Sixteen texels walk at a time (neighbours in the list: coherent rays), each query one Embree
  // packet of those still walking, whose filter (profileReceiver) passes over the surfaces a walk
  // does not probe, so that a query returns each ray's next receiver to probe in one traversal. A
  // texel leaves the walk when its ray leaves the scene, after kMaxProbes probes, or when b is
  // found. Which of two coincident faces (a box's bottom on the ground) a traversal meets first is
  // arbitrary, and differs between packet and single-ray traversals; through the filter the face
  // turned away is passed over at any order, so the receiver is probed whichever comes first.
  void findLowerLimits(const Scene& scene, const Light& light, const std::vector<int>& texels) {
    // The scene's BVH depends on the geometry alone: kept from the last prepare while every mesh's
    // positions and triangles are the same to the bit (a static scene under a moving light).
    const RayScene& rays = raysCache_.get(scene);
    const int n = map_.size;
    // The grid's half of each sample, made once (Light::patternPoint; every probe sees the same grid).
    LightPatternPoint pattern[kProfileSamples];
    for (int q = 0; q < kProfileSamples; ++q)
      pattern[q] = light.patternPoint(Vec2((static_cast<float>(q % kProfileGrid) + 0.5f) / kProfileGrid,
                                           (static_cast<float>(q / kProfileGrid) + 0.5f) / kProfileGrid));
    // The packets are fixed sixteens of the list, not cut from the threads' ranges: a texel's packet
    // neighbours are the same at any thread count, so V never rests on a lane's hit being the same
    // whatever else its packet holds.
    const size_t groups = (texels.size() + 15) / 16;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, groups, 4), [&](const tbb::blocked_range<size_t>& range) {
      for (size_t first = 16 * range.begin(); first < std::min(16 * range.end(), texels.size()); first += 16) {
        WalkGroup group{this, {}};
        int walking = 0;
        for (size_t k = first; k < std::min(first + 16, texels.size()); ++k) {
          const int i = texels[k] % n, j = texels[k] / n;
          // Only receivers below the surface the map sees are probed: none where that is the deepest.
          const float seenDepth = map_.lsDepth(i, j);
          const float farthest = space_.lsDepth(plm::farthestZeta(map_, space_, i, j));
          if (!(farthest > seenDepth + 2.0f * map_.texelWorldSize(seenDepth))) continue;
          const float s = static_cast<float>(i) + 0.5f, t = static_cast<float>(j) + 0.5f;
          const float cDepth = space_.lsDepth(limits_(i, j).c);
          const float start = cDepth + map_.texelWorldSize(cDepth);
          LowerLimitWalk& w = group.walks[walking++];
          w.i = i;
          w.j = j;
          w.ray.origin = map_.unproject(s, t, start);
          w.ray.direction = map_.orthographic ? map_.lsFrame.z : glm::normalize(w.ray.origin - map_.wsOrigin);
        }
        const HitFilter filter{&acceptsProfileHit, &group};
        while (walking > 0) {
          RayHitPacket16 packet;
          for (int lane = 0; lane < walking; ++lane) {
            packet.ray.set(lane, group.walks[lane].ray);
            packet.ray.id[lane] = static_cast<uint32_t>(lane);  // the filter's index into group.walks
          }
          rays.intersect16(packet, walking, filter);
          ProbeBatch batch;
          for (int lane = 0; lane < walking; ++lane) {
            if (packet.hit.geomId[lane] == HitPacket16::kNoHit) continue;  // the ray left the scene
            const LowerLimitWalk& w = group.walks[lane];
            const std::optional<ProfileReceiver> receiver = profileReceiver(
                w, packet.ray.tMax[lane], Vec3(packet.hit.ngX[lane], packet.hit.ngY[lane], packet.hit.ngZ[lane]));
            assert(receiver);  // the filter accepted the hit
            batch.add(w, *receiver);
          }
          probe(light, pattern, rays, batch);
          int kept = 0;
          for (int lane = 0, q = 0; lane < walking; ++lane) {
            LowerLimitWalk& w = group.walks[lane];
            if (packet.hit.geomId[lane] == HitPacket16::kNoHit) continue;
            const ProbeBatch::Receiver& r = batch.receivers[q++];
            if (r.shadowed) {  // b found: just above the receiver
              limits_(w.i, w.j).b = space_.zeta(r.profile.probeDepth);
              continue;
            }
            w.ray.tMin = std::nextafter(packet.ray.tMax[lane], kInfinity);
            if (++w.probes < kMaxProbes) group.walks[kept++] = w;
          }
          walking = kept;
        }
      }
    });
  }

  // One texel's walk down its light ray (findLowerLimits): its texel, how many receivers it probed,
  // and the ray from just below c, past the last of them.
  struct LowerLimitWalk {
    int i = 0, j = 0, probes = 0;
    Ray ray;
  };
  // The walks of one packet, as its filter sees them (a lane's ray id indexes walks).
  struct WalkGroup {
    const PlmTechnique* self;
    LowerLimitWalk walks[16];
  };
  // A receiver on a walk's ray: the hit, the depth its visibility is probed at (lifted off the surface
  // towards the light) and what Equation 1 predicts there.
  struct ProfileReceiver {
    Vec3 wsHit;
    float lift, probeDepth, predicted;
  };

  // The hit at distance t on a walk's ray (ng: its unnormalized geometric normal) as a receiver to
  // probe, or nothing where the walk passes over it: a surface turned away from the light, one the
  // map sees, or one where Equation 1 predicts too little light to find less.
  std::optional<ProfileReceiver> profileReceiver(const LowerLimitWalk& w, float t, const Vec3& ng) const {
    const float len = glm::length(ng);  // normalized as RayScene::intersect does
    const Vec3 normal = len > 0.0f ? ng / len : Vec3(0.0f);
    if (!(glm::dot(normal, -w.ray.direction) > 0.0f)) return std::nullopt;  // faces away: no receiver
    const PlmTexel& texel = limits_(w.i, w.j);
    ProfileReceiver r;
    r.wsHit = w.ray.origin + t * w.ray.direction;
    const float depth = map_.lsFromWs(r.wsHit).z;
    r.lift = 2.0f * map_.texelWorldSize(depth);  // off the surface, towards the light
    // A receiver the map sees (lit from the light's centre) is not in an umbra: not probed.
    if (!(depth > map_.lsDepth(w.i, w.j) + r.lift)) return std::nullopt;
    r.probeDepth = depth - r.lift;
    if (!(r.probeDepth > 0.0f)) return std::nullopt;
    const float l =
        std::clamp(0.5f + 0.5f * texel.pi / std::max(space_.zeta(r.probeDepth) - texel.c, 1e-30f), 0.0f, 1.0f);
    r.predicted = options_.illuminationTable ? table_(l) : l;
    // A prediction under kProfileMinDeficit samples cannot be missed by that many: not probed.
    if (!(r.predicted * kProfileSamples >= kProfileMinDeficit)) return std::nullopt;
    return r;
  }

  static bool acceptsProfileHit(const void* state, uint32_t rayId, float t, const Vec3& ng) {
    const auto& group = *static_cast<const WalkGroup*>(state);
    return group.self->profileReceiver(group.walks[rayId], t, ng).has_value();
  }

  // The receivers one step of a packet's walks met, each to be probed: where its probe starts (lifted
  // off the surface towards the light), how many of its samples traced so far see the light, and the
  // answer.
  struct ProbeBatch {
    struct Receiver {
      ProfileReceiver profile;
      Vec3 at;
      int seen = 0;
      bool decided = false, shadowed = false;
    };
    Receiver receivers[16];
    int count = 0;
    void add(const LowerLimitWalk& w, const ProfileReceiver& r) {
      receivers[count++] = Receiver{r, r.wsHit - r.lift * w.ray.direction};
    }
  };

  // Whether a receiver that Equation 1 expects to see `expected` of kProfileSamples samples is shadowed
  // by more than the ribbon's edge when `seen` of them see the light; true for fewer seen whenever it is
  // for more.
  static bool seesTooLittle(int seen, float expected) {
    return static_cast<float>(seen) < kProfileFraction * expected &&
           expected - static_cast<float>(seen) >= kProfileMinDeficit;
  }

  // Probes each receiver of the batch with kProfileSamples rays to the light (stratified over the
  // emitter): shadowed where it sees too little (seesTooLittle). The samples go in stages
  // (kProbeOrder): a receiver whose answer the samples traced so far settle — it sees too little even
  // if every sample left sees the light, or enough even if none does (seesTooLittle falls as more
  // see it) — traces no more. Receivers whose probes start close together (neighbouring texels on
  // one surface) share a stage's packet; a receiver with no close neighbour left open traces all its
  // remaining samples in a packet of its own (rays from far-apart points share little of a
  // traversal, and a packet costs about as much with fewer rays). The answer is the one the sixteen
  // samples give together.
  void probe(const Light& light, const LightPatternPoint* pattern, const RayScene& rays, ProbeBatch& batch) const {
    struct Job {
      int receiver, begin, end;  // the samples kProbeOrder[begin, end)
      bool opensPacket;          // no earlier job shares its packet
    };
    // Each packet's jobs traced in one Embree query, and the receivers they settle marked.
    const auto trace = [&](const Job* jobs, int count) {
      for (int first = 0; first < count;) {
        Ray toLight[16];
        bool blocked[16];
        int lanes = 0, last = first;
        for (; last < count && (last == first || !jobs[last].opensPacket); ++last) {
          const ProbeBatch::Receiver& r = batch.receivers[jobs[last].receiver];
          for (int k = jobs[last].begin; k < jobs[last].end; ++k) {
            const LightSample sample = light.sampleFrom(r.at, pattern[kProbeOrder[k]]);
            Ray& ray = toLight[lanes++];
            ray.origin = r.at;
            ray.direction = sample.wsDirection;
            ray.tMax = sample.distance;  // kInfinity for a directional light
          }
        }
        assert(lanes <= 16);
        rays.occluded16(toLight, lanes, blocked);
        for (int j = first, lane = 0; j < last; ++j) {
          ProbeBatch::Receiver& r = batch.receivers[jobs[j].receiver];
          for (int k = jobs[j].begin; k < jobs[j].end; ++k) r.seen += blocked[lane++] ? 0 : 1;
          const float expected = r.profile.predicted * kProfileSamples;
          const int unseen = kProfileSamples - jobs[j].end;  // samples still to trace
          if (unseen == 0 || seesTooLittle(r.seen + unseen, expected) || !seesTooLittle(r.seen, expected)) {
            r.decided = true;
            r.shadowed = seesTooLittle(r.seen, expected);
          }
        }
        first = last;
      }
    };
    const auto close = [&](int r, int q) {
      const ProbeBatch::Receiver& a = batch.receivers[r];
      return glm::length(batch.receivers[q].at - a.at) <=
             kPairedProbeTexels * map_.texelWorldSize(a.profile.probeDepth);
    };
    Job jobs[16];
    for (int stage = 0, begin = 0; stage < kProbeStages; begin = kProbeStageEnd[stage++]) {
      const int end = kProbeStageEnd[stage], perPacket = 16 / (end - begin);
      int open[16], openCount = 0, count = 0;
      for (int r = 0; r < batch.count; ++r)
        if (!batch.receivers[r].decided) open[openCount++] = r;
      for (int q = 0; q < openCount;) {
        // The close receivers that follow the first open one, as many as the packet holds.
        int members = 1;
        while (members < perPacket && q + members < openCount && close(open[q], open[q + members])) ++members;
        for (int m = 0; m < members; ++m)
          jobs[count++] = Job{open[q + m], begin, members > 1 ? end : kProfileSamples, m == 0};
        q += members;
      }
      trace(jobs, count);
    }
  }

  PlmOptions options_;
  LightMap map_;
  plm::Space space_;
  VisibilityToIllumination table_;
  std::optional<Light> light_;                  //!< the light the last prepare()'s map looks from (lightAtMapOrigin)
  Image<PlmTexel> limits_;                      //!< written where a ribbon holds the texel only (texelAt)
  std::vector<std::vector<int>> coveredInRow_;  //!< prepare's scratch: each row's ribbon texels
  Image<float> g_;                              //!< limits_' g alone, for the lit fast path
  Image<uint8_t> footprint2x2_;                 //!< kFootprint* of the 2x2 texels whose top-left this is
  Image<uint8_t> ribbonAt_;                     //!< kRibbonHere | kRibbonBelowNone where a ribbon holds the texel
  // prepare()'s working storage, kept so that a new light or scene refills it rather than faulting in
  // fresh pages.
  plm::RibbonImage ribbons_;
  std::vector<plm::Edge> edges_;  //!< the silhouette edges, which visibility() asks for neighbours
  std::vector<int> needLower_;
  RaySceneCache raysCache_;        //!< findLowerLimits' BVH of the scene
  plm::EdgeCache edgeCache_;       //!< the meshes' edge adjacency, kept while the geometry is unchanged
  std::vector<uint8_t> farTiles_;  //!< where map_ keeps its far layer
};

}  // namespace

std::unique_ptr<ShadowTechnique> makeTechnique(const PlmOptions& o) {
  validateOptions("plm", o);
  return std::make_unique<PlmTechnique>(o);
}

TechniqueInfo plmTechniqueInfo() {
  TechniqueInfo info;
  info.name = "plm";
  info.usesMeshEdges = true;
  info.summary =
      "penumbra limit map: occluder depth, geometry limits and a planar signed penumbra limit, one bilinear fetch";
  info.source = "Lawlor 2006, Interpolation-friendly soft shadow maps";
  info.tracesRays = true;
  info.setOptions<PlmOptions>([](const PlmOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
