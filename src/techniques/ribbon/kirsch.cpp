// `kirsch`: inner penumbrae only (Kirsch & Döllner 2003, "Real-time soft shadows using a single
// light sample", WSCG / Journal of WSCG 11(1)), a baseline row of Lawlor 2006's Fig. 10.
//
// The method: a hard shadow map from the light's centre sample and a "shadow-width map" that holds,
// for every texel covered by an occluder, how deep the texel lies inside the occluder's shadow: its
// distance to the occluder's border in the map. A pixel outside the hard shadow is lit (V = 1); a
// pixel in it is attenuated by a bivariate function of (1) the distance from the occluding point to
// the pixel and (2) the shadow width at the pixel's texel, so the shadow fades from the hard edge
// inwards over a width that grows with the occluder distance. The hard shadow's outline stays the
// outer border of the shadow: this row sees half of every penumbra, from the inside, and Lawlor 2006
// measures it against that half (Fig. 11; penumbra/metrics.h, halfPenumbraTruth, PenumbraHalf::Inner).
//
// Our implementation: the attenuation is the disk light's inner penumbra in plm.h's zeta and depth
// rate, from the hard edge (V = 1) to the umbra (V = 0),
//     V = 1 - sat(|w| s r / (z - c)),
// with c the occluding point's depth (the hard map's texel, as in the paper: "the distance of the
// occluding point to the shadowed point") and |w| the shadow width in texels. On a rounded occluder
// that point is its top, nearer the light than the silhouette that bounds the shadow, so the fade is
// wider than the penumbra and lights umbra pixels near the hard edge; the paper's caveat: "The
// shadow-casting surfaces, however, should satisfy a few geometric properties to prevent artifacts". The shadow-width
// map is the inner halves of the silhouette ribbons of plm.h (distance to the nearest silhouette segment, measured at
// texel centres, "highest penumbra limit wins") instead of the paper's iterative image passes over the depth map, which
// estimate the same distance in whole texels. Only edges on the border of their object's footprint in the map count
// (plm::RibbonFilter: beyond the edge the map sees another object or nothing, and nothing above the edge): the paper's
// distance is the one to the border of the shadow, and the silhouettes inside an object's footprint
// (a fin over the crankcase, an arm over the body, a contour behind the object's own front) border
// no lit texel — as widths they faded the middle of an umbra to nearly 1. Both maps are read at the texel holding the
// pixel (no filtering). With `sub_texel` on (the default) the width is then measured from the pixel's own point in
// the map to the edge that won the texel, so the fade follows the silhouette below a texel; the paper's per-texel width
// map (`sub_texel` off) moves it in whole-texel steps, which pop as the light moves. V goes through Appendix A's table
// of Lawlor 2006 (penumbra/light_profile.h) when `illumination_table` is on. A blocked texel no ribbon reaches lies
// deeper in the shadow than any penumbra: V = 0. The ribbons reach only as far as the widest shadow width the surfaces
// around them can show, from the shallowest occluding point to the deepest receiver there (plm::RibbonReach::
// SurfacesInRange): a texel beyond it reads V = 0 either way, and the ribbon pass costs far fewer texels. Lights: as
// plm (sphere, disk, rect, polygon, directional; segments rejected). Parameters: map_size (texels), bias_constant
// (texels), bias_slope (shadow_map.h), margin (texels added to every ribbon's width), illumination_table (bool),
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

class KirschTechnique final : public ShadowTechnique {
 public:
  explicit KirschTechnique(const KirschOptions& options) : options_(options) {}

  std::string_view name() const override { return "kirsch"; }

 private:
  static constexpr LightMapLayers kLayers = LightMapLayers::NearestAndFarthest;

  void reserveImpl(int, int) override {
    reserveShadowMap(options_.lightMap, map_, kLayers);
    plm::reserveRibbons(options_.lightMap.size, widths_);
  }

  void prepareImpl(const Scene& scene, const Light& sceneLight) override {
    plm::emitterRadius(sceneLight, "kirsch");
    // The silhouettes come from the map's projection alone, and the far layer is kept only where
    // their ribbons can reach: the map is fitted first and rasterized once they are known.
    fitShadowMap(scene, sceneLight, options_.lightMap, map_);
    const Light light = lightAtMapOrigin(sceneLight, map_);  // the silhouettes look from the map's origin
    setHorizonClamp(options_.lightMap.horizon, light);
    space_ = plm::makeSpace(map_, light, "kirsch");
    table_ = VisibilityToIllumination::forLight(light);
    const std::vector<plm::Edge> edges = plm::silhouetteEdges(scene, light, map_, space_, &edgeCache_);
    plm::farTilesForRibbons(edges, space_, map_.size, options_.marginTexels, plm::RibbonSides::Inner, farTiles_);
    rasterizeLightMap(scene, map_, kLayers, farTiles_);
    plm::edgeLines(edges, lines_);  // what sub_texel reads per pixel
    plm::rasterizeRibbons(edges, space_, map_, plm::RibbonSides::Inner, options_.marginTexels,
                          plm::RibbonFilter{&map_.objectId, &map_.lsDepth, true}, widths_,
                          plm::RibbonReach::SurfacesInRange);
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (map_.size == 0) fail("kirsch: visibility() called before prepare()");
    forEachReceiver(
        gbuffer, map_, options_.bias, v,
        [&](int, int, const ShadowReceiver& r) {
          if (!r.inMap || hardShadow(map_, r) == 1.0f) return 1.0f;
          const int i = static_cast<int>(std::floor(r.s)), j = static_cast<int>(std::floor(r.t));
          const plm::RibbonTexel& width = widths_(i, j);
          if (!width.covered()) return 0.0f;
          const float c = space_.zeta(map_.lsDepth(i, j));  // the occluding point
          const float z = space_.zeta(r.lsDepth);
          // The shadow width at the pixel's own point (sub_texel) moves with the silhouette below a texel;
          // at the texel's centre it steps a whole texel at a time.
          const plm::EdgeLine& line = lines_[static_cast<size_t>(width.edge)];
          const float inside = options_.subTexel ? line.nearest(Vec2(r.s, r.t)).distance : -width.w;
          const float blocked = std::clamp(inside * line.rate / std::max(z - c, 1e-30f), 0.0f, 1.0f);
          return options_.illuminationTable ? table_(1.0f - blocked) : 1.0f - blocked;
        },
        horizonForRows());
  }

  KirschOptions options_;
  LightMap map_;
  plm::Space space_;
  VisibilityToIllumination table_;
  plm::RibbonImage widths_;
  std::vector<plm::EdgeLine> lines_;  //!< the silhouette edges widths_ names
  plm::EdgeCache edgeCache_;          //!< the meshes' edge adjacency, kept while the geometry is unchanged
  std::vector<uint8_t> farTiles_;     //!< where map_ keeps its far layer
};

}  // namespace

std::unique_ptr<ShadowTechnique> makeTechnique(const KirschOptions& o) {
  validateOptions("kirsch", o);
  return std::make_unique<KirschTechnique>(o);
}

TechniqueInfo kirschTechniqueInfo() {
  TechniqueInfo info;
  info.name = "kirsch";
  info.usesMeshEdges = true;
  info.summary = "hard shadow map plus a shadow-width map that fades the shadow inwards (inner penumbra only)";
  info.source = "Kirsch & Döllner 2003, Real-time soft shadows using a single light sample (baseline in Lawlor 2006)";
  info.setOptions<KirschOptions>([](const KirschOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
