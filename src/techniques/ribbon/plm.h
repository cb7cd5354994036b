// Shared stages of the silhouette-ribbon techniques — `plm` (Lawlor 2006, "Interpolation-friendly
// soft shadow maps", CGVR, Sec. 2-3; docs/papers.md),
// `smoothies` (Chan & Durand 2003) and `kirsch` (Kirsch & Döllner 2003): the light-space depth
// parameterization in which a straight occluder edge casts a planar penumbra limit, the silhouette
// edges of the scene seen from the light, and the rasterization of their soft-shadow ribbons.
//
// PLM space. Lawlor derives Equation 1 for an infinitely distant light: with depth z measured along
// the light's axis, an edge at depth c and a receiver at horizontal distance w from it,
//     l = 1/2 + 1/2 p_i / (z - c),   p_i = w s r   (Sec. 3: s the texel size, r = 1 / tan(angle / 2)),
// l the visible fraction of the light's diameter. For a directional light we use exactly that
// (zeta = light-space depth, world units). For a local light of radius R the paper names, as future
// work, a perspective transform that pushes the light to infinity: with u = x / z the map's
// projective coordinate and zeta = -1 / z, similar triangles through the edge give
//     l = 1/2 + 1/2 (u_r - u_e) / (R (zeta_r - zeta_c))
// exactly for a disk emitter of radius R facing the map's axis, i.e. Equation 1 in (u, zeta) with
// s = the texel's size in u and r = 1 / R. Sphere lights are modelled by the disk of their radius at
// their centre (their silhouette disk sits slightly nearer the receiver); for plm that disk faces the
// receiver, not the map's axis: seen along (u, 1) it projects onto the map's plane as an ellipse
// R sqrt(1 + (n . u)^2) wide across an edge of normal n, and each edge takes its own rate
// (Edge::rate; smoothies and kirsch keep the disk facing the axis). Rect and polygon lights are
// modelled by the disk of equal area; segment lights, which have no width across their axis, are not
// supported.
//
// Silhouette edges (Sec. 3.1). Per object, vertices are welded by position; a triangle faces the
// light when its wound normal points to the light's centre (directional: its direction); the techniques
// pass the light the map looks from (lightAtMapOrigin of shadow_map.h: under a stable fit, moved to the
// map's snapped origin), so that the silhouettes hold still with the map. An edge is
// a silhouette when its triangles face both ways, or when it has one triangle (the border of an open
// mesh: a single triangle, a plane). Its outer side, in the map, is the side away from its
// (front-facing) triangle. Degenerate triangles and edges seen end-on are skipped.
//
// Ribbons. Each silhouette edge covers the texels within W(c) = (zeta_far - c) / (s r) + margin +
// kRibbonBorderTexels texels of its projected segment: the widest penumbra it can cast on anything
// in the map (smoothies and kirsch: on the surfaces there are around it; RibbonReach), plus a margin so that bilinear
// interpolation near the penumbra reads texels of the same ribbon (the paper's "bias up the z-buffer depth to expand
// the penumbra limit over a few extra pixels"), plus a border of texels beyond any penumbra, where a bilinear lookup
// that straddles the ribbon's end sees values that all agree the receiver is lit (plm.cpp). At a texel the edge gives c
// (its zeta at the nearest point of the segment) and w (the signed distance to the segment in texels, + on the outer
// side; the distance to the line where the texel lies beside the segment, so p_i is a plane along a straight edge).
// Beyond an end, where the nearest point is a corner shared with the next silhouette edge, the side is the corner's:
// outer at a convex corner (beyond a sharp convex corner a texel can lie on the inner side of one edge's line and still
// outside the occluder), inner at a concave one; the two edges then tie exactly (the same corner,
// the same distance) and the first keeps the texel. Overlapping ribbons are resolved per texel
// like a depth buffer, by "highest penumbra limit wins" (priority c + |w| s r, Sec. 3.1), among the
// candidates a RibbonFilter lets through (hidden shadows, kirsch's footprint border). Ties go to the
// edge listed first, and edges
// are binned to tiles processed in parallel in edge order, so the result is the same for any thread
// count.
//
// Cost (docs/real-meshes.md, "Cost at 1024²"). The welding and edge matching depend on the geometry
// alone and are kept between prepares (EdgeCache); an edge whose every candidate the hidden-shadow
// test would drop is not rasterized at all (most silhouettes of a dense model lie behind its own
// front), nor, where only footprint borders count, an edge inside its object's footprint; each row of
// a ribbon is trimmed to the texels whose current winner it may still beat (a bound on its priority
// there) and, where one side is wanted and no corner puts the texels beyond an end on it, to that side
// of the edge's line, and such a ribbon goes only to the tiles on that side (ribbonMayTake); the
// filters that read the texel's own row run in the vectorized pass over the row; none of these
// changes a texel.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "penumbra/image.h"
#include "penumbra/light.h"
#include "penumbra/math.h"
#include "penumbra/options.h"
#include "penumbra/raster.h"
#include "penumbra/scene.h"

