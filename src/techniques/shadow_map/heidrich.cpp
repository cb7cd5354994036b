// `heidrich`: soft shadow maps for linear lights (Heidrich, Brabec, Seidel 2000, "Soft shadow maps for
// linear lights", Rendering Techniques 2000, pp. 269-280; the talk's slides are the source followed
// here, slide titles quoted; docs/papers.md).
//
// The light is a segment. Each sample point of it gets a two-channel shadow map ("Visibility Map"):
// the depth channel of a point light there, and a visibility channel holding, in the penumbra, the
// fraction of the light that is visible. For the two end points L1, L2 of a linear light the visible
// fraction falls from 100% to 0% across [p1, p2], where L2 is hidden and L1 is not ("Visibility of
// Light Source"); the slides interpolate it linearly there ("Linear Interpolation of Visibility"):
// the exact relation between positions in the penumbra is the rational x1 = x2 t / (n x2 - m x2 + s),
// approximated by x1 = (t / s) x2, valid where the penumbra is large (n ~ m). The visibility channel
// is made so:
//  1. a shadow map per sample point ("Step 1");
//  2. edge detection on each depth map ("Step 2"; the slides use the Laplacian-of-Gaussian of the
//     OpenGL imaging subset): heidrich::detectEdges;
//  3. the depth discontinuities triangulated into "skin" polygons spanning occluder and receiver
//     depths, warped into the other sample point's view and rasterized there with Gouraud
//     interpolation, white (1) at receiver vertices, black (0) at occluder vertices ("Step 3");
//     texels no skin covers take the default 1/2 (a completely lit region: each end point's share);
//  4. shading ("new shadow map algorithm", shade(p)): l_i = 0 where the depth channel of sample i
//     shadows p, else V_i[p]; V = l1 + l2.
// Light subdivision ("Sampling the Light Source"): with k sub-segments (k + 1 sample points, the end
// points at k = 1) each sub-segment is a linear light of its own, shaded as above with weight 1 / k;
// this fixes the undersampling case where part of the light is visible but neither end point is.
//
// What a skin gives, exactly. Take p lit by L1 and hidden from L2 by an occluder, and the plane through
// p and the light. An occluder point S hides from p the light points beyond l_S, where the line p-S
// meets the light; the visible fraction is |L1 l*| / |L1 L2| for the S that hides the most. The skin
// of L2's silhouette point S2 is the ray L2 -> S2 -> R2 (R2 on the receiver); warped into L1's view it
// runs from S2's image (black) to R2's (white). For a receiver parallel to the light (the slides'
// setting) the fraction l_S2 gives falls linearly along the receiver from 1 at R2 to 0 at Q2, where
// L1's ray through S2 meets the receiver, and so does the position along the skin in L1's map
// coordinates, which are linear along such a receiver when the map plane is parallel to it: screen-
// linear (Gouraud) interpolation, not perspective-correct, is the exact one, and the skin gives the
// fraction S2 alone allows. That is V exactly where S2 is what hides the most: a straight edge, the
// top edge of a box where the penumbra lies beyond the box's side. It is not V where another occluder
// point hides more: below a box floating over the ground, its bottom edge B (L1's silhouette, hidden
// from L2) decides, and the skin of S2 there is too bright (up to 0.26 of V in the tests); round a
// sphere the deciding tangent point slides from L2's silhouette to L1's across the penumbra.
//
// Deviations and additions (besides the slides' linear interpolation), each measured in the tests:
//  - Penumbra: two bounds, the smaller taken. The slides' one: the lit sample's visibility channel
//    (the hidden sample's skins). And its mirror image: L1's own silhouette point S1 (B above) allows
//    the fraction 1 - g, where g is the value of S1's skin where L2's ray to p crosses it, behind the
//    occluder L2 sees. Each sample's map therefore holds a second channel, the nearest skin *behind*
//    the surface it sees (value and depth), read where that skin lies in front of p; a second channel
//    whose 2x2 lookup spreads over more than 1/4 is a skin seen edge-on near its occluder end and
//    gives no bound. With both, a box over a plane is exact but for its edge pixels and a sphere
//    close (the scan-line tests of tests/techniques/shadow_map/heidrich_test.cpp print both).
//  - Self-shadowing: where p's own plane hides one end of a sub-segment (its geometric normal faces
//    one sample point and not the other: between the two terminators of a curved or a box surface),
//    the skins near p are its own object's and say nothing about it; V there is the part of the
//    sub-segment in front of p's plane, g_a / (g_a - g_b) with g_j = N . (L_j - p), if the depth
//    channel of the facing sample lights p, else 0. Other occluders' penumbrae across such a band
//    are not seen.
//  - Edge detection: LoG = the 5-point Laplacian of the depth blurred by a 3x3 binomial; a texel is an
//    edge where |LoG| exceeds edge_threshold / 4 texel sizes (a step of D texel sizes gives D / 4).
//    The depth map is triangulated as a mesh of texel centres, two triangles per 2x2 quad; a quad is
//    skin where it touches an edge texel and a pair of its neighbouring corners steps by more than
//    edge_threshold texel sizes *plus the steeper of the steps beyond them on either side*: a surface
//    seen at a grazing angle (a box face nearly edge-on, a sphere near its outline) or a crease next
//    to such a face steps as much, but continues, and its skins would darken it in the other view.
//    Corners nearer than the middle of the gap are occluder vertices. Triangles whose vertices are
//    all on one side are dropped (they are no skin). A quad with an empty corner (nothing behind the
//    occluder) gives no skin: there is no receiver to shade.
//  - Skins are rasterized into the other view by a scanline loop of our own (screen-linear value,
//    1 / z linear for the depth), which keeps per texel both the nearest skin in front of the surface
//    the view sees and the nearest behind it. Within two texels of depth of that surface only a skin's
//    receiver half (value >= 1/2) counts as in front: there a skin meets its receiver; its occluder
//    half lying on a surface lies on its own occluder, which it does not shadow.
//  - Lookups: the visibility channel is read bilinearly at the receiver's map position. Where the
//    depth channels say p is in the penumbra (one end point lit, the other not), only texels a skin
//    covers are read: a skin's edge texel sits up to a texel off the hard shadow edges, and the
//    default 1/2 of an uncovered neighbour would otherwise drop V by half in a one-texel band along
//    the penumbra's edges. Where neither channel has a covered texel, the slides' default 1/2
//    stands. Where both end points are lit, the sum of their two shares is limited to 1 (overlapping
//    skins can claim more than the whole sub-segment). Each texel records whether a skin covers any
//    texel of its 3x3 neighbourhood; where none does, the lookup is the default without reading more:
//    fully lit and umbra pixels cost one texel read per map, the visibility channel sitting next to
//    the depth in one two-channel texel.
//  - All maps share one orientation, the segment's light frame (Light::lightFrame: +z from the
//    segment's centre to the scene's centre); each is a perspective map fitted to the scene from its
//    own sample point (renderLightMap). Each pixel is taken into map 0's light space and moved by each
//    map's origin there (heidrich::receiverInMap), a row of pixels per map at once in the visibility
//    pass (makeReceiverRowInFrame, shadow_map.h: the same receivers to the bit).
//  - The depth channel's compare is the hard shadow of shadow_map.h (receiver plane, slope-scaled
//    bias); receivers outside a map are lit by that sample point.
//
// Light shapes: segment only; every other shape is rejected with an Error naming it (a rect light as
// several segments is not offered: its 2D penumbra is no linear interpolation along one direction).
//
// Parameters: map_size (texels per side of every map, default 1024), subdivisions (k, default 1: the
// slides' two samples), edge_threshold (texel sizes, default 4), bias_constant and bias_slope (the
// depth compare's, shadow_map.h). Memory: (k + 1) shadow maps (depth and object id, map_size^2 each),
// per sub-segment two two-channel maps (depth and visibility side by side) of 2 map_size^2 floats and
// two second channels (value and depth) of 2 map_size^2 floats, and prepare()'s working images (about
// 5 map_size^2 floats), all kept between calls.
// prepare() builds every map; visibility() only reads them, so a camera-only change costs one
// visibility pass (the slides' "minimal overhead for static walk-throughs"). A new light or scene
// refills the maps in place.
#include "heidrich.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/image_fill.h"
#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/timer.h"

