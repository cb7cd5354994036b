// The `reference` technique (docs/architecture.md, "Reference"): V estimated by stratified Monte Carlo ray
// tracing over the light's emitting area with Embree occlusion rays, deterministic for a seed, with
// a per-pixel standard error. Declared here (rather than only registered) so that callers can read
// the standard-error image of the last run.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>

#include "penumbra/image.h"
#include "penumbra/light.h"
#include "penumbra/options.h"
#include "penumbra/technique.h"

namespace penumbra {

class RayScene;       // the Embree scene the rays are traced in (internal)
class RaySceneCache;  // keeps it while the geometry is the same (internal)

struct ReferenceOptions {
  uint32_t samplesPerPixel = 256;  //!< shadow rays per pixel (CMJ-stratified over the light)
  uint64_t seed = 1;               //!< selects the sample patterns; pattern of pixel i = hashCombine(seed, i)

  static void describe(OptionFields<ReferenceOptions>& f) {
    // 65536 puts the standard error of V under 0.002, half an 8-bit step: more buys nothing.
    f.add(&ReferenceOptions::samplesPerPixel, OptionDecl("spp").range(1, 65536).unit("samples").help(
                                                  "samples per pixel (shadow rays, CMJ-stratified over the light)"));
    f.add(&ReferenceOptions::seed,
          OptionDecl("seed").range(0, 4294967295.0).help("random seed; the same seed gives bit-identical output"));
  }
};

class ReferenceTechnique final : public ShadowTechnique {
 public:
  explicit ReferenceTechnique(const ReferenceOptions& options);
  ~ReferenceTechnique() override;

  std::string_view name() const override { return "reference"; }
  // "rays", "rays_per_second", "mean_std_error", "max_std_error" (the last two over pixels that hit
  // geometry) of the last visibility() pass.
  std::vector<std::pair<std::string, double>> stats() const override;

  // Per-pixel standard error of V of the last visibility() pass (0 where the pixel sees nothing):
  // the sample standard deviation of the weighted estimate over sqrt(spp). For stratified samples
  // this overestimates the true error, so it is a conservative bound.
  const Image<float>& standardError() const { return stdError_; }
  const ReferenceOptions& options() const { return options_; }
  // New samples or seed for the next visibility() passes, keeping what prepare() built (the ray
  // scene): a progressive caller traces batch after batch with a new seed each without rebuilding it.
  // Throws Error for spp < 1.
  void setOptions(const ReferenceOptions& options);

 private:
  void prepareImpl(const Scene& scene, const Light& light) override;
  void visibilityImpl(const GBuffer& gbuffer, Image<float>& v) override;

  ReferenceOptions options_;
  // The ray scene depends on the geometry alone: a prepare under another light (or camera) keeps it.
  std::unique_ptr<RaySceneCache> raysCache_;
  const RayScene* rays_ = nullptr;
  std::optional<Light> light_;
  float epsilon_ = 0.0f;
  Image<float> stdError_;
  double rayCount_ = 0.0;
  double meanStdError_ = 0.0;
  double maxStdError_ = 0.0;
};

// The technique made from its options (the registry's `reference` made from parameters by name).
std::unique_ptr<ShadowTechnique> makeTechnique(const ReferenceOptions& options);

}  // namespace penumbra