namespace penumbra::plm {

struct Space {
  bool orthographic = true;
  float zetaNear = 0.0f, zetaFar = 1.0f;  //!< zeta of the map's depth range
  float zetaNone = 2.0f;                  //!< stands for "nothing here": deeper than anything in the map, finite
  float ratePerTexel = 1.0f;              //!< s r: zeta of penumbra-limit depth per texel of horizontal distance
  bool sphere = false;  //!< a sphere light in a perspective map, measured across each edge (Edge::rate)
  // zeta of a light-space depth: z (orthographic) or -1 / z (perspective).
  float zeta(float lsDepth) const { return orthographic ? lsDepth : -1.0f / lsDepth; }
  float lsDepth(float zeta) const { return orthographic ? zeta : -1.0f / zeta; }
};

// The emitter radius R of the file comment (world units; directional: tan(angular_diameter / 2)).
// Throws Error naming the shape and the supported ones for a segment light; `technique` names the
// caller in the message.
float emitterRadius(const Light& light, const char* technique);

// sphereAcrossEdges: a sphere light's width across each edge as a receiver off the map's axis sees it
// (Edge::rate; plm), else the disk facing the map's axis for every edge (smoothies and kirsch, whose
// half penumbrae measured against the full truth widened with it: docs/results.md).
Space makeSpace(const LightMap& map, const Light& light, const char* technique, bool sphereAcrossEdges = false);

struct Edge {
  Vec2 a, b;  //!< projected end points, map texels
  float zetaA = 0.0f, zetaB = 0.0f;
  Vec2 outward{0.0f};  //!< unit normal of the segment in the map, towards the outer side
  // zeta of penumbra-limit depth per texel of distance across this edge: Space::ratePerTexel, but for
  // a sphere light, which a receiver off the map's axis sees as a disk turned from the map's plane:
  // along the receiver's direction (u, 1) that disk projects onto the plane as an ellipse of half-axes
  // R across u and R sqrt(1 + |u|^2) along it, R sqrt(1 + (n . u)^2) wide across an edge of normal n
  // (u at the edge's middle), and Equation 1 holds for it as for a disk of that radius.
  float rate = 0.0f;
  int32_t objectId = kNoObject;
  // Side (+1 outer, -1 inner) of the texels beyond each end, whose nearest point is the end point:
  // +1 at a convex corner of the silhouette, -1 at a concave one (the corner's other edge decides),
  // 0 where the end meets no single other edge (then the side of the edge's line is used).
  float endSideA = 0.0f, endSideB = 0.0f;
  // Index (in the list) of the other silhouette edge at each end, where exactly two meet; else -1.
  int32_t neighbourA = -1, neighbourB = -1;
};

// Edge::rate of an edge of `map` whose end points and outward normal are set (plm.cpp).
float edgeRate(const Space& space, const LightMap& map, const Edge& e);

// The meshes' welded vertices and edge adjacency (MeshEdgeCache of ../mesh_edges.h: kept in the
// scene's caches and shared with every technique on the scene, parker's outer objects included) and
// what this technique builds from them, which depend on the geometry alone: a technique passes the
// same cache to every prepare, and a mesh whose geometry is unchanged (its fingerprint, or the
// scene's declared revision) is not welded and matched again; only the faces' orientation to the
// light and the silhouettes are found again.
class EdgeCache {
 public:
  EdgeCache();
  ~EdgeCache();
  EdgeCache(const EdgeCache&) = delete;
  EdgeCache& operator=(const EdgeCache&) = delete;