namespace penumbra {
namespace heidrich {

namespace {

// One row of the edge test: the 5-point Laplacian of the blurred depth (rows up, mid, down; mid[-1] and
// mid[n] repeat its border texels) against k texel sizes at the texel's depth z. Values in, restrict
// pointers: the byte stores may alias nothing the loop reads, so it vectorizes.
void edgeRow(const float* __restrict up, const float* __restrict mid, const float* __restrict down,
             const float* __restrict z, int n, float k, float texelPerDepth, float texelConstant,
             uint8_t* __restrict e) {
  for (int x = 0; x < n; ++x) {
    const float log = mid[x - 1] + mid[x + 1] + up[x] + down[x] - 4.0f * mid[x];
    const float threshold = k * (texelPerDepth * z[x] + texelConstant);
    e[x] = !(std::abs(log) <= threshold);  // NaN and inf (empty texels nearby) are edges
  }
}

}  // namespace

void detectEdges(const LightMap& map, float edgeThresholdTexels, Image<uint8_t>& edges) {
  const int n = map.size;
  edges.resizeForOverwrite(n, n);  // every texel written below, in parallel
  if (n == 0) return;
  auto clampIndex = [n](int i) { return std::clamp(i, 0, n - 1); };
  const float* depth = map.lsDepth.data();
  // texelWorldSize(z) is linear in z for a perspective map and constant for an orthographic one.
  const float texelPerDepth = map.orthographic ? 0.0f : map.texelWorldSize(1.0f);
  const float texelConstant = map.orthographic ? map.texelWorldSize(1.0f) : 0.0f;
  const float k = 0.25f * edgeThresholdTexels;
  // Bands of rows, each blurred and filtered in its own buffers (a band's rows of the horizontal blur,
  // with two rows beyond it on either side, then of the full blur, with one): the passes meet in the
  // cache instead of in two map-sized images. The band's outer rows are computed twice; every value
  // is the same expression of the same texels whichever band computes it.
  constexpr int kBand = 32;
  const auto stride = static_cast<size_t>(n) + 2;  // blurred rows keep their border texels repeated
  tbb::enumerable_thread_specific<std::vector<float>> horizontalRows(static_cast<size_t>(kBand + 4) * n);
  tbb::enumerable_thread_specific<std::vector<float>> blurredRows(static_cast<size_t>(kBand + 2) * stride);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, kBand), [&](const tbb::blocked_range<int>& rows) {
    const int y0 = rows.begin(), y1 = rows.end();
    // The binomial blur, separable; borders repeat the edge texel. Empty texels (+inf) spread +inf over
    // the blur's support, and the Laplacian turns that into NaN or inf: flagged below, skipped later.
    const int h0 = std::max(0, y0 - 2), h1 = std::min(n, y1 + 2);
    std::vector<float>& hBuffer = horizontalRows.local();
    hBuffer.resize(static_cast<size_t>(h1 - h0) * n);
    auto horizontal = [&](int y) { return hBuffer.data() + static_cast<size_t>(y - h0) * n; };
    for (int y = h0; y < h1; ++y) {
      const float* z = depth + static_cast<size_t>(y) * n;
      float* h = horizontal(y);
      h[0] = 0.25f * z[0] + 0.5f * z[0] + 0.25f * z[clampIndex(1)];
      for (int x = 1; x < n - 1; ++x) h[x] = 0.25f * z[x - 1] + 0.5f * z[x] + 0.25f * z[x + 1];
      if (n > 1) h[n - 1] = 0.25f * z[n - 2] + 0.5f * z[n - 1] + 0.25f * z[n - 1];
    }
    const int b0 = std::max(0, y0 - 1), b1 = std::min(n, y1 + 1);
    std::vector<float>& bBuffer = blurredRows.local();
    bBuffer.resize(static_cast<size_t>(b1 - b0) * stride);
    // Blurred row y, padded: [-1] and [n] repeat its border texels, so the Laplacian's loop reads x - 1
    // and x + 1 unclamped and vectorizes.
    auto blurred = [&](int y) { return bBuffer.data() + static_cast<size_t>(y - b0) * stride + 1; };
    for (int y = b0; y < b1; ++y) {
      const float* up = horizontal(clampIndex(y - 1));
      const float* mid = horizontal(y);
      const float* down = horizontal(clampIndex(y + 1));
      float* b = blurred(y);
      for (int x = 0; x < n; ++x) b[x] = 0.25f * up[x] + 0.5f * mid[x] + 0.25f * down[x];
      b[-1] = b[0];
      b[n] = b[n - 1];
    }
    for (int y = y0; y < y1; ++y) {
      const float* up = blurred(clampIndex(y - 1));
      const float* mid = blurred(y);
      const float* down = blurred(clampIndex(y + 1));
      const float* z = depth + static_cast<size_t>(y) * n;
      edgeRow(up, mid, down, z, n, k, texelPerDepth, texelConstant, edges.row(y));
    }
  });
}

