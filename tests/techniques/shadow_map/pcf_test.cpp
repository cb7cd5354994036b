// Tests of the `pcf` technique (src/techniques/shadow_map/pcf.cpp) on `torus` and `crowded` at 512x512 with a
// 256x256 map: the error against the reference (thresholds: measured values plus a margin, printed),
// that filtering helps against `hard`, that the kernel blurs with its size in texels whatever the
// occluder distance (the fixed kernel PCSS improves on), and that V stays in [0, 1].
#include <gtest/gtest.h>

#include <cstdio>

#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

using testing::errorAgainstReference;
using testing::runTechnique;
using testing::shadowTestScene;
using testing::ShadowTestScene;

TEST(Pcf, ErrorAgainstReference) {
  struct Expected {
    const char* scene;
    double rmse8, penumbraRmse8;
  };
  for (const Expected& expected : {Expected{"torus", 14.5, 36.5}, Expected{"crowded", 17.0, 40.5}}) {
    const ShadowTestScene& s = shadowTestScene(expected.scene);
    const Image<float> v = runTechnique("pcf", s, {"map_size=256"});
    for (float x : v) ASSERT_TRUE(x >= 0.0f && x <= 1.0f);
    const ErrorStats pcf = errorAgainstReference(v, s);
    const ErrorStats hard = errorAgainstReference(runTechnique("hard", s, {"map_size=256"}), s);
    std::printf("[ measured ] %s pcf: RMSE8 %.2f, penumbra RMSE8 %.2f (hard %.2f)\n", expected.scene, pcf.rmse8,
                pcf.penumbraRmse8, hard.rmse8);
    EXPECT_LT(pcf.rmse8, expected.rmse8) << expected.scene;
    EXPECT_LT(pcf.penumbraRmse8, expected.penumbraRmse8) << expected.scene;
    EXPECT_LT(pcf.rmse8, hard.rmse8) << expected.scene;
  }
}

// Width (samples with V in (0.05, 0.95)) of the transition along a ground line.
int transitionWidth(const Image<float>& v) {
  int n = 0;
  for (float x : v) n += x > 0.05f && x < 0.95f;
  return n;
}

TEST(Pcf, BlurFollowsTheKernelNotTheOccluderDistance) {
  // Ground lines across the shadow edge of an object resting on the floor (the flat box, top 0.3
  // above the ground) and of one floating high (the sphere 3 above it), samples 0.005 apart, in
  // `crowded` (see pcss_test.cpp for the geometry).
  const Scene scene = loadScene("crowded");
  const GBuffer low = testing::groundLineGBuffer(Vec3(2.6f, 0.0f, 1.6f), Vec3(3.6f, 0.0f, 1.6f), 201);
  const GBuffer high = testing::groundLineGBuffer(Vec3(0.5f, 0.0f, 0.6f), Vec3(2.5f, 0.0f, 0.6f), 401);
  int widths[2][2];
  for (int k = 0; k < 2; ++k) {
    ParamSet p;
    p.setFromKeyValue("map_size=256", "test");
    p.setFromKeyValue(k == 0 ? "kernel=3" : "kernel=9", "test");
    auto pcf = createTechnique("pcf", p);
    pcf->prepare(scene, scene.lights.at(0));
    for (int line = 0; line < 2; ++line) {
      Image<float> v;
      pcf->visibility(line == 0 ? low : high, v);
      widths[k][line] = transitionWidth(v);
    }
  }
  std::printf(
      "[ measured ] pcf transition widths (samples of 0.005): kernel 3: low %d high %d; kernel 9: low %d high %d\n",
      widths[0][0], widths[0][1], widths[1][0], widths[1][1]);
  EXPECT_GT(widths[1][0], 2 * widths[0][0]);  // the blur grows with the kernel ...
  EXPECT_GT(widths[0][0], 0);
  for (int k = 0; k < 2; ++k) EXPECT_LT(widths[k][1], 2 * widths[k][0]);  // ... but not with the occluder's height
}

}  // namespace
}  // namespace penumbra
