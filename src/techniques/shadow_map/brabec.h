// `brabec`: single-sample soft shadows from a light-space depth + object-id map (Brabec & Seidel
// 2002, "Single Sample Soft Shadows using Depth Maps", Graphics Interface; docs/papers.md). Internals
// are declared here so the tests can run
// the scalar oracle search against the vectorized one and the exhaustive pass against the
// interpolated one.
//
// The method, per camera pixel P warped to the light map as P' = (s, t, z) (map texels, light-space
// depth in world units; Sec. 3.2):
//  - hard test (Williams): blocked when the map's depth at P's texel lies in front of P (the shared
//    shadow-map compare of techniques/shadow_map/shadow_map.h: receiver plane + slope-scaled bias);
//  - outer penumbra (lit pixels): the nearest texel, by Euclidean distance r from the non-rounded P'
//    to texel centres (Sec. 4.3 "subpixel accuracy"), with depth < z and an object id != P's id;
//    V = meet + (1 - meet) clamp(r / r_max), V = 1 when none lies within the search radius;
//  - inner penumbra (blocked pixels, Sec. 3.3): the nearest texel with depth >= z and the same id
//    as P (a lit point of P's own object); V = meet (1 - clamp(r / r_max)), V = 0 when none is found.
//    Deviation: the listing of Sec. 3.3 writes the return values as 1 - 0.5 clamp(r/r_max) and
//    0.5 clamp(r/r_max). Read literally they run backwards with respect to Sec. 3.2 ("f = r / r_max
//    rises from 0 to 1 as the distance to the blocker increases") and to the listing's own fall-backs
//    (1 when no blocker is found, 0 when no lit texel is found): V would jump from 0.5 to 1 at r_max.
//    We use the form that is continuous at r_max and meets at `meet` on the hard-shadow edge.
//  - pixels that see nothing or lie outside the map get V = 1; a surface turned away from the
//    light's centre (geometric normal) gets V = 0 without a search (the error mask skips it);
//  - depth layers: the outer search compares against the constant layer z - bias (the paper's
//    "virtual layers"): the object-id test is what keeps a receiver that crosses layers (a tilted
//    plane, Fig. 3) from shadowing itself, and `id_test = false` shows that artifact. Deviation: the
//    inner search compares against P's receiver plane (depth z + grad z . (texel - P') - bias, the
//    plane of techniques/shadow_map/shadow_map.h) instead: with the constant layer, the lit part of a receiver
//    tilted towards the light (the ground under a light off to the side) lies in front of the layer
//    and never counts as lit, so the inner penumbra only grows away from the light. On a ground
//    that nearly faces the light the two give the same V.
//
// r_max, physically (the paper's future work, Sec. 6). A light of radius R (Light::extent(), the
// emitter modelled as a disk of that radius facing the map), a blocker edge at depth z_b and a
// receiver at depth z_r: rays from the light's rim through the edge land R (z_r - z_b) / z_b either
// side of the hard-shadow edge (similar triangles), so the outer and the inner penumbra are each
//     w = R (z_r - z_b) / z_b                      world units on a receiver facing the light,
//     w_tex = w / texelWorldSize(z_r)              texels in the map, at the receiver's depth;
// for a perspective map texelWorldSize(z) = 2 z tanHalfFov / N, so w_tex = R N (z_r - z_b) /
// (2 tanHalfFov z_r z_b). A directional light of angular diameter theta gives w = tan(theta/2)
// (z_r - z_b) and a constant texel size. r_max = w_tex with z_b the depth of the texel found (outer)
// or of the blocker over P (inner); the search radius is w_tex for the nearest depth in the map
// (outer) or for the blocker over P (inner), capped at `max_radius` (default 96 texels: the cost of
// a search grows with the radius squared, and the widest physical radius of the built-in scenes at
// the default map_size 1024 is 69 texels, `linear`; torus 14, crowded 24). Lights other than
// spheres and disks are modelled by their bounding circle (a segment's penumbra is overestimated
// across its axis).
// Defaults: map_size 1024, as the other shadow-map techniques, so that a comparison at defaults is
// at equal map resolution; map_size = 256 is the paper's setup.
// The paper's knobs (all three given together, texels and world units): search radius
// r_scale |z_r| + r_bias, then r_max = (r_scale |z_r| + r_bias) r_shrink (depth difference). They
// match the physical r_max when r_shrink (r_scale z_r + r_bias) = R N / (2 tanHalfFov z_r z_b): a
// constant stands in for 1 / (z_r z_b), which is why one setting cannot fit every receiver and
// blocker depth.
//
// Search (Sec. 4.2): texel rows of the radius' bounding box, nearest row first, each row's span
// limited to the circle; a row's criterion and distance are computed for all its texels in one
// branch-free loop the compiler vectorizes, reduced with an integer min over the distances' bit
// patterns (non-negative floats order like their bits). Rows stop once no nearer texel can follow,
// and a row's span shrinks to the best distance found so far.
// Ties go to the smallest (t, s). Tiles of 8x8 texels summarize the map (nearest and farthest depth,
// the id when all texels share one) so a row skips the tiles that cannot qualify — a blocker-free
// tile, or one that is all the receiver's own object — the "tiled depth maps" of the paper's future
// work; it changes the cost, never the texel found. The outer search radius also shrinks to w_tex of
// the nearest depth among the tiles within it that may hold a blocker (not of the whole map): a
// texel beyond that gives r >= r_max, V = 1, exactly as finding none, so no result changes. The
// scalar oracle visits the whole box in plain order without tiles.
//
// Adaptive sampling (Sec. 4.3): hard test + id for every pixel; every 4th column (and the last) in
// groups of 5 pixels: search the two borders; interpolate linearly when all 5 share the hard-test
// result and the id (the blocker's id when blocked, the receiver's when lit), else search the middle
// and repeat on the two groups of 3; then every row, between those columns, in the same way. Since a
// group interpolates only when its ids agree, an interpolated pixel keeps the id of its interpolants.
// The block's side (option `interpolate_block`, pixels): the paper's 4 on images up to 1023 pixels on
// their longer side, doubled at every doubling of it (8 at 1024, 16 at 2048). Sec. 4.3: "The size of
// the pixel group used for interpolation should depend on the image size ... blocks of 4 x 4 pixels
// are a good speed/quality tradeoff when rendering images of moderate size (512 x 512, 800 x 600
// pixels)"; a block scaled with the image covers the same part of the view, so a penumbra spans as
// many blocks as at the paper's size. A group of b + 1 pixels halves as above down to groups of 3.
// Deviation (option `interpolate_kinks`, on by default): two more refinement criteria, in the spirit
// of the paper's "very conservative refinement". Linear interpolation is exact where V is linear in
// the pixel position, and V = f(clamp(r / r_max)) with r the distance to the nearest qualifying texel
// is close to linear except at two kinds of kink: (1) the clamp, where the penumbra ends at r = r_max
// (V = 1 lit, 0 blocked): refine when exactly one border is at that end value; (2) the ridges and
// valleys of the distance field r (the medial axis: midway between two blockers, the middle of an
// umbra, a blocker's corner), where the nearest texel jumps to another edge: refine when the
// directions from the two borders' P' to their texels differ by more than `interpolate_max_angle`
// (default 30 degrees). An interpolated pixel carries its nearer interpolant's direction into the
// row pass, as it carries its id. Both kinks matter: against the exhaustive search the paper's
// criteria alone leave about four times the error of (1) and (2) together, for a few percent more
// searched pixels (tests/techniques/shadow_map/brabec_test.cpp checks the interpolated pass against
// the exhaustive one). Different blocker ids at the borders (the paper's other cue) add nothing once
// (2) is in: a change of blocker turns the direction. Option `interpolate_max_step` (default 1: off) also refines a
// group whose border V differ by more than the step.
//
// Jitter (Sec. 4.3): texel positions offset by up to `jitter` texels in s and t, a deterministic hash
// of the texel. Units: map coordinates and radii in texels, depths in world units.
//
// Coverage bound (option `coverage_bound`, on by default): our extension, not the paper's. The
// method darkens P from the distance to one blocker edge as if the blocker covered the whole light
// wherever it covers the centre; the paper says as much of Parker's scheme it builds on (Sec. 3.1:
// good "as long as the occluder objects aren't too small compared to the simulated light source
// area"). Under an occluder smaller than the light the true shadow is faint, and the method draws a
// dark blob (V <= meet inside the hard shadow, a meet-to-1 ramp around it). The bound: seen from P,
// the light through a blocker plane at depth z_b covers in the map the light's own shape around P',
// scaled so that radius R becomes the penumbra width w_tex(z_b) above (the physical r_max, also under
// the paper's knobs); so the blockers at z_b hide about the fraction
//     f = (footprint texels in front of P's receiver plane, the hard test's compare) / (footprint texels)
// of the light, and V' = max(V, 1 - f). The footprint's shape: a polygon for rect and polygon lights
// (their corners; a planar light lies in light space's z = 0 plane), a segment for a segment light
// (its component across the light's axis, sampled once per texel of its length), a disk for
// spheres, disks and directional lights. z_b is the depth of the blocker's silhouette: the texel
// the outer search found (it lies on the edge), or, inside the hard shadow, the deepest blocker
// texel next to the lit texel the inner search found (the texel over P is the blocker's top, whose
// footprint is wider). The bound is not applied inside the shadow of P's own object (blocker id =
// P's id): the part of an object below its silhouette from the light's centre is missing from the
// map and reaches down towards P, so one plane at z_b undercounts it. Nor where the footprint holds
// fewer than `coverage_min_texels` texels (default 32; samples along a segment): a few texels
// cannot resolve the covered fraction (the footprint shrinks to nothing where a blocker touches the
// receiver, and at small maps), and its steps of 1/3 or 1/2 made specks in contact shadows that the
// interpolation could not follow. The interpolation refines a group whose borders differ in whether
// the bound raised V (the kink of the max). V' >= V everywhere; f ~ 1 in an umbra, so V' = V there.
// Cost: a count over the footprint's texels per searched pixel (about pi w_tex^2 for a disk); a
// footprint of more than `coverage_samples` texels (default 256, f to about one 8-bit step) is
// counted on a lattice of every k-th texel in s and t, fixed in the map, with the smallest k that
// keeps the count within it. docs/small-occluders.md has the measurements: RMSE8 and umbra leaks per
// scene and light with and without, and the time.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/light.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/technique.h"
#include "penumbra/techniques/shadow_map.h"
#include "techniques/shadow_map/shadow_map.h"