Image<uint8_t> detectEdges(const LightMap& map, float edgeThresholdTexels) {
  Image<uint8_t> edges;
  detectEdges(map, edgeThresholdTexels, edges);
  return edges;
}

namespace {

// Whether the depths of texels (i, j) and (i + di, j + dj) differ by more than `gap` plus the depth
// step from each of them to the texel beyond it (its side's slope): a depth discontinuity, rather than
// a steep stretch of one surface or a crease between a face and a steep face, whose steps the slope
// on one side explains. Beyond the map's border a side has no slope.
bool steepStep(const Image<float>& z, int i, int j, int di, int dj, float gap) {
  const int n = z.width();
  const float za = z(i, j), zb = z(i + di, j + dj);
  const int ia = i - di, ja = j - dj, ib = i + 2 * di, jb = j + 2 * dj;
  const float slopeA = ia >= 0 && ja >= 0 ? std::abs(za - z(ia, ja)) : 0.0f;
  const float slopeB = ib < n && jb < n ? std::abs(z(ib, jb) - zb) : 0.0f;
  // An empty texel beyond (+inf) gives an infinite or NaN slope: no slope there.
  const float slope = std::max(std::isfinite(slopeA) ? slopeA : 0.0f, std::isfinite(slopeB) ? slopeB : 0.0f);
  return std::abs(zb - za) > gap + slope;
}

}  // namespace

void buildSkin(const LightMap& map, const Image<uint8_t>& edges, float edgeThresholdTexels, SkinMesh& skin,
               std::vector<SkinMesh>& rows) {
  const int n = map.size;
  skin.wsPositions.clear();
  skin.value.clear();
  skin.triangles.clear();
  if (n < 2) return;
  // Rows of quads in parallel, each into its own mesh, joined in row order: the same mesh for any
  // thread count.
  if (rows.size() < static_cast<size_t>(n - 1)) rows.resize(static_cast<size_t>(n - 1));
  tbb::parallel_for(tbb::blocked_range<int>(0, n - 1), [&](const tbb::blocked_range<int>& range) {
    for (int j = range.begin(); j < range.end(); ++j) {
      SkinMesh& out = rows[static_cast<size_t>(j)];
      out.wsPositions.clear();
      out.value.clear();
      out.triangles.clear();
      const uint8_t* edgesHere = edges.row(j);
      const uint8_t* edgesBelow = edges.row(j + 1);
      const float* depthHere = map.lsDepth.row(j);
      const float* depthBelow = map.lsDepth.row(j + 1);
      for (int i = 0; i < n - 1; ++i) {
        // Most quads touch no edge texel, or lie where the map is empty (every empty texel is an edge,
        // and a quad with an empty corner gives no skin, below): eight of them at a time are passed over.
        if ((i & 7) == 0 && i + 9 <= n) {
          uint64_t a, b, c, d;
          std::memcpy(&a, edgesHere + i, 8);
          std::memcpy(&b, edgesHere + i + 1, 8);
          std::memcpy(&c, edgesBelow + i, 8);
          std::memcpy(&d, edgesBelow + i + 1, 8);
          bool empty = true;
          for (int k = 0; k <= 8; ++k) empty &= (depthHere[i + k] == kInfinity) & (depthBelow[i + k] == kInfinity);
          if ((a | b | c | d) == 0 || empty) {
            i += 7;
            continue;
          }
        }
        if (!(edgesHere[i] | edgesHere[i + 1] | edgesBelow[i] | edgesBelow[i + 1])) continue;
        // Corners in the order 00, 10, 11, 01 (a cycle around the quad).
        const int ci[4] = {i, i + 1, i + 1, i};
        const int cj[4] = {j, j, j + 1, j + 1};
        float z[4];
        float zMin = kInfinity, zMax = -kInfinity;
        for (int c = 0; c < 4; ++c) {
          z[c] = map.lsDepth(ci[c], cj[c]);
          zMin = std::min(zMin, z[c]);
          zMax = std::max(zMax, z[c]);
        }
        if (!std::isfinite(zMax)) continue;  // nothing behind the occluder: no receiver to shade
        const float gap = edgeThresholdTexels * map.texelWorldSize(zMin);
        if (!(zMax - zMin > gap)) continue;
        // A surface seen at a grazing angle (a box face nearly edge-on, a sphere near its outline)
        // has depth steps as large as a discontinuity's, but continues across them: one side's depths,
        // extrapolated linearly over the step, meet the other side's. Only a step that neither side
        // continues is a discontinuity; skins on a continuous surface would darken it in the other view.
        const bool step = steepStep(map.lsDepth, i, j, 1, 0, gap) || steepStep(map.lsDepth, i, j + 1, 1, 0, gap) ||
                          steepStep(map.lsDepth, i, j, 0, 1, gap) || steepStep(map.lsDepth, i + 1, j, 0, 1, gap);
        if (!step) continue;
        const float middle = 0.5f * (zMin + zMax);
        bool occluder[4];
        for (int c = 0; c < 4; ++c) occluder[c] = z[c] < middle;
        const auto base = static_cast<uint32_t>(out.wsPositions.size());
        for (int c = 0; c < 4; ++c) {
          out.wsPositions.push_back(
              map.unproject(static_cast<float>(ci[c]) + 0.5f, static_cast<float>(cj[c]) + 0.5f, z[c]));
          out.value.push_back(occluder[c] ? 0.0f : 1.0f);
        }
        // Two triangles, 00-10-11 and 00-11-01; one with all vertices on one side is no skin.
        const int tris[2][3] = {{0, 1, 2}, {0, 2, 3}};
        for (const auto& t : tris) {
          const int occluders = occluder[t[0]] + occluder[t[1]] + occluder[t[2]];
          if (occluders == 0 || occluders == 3) continue;
          out.triangles.emplace_back(base + t[0], base + t[1], base + t[2]);
        }
      }
    }
  });
  size_t vertexCount = 0, triangleCount = 0;
  for (int j = 0; j < n - 1; ++j) {
    vertexCount += rows[static_cast<size_t>(j)].wsPositions.size();
    triangleCount += rows[static_cast<size_t>(j)].triangles.size();
  }
  skin.wsPositions.reserve(vertexCount);
  skin.value.reserve(vertexCount);
  skin.triangles.reserve(triangleCount);
  for (int j = 0; j < n - 1; ++j) {
    const SkinMesh& r = rows[static_cast<size_t>(j)];
    const auto offset = static_cast<uint32_t>(skin.wsPositions.size());
    skin.wsPositions.insert(skin.wsPositions.end(), r.wsPositions.begin(), r.wsPositions.end());
    skin.value.insert(skin.value.end(), r.value.begin(), r.value.end());
    for (const glm::uvec3& t : r.triangles) skin.triangles.push_back(t + glm::uvec3(offset));
  }
}

