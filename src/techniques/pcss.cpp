// `pcss`: percentage-closer soft shadows (Fernando 2005, "Percentage-closer soft shadows",
// SIGGRAPH sketch; NVIDIA whitepaper of the same name). One shadow map from the light's centre, then
// per camera pixel three steps:
//  1. blocker search: the mean depth z_b of the map texels in front of the receiver inside the
//     region through which the receiver sees the light — by similar triangles, a light of radius
//     R at depth 0 seen from a receiver at depth z_r covers, at depth z, a disk of radius
//     R (z_r - z) / z_r, which projects into the map (from the centre) with radius
//     R (z_r - z) / (z_r z) at unit depth; taken at the nearest depth in the map (z = zMin, found in
//     prepare(); the sketch uses the near plane, which only wastes samples);
//  2. penumbra estimate: a planar blocker at z_b parallel to the light blurs the shadow by the
//     light's projection through it, a disk of radius w = R (z_r - z_b) / z_b on the receiver's
//     plane (the sketch's w_penumbra = (d_receiver - d_blocker) w_light / d_blocker);
//  3. PCF over that disk: `filter_samples` taps, each a 1-texel box compare (bilinear weights), so
//     narrow penumbrae stay antialiased.
// Both disks use Vogel's spiral (deterministic; the sketch uses a Poisson disk), rotated per pixel
// by a hash when `rotate` is on (banding becomes fine noise). Directional lights use the
// orthographic variant: R is tan(angular_diameter / 2), the solar disk's radius at unit distance,
// and the radii are R (z_r - z) and R (z_r - z_b) in world units (no perspective division).
//
// Approximations (the sketch's): the blockers are replaced by one plane at their mean depth (so
// overlapping occluders at different depths get one penumbra width); the light is a disk of radius
// `light_size` facing the receivers — by default Light::extent(), the radius of the circle holding
// the emitter (exact for sphere and disk lights, the circumscribed disk of a rect or polygon, half
// the length of a segment); the map is taken from the centre sample, so blockers hidden behind
// others from the centre are missed. Receiver-plane compare and bias as in shadow_map.h.
#include <memory>
#include <optional>
#include <vector>

#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/timer.h"
#include "shadow_map.h"

namespace penumbra {

struct PcssOptions {
  int mapSize = 1024;                //!< texels per side of the light map, in [16, 8192]
  int blockerSamples = 16;           //!< taps of the blocker search, in [1, 1024]
  int filterSamples = 32;            //!< taps of the PCF filter, in [1, 1024]
  std::optional<float> lightSize;    //!< light radius, world units (directional: tan of the half angle); empty = Light::extent()
  bool rotate = true;                //!< rotate the sample disks per pixel by a hash
  DepthBias bias;                    //!< depth-compare bias (shadow_map.h)
};

class PcssTechnique final : public ShadowTechnique {
 public:
  explicit PcssTechnique(const PcssOptions& options)
      : options_(options), blockerDisk_(vogelDisk(options.blockerSamples)), filterDisk_(vogelDisk(options.filterSamples)) {}

  std::string_view name() const override { return "pcss"; }

  void prepare(const Scene& scene, const Light& light) override {
    timings_ = {};
    Timer timer;
    lightSize_ = options_.lightSize ? *options_.lightSize : light.extent();
    map_ = createShadowMap(scene, light, options_.mapSize);
    zMin_ = minMapDepth(map_);
    timings_.add("prepare", timer.elapsedMs());
  }

