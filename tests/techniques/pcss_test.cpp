// Tests of the `pcss` technique (src/techniques/pcss.cpp) on `torus` and `crowded` at 512x512 with
// a 256x256 map: the error against the reference (thresholds: measured values plus a margin,
// printed), clearly below the hard shadow's; contact hardening — on `crowded`, the penumbra of an
// object resting on the floor is much narrower than that of an object floating high, as in the
// reference (a fixed-kernel filter fails this, see pcf_test.cpp); a larger light_size widens the
// penumbra; directional lights (orthographic variant) against the reference; determinism.
#include <gtest/gtest.h>

#include <cstdio>

#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

using testing::errorAgainstReference;
using testing::groundLineGBuffer;
using testing::runTechnique;
using testing::shadowTestScene;
using testing::ShadowTestScene;

TEST(Pcss, ErrorAgainstReference) {
  struct Expected {
    const char* scene;
    double rmse8, penumbraRmse8;
  };
  for (const Expected& expected : {Expected{"torus", 14.5, 28.5}, Expected{"crowded", 12.5, 27.0}}) {
    const ShadowTestScene& s = shadowTestScene(expected.scene);
    const Image<float> v = runTechnique("pcss", s, {"map_size=256"});
    for (float x : v) ASSERT_TRUE(x >= 0.0f && x <= 1.0f);
    const ErrorStats pcss = errorAgainstReference(v, s);
    const ErrorStats hard = errorAgainstReference(runTechnique("hard", s, {"map_size=256"}), s);
    std::printf("[ measured ] %s pcss: RMSE8 %.2f, penumbra RMSE8 %.2f (hard %.2f, %.2f)\n", expected.scene, pcss.rmse8,
                pcss.penumbraRmse8, hard.rmse8, hard.penumbraRmse8);
    EXPECT_LT(pcss.rmse8, expected.rmse8) << expected.scene;
    EXPECT_LT(pcss.penumbraRmse8, expected.penumbraRmse8) << expected.scene;
    // A soft technique that regressed to a hard shadow would fail this.
    EXPECT_GT(hard.rmse8, 1.6 * pcss.rmse8) << expected.scene;
    EXPECT_GT(hard.penumbraRmse8, 2.0 * pcss.penumbraRmse8) << expected.scene;
    // Deterministic: the same input gives the same bits.
    EXPECT_EQ(std::vector<float>(v.begin(), v.end()),
              [&] { const Image<float> w = runTechnique("pcss", s, {"map_size=256"}); return std::vector<float>(w.begin(), w.end()); }());
  }
}

int transitionWidth(const Image<float>& v) {
  int n = 0;
  for (float x : v) n += x > 0.05f && x < 0.95f;
  return n;
}

// Transition widths (samples 0.005 apart with V in (0.05, 0.95)) on two ground lines of `crowded`
// (light: sphere of radius 0.8 at (0.5, 8, -1)):
//  - low: across the far edge of the flat box on the floor (top 0.3 above the ground; its edge at
//    x = 3 casts the shadow edge near x = 3.1 on z = 1.6): occluder-receiver distance 0.3;
//  - high: from below the floating sphere (radius 0.3, 3 above the ground; shadow centre near
//    (0.5, 0, 0.6)) outwards along x: occluder-receiver distance 3.
struct Widths {
  int low, high;
};

Widths contactWidths(const std::string& technique, const std::vector<std::string>& keyValues) {
  const Scene scene = loadScene("crowded");
  ParamSet p;
  for (const std::string& kv : keyValues) p.setFromKeyValue(kv, "test");
  auto t = createTechnique(technique, p);
  t->prepare(scene, scene.lights.at(0));
  Image<float> low, high;
  t->visibility(groundLineGBuffer(Vec3(2.6f, 0.0f, 1.6f), Vec3(3.6f, 0.0f, 1.6f), 201), low);
  t->visibility(groundLineGBuffer(Vec3(0.5f, 0.0f, 0.6f), Vec3(2.5f, 0.0f, 0.6f), 401), high);
  return {transitionWidth(low), transitionWidth(high)};
}

TEST(Pcss, ContactHardening) {
  const Widths pcss = contactWidths("pcss", {"map_size=256"});
  const Widths reference = contactWidths("reference", {"spp=256"});
  std::printf("[ measured ] transition widths (samples of 0.005): pcss low %d high %d; reference low %d high %d\n", pcss.low,
              pcss.high, reference.low, reference.high);
  ASSERT_GT(reference.high, 4 * reference.low);  // the scene does what this test assumes
  EXPECT_GT(pcss.low, 0);
  EXPECT_GT(pcss.high, 3 * pcss.low);
  // The wide penumbra is about as wide as the true one.
  EXPECT_NEAR(pcss.high, reference.high, 0.25 * reference.high);
}

TEST(Pcss, LightSizeWidensThePenumbra) {
  const Widths automatic = contactWidths("pcss", {"map_size=256"});
  const Widths half = contactWidths("pcss", {"map_size=256", "light_size=0.4"});
  std::printf("[ measured ] pcss high transition: light_size auto (0.8) %d, 0.4: %d\n", automatic.high, half.high);
  EXPECT_NEAR(half.high, 0.5 * automatic.high, 0.2 * automatic.high);
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

TEST(Pcss, DirectionalLightUsesTheOrthographicVariant) {
  // The torus scene under a sun of 10 degrees from the sphere light's direction: pcss and
  // multisample against the reference, which samples the solar disk independently.
  const testing::ShadowTestScene& base = testing::shadowTestScene("torus");
  testing::ShadowTestScene s;
  s.scene = base.scene;
  s.scene.lights = {Light::directional(Vec3(-1.0f, 6.0f, -1.5f), radians(10.0f))};
  s.gbuffer = base.gbuffer;
  s.mask = errorMask(s.gbuffer, s.light());
  ReferenceTechnique reference(ReferenceOptions{64, 1});
  reference.prepare(s.scene, s.light());
  reference.visibility(s.gbuffer, s.reference);
  const ErrorStats pcss = testing::errorAgainstReference(testing::runTechnique("pcss", s, {"map_size=256"}), s);
  const ErrorStats multi = testing::errorAgainstReference(testing::runTechnique("multisample", s, {"map_size=256"}), s);
  const ErrorStats hard = testing::errorAgainstReference(testing::runTechnique("hard", s, {"map_size=256"}), s);
  std::printf("[ measured ] torus under a 10-degree sun: pcss RMSE8 %.2f, penumbra %.2f; multisample %.2f, %.2f; hard %.2f, %.2f\n",
              pcss.rmse8, pcss.penumbraRmse8, multi.rmse8, multi.penumbraRmse8, hard.rmse8, hard.penumbraRmse8);
  EXPECT_LT(pcss.penumbraRmse8, 0.5 * hard.penumbraRmse8);
  EXPECT_LT(multi.penumbraRmse8, 0.5 * hard.penumbraRmse8);
}

}  // namespace
}  // namespace penumbra