SkinMesh buildSkin(const LightMap& map, const Image<uint8_t>& edges, float edgeThresholdTexels) {
  SkinMesh skin;
  std::vector<SkinMesh> rows;
  buildSkin(map, edges, edgeThresholdTexels, skin, rows);
  return skin;
}

void clearBehindLayer(int size, Image<Vec2>& behind, std::vector<uint8_t>& behindRows) {
  resetInParallel(behind, size, size, kNoSkinBehind);
  behindRows.assign(static_cast<size_t>(size), 0);
}

void renderVisibilityLayers(const SkinMesh& skin, const LightMap& view, Image<float>& front, Image<Vec2>& behind,
                            std::vector<uint8_t>& behindRows, Image<float>& frontDepth,
                            std::vector<uint8_t>& skinRows) {
  // `behind` keeps its pixels from the last call: only the rows a skin reached then are cleared (all of
  // them when the size changed). Most rows of a map never hold a skin.
  const auto n = static_cast<size_t>(view.size);
  if (behind.width() != view.size || behind.height() != view.size || behindRows.size() != n) {
    clearBehindLayer(view.size, behind, behindRows);
  } else {
    tbb::parallel_for(tbb::blocked_range<int>(0, view.size, 16), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j)
        if (behindRows[static_cast<size_t>(j)]) std::fill(behind.row(j), behind.row(j) + view.size, kNoSkinBehind);
    });
  }
  // `front` and `frontDepth` are filled below on the rows a skin may reach only, and makeTwoChannelMap
  // reads no other.
  front.resizeForOverwrite(view.size, view.size);
  frontDepth.resizeForOverwrite(view.size, view.size);
  skinRows.assign(n, 0);
  behindRows.assign(n, 0);
  if (skin.triangles.empty() || view.size == 0) return;
  if (view.orthographic) fail("heidrich: visibility maps need a perspective map (a local light)");
  // Vertices in the view's map coordinates (s, t) and light-space depth z. A skin lies between an
  // occluder and its receiver, in front of every sample point; a vertex nearer than half the near
  // plane (or not finite) can only come from a texel at a map's border: its triangle is skipped.
  const float zMin = 0.5f * view.zNear;
  struct Setup {
    double s[3], t[3], area;
    float invZ[3], value[3];
    int rowBegin, rowEnd;  //!< the rows whose texel centres the triangle's bounds hold
  };
  std::vector<Setup> setups;
  setups.reserve(skin.triangles.size());
  for (const glm::uvec3& tri : skin.triangles) {
    Setup u{};
    bool valid = true;
    double tMin = 1e30, tMax = -1e30;
    for (int c = 0; c < 3; ++c) {
      const Vec3 v = view.project(skin.wsPositions[tri[c]]);
      valid = valid && std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && v.z > zMin;
      u.s[c] = v.x;
      u.t[c] = v.y;
      u.invZ[c] = 1.0f / v.z;
      u.value[c] = skin.value[tri[c]];
      tMin = std::min(tMin, u.t[c]);
      tMax = std::max(tMax, u.t[c]);
    }
    if (!valid) continue;
    u.area = (u.s[1] - u.s[0]) * (u.t[2] - u.t[0]) - (u.t[1] - u.t[0]) * (u.s[2] - u.s[0]);
    if (!(std::abs(u.area) > 1e-9)) continue;  // seen edge-on from this view: it covers nothing
    u.rowBegin = std::max(0, static_cast<int>(std::ceil(tMin - 0.5)));
    u.rowEnd = std::min(view.size, static_cast<int>(std::floor(tMax - 0.5)) + 1);
    if (u.rowBegin < u.rowEnd) setups.push_back(u);
  }
  for (const Setup& u : setups) std::fill(skinRows.begin() + u.rowBegin, skinRows.begin() + u.rowEnd, uint8_t{1});
  behindRows = skinRows;
  // Bands of rows in parallel; within a band, the triangles in input order and a strict "nearer wins":
  // the same maps for any thread count. Edges are inclusive (a texel centre on the edge two skin
  // triangles share takes the first one's value; both interpolate alike there), so no texel centre
  // falls between the triangles of a skin.
  const float texelPerDepth = view.texelWorldSize(1.0f);
  constexpr int kBand = 16;
  const int bands = (view.size + kBand - 1) / kBand;
  tbb::parallel_for(tbb::blocked_range<int>(0, bands), [&](const tbb::blocked_range<int>& range) {
    for (int band = range.begin(); band < range.end(); ++band) {
      const int y0 = band * kBand, y1 = std::min(view.size, y0 + kBand);
      for (int j = y0; j < y1; ++j)
        if (skinRows[static_cast<size_t>(j)]) {
          std::fill(front.row(j), front.row(j) + view.size, kUncovered);
          std::fill(frontDepth.row(j), frontDepth.row(j) + view.size, kInfinity);
        }
      for (const Setup& u : setups) {
        const int jBegin = std::max(u.rowBegin, y0), jEnd = std::min(u.rowEnd, y1);
        for (int j = jBegin; j < jEnd; ++j) {
          const double t = j + 0.5;
          // Screen-space barycentric of vertex c along this row: lambda_c(s) = alpha_c s + beta_c (the
          // edge function of the opposite edge over the signed area).
          double alpha[3], beta[3];
          for (int c = 0; c < 3; ++c) {
            const int a = (c + 1) % 3, b = (c + 2) % 3;
            alpha[c] = -(u.t[b] - u.t[a]) / u.area;
            beta[c] = ((u.s[b] - u.s[a]) * (t - u.t[a]) + (u.t[b] - u.t[a]) * u.s[a]) / u.area;
          }
          constexpr double kEdge = -1e-9;  // inclusive edges, up to rounding
          double sLo = -1e30, sHi = 1e30;
          bool empty = false;
          for (int c = 0; c < 3; ++c) {
            if (alpha[c] > 0.0)
              sLo = std::max(sLo, (kEdge - beta[c]) / alpha[c]);
            else if (alpha[c] < 0.0)
              sHi = std::min(sHi, (kEdge - beta[c]) / alpha[c]);
            else
              empty = empty || beta[c] < kEdge;
          }
          if (empty || !(sLo <= sHi)) continue;
          const int iBegin = std::max(0, static_cast<int>(std::ceil(sLo - 0.5)));
          const int iEnd = std::min(view.size, static_cast<int>(std::floor(sHi - 0.5)) + 1);
          float* frontRow = front.row(j);
          float* zFront = frontDepth.row(j);
          Vec2* behindRow = behind.row(j);
          const float* zSurface = view.lsDepth.row(j);
          for (int i = iBegin; i < iEnd; ++i) {
            const double s = i + 0.5;
            float l[3];
            for (int c = 0; c < 3; ++c) l[c] = static_cast<float>(std::clamp(alpha[c] * s + beta[c], 0.0, 1.0));
            // 1 / z is linear in screen space; the value is Gouraud-shaded, linear in screen space
            // (the file comment derives why that is the right interpolation).
            const float zSkin = 1.0f / (l[0] * u.invZ[0] + l[1] * u.invZ[1] + l[2] * u.invZ[2]);
            const float value = std::clamp(l[0] * u.value[0] + l[1] * u.value[1] + l[2] * u.value[2], 0.0f, 1.0f);
            // In front of the surface this view sees: the slides' channel. Within two texels of depth
            // of that surface, only the receiver half of a skin (value >= 1/2), where the skin meets
            // its receiver: the occluder half of a skin there lies on its own occluder, which it does
            // not shadow. Behind the surface: the second channel. Nearest wins in each.
            const float tolerance = 2.0f * texelPerDepth * zSurface[i];
            if (zSkin < zSurface[i] - tolerance || (zSkin <= zSurface[i] + tolerance && value >= 0.5f)) {
              if (zSkin < zFront[i]) {
                zFront[i] = zSkin;
                frontRow[i] = value;
              }
            } else if (zSkin > zSurface[i] + tolerance && zSkin < behindRow[i].y) {
              behindRow[i] = Vec2(value, zSkin);
            }
          }
        }
      }
    }
  });
}