namespace penumbra {

namespace brabec {

// Tiles of kTileSize^2 texels summarize the map so the search skips what cannot qualify.
inline constexpr int kTileShift = 3;
inline constexpr int kTileSize = 1 << kTileShift;
inline constexpr int32_t kMixedTile = INT32_MIN;  //!< tile id when its texels' ids differ

// The searched light map: depth and id rows, the per-texel jitter (null when off) and the tile
// summary (null: no skipping; the oracle never skips).
struct SearchMap {
  int size = 0;
  const float* lsDepth = nullptr;
  const int32_t* objectId = nullptr;
  const float* jitterS = nullptr;  //!< size*size offsets added to texel centres' s, or null
  const float* jitterT = nullptr;
  float maxJitter = 0.0f;  //!< bound of |jitter|, texels
  int tilesPerRow = 0;
  const float* tileMinDepth = nullptr;    //!< per tile: nearest depth
  const float* tileMaxDepth = nullptr;    //!< per tile: farthest depth (kInfinity if a texel is empty)
  const int32_t* tileObjectId = nullptr;  //!< per tile: the id all its texels share, or kMixedTile
};

// The interpolation's block side in pixels for an image of width x height: `option` when it is
// positive, else the paper's 4 scaled with the image (see "Adaptive sampling" above).
int interpolationBlock(int option, int width, int height);

// Fills the tile summary of `map` (tilesPerRow^2 tiles, row-major).
void buildTiles(const LightMap& map, std::vector<float>& minDepth, std::vector<float>& maxDepth,
                std::vector<int32_t>& objectId, int& tilesPerRow);

// The nearest tile depth over a rectangle of tiles, excluding the tiles that hold only the query's
// own object, in a handful of lookups whatever the rectangle's size: a sparse table (level k holds, at
// every tile, the summary of the 2^k x 2^k tiles from it), read as at most a few overlapping squares
// of the largest level that fits. Each summary keeps the nearest depth, the id of the tile that holds
// it, and the nearest depth of the tiles with any other id, which is exactly what a query whose
// object is that id needs; min is idempotent, so overlapping squares are counted twice harmlessly.
class TileNearestTable {
 public:
  void build(const std::vector<float>& tileMinDepth, const std::vector<int32_t>& tileObjectId, int tilesPerRow);
  // min over tiles [tx0, tx1] x [ty0, ty1] (inclusive, within the grid, non-empty) whose id is not
  // `objectId` (every tile when !idTest) of their nearest depth; kInfinity if there is none.
  float nearest(int tx0, int tx1, int ty0, int ty1, int32_t objectId, bool idTest) const;

