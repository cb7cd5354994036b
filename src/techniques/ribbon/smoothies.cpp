// `smoothies`: outer penumbrae only (Chan & Durand 2003, "Rendering fake soft shadows with
// smoothies", Eurographics Symposium on Rendering), a baseline row of Lawlor 2006's Fig. 10.
//
// The method: a hard shadow map from the light's centre sample, plus "smoothies": planar strips
// attached to the silhouette edges of the occluders, extending outwards, rendered from the light into
// a smoothie buffer that keeps, per texel, the smoothie nearest the light — its depth and an alpha
// ramping from 0 at the silhouette edge to 1 at the strip's outer border. A pixel in the hard shadow
// gets V = 0; a lit pixel behind a smoothie gets the alpha remapped by the blocker and receiver
// depths, alpha' = alpha / (1 - b / r) (Chan & Durand, Sec. 4), so the penumbra widens with the
// distance to the occluder; V = 1 elsewhere. The hard shadow stays the umbra: the shadow only grows
// outwards, never into the umbra, which is why this row sees half of every penumbra; Lawlor 2006
// measures it against that half (Fig. 11; penumbra/metrics.h, halfPenumbraTruth, PenumbraHalf::Outer).
//
// Our implementation: the smoothies are the outer halves of the silhouette ribbons of plm.h. With the
// strip as wide as the widest physical penumbra, the remapped alpha is the distance from the edge
// over the penumbra's width at the receiver's depth,
//     V = sat(w s r / (z - c))    (in plm.h's zeta and depth rate: the disk light's outer penumbra),
// which is Chan & Durand's remap with the strip width set from the light's size instead of a user
// knob: the widest penumbra the edge casts on the surfaces below it (the deepest one the far layer holds
// around it; plm::RibbonReach::SurfacesBelow), beyond which every receiver reads V = 1 either way. Deviation that
// follows from it: per texel the buffer keeps the strip whose penumbra begins highest on the texel's light ray
// (priority c + w s r, plm's "highest penumbra limit wins"), not the strip nearest the light. A strip as wide as the
// widest penumbra in the map reaches far beyond a raised object's own penumbra, and kept by depth it covered the strips
// of every lower object around it, whose fades then vanished (V = 1 there: a receiver outside the raised edge's
// penumbra); with Chan & Durand's narrow strips the two rules pick the same strip. Strips whose shadow is hidden from
// the light's centre are dropped as in plm (plm::RibbonFilter). The smoothie buffer and the hard map are read at the
// texel holding the pixel (no filtering: the 2003 hardware filtered no float textures). With `sub_texel` on (the
// default) the strip's alpha is then taken at the pixel's own point in the map, from the edge that won the texel (its
// distance and depth there), so the fade follows the silhouette below a texel; the paper's buffer, alpha at the
// texel's centre (`sub_texel` off), moves it in whole-texel steps, which pop as the light moves. V goes through
// Appendix A's table of Lawlor 2006 (penumbra/light_profile.h) when `illumination_table` is on. Lights: as plm
// (sphere, disk, rect, polygon, directional; segments rejected). Parameters: map_size (texels), bias_constant
// (texels), bias_slope (shadow_map.h), margin (texels added to every strip's width), illumination_table (bool),
// sub_texel (bool).
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "core/light_profile.h"
#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/techniques/ribbon.h"
#include "techniques/ribbon/plm.h"
#include "techniques/shadow_map/shadow_map.h"

namespace penumbra {
namespace {

class SmoothiesTechnique final : public ShadowTechnique {
 public:
  explicit SmoothiesTechnique(const SmoothiesOptions& options) : options_(options) {}

  std::string_view name() const override { return "smoothies"; }

 private:
  // Its compares and ribbons read depths only (the ribbons' filter takes no coverage).
  static constexpr LightMapLayers kLayers = LightMapLayers::NearestDepthAndFarthest;