void makeTwoChannelMap(const LightMap& map, const Image<float>& visibility, const std::vector<uint8_t>& skinRows,
                       Image<TwoChannelTexel>& out, Image<uint8_t>& horizontal) {
  const int n = map.size;
  // Every texel of `out` is written below, in parallel; `horizontal` on the rows with skin.
  out.resizeForOverwrite(n, n);
  if (n == 0) return;
  auto hasSkin = [&](int j) { return skinRows[static_cast<size_t>(j)] != 0; };
  // Coverage dilated by one texel (3x3), separably: a horizontal then a vertical OR. A row without skin
  // has no coverage.
  horizontal.resizeForOverwrite(n, n);
  const std::vector<uint8_t> noCoverage(static_cast<size_t>(n), 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
    for (int j = rows.begin(); j < rows.end(); ++j) {
      if (!hasSkin(j)) continue;
      const float* v = visibility.row(j);
      uint8_t* h = horizontal.row(j);
      for (int i = 0; i < n; ++i) h[i] = v[i] >= 0.0f;
      uint8_t previous = 0;
      for (int i = 0; i < n; ++i) {
        const uint8_t here = h[i];
        h[i] = static_cast<uint8_t>(previous | here | (i + 1 < n && v[i + 1] >= 0.0f));
        previous = here;
      }
    }
  });
  tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
    for (int j = rows.begin(); j < rows.end(); ++j) {
      const int jUp = std::max(j - 1, 0), jDown = std::min(j + 1, n - 1);
      const float* z = map.lsDepth.row(j);
      TwoChannelTexel* o = out.row(j);
      if (!hasSkin(jUp) && !hasSkin(j) && !hasSkin(jDown)) {
        for (int i = 0; i < n; ++i) o[i] = TwoChannelTexel{z[i], kNoSkinNearby};
        continue;
      }
      const uint8_t* up = hasSkin(jUp) ? horizontal.row(jUp) : noCoverage.data();
      const uint8_t* mid = hasSkin(j) ? horizontal.row(j) : noCoverage.data();
      const uint8_t* down = hasSkin(jDown) ? horizontal.row(jDown) : noCoverage.data();
      if (!hasSkin(j)) {  // no skin here, one nearby
        for (int i = 0; i < n; ++i) o[i] = TwoChannelTexel{z[i], (up[i] | down[i]) != 0 ? kUncovered : kNoSkinNearby};
        continue;
      }
      const float* v = visibility.row(j);
      for (int i = 0; i < n; ++i) {
        const bool near = (up[i] | mid[i] | down[i]) != 0;
        o[i] = TwoChannelTexel{z[i], v[i] >= 0.0f ? v[i] : (near ? kUncovered : kNoSkinNearby)};
      }
    }
  });
}