 private:
  friend std::vector<Edge> silhouetteEdges(const Scene&, const Light&, const LightMap&, const Space&, EdgeCache*);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

std::vector<Edge> silhouetteEdges(const Scene& scene, const Light& light, const LightMap& map, const Space& space,
                                  EdgeCache* cache = nullptr);

inline constexpr float kRibbonBorderTexels = 1.5f;

enum class RibbonSides { Both, Outer, Inner };

// How far a ribbon reaches (rasterizeRibbons):
//  - MapDepthRange: as wide as the widest penumbra its edge can cast in the map's depth range (W(c) of
//    the file comment, at zeta_far);
//  - SurfacesBelow: only as wide as the widest one on the surfaces there are: zeta_far lowered to the
//    deepest surface of the far layer in the tiles the first width reaches on the ribbon's sides
//    (ribbonMayTake; smoothies, whose V measures the penumbra from the edge's c);
//  - SurfacesInRange: the same, measured from the shallowest surface the map sees in those tiles where
//    that lies above the edge (kirsch, whose V measures the shadow width from the occluder's depth at
//    the texel, which may lie above the edge).
// A texel a narrower ribbon gives up lies beyond the whole penumbra (kirsch: beyond the whole shadow
// width) of every surface in its tile by the margin and border, so the V of a receiver there does not
// change — but for a receiver deeper than every far-layer texel centre of the tile by more than that,
// a surface seen edge-on from the light, whose texels the far layer samples at their centres. plm's
// interpolation and its fit of b read ribbon texels that no receiver's V uses alone, so plm keeps the
// map's range.
enum class RibbonReach { MapDepthRange, SurfacesBelow, SurfacesInRange };

// 12 bytes: the tiles of a 1024^2 ribbon image that a ribbon reaches are written whole every prepare
// (its winners' priorities stay in rasterizeRibbons' tiles; the edge's object is the Edge's). Trivially constructible,
// so that a fresh image's pages are first touched by rasterizeRibbons' parallel tiles (DefaultInitAllocator, image.h);
// kNoRibbon is the texel no ribbon covers.
struct RibbonTexel {
  float c;       //!< zeta of the winning edge at its nearest point
  float w;       //!< signed distance to it, texels, + outside the silhouette
  int32_t edge;  //!< index of the winning edge in the list given to rasterizeRibbons; -1: no ribbon
  bool covered() const { return edge >= 0; }
};
inline constexpr RibbonTexel kNoRibbon{0.0f, 0.0f, -1};

// A ribbon texel's unsigned distance and c measured at a point p of the map (texels) instead of at
// the texel's centre: the distance from p to the edge's segment and the edge's zeta at the segment's
// point nearest p (an end point beyond either end), as rasterizeRibbons measures them at the centre.
struct EdgePoint {
  float distance;  //!< texels, >= 0
  float c;         //!< zeta of the edge at its point nearest p
};
// An edge's segment as the per-pixel lookup needs it (28 bytes, where an Edge takes 52).
struct EdgeLine {
  Vec2 a{0.0f}, d{0.0f};    //!< the segment a .. a + d, map texels
  float invLength2 = 0.0f;  //!< 1 / |d|^2; 0 for a segment of one point
  float zetaA = 0.0f, dZeta = 0.0f;
  float rate = 0.0f;  //!< Edge::rate

  explicit EdgeLine(const Edge& e)
      : a(e.a),
        d(e.b - e.a),
        invLength2(glm::dot(d, d) > 0.0f ? 1.0f / glm::dot(d, d) : 0.0f),
        zetaA(e.zetaA),
        dZeta(e.zetaB - e.zetaA),
        rate(e.rate) {}
  EdgePoint nearest(const Vec2& p) const {
    const Vec2 ap = p - a;
    const float u = std::clamp(glm::dot(ap, d) * invLength2, 0.0f, 1.0f);
    return EdgePoint{glm::length(ap - u * d), zetaA + u * dZeta};
  }
};
// One EdgeLine per edge, in the list's order (a ribbon texel's `edge` indexes both), into `out`.
inline void edgeLines(const std::vector<Edge>& edges, std::vector<EdgeLine>& out) {
  out.clear();
  out.reserve(edges.size());
  for (const Edge& e : edges) out.emplace_back(e);
}

// The deepest surface along texel (i, j)'s light ray (the light map's far layer, rendered with
// LightMapLayers::NearestAndFarthest or NearestDepthAndFarthest), in zeta; zetaNone where the texel
// sees nothing. A ribbon texel is only taken where a surface lies below the edge: elsewhere there is
// nothing to receive its shadow (the border of a ground plane, seen from above, would otherwise lay an
// inner ribbon over the ground itself, whose texels then interpolate with the ribbons of the occluders
// above it). rasterizeRibbons takes it where a ribbon reaches, not over the whole map.
// Whether a light-map depth (either layer) is a surface: finite, and in front of a perspective map's origin.
inline bool isSurface(const LightMap& map, float lsDepth) {
  return lsDepth < kInfinity && (map.orthographic || lsDepth > 0.0f);
}
inline float farthestZeta(const LightMap& map, const Space& space, int i, int j) {
  const float z = map.lsFarDepth(i, j);
  return isSurface(map, z) ? space.zeta(z) : space.zetaNone;
}
// farthestZeta of `count` texels of one row of the far layer from `lsFar` on, into `out`: the same
// values, four at a time in SSE where the build has it (plm.cpp).
void farthestZetaRow(const LightMap& map, const Space& space, const float* lsFar, int count, float* out);
// The ribbons' tiles (rasterizeRibbons): a span lies within one row of one tile.
inline constexpr int kRibbonTile = 32;
// Tiles along a side of a mapSize x mapSize ribbon image (the last one may be partial).
inline int ribbonTilesPerRow(int mapSize) { return (mapSize + kRibbonTile - 1) / kRibbonTile; }

// rasterizeRibbons' output: the ribbon texel of every map texel, and per kRibbonTile tile (row-major)
// whether it may hold a ribbon texel. A tile that held none after the last frame and that no ribbon
// reaches in this one still holds kNoRibbon throughout, so rasterizeRibbons leaves it alone: a frame
// writes the tiles its ribbons reach and those they have left, not the whole map (most of a map's
// tiles hold no ribbon, and its 12-byte texels are most of what a frame would write).
struct RibbonImage {
  Image<RibbonTexel> texels;
  std::vector<uint8_t> mayHoldRibbon;  //!< per tile; a size that does not fit the image: nothing known

