// `heidrich`: soft shadow maps for linear lights (Heidrich, Brabec, Seidel 2000, "Soft shadow maps for
// linear lights", Rendering Techniques 2000, pp. 269-280; its talk's slides are the source followed,
// docs/papers.md).
// Declared here (rather than only registered) so that tests can run the stages on their own and read
// the maps and counters of a run. See heidrich.cpp for the algorithm, its approximations and its
// parameters.
#pragma once

#include <cstdint>
#include <string_view>
#include <utility>
#include <vector>

#include "penumbra/image.h"
#include "penumbra/raster.h"
#include "penumbra/technique.h"
#include "penumbra/techniques/shadow_map.h"
#include "shadow_map.h"

namespace penumbra {

namespace heidrich {

// Value of a visibility-map texel that no skin polygon covers: "no penumbra information here". A
// lookup reads it as the lit default (the sample's full share, 1/2 of its sub-segment; slides,
// "Generating the Visibility Map") or skips it (see heidrich.cpp, "Lookups").
inline constexpr float kUncovered = -1.0f;
// In a two-channel map: uncovered, and so is every texel of its 3x3 neighbourhood, which holds every
// texel a bilinear lookup at a point of this texel reads: the lookup needs no other texel.
inline constexpr float kNoSkinNearby = -2.0f;

// Edge detection (slides, "Step 2"): 1 where the Laplacian of the Gaussian-smoothed depth (3x3
// binomial, then the 5-point Laplacian) exceeds edgeThresholdTexels / 4 texel sizes at that texel's
// depth, or where its support holds an empty texel. A depth step of D texel sizes gives |LoG| = D / 4
// at the texels on both sides of it, so the test flags steps of more than edgeThresholdTexels.
// Into `edges`, which keeps its storage where it is large enough.
void detectEdges(const LightMap& map, float edgeThresholdTexels, Image<uint8_t>& edges);
Image<uint8_t> detectEdges(const LightMap& map, float edgeThresholdTexels);

// The skin polygons of one depth map (slides, "Step 3: triangulate depth values"): the depth map as a
// mesh of texel centres, keeping the triangles of every 2x2 quad that touches an edge texel and has
// two neighbouring corners whose depths step by more than edgeThresholdTexels texel sizes plus the
// steeper of the steps beyond them (a discontinuity, not a steep or creased continuous surface); each
// vertex carries its Gouraud value, 0 ("black") on the occluder side of the gap, 1 ("white") on the
// receiver side.
struct SkinMesh {
  std::vector<Vec3> wsPositions;
  std::vector<float> value;  //!< per vertex: 0 occluder, 1 receiver
  std::vector<glm::uvec3> triangles;
};
// Into `skin`, one mesh per row of quads in `rows` first; both keep their capacity.
void buildSkin(const LightMap& map, const Image<uint8_t>& edges, float edgeThresholdTexels, SkinMesh& skin,
               std::vector<SkinMesh>& rows);
SkinMesh buildSkin(const LightMap& map, const Image<uint8_t>& edges, float edgeThresholdTexels);

// The skin warped into `view` (a perspective map) and rasterized there with Gouraud (screen-linear)
// interpolation, against the view's depth channel. `front`: the slides' visibility channel, the nearest
// skin in front of the surface the view sees (or at it, for a skin's receiver half: heidrich.cpp);
// kUncovered where none lands. `behind`: the nearest skin behind that surface, as (value, light-space
// depth); value kUncovered where none lands. `behindRows` marks the rows of `behind` a skin may have
// reached: passed back from the last call on the same image, only those are cleared (all of them when
// the size differs). `frontDepth` holds the depth of `front`'s skin. `skinRows`: 1 for each row a
// skin triangle's bounds reach, 0 for the others, where `front` and `frontDepth` are left unset (no skin
// lands there). Every image keeps its storage where it is large enough.
void renderVisibilityLayers(const SkinMesh& skin, const LightMap& view, Image<float>& front, Image<Vec2>& behind,
                            std::vector<uint8_t>& behindRows, Image<float>& frontDepth, std::vector<uint8_t>& skinRows);
// A texel of `behind` where no skin lands: value kUncovered, infinite depth.
inline const Vec2 kNoSkinBehind{kUncovered, kInfinity};
// `behind` and `behindRows` as renderVisibilityLayers leaves them for a size x size view where no
// skin landed: kNoSkinBehind everywhere, no row marked.
void clearBehindLayer(int size, Image<Vec2>& behind, std::vector<uint8_t>& behindRows);

// One texel of a sample point's two-channel shadow map (slides, "Visibility Map": "additional shadow
// map channel"), the channels side by side so a lookup reads both from one cache line.
struct TwoChannelTexel {
  float lsDepth;     //!< the depth channel (LightMap::lsDepth)
  float visibility;  //!< the visibility channel; kUncovered or kNoSkinNearby where no skin lands
};
// Into `out`, from renderVisibilityLayers' `front` (read on the rows skinRows marks, uncovered on the
// others), with the coverage's horizontal dilation in `coverage`; both keep their storage.
void makeTwoChannelMap(const LightMap& map, const Image<float>& visibility, const std::vector<uint8_t>& skinRows,
                       Image<TwoChannelTexel>& out, Image<uint8_t>& coverage);

// makeReceiver (shadow_map.h) for a perspective map, from the receiver's position and geometric normal
// already in the map's light space: the maps of one segment share their axes, so a pixel transforms
// its point and normal once and each map only subtracts its origin's offset. The definition, one pixel
// at a time, of what the visibility pass computes a row at a time (makeReceiverRowInFrame).
ShadowReceiver receiverInMap(const LightMap& map, const Vec3& lsPosition, const Vec3& lsNormal, const DepthBias& bias);

}  // namespace heidrich

class HeidrichTechnique final : public ShadowTechnique {
 public:
  explicit HeidrichTechnique(const HeidrichOptions& options);

