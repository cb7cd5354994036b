// Tests of the `multisample` technique (src/techniques/shadow_map/multisample.cpp) on `torus` and `crowded` at
// 512x512 with 256x256 maps: the error against the reference (thresholds: measured values plus a
// margin, printed), clearly below the hard shadow's; V takes only the values k/N of N equally
// weighted maps; more light samples converge towards the reference; planar lights (a rect) are
// sampled on the emitter.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

using testing::errorAgainstReference;
using testing::runTechnique;
using testing::shadowTestScene;
using testing::ShadowTestScene;

TEST(Multisample, ErrorAgainstReference) {
  struct Expected {
    const char* scene;
    double rmse8, penumbraRmse8;
  };
  for (const Expected& expected : {Expected{"torus", 13.0, 20.0}, Expected{"crowded", 11.0, 21.5}}) {
    const ShadowTestScene& s = shadowTestScene(expected.scene);
    const Image<float> v = runTechnique("multisample", s, {"map_size=256"});
    for (float x : v) {
      ASSERT_TRUE(x >= 0.0f && x <= 1.0f);
      ASSERT_NEAR(x * 16.0f, std::round(x * 16.0f), 1e-3f);  // 16 equally weighted maps
    }
    const ErrorStats multi = errorAgainstReference(v, s);
    const ErrorStats hard = errorAgainstReference(runTechnique("hard", s, {"map_size=256"}), s);
    std::printf("[ measured ] %s multisample: RMSE8 %.2f, penumbra RMSE8 %.2f (hard %.2f, %.2f)\n", expected.scene,
                multi.rmse8, multi.penumbraRmse8, hard.rmse8, hard.penumbraRmse8);
    EXPECT_LT(multi.rmse8, expected.rmse8) << expected.scene;
    EXPECT_LT(multi.penumbraRmse8, expected.penumbraRmse8) << expected.scene;
    EXPECT_GT(hard.rmse8, 1.6 * multi.rmse8) << expected.scene;
    EXPECT_GT(hard.penumbraRmse8, 2.0 * multi.penumbraRmse8) << expected.scene;
  }
}

TEST(Multisample, MoreSamplesConverge) {
  const ShadowTestScene& s = shadowTestScene("torus");
  const ErrorStats four = errorAgainstReference(runTechnique("multisample", s, {"map_size=256", "samples=4"}), s);
  const ErrorStats many = errorAgainstReference(runTechnique("multisample", s, {"map_size=256", "samples=64"}), s);
  std::printf("[ measured ] torus multisample penumbra RMSE8: 4 samples %.2f, 64 samples %.2f\n", four.penumbraRmse8,
              many.penumbraRmse8);
  EXPECT_LT(many.penumbraRmse8, 0.75 * four.penumbraRmse8);
}

TEST(Multisample, RectLightIsSampledOnTheEmitter) {
  // The torus scene lit by a rect light of the sphere's size instead: the multisample penumbra must
  // still follow the reference, which samples the same emitter independently.
  const ShadowTestScene& base = shadowTestScene("torus");
  ShadowTestScene s;
  s.scene = base.scene;
  s.scene.lights = {Light::rect(Vec3(-1.0f, 6.0f, -1.5f), Vec3(0.6f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, 0.6f))};
  s.gbuffer = base.gbuffer;
  s.mask = errorMask(s.gbuffer, s.light());
  ReferenceTechnique reference(ReferenceOptions{64, 1});
  reference.prepare(s.scene, s.light());
  reference.visibility(s.gbuffer, s.reference);
  const ErrorStats multi = errorAgainstReference(runTechnique("multisample", s, {"map_size=256"}), s);
  const ErrorStats hard = errorAgainstReference(runTechnique("hard", s, {"map_size=256"}), s);
  std::printf("[ measured ] torus with a rect light: multisample RMSE8 %.2f, penumbra %.2f (hard %.2f, %.2f)\n",
              multi.rmse8, multi.penumbraRmse8, hard.rmse8, hard.penumbraRmse8);
  EXPECT_LT(multi.penumbraRmse8, 0.5 * hard.penumbraRmse8);
  EXPECT_LT(multi.rmse8, 0.6 * hard.rmse8);
}

}  // namespace
}  // namespace penumbra