 private:
  struct Entry {
    float nearest = kInfinity;
    int32_t id = kMixedTile;  //!< the id of the tile that holds `nearest`
    float other = kInfinity;  //!< nearest depth of the tiles whose id is not `id`
  };
  static Entry merge(const Entry& a, const Entry& b);
  int n_ = 0;
  std::vector<std::vector<Entry>> levels_;  //!< levels_[k][ty * n_ + tx]
};

struct SearchQuery {
  float s = 0.0f, t = 0.0f;  //!< P' in map coordinates, not rounded
  float zLayer = 0.0f;       //!< depth layer: P'z minus the bias, world units
  float dzds = 0.0f;         //!< inner search: receiver plane's depth change per texel along s, world units
  float dzdt = 0.0f;         //!< ... along t
  int32_t objectId = kNoObject;
  bool inner = false;  //!< search a lit texel of P's object (true) or a blocker (false)
  bool idTest = true;
  float radius = 0.0f;  //!< texels; texels at distance < radius qualify
  // A texel to start from (optional, -1: none), e.g. the one the search found for a pixel nearby: when it
  // qualifies, the search looks only for nearer ones. The answer does not depend on it, only the cost.
  int seedS = -1, seedT = -1;
};

struct SearchHit {
  bool found = false;
  float distance2 = 0.0f;  //!< squared distance to the texel (centre + jitter), texels^2
  int s = -1, t = -1;      //!< the texel
};

// The nearest qualifying texel (ties: the smallest t, then the smallest s), rows nearest first,
// vectorized within a row, skipping the tiles that cannot qualify.
SearchHit searchVectorized(const SearchMap& map, const SearchQuery& query);
// The same answer from every texel of the radius' box in row-major order: the oracle (no seed).
SearchHit searchScalar(const SearchMap& map, const SearchQuery& query);

// Per-texel jitter offset in [-amplitude, amplitude], a deterministic hash of (s, t, axis).
float texelJitter(int s, int t, int axis, float amplitude);

// The coverage bound's count (brabec.h, "Coverage bound"): of the texels in a light's footprint
// around P' = (s, t), how many hold a blocker for P's receiver plane: depth < zLayer + dzds (s_c - s)
// + dzdt (t_c - t), the compare of the hard test (shadow_map.h), without the id test. Texels outside
// the map count as lit.
struct Coverage {
  int blocked = 0;
  int total = 0;
};
// The lattices of the counts with stride k > 1: every k-th texel of the map's depth in s and t, stored
// row after row, so a count reads a lattice row from whole cache lines in one vectorized loop instead
// of one texel every k from rows k apart. Same depths, same compares: the counts are unchanged.
class LatticeDepths {
 public:
  // Lattices of strides 2 .. maxStride (none if maxStride < 2).
  void build(const LightMap& map, int maxStride);
  // Lattice row j (texels (0, jk), (k, jk), ...) of stride k, columns(k) floats; null when stride k
  // was not built.
  const float* row(int k, int j) const {
    return k >= 2 && k < static_cast<int>(lattices_.size())
               ? lattices_[static_cast<size_t>(k)].data() + static_cast<size_t>(j) * columns(k)
               : nullptr;
  }
  int columns(int k) const { return (size_ + k - 1) / k; }

