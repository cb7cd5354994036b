// `pcf`: percentage-closer filtering with a fixed kernel (Reeves, Salesin, Cook 1987, "Rendering
// antialiased shadows with depth maps", SIGGRAPH, Sec. 3): instead of filtering depths, filter the
// *results* of the depth compare over a region of the map around the pixel's texel, giving the
// fraction of the region that is lit. V in [0, 1].
//
// Kernel: a square box `kernel` texels wide centred at the pixel's exact map position, integrated
// exactly over the nearest-texel compare function — texels fully inside weigh 1, the border texels
// weigh their covered fraction (shadow_map.h, pcfBox) — so V is continuous across texels (Reeves
// used jittered samples in the region; the exact box is the noise-free limit). The kernel is fixed in
// texels: the blur does not follow the light's size or the occluder distance, which is what this
// baseline shows against `pcss`.
//
// Approximations: a point light at the light's centre for the map; the receiver-plane compare and
// slope-scaled bias of shadow_map.h at every texel of the kernel. Works for every light shape.
#include <memory>

#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/techniques/shadow_map.h"
#include "shadow_map.h"

namespace penumbra {

class PcfTechnique final : public ShadowTechnique {
 public:
  explicit PcfTechnique(const PcfOptions& options) : options_(options) {
    if (options_.kernel < 1 || options_.kernel > 63 || options_.kernel % 2 == 0)
      fail("pcf: kernel = {} is not valid: expected an odd int in [1, 63] texels", options_.kernel);
  }

  std::string_view name() const override { return "pcf"; }

 private:
  static constexpr LightMapLayers kLayers = LightMapLayers::NearestDepth;  // compares depths only

  void reserveImpl(int, int) override { reserveShadowMap(options_.lightMap, map_, kLayers); }

  void prepareImpl(const Scene& scene, const Light& light) override {
    createShadowMap(scene, light, options_.lightMap, map_, kLayers);
    setHorizonClamp(options_.lightMap.horizon, lightAtMapOrigin(light, map_));
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (map_.size == 0) fail("pcf: visibility() called before prepare()");
    const float width = static_cast<float>(options_.kernel);
    forEachReceiver(
        gbuffer, map_, options_.bias, v,
        [&](int, int, const ShadowReceiver& r) { return r.inMap ? pcfBox(map_, r, r.s, r.t, width) : 1.0f; },
        horizonForRows());
  }

  PcfOptions options_;
  LightMap map_;
};

std::unique_ptr<ShadowTechnique> makeTechnique(const PcfOptions& o) {
  validateOptions("pcf", o);
  return std::make_unique<PcfTechnique>(o);
}

TechniqueInfo pcfTechniqueInfo() {
  TechniqueInfo info;
  info.name = "pcf";
  info.summary = "percentage-closer filtering of the shadow-map compare over a fixed box kernel";
  info.source = "Reeves, Salesin, Cook 1987 (baseline)";
  info.setOptions<PcfOptions>([](const PcfOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