  void reserveImpl(int, int) override {
    reserveShadowMap(options_.lightMap, map_, kLayers);
    plm::reserveRibbons(options_.lightMap.size, smoothies_);
  }

  void prepareImpl(const Scene& scene, const Light& sceneLight) override {
    plm::emitterRadius(sceneLight, "smoothies");
    // The silhouettes come from the map's projection alone, and the far layer is kept only where
    // their ribbons can reach: the map is fitted first and rasterized once they are known.
    fitShadowMap(scene, sceneLight, options_.lightMap, map_);
    const Light light = lightAtMapOrigin(sceneLight, map_);  // the silhouettes look from the map's origin
    setHorizonClamp(options_.lightMap.horizon, light);
    space_ = plm::makeSpace(map_, light, "smoothies");
    table_ = VisibilityToIllumination::forLight(light);
    const std::vector<plm::Edge> edges = plm::silhouetteEdges(scene, light, map_, space_, &edgeCache_);
    plm::farTilesForRibbons(edges, space_, map_.size, options_.marginTexels, plm::RibbonSides::Outer, farTiles_);
    rasterizeLightMap(scene, map_, kLayers, farTiles_);
    plm::edgeLines(edges, lines_);  // what sub_texel reads per pixel
    plm::rasterizeRibbons(edges, space_, map_, plm::RibbonSides::Outer, options_.marginTexels,
                          plm::RibbonFilter{nullptr, &map_.lsDepth, false}, smoothies_,
                          plm::RibbonReach::SurfacesBelow);
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (map_.size == 0) fail("smoothies: visibility() called before prepare()");
    forEachReceiver(
        gbuffer, map_, options_.bias, v,
        [&](int, int, const ShadowReceiver& r) {
          if (!r.inMap) return 1.0f;
          if (hardShadow(map_, r) == 0.0f) return 0.0f;
          const plm::RibbonTexel& s = smoothies_(static_cast<int>(std::floor(r.s)), static_cast<int>(std::floor(r.t)));
          if (!s.covered()) return 1.0f;
          // The strip's distance and depth at the pixel's own point (sub_texel) move with the silhouette
          // below a texel; at the texel's centre they step a whole texel at a time.
          const plm::EdgeLine& line = lines_[static_cast<size_t>(s.edge)];
          const plm::EdgePoint at = options_.subTexel ? line.nearest(Vec2(r.s, r.t)) : plm::EdgePoint{s.w, s.c};
          const float biased = r.lsDepth - r.bias;
          if (!(space_.orthographic || biased > 0.0f) || !(space_.zeta(biased) > at.c)) return 1.0f;
          const float z = space_.zeta(r.lsDepth);
          const float alpha = std::clamp(at.distance * line.rate / (z - at.c), 0.0f, 1.0f);
          return options_.illuminationTable ? table_(alpha) : alpha;
        },
        horizonForRows());
  }

  SmoothiesOptions options_;
  LightMap map_;
  plm::Space space_;
  VisibilityToIllumination table_;
  plm::RibbonImage smoothies_;
  std::vector<plm::EdgeLine> lines_;  //!< the silhouette edges smoothies_ names
  plm::EdgeCache edgeCache_;          //!< the meshes' edge adjacency, kept while the geometry is unchanged
  std::vector<uint8_t> farTiles_;     //!< where map_ keeps its far layer
};

}  // namespace

std::unique_ptr<ShadowTechnique> makeTechnique(const SmoothiesOptions& o) {
  validateOptions("smoothies", o);

  return std::make_unique<SmoothiesTechnique>(o);
}

TechniqueInfo smoothiesTechniqueInfo() {
  TechniqueInfo info;
  info.name = "smoothies";
  info.usesMeshEdges = true;
  info.summary = "hard shadow map plus silhouette strips that fade the shadow outwards (outer penumbra only)";
  info.source = "Chan & Durand 2003, Rendering fake soft shadows with smoothies (baseline in Lawlor 2006)";
  info.setOptions<SmoothiesOptions>([](const SmoothiesOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