  void visibility(const GBuffer& gbuffer, Image<float>& v) override {
    if (map_.size == 0) fail("pcss: visibility() called before prepare()");
    Timer timer;
    const float maxRadius = static_cast<float>(map_.size);  // a search wider than the map finds nothing more
    forEachReceiverPixel(gbuffer, v, [&](int x, int y) {
      const ShadowReceiver r = makeReceiver(map_, gbuffer.wsPosition(x, y), gbuffer.wsGeometricNormal(x, y), options_.bias);
      if (!r.inMap || !(r.lsDepth > zMin_)) return 1.0f;
      const float zr = r.lsDepth;
      // In texels: the world radius at the receiver's depth over the texel size there.
      const float searchRadius = map_.orthographic ? lightSize_ * (zr - zMin_) / r.texelWorld
                                                   : lightSize_ * (zr - zMin_) / zMin_ / r.texelWorld;
      const Vec2 rotation = options_.rotate ? pixelRotation(x, y) : Vec2(1.0f, 0.0f);
      const BlockerSearch blockers = searchBlockers(map_, r, std::min(searchRadius, maxRadius), blockerDisk_, rotation);
      if (blockers.blockers == 0) return 1.0f;
      // Every search tap blocked: umbra. The filter disk lies inside the search disk (z_b >= zMin
      // makes w <= the search radius), so filtering would find (nearly) only blockers too; skipping
      // it halves the cost of PCSS in shadowed regions (NVIDIA's PCSS sample does the same).
      if (blockers.blockers == static_cast<int>(blockerDisk_.size())) return 0.0f;
      const float zb = blockers.meanDepth;
      const float penumbraWorld = map_.orthographic ? lightSize_ * (zr - zb) : lightSize_ * (zr - zb) / zb;
      return pcfDisk(map_, r, std::min(penumbraWorld / r.texelWorld, maxRadius), filterDisk_, rotation);
    });
    timings_.add("visibility", timer.elapsedMs());
  }

  PassTimings timings() const override { return timings_; }
  std::vector<std::pair<std::string, double>> stats() const override {
    return {{"light_size", lightSize_}, {"min_map_depth", zMin_}};
  }

 private:
  PcssOptions options_;
  std::vector<Vec2> blockerDisk_, filterDisk_;
  LightMap map_;
  float lightSize_ = 0.0f;
  float zMin_ = 0.0f;
  PassTimings timings_;
};

TechniqueInfo pcssTechniqueInfo() {
  TechniqueInfo info;
  info.name = "pcss";
  info.summary = "percentage-closer soft shadows: blocker search, penumbra width by similar triangles, PCF";
  info.source = "Fernando 2005 (modern baseline)";
  info.params = {
      mapSizeParamSpec(),
      ParamSpec{.name = "blocker_samples", .type = ParamType::Int, .defaultValue = int64_t{16}, .min = 1.0, .max = 1024.0, .choices = {},
                .unit = "samples", .help = "taps of the blocker search (Vogel disk)"},
      ParamSpec{.name = "filter_samples", .type = ParamType::Int, .defaultValue = int64_t{32}, .min = 1.0, .max = 1024.0, .choices = {},
                .unit = "samples", .help = "taps of the PCF filter (Vogel disk, each a bilinear compare)"},
      ParamSpec{.name = "light_size", .type = ParamType::Float, .defaultValue = 0.0, .min = 1e-6, .max = 1e6, .choices = {}, .unit = "world units",
                .help = "light radius (directional: tan of half the angular diameter); auto = the light's extent",
                .autoDefault = true},
      ParamSpec{.name = "rotate", .type = ParamType::Bool, .defaultValue = true, .min = std::nullopt,
                .max = std::nullopt, .choices = {}, .unit = "",
                .help = "rotate the sample disks per pixel by a hash (noise instead of banding)"},
      biasConstantParamSpec(),
      biasSlopeParamSpec(),
  };
  info.create = [](const Params& params) -> std::unique_ptr<ShadowTechnique> {
    PcssOptions options;
    options.mapSize = static_cast<int>(params.getInt("map_size"));
    options.blockerSamples = static_cast<int>(params.getInt("blocker_samples"));
    options.filterSamples = static_cast<int>(params.getInt("filter_samples"));
    if (!params.isAuto("light_size")) options.lightSize = static_cast<float>(params.getFloat("light_size"));
    options.rotate = params.getBool("rotate");
    options.bias = depthBiasFromParams(params);
    return std::make_unique<PcssTechnique>(options);
  };
  return info;
}

}  // namespace penumbra