ShadowReceiver receiverInMap(const LightMap& map, const Vec3& lsP, const Vec3& lsN, const DepthBias& bias) {
  // makeReceiver for a perspective map whose frame the caller already transformed into.
  if (!(lsP.z > 0.0f)) return {};
  return receiverAt(map, map.projectLightSpace(lsP), lsP, lsN, bias);
}

}  // namespace heidrich

namespace {

// The sample points' maps: their compares and skins read depths only.
constexpr LightMapLayers kMapLayers = LightMapLayers::NearestDepth;
constexpr float kLitShare = 0.5f;  // an uncovered texel: each end point's share of its sub-segment
// Largest spread of the second channel over a lookup's 2x2 texels that is read as one skin.
constexpr float kMaxBehindSpread = 0.25f;

using heidrich::TwoChannelTexel;

// The texel holding p in one two-channel map: the depth channel's compare (hardShadow of
// shadow_map.h) and whether a skin lies near enough for the visibility lookups to read one.
struct TexelRead {
  bool lit = true;
  bool nearSkin = false;
};

// Pixel x of a row of receivers (makeReceiverRow): the row's nearest texel and its blocker threshold are
// hardShadow's, to the bit.
TexelRead readTexel(const Image<TwoChannelTexel>& m, const ReceiverRow& row, int x) {
  const auto i = static_cast<size_t>(x);
  if (!row.inMap[i]) return {};  // lit, and no visibility information: the lit share
  const TwoChannelTexel& t = m.data()[static_cast<size_t>(row.nearestTexel[i])];
  return TexelRead{!(t.lsDepth < row.nearestThreshold[i]), t.visibility != heidrich::kNoSkinNearby};
}

// Bilinear footprint of map position (s, t) over texel centres, clamped to the map.
struct Footprint {
  size_t i00, i10, i01, i11;  //!< texel indices
  float w00, w10, w01, w11;   //!< weights
};

Footprint footprint(int n, const ShadowReceiver& r) {
  const float sc = r.s - 0.5f, tc = r.t - 0.5f;
  const float fs0 = std::floor(sc), ft0 = std::floor(tc);
  const float ws = sc - fs0, wt = tc - ft0;
  const int i0 = static_cast<int>(fs0), j0 = static_cast<int>(ft0);
  const size_t ia = static_cast<size_t>(std::clamp(i0, 0, n - 1)),
               ib = static_cast<size_t>(std::clamp(i0 + 1, 0, n - 1));
  const size_t ja = static_cast<size_t>(std::clamp(j0, 0, n - 1)),
               jb = static_cast<size_t>(std::clamp(j0 + 1, 0, n - 1));
  const size_t stride = static_cast<size_t>(n);
  return Footprint{ja * stride + ia,          ja * stride + ib, jb * stride + ia, jb * stride + ib,
                   (1.0f - ws) * (1.0f - wt), ws * (1.0f - wt), (1.0f - ws) * wt, ws * wt};
}

// The visibility channel where both sample points light p: bilinear, uncovered texels at the lit share.
float lookupLit(const Image<TwoChannelTexel>& m, const ShadowReceiver& r) {
  if (!r.inMap) return kLitShare;
  const Footprint f = footprint(m.width(), r);
  const TwoChannelTexel* t = m.data();
  auto value = [](float v) { return v >= 0.0f ? v : kLitShare; };
  return f.w00 * value(t[f.i00].visibility) + f.w10 * value(t[f.i10].visibility) + f.w01 * value(t[f.i01].visibility) +
         f.w11 * value(t[f.i11].visibility);
}

// The visibility channel in the penumbra (the other sample point is hidden): bilinear over covered
// texels only (weights renormalized); kUncovered where none is covered (file comment, "Lookups").
float lookupPenumbra(const Image<TwoChannelTexel>& m, const ShadowReceiver& r) {
  if (!r.inMap) return heidrich::kUncovered;
  const Footprint f = footprint(m.width(), r);
  const TwoChannelTexel* t = m.data();
  const float v00 = t[f.i00].visibility, v10 = t[f.i10].visibility;
  const float v01 = t[f.i01].visibility, v11 = t[f.i11].visibility;
  const float w00 = v00 >= 0.0f ? f.w00 : 0.0f, w10 = v10 >= 0.0f ? f.w10 : 0.0f;
  const float w01 = v01 >= 0.0f ? f.w01 : 0.0f, w11 = v11 >= 0.0f ? f.w11 : 0.0f;
  const float weight = w00 + w10 + w01 + w11;
  if (!(weight > 0.0f)) return heidrich::kUncovered;
  return (w00 * v00 + w10 * v10 + w01 * v01 + w11 * v11) / weight;
}

// The second channel of the hidden sample point's map at p: bilinear over the texels whose skin lies
// between that sample's visible surface and p (nearer than p by more than the depth bias), weights
// renormalized; kUncovered where none does.
float lookupBehind(const Image<Vec2>& m, const ShadowReceiver& r) {
  if (!r.inMap) return heidrich::kUncovered;
  const Footprint f = footprint(m.width(), r);
  const Vec2* t = m.data();
  const float zMax = r.lsDepth - r.bias;
  auto weight = [&](size_t i, float w) { return t[i].x >= 0.0f && t[i].y < zMax ? w : 0.0f; };
  const float w00 = weight(f.i00, f.w00), w10 = weight(f.i10, f.w10);
  const float w01 = weight(f.i01, f.w01), w11 = weight(f.i11, f.w11);
  const float sum = w00 + w10 + w01 + w11;
  if (!(sum > 0.0f)) return heidrich::kUncovered;
  // A skin seen nearly edge-on from this map (its occluder end, where the occluder vertices' depths
  // jump from row to row) gives unrelated values in neighbouring texels: no bound there.
  float lo = 1.0f, hi = 0.0f;
  for (const auto& [i, w] :
       {std::pair{f.i00, w00}, std::pair{f.i10, w10}, std::pair{f.i01, w01}, std::pair{f.i11, w11}})
    if (w > 0.0f) {
      lo = std::min(lo, t[i].x);
      hi = std::max(hi, t[i].x);
    }
  if (hi - lo > kMaxBehindSpread) return heidrich::kUncovered;
  return (w00 * t[f.i00].x + w10 * t[f.i10].x + w01 * t[f.i01].x + w11 * t[f.i11].x) / sum;
}

// V of a sub-segment where its sample point `lit` lights p and `hidden` does not (file comment,
// "Penumbra"): the lit sample's visibility channel (the hidden sample's skins) bounds V from above, and
// so does one minus the hidden sample's second channel (the lit sample's own skins, seen from the
// hidden one); the smaller bound is taken.
float penumbraShare(const Image<TwoChannelTexel>& lit, const ShadowReceiver& rLit, const Image<Vec2>& hiddenBehind,
                    const ShadowReceiver& rHidden) {
  const float front = lookupPenumbra(lit, rLit);
  const float behind = lookupBehind(hiddenBehind, rHidden);
  if (front >= 0.0f && behind >= 0.0f) return std::min(front, 1.0f - behind);
  if (front >= 0.0f) return front;
  if (behind >= 0.0f) return 1.0f - behind;
  return kLitShare;
}

}  // namespace

