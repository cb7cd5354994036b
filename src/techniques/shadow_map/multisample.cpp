// `multisample`: N hard shadow maps, one from each of N light samples, averaged — the brute-force
// soft shadow of the accumulation-buffer era (Herf & Heckbert's and Brotman & Badler's approach as
// cited by Brabec & Seidel 2002, Sec. 2; the "16 samples" row of Lawlor 2006's comparison table).
// V in {0, 1/N, ..., 1} (weighted for a limb-darkened sun): it converges to the true visibility as
// N grows, with banding of N steps in the penumbra instead of noise.
//
// Light samples: N points stratified over the emitting area with correlated multi-jittered sampling
// (CmjSampler, one fixed pattern selected by `seed`), each rendered as a point-light map with the
// light's own light-space axis (rect, disk and polygon lights keep their normal):
//  - disk, rect, polygon, segment: points of the emitter, uniform in area (length), as Light::sample;
//  - sphere: points of the sphere's great disk facing the scene's centre — approximation: a receiver
//    sees the silhouette disk facing itself, which is this disk for receivers far from the light
//    relative to its radius (the silhouette shrinks and moves towards the receiver as it nears);
//  - directional: N directions of the solar disk (orthographic maps), weighted by its profile.
// Each map's compare is the hard shadow of shadow_map.h (receiver plane, slope-scaled bias).
// Memory: N maps of map_size^2 depths.
#include <algorithm>
#include <memory>
#include <vector>

#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/sampling.h"
#include "penumbra/techniques/shadow_map.h"
#include "shadow_map.h"

namespace penumbra {

namespace {

// A point-like light at sample u of `light`, with the light's own axis where it has one, and the
// sample's radiance-profile weight.
std::pair<Light, float> pointLightAtSample(const Light& light, const Scene& scene, const Vec2& u, LightMapFit fit) {
  // Emitter size of the stand-in: any positive value works (a light map only uses the centre and
  // axis); a tiny fraction of the light keeps it well inside the emitter.
  const float tiny = 1e-4f * light.extent();
  switch (light.shape()) {
    case LightShape::Directional: {
      const LightSample s = light.sample(Vec3(0.0f), u);
      return {Light::directional(s.wsDirection, 1e-6f), s.weight};
    }
    case LightShape::Sphere: {
      // The disk of samples faces the map's axis, so a stable fit's samples do not turn either.
      const Frame frame = lightMapFrame(light, scene.bounds(), fit);
      const Vec2 q = concentricDisk(u) * light.radius();
      return {Light::sphere(light.center() + q.x * frame.x + q.y * frame.y, tiny), 1.0f};
    }
    default: {
      // Light::sample's point x of the emitter is independent of the viewpoint for planar and
      // linear lights: recover it from a viewpoint on the light's axis, one extent away.
      const Frame frame = light.lightFrame(scene.bounds());
      const Vec3 viewpoint = light.center() + frame.z * (2.0f * light.extent());
      const LightSample s = light.sample(viewpoint, u);
      const Vec3 x = viewpoint + s.wsDirection * s.distance;
      if (light.shape() == LightShape::Segment) return {Light::sphere(x, tiny), 1.0f};
      return {Light::disk(x, light.normal(), tiny), 1.0f};
    }
  }
}

}  // namespace

class MultisampleTechnique final : public ShadowTechnique {
 public:
  explicit MultisampleTechnique(const MultisampleOptions& options) : options_(options) {}

  std::string_view name() const override { return "multisample"; }

 private:
  static constexpr LightMapLayers kLayers = LightMapLayers::NearestDepth;

  void reserveImpl(int, int) override {
    maps_.resize(CmjSampler(static_cast<uint32_t>(options_.samples)).count());
    for (LightMap& map : maps_) reserveShadowMap(options_.lightMap, map, kLayers);
    reserveShadowMap(options_.lightMap, scratch_, kLayers);
  }

  void prepareImpl(const Scene& scene, const Light& light) override {
    setHorizonClamp(options_.lightMap.horizon, light);  // one map per sample point: the light itself
    weights_.clear();
    const CmjSampler sampler(static_cast<uint32_t>(options_.samples));
    maps_.resize(sampler.count());
    float weightSum = 0.0f;
    for (uint32_t k = 0; k < sampler.count(); ++k) {
      const auto [pointLight, weight] =
          pointLightAtSample(light, scene, sampler.sample(k, options_.seed), options_.lightMap.fit);
      // Depths only (only depths are compared: half the memory of N maps with ids), rendered into the
      // scratch map, whose depth storage goes to the sample in exchange for the storage the sample had
      // before: a steady prepare touches no fresh page.
      createShadowMap(scene, pointLight, options_.lightMap, scratch_, kLayers);
      LightMap& map = maps_[k];
      Image<float> previousDepth = std::move(map.lsDepth);
      map = std::move(scratch_);
      scratch_.lsDepth = std::move(previousDepth);
      weights_.push_back(weight);
      weightSum += weight;
      reportProgress(static_cast<double>(k + 1) / sampler.count());
    }
    for (float& w : weights_) w /= weightSum;
  }

  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override {
    if (maps_.empty()) fail("multisample: visibility() called before prepare()");
    forEachReceiverPixel(gbuffer, v, [&](int x, int y) {
      const Vec3& p = gbuffer.wsPosition(x, y);
      const Vec3& n = gbuffer.wsGeometricNormal(x, y);
      float sum = 0.0f;
      for (size_t k = 0; k < maps_.size(); ++k)
        sum += weights_[k] * hardShadow(maps_[k], makeReceiver(maps_[k], p, n, options_.bias));
      return std::min(sum, 1.0f);  // the normalized weights can sum to 1 + rounding
    });
  }

  MultisampleOptions options_;
  LightMap scratch_;  //!< each sample's map is rendered here first (its storage kept across frames)
  std::vector<LightMap> maps_;
  std::vector<float> weights_;
};

std::unique_ptr<ShadowTechnique> makeTechnique(const MultisampleOptions& o) {
  validateOptions("multisample", o);

  return std::make_unique<MultisampleTechnique>(o);
}

TechniqueInfo multisampleTechniqueInfo() {
  TechniqueInfo info;
  info.name = "multisample";
  info.summary = "N hard shadow maps from N stratified light samples, averaged";
  info.source = "baseline (Lawlor 2006's \"16 samples\" row)";
  info.setOptions<MultisampleOptions>([](const MultisampleOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
