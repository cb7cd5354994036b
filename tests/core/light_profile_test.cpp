// Tests of the visibility-to-illumination table (src/core/light_profile.h, Lawlor 2006
// Appendix A): the table against its closed forms, the closed forms against a Monte Carlo estimate
// over the light's own samples (Light::sample, with the limb-darkening weights the reference uses),
// the paper's stated properties (complementarity, "covering up the first 10% of the diameter of a
// disk light source decreases the delivered illumination by less than 6%", limb darkening flattens
// the curve), and which lights ask for which profile.
#include "core/light_profile.h"

#include <gtest/gtest.h>

#include <cmath>

namespace penumbra {
namespace {

TEST(LightProfile, TableFollowsItsClosedForms) {
  const VisibilityToIllumination uniform(VisibilityProfile::UniformDisk);
  const VisibilityToIllumination limb(VisibilityProfile::LimbDarkenedDisk);
  const VisibilityToIllumination linear(VisibilityProfile::Linear);
  double worstUniform = 0.0, worstLimb = 0.0, worstLinear = 0.0;
  for (int i = 0; i <= 10000; ++i) {
    const double l = i / 10000.0;
    worstUniform = std::max(worstUniform, std::abs(uniform(static_cast<float>(l)) - uniformDiskIllumination(l)));
    worstLimb = std::max(worstLimb, std::abs(limb(static_cast<float>(l)) - limbDarkenedDiskIllumination(l)));
    worstLinear = std::max(worstLinear, std::abs(linear(static_cast<float>(l)) - l));
  }
  // Measured: 2.2e-5, 1.2e-5 and 3e-8 (linear interpolation of 513 samples; the error is largest
  // near l = 0 and 1, where the curves bend most).
  EXPECT_LT(worstUniform, 1e-4);
  EXPECT_LT(worstLimb, 1e-4);
  EXPECT_LT(worstLinear, 1e-6);
  EXPECT_EQ(uniform(-0.5f), 0.0f);  // l is clamped to [0, 1]
  EXPECT_EQ(uniform(1.5f), 1.0f);
}

TEST(LightProfile, ComplementarityAndThePapersTenPercentClaim) {
  for (double l = 0.0; l <= 1.0; l += 0.01) {
    EXPECT_NEAR(uniformDiskIllumination(l) + uniformDiskIllumination(1.0 - l), 1.0, 1e-12) << l;
    EXPECT_NEAR(limbDarkenedDiskIllumination(l) + limbDarkenedDiskIllumination(1.0 - l), 1.0, 1e-12) << l;
  }
  // Covering the first 10% of the diameter removes 5.2% of a uniform disk's light (< 6%, Appendix A).
  const double lost = 1.0 - uniformDiskIllumination(0.9);
  EXPECT_GT(lost, 0.05);
  EXPECT_LT(lost, 0.06);
  // Limb darkening: the covered rim is darker still, so even less is lost (measured 4.0%), and the
  // curve is flatter at its ends (Fig. 12).
  EXPECT_LT(1.0 - limbDarkenedDiskIllumination(0.9), lost);
  EXPECT_LT(limbDarkenedDiskIllumination(0.1), uniformDiskIllumination(0.1));
}

// Monte Carlo over a directional light's own samples: the weighted fraction of samples whose offset
// from the centre, along an axis across the edge, is below 2 l - 1 disk radii.
double sampledIllumination(const Light& light, double l) {
  const Frame frame = Frame::fromZ(light.direction());
  const float radius = std::tan(0.5f * light.angularDiameter());
  constexpr int kGrid = 400;
  double visible = 0.0, total = 0.0;
  for (int j = 0; j < kGrid; ++j)
    for (int i = 0; i < kGrid; ++i) {
      const Vec2 u((static_cast<float>(i) + 0.5f) / kGrid, (static_cast<float>(j) + 0.5f) / kGrid);
      const LightSample s = light.sample(Vec3(0.0f), u);
      const float x = glm::dot(s.wsDirection / glm::dot(s.wsDirection, light.direction()), frame.x) / radius;
      total += s.weight;
      if (x < 2.0 * l - 1.0) visible += s.weight;
    }
  return visible / total;
}

TEST(LightProfile, ClosedFormsMatchTheLightsOwnSamples) {
  const Light uniform = Light::directional(Vec3(0.2f, 1.0f, 0.1f), radians(10.0f), LightProfile::Uniform);
  const Light limb = Light::directional(Vec3(0.2f, 1.0f, 0.1f), radians(10.0f), LightProfile::LimbDarkened);
  double worst = 0.0;
  for (double l : {0.05, 0.2, 0.35, 0.5, 0.7, 0.93}) {
    worst = std::max(worst, std::abs(sampledIllumination(uniform, l) - uniformDiskIllumination(l)));
    worst = std::max(worst, std::abs(sampledIllumination(limb, l) - limbDarkenedDiskIllumination(l)));
  }
  EXPECT_LT(worst, 2e-3);  // measured: 4.4e-5 (160,000 stratified samples)
}

TEST(LightProfile, LightsAskForTheirProfile) {
  EXPECT_EQ(VisibilityToIllumination::forLight(Light::sphere(Vec3(0.0f), 1.0f)).profile(),
            VisibilityProfile::UniformDisk);
  EXPECT_EQ(VisibilityToIllumination::forLight(Light::disk(Vec3(0.0f), Vec3(0, 1, 0), 1.0f)).profile(),
            VisibilityProfile::UniformDisk);
  EXPECT_EQ(VisibilityToIllumination::forLight(Light::directional(Vec3(0, 1, 0), 0.1f)).profile(),
            VisibilityProfile::UniformDisk);
  EXPECT_EQ(
      VisibilityToIllumination::forLight(Light::directional(Vec3(0, 1, 0), 0.1f, LightProfile::LimbDarkened)).profile(),
      VisibilityProfile::LimbDarkenedDisk);
  EXPECT_EQ(VisibilityToIllumination::forLight(Light::rect(Vec3(0.0f), Vec3(1, 0, 0), Vec3(0, 0, 1))).profile(),
            VisibilityProfile::Linear);
  EXPECT_EQ(VisibilityToIllumination::forLight(Light::segment(Vec3(0.0f), Vec3(1.0f))).profile(),
            VisibilityProfile::Linear);
}

}  // namespace
}  // namespace penumbra