HeidrichTechnique::HeidrichTechnique(const HeidrichOptions& options) : options_(options) {
  if (options.subdivisions < 1 || options.subdivisions > 64)
    fail("heidrich: subdivisions = {} is not valid: expected an int in [1, 64]", options.subdivisions);
  if (!(options.edgeThreshold > 0.0f) || !std::isfinite(options.edgeThreshold))
    fail("heidrich: edge_threshold = {} is not valid: expected a finite number of texel sizes > 0",
         options.edgeThreshold);
}

void HeidrichTechnique::reserveImpl(int, int) {
  const auto samples = static_cast<size_t>(options_.subdivisions) + 1;
  const size_t ends = 2 * static_cast<size_t>(options_.subdivisions);
  const int n = options_.lightMap.size;
  maps_.resize(samples);
  for (LightMap& map : maps_) reserveShadowMap(options_.lightMap, map, kMapLayers);
  visibility_.resize(ends);
  behind_.resize(ends);
  behindRows_.resize(ends);
  for (size_t slot = 0; slot < ends; ++slot) {
    resetInParallel(visibility_[slot], n, n, TwoChannelTexel{kInfinity, heidrich::kUncovered});
    heidrich::clearBehindLayer(n, behind_[slot], behindRows_[slot]);
  }
  Scratch& w = scratch_;
  resetInParallel(w.edges, n, n, uint8_t{0});
  resetInParallel(w.front, n, n, heidrich::kUncovered);
  resetInParallel(w.frontDepth, n, n, kInfinity);
  resetInParallel(w.coverage, n, n, uint8_t{0});
}

void HeidrichTechnique::prepareImpl(const Scene& scene, const Light& light) {
  setHorizonClamp(options_.lightMap.horizon, light);  // its maps look from several points: the light itself
  prepared_ = false;                                  // a failed prepare() leaves nothing for visibility() to use
  if (light.shape() != LightShape::Segment)
    fail(
        "heidrich: a {} light is not supported: soft shadow maps for linear lights need a segment light "
        "(\"type\": \"segment\" with end points a and b)",
        toString(light.shape()));
  const int k = options_.subdivisions;
  const auto samples = static_cast<size_t>(k + 1);
  // Every map looks along the segment's own light axis (see the file comment). A disk stand-in keeps
  // that axis: Light::lightFrame takes a disk's normal, turned to face the scene (a stable fit
  // quantizes the segment's axis here, and the disks keep it).
  const Frame frame = lightMapFrame(light, scene.bounds(), options_.lightMap.fit);
  const float tiny = 1e-4f * light.extent();
  Timer stage;
  maps_.resize(samples);
  wsSamples_.clear();
  for (size_t j = 0; j < samples; ++j) {
    const float u = static_cast<float>(j) / static_cast<float>(k);
    const Vec3 wsSample = light.a() + u * (light.b() - light.a());
    createShadowMap(scene, Light::disk(wsSample, frame.z, tiny), options_.lightMap, maps_[j], kMapLayers);
    // The point the map looks from: the sample itself, or its lattice point in a stable map, so that
    // the facing test and the map agree.
    wsSamples_.push_back(maps_[j].wsOrigin);
    ++shadowMapsBuilt_;
    reportProgress(0.5 * static_cast<double>(j + 1) / static_cast<double>(samples));
  }
  sharedFrame_ = true;
  lsOffsets_.clear();
  for (const LightMap& map : maps_) {
    sharedFrame_ = sharedFrame_ && map.lsFrame.x == maps_[0].lsFrame.x && map.lsFrame.y == maps_[0].lsFrame.y &&
                   map.lsFrame.z == maps_[0].lsFrame.z;
    lsOffsets_.push_back(maps_[0].lsFromWs(map.wsOrigin));
  }
  shadowMapsMs_ = stage.elapsedMs();
  stage.reset();
  Scratch& w = scratch_;
  w.skins.resize(samples);
  skinTriangles_ = 0;
  for (size_t j = 0; j < samples; ++j) {
    heidrich::detectEdges(maps_[j], options_.edgeThreshold, w.edges);
    heidrich::buildSkin(maps_[j], w.edges, options_.edgeThreshold, w.skins[j], w.skinRows);
    skinTriangles_ += w.skins[j].triangles.size();
  }
  skinsMs_ = stage.elapsedMs();
  stage.reset();
  // Sub-segment q = [sample q, sample q + 1]: each end's visibility channel holds the other end's
  // skins, warped into its view.
  visibility_.resize(2 * static_cast<size_t>(k));
  behind_.resize(2 * static_cast<size_t>(k));
  behindRows_.resize(2 * static_cast<size_t>(k));
  for (int q = 0; q < k; ++q) {
    for (size_t end = 0; end < 2; ++end) {
      const size_t self = static_cast<size_t>(q) + end, other = static_cast<size_t>(q) + 1 - end;
      const size_t slot = 2 * static_cast<size_t>(q) + end;
      heidrich::renderVisibilityLayers(w.skins[other], maps_[self], w.front, behind_[slot], behindRows_[slot],
                                       w.frontDepth, w.frontRows);
      heidrich::makeTwoChannelMap(maps_[self], w.front, w.frontRows, visibility_[slot], w.coverage);
    }
    visibilityMapsBuilt_ += 2;
    reportProgress(0.5 + 0.5 * (q + 1) / k);
  }
  visibilityMapsMs_ = stage.elapsedMs();
  prepared_ = true;
}