  const RibbonTexel& operator()(int i, int j) const { return texels(i, j); }
};

// The storage rasterizeRibbons fills for a mapSize x mapSize map made in `ribbons`, its pages touched
// (ShadowTechnique::reserve).
void reserveRibbons(int mapSize, RibbonImage& ribbons);

// Which candidate texels of a ribbon may compete for a texel at all (before the priority decides
// among them); every test is made per edge and texel, so a dropped candidate leaves the texel to the
// next one rather than to no ribbon.
struct RibbonFilter {
  // The light map's object ids, or nullptr: a texel on an edge's inner side is only taken where the
  // light map sees the edge's own object — the inner side of one edge's line reaches past the other
  // edges of a thin occluder, where the texel lies outside it.
  const Image<int32_t>* coverage = nullptr;
  // The light map's depths (light-space z), or nullptr: a candidate whose shadow is hidden from the
  // light's centre is dropped — on the outer side (or the inner side over another object) where the
  // topmost surface of the texel lies above the edge (Fig. 7 C: a higher occluder hides what lies
  // below it), and on both sides where the topmost surface kHiddenProbeTexels beyond the edge lies
  // above it (the edge is not on the outline seen from the light: a contour behind the object's own
  // front, or a fold of a tessellated silhouette, whose outer side faces into the occluder).
  const Image<float>* topDepth = nullptr;
  // With coverage: the inner side only of edges on the border of their object's footprint in the map
  // (kHiddenProbeTexels beyond the edge the map sees another object or nothing): the distance to the
  // edge is then the distance to the border of the object's hard shadow (kirsch's shadow width).
  bool footprintBorderOnly = false;
};

inline constexpr float kHiddenProbeTexels = 1.5f;

// A surface of the far layer counts as below an edge (a ribbon candidate's test) when deeper by this
// fraction of the edge's zeta: float rounding of the two rasterizations of one surface stays well
// inside it.
inline constexpr float kBelowEdge = 1e-5f;

// One span of rasterizeRibbons: the texels [first, first + count) of one row (at most kRibbonTile)
// that an edge may still take, and what its pass reads there.
struct RibbonSpan {
  float ax = 0.0f, bx = 0.0f, dx = 0.0f, dy = 0.0f;  //!< the x of the edge's ends a and b, and b - a (texels)
  float aqy = 0.0f, by = 0.0f;                       //!< the row's y - a.y and y - b.y
  float invLength2 = 0.0f;                           //!< 1 / |b - a|^2
  float outX = 0.0f, outY = 0.0f;                    //!< Edge::outward
  float endSideA = 0.0f, endSideB = 0.0f;            //!< Edge::endSideA, endSideB
  float zetaA = 0.0f, zetaB = 0.0f, rate = 0.0f;     //!< Edge::zetaA, zetaB, rate
  float halfWidth = 0.0f;                            //!< the ribbon's half width, texels
  int32_t objectId = kNoObject;
  int first = 0;           //!< the span's first texel (column)
  bool bothSides = false;  //!< both sides wanted; else the outer one where wantOuter, the inner one where not
  bool wantOuter = false;
  bool ties = false;                  //!< a priority equal to the texel's winner's takes it (the caller breaks the tie)
  bool orthographic = false;          //!< Space::orthographic
  const float* far = nullptr;         //!< the far layer in zeta (farthestZeta) from `first`
  const int32_t* coverage = nullptr;  //!< the object the map sees from `first`; null: not filtered by it
  const float* top = nullptr;         //!< the topmost surface's depth from `first`; null: not filtered by it
  const float* priority = nullptr;    //!< the tile's priorities from `first`
};

// What the pass writes for each texel m of a span: the nearest point's parameter u along the edge,
// c there, the distance, the priority p where the edge takes the texel (else infinity), bit m of
// `outer` where the texel lies on the edge's outer side and bit m of `taken` where p is finite.
struct RibbonSpanTexels {
  float u[kRibbonTile], c[kRibbonTile], distance[kRibbonTile], p[kRibbonTile];
  uint32_t outer, taken;
};

// The implementations of the span pass: one texel at a time (the definition), four to an SSE vector,
// sixteen to an AVX-512 one. rasterizeRibbons takes the widest the CPU has; all give the same values to
// the bit.
enum class SpanPath { Scalar, Sse, Avx512 };
bool spanPathAvailable(SpanPath path);
// The span's texels [0, count) (count at most kRibbonTile) into `out` through `path` (available).
void ribbonSpan(SpanPath path, const RibbonSpan& s, int count, RibbonSpanTexels& out);

// The widest penumbra (texels) the edge casts on a receiver at zeta zetaDeepest, measured from its
// nearest end's c or from zetaFrom where that lies above it (RibbonReach).
float penumbraTexels(const Edge& e, float zetaDeepest, float zetaFrom = kInfinity);
// The texels an edge's ribbon may reach in a mapSize map (inclusive bounds, clipped to the map; none
// where i0 > i1 or j0 > j1): the edge's bounding box widened by the ribbon's half width (texels: a
// penumbra `width` wide, plus the margin and kRibbonBorderTexels).
struct RibbonBox {
  int i0, j0, i1, j1;
  float halfWidth;
};
RibbonBox ribbonBox(const Edge& e, float width, int mapSize, float marginTexels);
// ribbonBox at the widest penumbra the map's depth range allows (to zeta_far): the tiles
// farTilesForRibbons flags, and the first box rasterizeRibbons takes for every reach.
inline RibbonBox mapRangeRibbonBox(const Edge& e, const Space& space, int mapSize, float marginTexels) {
  return ribbonBox(e, penumbraTexels(e, space.zetaFar), mapSize, marginTexels);
}

// Whether only one side of the edge is wanted and neither end's corner puts the texels beyond it on
// that side (kirsch's inner sides at convex corners, smoothies' outer ones at concave corners): then
// every texel the ribbon takes lies on that side of the edge's line.
bool ribbonOneSided(const Edge& e, RibbonSides sides);
// Whether the edge's ribbon may take a texel whose centre lies in the rectangle [lo, hi] (map texels)
// on the wanted sides: always where it is not one-sided (ribbonOneSided; its box bounds it); else where
// part of the rectangle lies on that side of the edge's line, with a texel's slack against rounding.
// The other side's texels are ones rasterizeRibbons' per-texel test rejects. Monotone in the rectangle,
// so a tile holds whenever a tile it contains does.
bool ribbonMayTake(const Edge& e, RibbonSides sides, Vec2 lo, Vec2 hi);

// Into `tiles`, one flag per kFarLayerTile tile of a mapSize map (LightMap::farTiles' layout): nonzero
// where an edge's ribbon may take a texel (mapRangeRibbonBox, on the wanted sides: ribbonMayTake), the
// only texels where rasterizeRibbons reads the far layer. Made from the map's projection alone
// (fitLightMap), for rasterizeLightMap's farTiles.
void farTilesForRibbons(const std::vector<Edge>& edges, const Space& space, int mapSize, float marginTexels,
                        RibbonSides sides, std::vector<uint8_t>& tiles);

// Into `out`, which keeps its storage where it is large enough (and writes only the tiles that need it:
// RibbonImage). `map` gives the far layer (farthestZeta; Error without it, or without it in a tile a ribbon reaches)
// and the size.
void rasterizeRibbons(const std::vector<Edge>& edges, const Space& space, const LightMap& map, RibbonSides sides,
                      float marginTexels, const RibbonFilter& filter, RibbonImage& out,
                      RibbonReach reach = RibbonReach::MapDepthRange);

}  // namespace penumbra::plm