 private:
  int size_ = 0;
  std::vector<std::vector<float>> lattices_;  //!< [k]: columns(k)^2 depths; empty below 2
};

// Footprint: the texel centres within `radius` of (s, t), row by row (a disk, sphere or directional
// light). With stride k > 1 only the texels whose s and t are multiples of k (total: of those), read
// from `lattices` when it holds stride k.
Coverage countBlocked(const LightMap& map, float s, float t, float zLayer, float dzds, float dzdt, float radius,
                      int stride = 1, const LatticeDepths* lattices = nullptr);
// Footprint: the texel centres in the convex polygon (s, t) + scale * vertices[k] (either winding): a
// rect or polygon light.
Coverage countBlockedInPolygon(const LightMap& map, float s, float t, float zLayer, float dzds, float dzdt,
                               const std::vector<Vec2>& vertices, float scale, int stride = 1,
                               const LatticeDepths* lattices = nullptr);
// Footprint: the segment from (s, t) - half to (s, t) + half, sampled once per texel of its length
// (nearest texel): a segment light.
Coverage countBlockedAlong(const LightMap& map, float s, float t, float zLayer, float dzds, float dzdt, Vec2 half);

// What the hard test found for a camera pixel (BrabecTechnique::Pixel::cls).
enum PixelClass : uint8_t { Miss, OutOfMap, BackFacing, Lit, Blocked };

}  // namespace brabec

class BrabecTechnique final : public ShadowTechnique {
 public:
  explicit BrabecTechnique(const BrabecOptions& options);