void HeidrichTechnique::visibilityImpl(const GBuffer& gbuffer, Image<float>& v) {
  if (!prepared_) fail("heidrich: visibility() called before prepare()");
  const int k = static_cast<int>(maps_.size()) - 1;
  const auto samples = maps_.size();
  const float subWeight = 1.0f / static_cast<float>(k);
  const int width = gbuffer.width();
  v.resizeForOverwrite(width, gbuffer.height());  // every pixel written below, in parallel
  tbb::parallel_for(tbb::blocked_range<int>(0, gbuffer.height()), [&](const tbb::blocked_range<int>& rows) {
    // Each sample point's receivers of a row, set up in one vectorized loop per map (a pixel's
    // receiver in every map was most of this pass when computed pixel by pixel).
    std::vector<ReceiverRow> receivers(samples);  // per task: a few per frame
    for (int y = rows.begin(); y < rows.end(); ++y) {
      const Vec3* positions = gbuffer.wsPosition.row(y);
      const Vec3* normals = gbuffer.wsGeometricNormal.row(y);
      for (size_t j = 0; j < samples; ++j) {
        if (sharedFrame_)
          makeReceiverRowInFrame(maps_[0], lsOffsets_[j], maps_[j], positions, normals, width, options_.bias,
                                 receivers[j]);
        else
          makeReceiverRow(maps_[j], positions, normals, width, options_.bias, receivers[j]);
      }
      float* out = v.row(y);
      const int32_t* ids = gbuffer.objectId.row(y);
      for (int x = 0; x < width; ++x) {
        if (ids[x] == kNoObject) {
          out[x] = 1.0f;
          continue;
        }
        const Vec3& p = positions[x];
        const Vec3& n = normals[x];
        // shade(p) per sub-segment. Most pixels are fully lit or in the umbra, far from any skin: one
        // texel read per map decides them.
        float g0 = glm::dot(n, wsSamples_[0] - p);  // > 0: sample 0 lies in front of p's surface
        float sum = 0.0f;
        for (int q = 0; q < k; ++q) {
          const size_t a = static_cast<size_t>(2 * q), b = a + 1;
          const ReceiverRow& row0 = receivers[static_cast<size_t>(q)];
          const ReceiverRow& row1 = receivers[static_cast<size_t>(q + 1)];
          const float g1 = glm::dot(n, wsSamples_[static_cast<size_t>(q + 1)] - p);
          float l = 0.0f;
          if (g0 > 0.0f && g1 > 0.0f) {
            const TexelRead ta = readTexel(visibility_[a], row0, x), tb = readTexel(visibility_[b], row1, x);
            if (ta.lit && tb.lit)
              l = std::min(1.0f, (ta.nearSkin ? lookupLit(visibility_[a], row0[x]) : kLitShare) +
                                     (tb.nearSkin ? lookupLit(visibility_[b], row1[x]) : kLitShare));
            else if (ta.lit)
              l = penumbraShare(visibility_[a], row0[x], behind_[b], row1[x]);
            else if (tb.lit)
              l = penumbraShare(visibility_[b], row1[x], behind_[a], row0[x]);
          } else if (g0 > 0.0f) {
            // p's own surface hides sample q + 1: the part of the sub-segment in front of p's plane.
            if (readTexel(visibility_[a], row0, x).lit) l = g0 / (g0 - g1);
          } else if (g1 > 0.0f) {
            if (readTexel(visibility_[b], row1, x).lit) l = g1 / (g1 - g0);
          }
          sum += l;
          g0 = g1;
        }
        out[x] = std::min(1.0f, sum * subWeight);  // k terms of at most 1 each, times 1 / k, plus rounding
      }
    }
  });
}

std::vector<std::pair<std::string, double>> HeidrichTechnique::stats() const {
  return {{"sample_points", static_cast<double>(samplePoints())},
          {"skin_triangles", static_cast<double>(skinTriangles_)},
          {"shadow_maps_built", static_cast<double>(shadowMapsBuilt_)},
          {"visibility_maps_built", static_cast<double>(visibilityMapsBuilt_)},
          {"shadow_maps_ms", shadowMapsMs_},
          {"edges_and_skins_ms", skinsMs_},
          {"visibility_maps_ms", visibilityMapsMs_}};
}

std::unique_ptr<ShadowTechnique> makeTechnique(const HeidrichOptions& o) {
  validateOptions("heidrich", o);

  return std::make_unique<HeidrichTechnique>(o);
}

TechniqueInfo heidrichTechniqueInfo() {
  TechniqueInfo info;
  info.name = "heidrich";
  info.summary =
      "soft shadow maps for linear lights: a depth + visibility map per sample point, skin polygons of the "
      "depth discontinuities warped into the other view and Gouraud-shaded (segment lights)";
  info.source = "Heidrich, Brabec & Seidel 2000, Soft shadow maps for linear lights";
  info.setOptions<HeidrichOptions>([](const HeidrichOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