  std::string_view name() const override { return "heidrich"; }
  // "sample_points", "skin_triangles" (of the last prepare), "shadow_maps_built" and
  // "visibility_maps_built" (counted over the technique's lifetime), and the prepare stages in ms:
  // "shadow_maps_ms", "edges_and_skins_ms", "visibility_maps_ms".
  std::vector<std::pair<std::string, double>> stats() const override;

  int samplePoints() const { return prepared_ ? static_cast<int>(maps_.size()) : 0; }
  const LightMap& shadowMap(int sample) const { return maps_.at(static_cast<size_t>(sample)); }
  // Two-channel map of sub-segment q's first (end = 0) or second (end = 1) sample point.
  const Image<heidrich::TwoChannelTexel>& visibilityMap(int subSegment, int end) const {
    return visibility_.at(static_cast<size_t>(2 * subSegment + end));
  }
  // Its second channel: the other end's skins behind the surface this end sees (value, depth).
  const Image<Vec2>& behindMap(int subSegment, int end) const {
    return behind_.at(static_cast<size_t>(2 * subSegment + end));
  }
  int shadowMapsBuilt() const { return shadowMapsBuilt_; }
  int visibilityMapsBuilt() const { return visibilityMapsBuilt_; }

 private:
  // The k + 1 shadow maps, the 2k visibility maps and prepare()'s working images at the map size.
  void reserveImpl(int width, int height) override;
  // Renders the k + 1 shadow maps and the 2k visibility maps; throws Error for a light that is not a
  // segment. Always rebuilds: prepare() is the call that says the light or the scene changed.
  void prepareImpl(const Scene& scene, const Light& light) override;
  // Reads the maps only: a camera-only change (a new G-buffer) re-runs this pass alone.
  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override;

  HeidrichOptions options_;
  bool prepared_ = false;       //!< the maps below are whole (a failed prepare() clears it)
  std::vector<LightMap> maps_;  //!< sample point j's shadow map (depth channel)
  std::vector<Image<heidrich::TwoChannelTexel>> visibility_;  //!< 2q + e: map of sub-segment q's end e
  std::vector<Image<Vec2>> behind_;               //!< 2q + e: the skins behind the surface sub-segment q's end e sees
  std::vector<std::vector<uint8_t>> behindRows_;  //!< 2q + e: the rows of behind_ a skin may have reached
  std::vector<Vec3> wsSamples_;                   //!< sample point j in world space
  bool sharedFrame_ = false;     //!< every map has map 0's axes (always, unless the light points at the scene)
  std::vector<Vec3> lsOffsets_;  //!< map j's origin in map 0's light space
  // prepare()'s working storage, kept so that a new light or scene costs passes over memory rather
  // than fresh pages (which dominated prepare on machines with costly page faults).
  struct Scratch {
    Image<uint8_t> edges;
    std::vector<heidrich::SkinMesh> skins, skinRows;
    Image<float> front, frontDepth;
    std::vector<uint8_t> frontRows;  //!< renderVisibilityLayers' skinRows
    Image<uint8_t> coverage;
  } scratch_;
  size_t skinTriangles_ = 0;
  int shadowMapsBuilt_ = 0;
  int visibilityMapsBuilt_ = 0;
  double shadowMapsMs_ = 0.0, skinsMs_ = 0.0, visibilityMapsMs_ = 0.0;
};

}  // namespace penumbra