  std::string_view name() const override { return "brabec"; }
  // "searches" (searched pixels), "search_fraction" (of pixels that see geometry), "map_min_depth".
  std::vector<std::pair<std::string, double>> stats() const override;

  const BrabecOptions& options() const { return options_; }
  const LightMap& lightMap() const { return map_; }

 private:
  friend struct BrabecTestAccess;  // tests hold classifyRow to classify, pixel for pixel
  void reserveImpl(int width, int height) override;
  void prepareImpl(const Scene& scene, const Light& light) override;
  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override;
  // What the hard test found for one camera pixel, and the warped point the searches start from.
  struct Pixel {
    using enum brabec::PixelClass;
    uint8_t cls = Miss;
    int32_t key = kNoObject;         //!< interpolation id: the blocker's when blocked, the receiver's otherwise
    int32_t objectId = kNoObject;    //!< the receiver's own id (P'_ID)
    float s = 0.0f, t = 0.0f;        //!< P' in map coordinates, texels
    float lsDepth = 0.0f;            //!< P'z, world units
    float zLayer = 0.0f;             //!< P'z less the bias: the searches' depth layer
    float dzds = 0.0f, dzdt = 0.0f;  //!< receiver plane's depth change per texel, world units
    float texelWorld = 1.0f;         //!< texelWorldSize(P'z)
    float blockerDepth = 0.0f;       //!< depth of the texel over P when blocked
  };
  Pixel classify(const GBuffer& gbuffer, int x, int y) const;
  // The same with the pixel's receiver already set up (makeReceiverRow: a row's at once).
  Pixel classify(const GBuffer& gbuffer, int x, int y, const ShadowReceiver& receiver) const;
  // A surface turned away from the light's centre is in its own shadow: no search can light it.
  bool facesAwayFromLight(const Vec3& wsP, const Vec3& wsNg) const {
    const Vec3 wsToLight = light_->isDirectional() ? light_->direction() : light_->center() - wsP;  // sign only
    return glm::dot(wsNg, wsToLight) <= 0.0f;
  }
  // classify's class and interpolation id of every pixel of row y, from the row's receivers: the hard
  // test read from the row (its nearest texel and threshold), no Pixel built.
  void classifyRow(const GBuffer& gbuffer, int y, const ReceiverRow& receivers, uint8_t* cls, int32_t* key) const;
  // V of a classified pixel; `toTexel` (optional) receives the unit direction in the map from P' to
  // the texel the search found, (0, 0) when it found none; `raised` (optional) whether the coverage
  // bound raised V.
  // `seeds` (optional): the texels the last outer and inner searches of this thread found, where the next
  // searches start (SearchQuery::seedS), updated by this one.
  struct SearchSeeds {
    struct Texel {
      int s = -1, t = -1;  //!< -1: none
    };
    Texel outer, inner;
  };
  float evaluate(const Pixel& pixel, Vec2* toTexel = nullptr, bool* raised = nullptr,
                 SearchSeeds* seeds = nullptr) const;
  // The coverage bound (our extension): max(v, 1 - the blocked fraction of the light's footprint at
  // blocker depth zb around the pixel's P').
  float boundByCoverage(const Pixel& pixel, float v, float zb) const;

  BrabecOptions options_;
  LightMap map_;
  Image<float> jitterS_, jitterT_;
  std::vector<float> tileMinDepth_, tileMaxDepth_;
  std::vector<int32_t> tileObjectId_;
  int tilesPerRow_ = 0;
  brabec::TileNearestTable tileNearest_;
  brabec::LatticeDepths lattices_;  //!< the coverage bound's sparse counts
  std::optional<Light> light_;
  float minDepth_ = kInfinity;
  float lightRadius_ = 0.0f;
  // The light's shape in map directions, in units of lightRadius_ (the footprint of the coverage
  // bound at a blocker depth is this shape scaled by the penumbra width there): a segment's half
  // axis, or a polygon's vertices; a disk when neither.
  bool segmentLight_ = false;
  Vec2 segmentAxis_{0.0f};
  std::vector<Vec2> polygon_;
  float polygonArea_ = 0.0f;  //!< of polygon_
  double searches_ = 0.0;
  double hitPixels_ = 0.0;
  // The interpolation's per-pixel scratch (brabec.cpp), kept between frames so that a frame does not
  // fault in 8 MB of fresh pages at 1024 x 1024.
  std::vector<uint8_t> scratchClass_, scratchKnown_;
  std::vector<int32_t> scratchKey_;
  std::vector<int8_t> scratchDirection_;
};

TechniqueInfo brabecTechniqueInfo();

}  // namespace penumbra
