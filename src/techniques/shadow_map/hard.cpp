// `hard`: the classic shadow map (Williams 1978, "Casting curved shadows on curved surfaces",
// SIGGRAPH): the scene's depth seen from the light's centre sample, and one depth compare per camera
// pixel at the texel holding it. V in {0, 1}: a hard shadow from a point light at the light's centre,
// with the map's aliasing — the baseline every soft technique is measured against.
//
// Approximations: the area light is replaced by its centre sample; the compare uses the receiver
// plane and the slope-scaled bias of shadow_map.h (bias in texel sizes, so it scales with the map's
// resolution); receivers outside the map are lit. Works for every light shape (all have a centre
// sample; directional lights get an orthographic map).
#include <memory>

#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/techniques/shadow_map.h"
#include "shadow_map.h"

namespace penumbra {

class HardShadowTechnique final : public ShadowTechnique {
 public:
  explicit HardShadowTechnique(const HardShadowOptions& options) : options_(options) {}

  std::string_view name() const override { return "hard"; }

 private:
  static constexpr LightMapLayers kLayers = LightMapLayers::NearestDepth;  // compares depths only

  void reserveImpl(int, int) override { reserveShadowMap(options_.lightMap, map_, kLayers); }

  void prepareImpl(const Scene& scene, const Light& light) override {
    createShadowMap(scene, light, options_.lightMap, map_, kLayers);
    setHorizonClamp(options_.lightMap.horizon, lightAtMapOrigin(light, map_));
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (map_.size == 0) fail("hard: visibility() called before prepare()");
    // hardShadow from the row's nearest-texel thresholds: one vectorized set-up per row, then one
    // compare per pixel.
    v.resizeForOverwrite(gbuffer.width(), gbuffer.height());  // every pixel written below, in parallel
    const float* depth = map_.lsDepth.row(0);
    const HorizonBound horizon = horizonForRows();
    forEachReceiverRow(gbuffer, map_, options_.bias, [&](int y, const ReceiverRow& r) {
      float* out = v.row(y);
      const int32_t* ids = gbuffer.objectId.row(y);
      for (int x = 0; x < gbuffer.width(); ++x) {
        const auto i = static_cast<size_t>(x);
        out[x] = ids[x] != kNoObject && r.inMap[i] && depth[r.nearestTexel[i]] < r.nearestThreshold[i] ? 0.0f : 1.0f;
      }
      clampRowToHorizon(gbuffer, horizon, y, out);
    });
  }

  HardShadowOptions options_;
  LightMap map_;
};

std::unique_ptr<ShadowTechnique> makeTechnique(const HardShadowOptions& o) {
  validateOptions("hard", o);

  return std::make_unique<HardShadowTechnique>(o);
}

TechniqueInfo hardTechniqueInfo() {
  TechniqueInfo info;
  info.name = "hard";
  info.summary = "shadow map from the light's centre sample, one depth compare per pixel (hard shadow)";
  info.source = "Williams 1978 (baseline)";
  info.setOptions<HardShadowOptions>([](const HardShadowOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
