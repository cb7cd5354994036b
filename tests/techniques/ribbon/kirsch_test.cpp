// Tests of `kirsch` (src/techniques/ribbon/kirsch.cpp, Kirsch & Döllner 2003): inner penumbra only — the
// hard shadow's outline stays the shadow's border and the shadow fades inwards over the width of the
// physical inner penumbra (checked against that model's closed form on a straight edge, and against
// the exact circular segment inside the hard shadow); its error on the paper's triangle scene lies
// between plm's and the hard shadow's, as in Lawlor 2006's Fig. 10.
#include <gtest/gtest.h>

#include <cstdio>

#include <cmath>

#include "core/light_profile.h"
#include "penumbra/primitives.h"
#include "penumbra/registry.h"
#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

using testing::errorAgainstReference;
using testing::groundLineGBuffer;
using testing::runTechnique;
using testing::shadowTestScene;

constexpr float kHeight = 1.5f;
constexpr float kAngleDegrees = 20.0f;
constexpr float kEdgeX = 0.37f;

Scene straightEdgeScene() { return testing::straightEdgeScene(kEdgeX, kHeight, kAngleDegrees); }

Image<float> run(const std::string& technique, const Scene& scene, const GBuffer& g, const std::string& param) {
  return runTechnique(technique, scene, g, {param});
}

TEST(Kirsch, LitOutsideTheHardShadowAndAnInnerFadeAcrossThePhysicalPenumbra) {
  const Scene scene = straightEdgeScene();
  const float half = kHeight * std::tan(radians(0.5f * kAngleDegrees));  // penumbra half-width
  const int n = 401;
  const GBuffer g = groundLineGBuffer(Vec3(kEdgeX - 0.4f, 0.0f, 0.3f), Vec3(kEdgeX + 0.4f, 0.0f, 0.3f), n);
  const Image<float> v = run("kirsch", scene, g, "map_size=256");
  const Image<float> perTexel = runTechnique("kirsch", scene, g, {"map_size=256", "sub_texel=false"});
  const Image<float> exact = run("reference", scene, g, "spp=4096");
  const VisibilityToIllumination table(VisibilityProfile::UniformDisk);
  const float texel = 8.008f / 256.0f;  // the orthographic map holds the 8 x 8 ground (0.1% margin)
  double worstModel = 0.0, worstModelPerTexel = 0.0, outsideMin = 1.0, insideError = 0.0;
  for (int i = 0; i < n; ++i) {
    const float d = g.wsPosition(i, 0).x - kEdgeX;  // - inside the occluder's shadow
    if (d > texel) outsideMin = std::min(outsideMin, static_cast<double>(v(i, 0)));
    if (d < -texel) {
      // The shadow width over the inner penumbra's width at the receiver: V = f(1 - |d| / half).
      worstModel = std::max(worstModel, static_cast<double>(std::abs(v(i, 0) - table(1.0f + d / half))));
      worstModelPerTexel =
          std::max(worstModelPerTexel, static_cast<double>(std::abs(perTexel(i, 0) - table(1.0f + d / half))));
      insideError = std::max(insideError, static_cast<double>(std::abs(v(i, 0) - exact(i, 0))));
    }
  }
  EXPECT_EQ(outsideMin, 1.0) << "outside the hard shadow everything is lit";
  // The width measured from each pixel's own point in the map follows the model; at the texel's centre
  // (the paper's width map) it is up to half a texel = 6% of this ramp away. Measured: below 1e-4 and 0.074. A
  // hard edge here would be off by 1.
  std::printf("[ measured ] worst against the model: %.4f, per texel %.4f\n", worstModel, worstModelPerTexel);
  EXPECT_LT(worstModel, 1e-3);
  EXPECT_GT(worstModelPerTexel, 0.05);
  EXPECT_LT(worstModelPerTexel, 0.1);
  // Half of the true penumbra is missing: where the truth is 1/2 at the edge, kirsch says 1.
  // Measured: 0.53.
  EXPECT_GT(insideError, 0.4);
}

// Half a penumbra is about as far from the truth as none: inside the true penumbra band the hard
// shadow is off by up to 1/2 on both halves, and so is a fade that starts at the hard edge, where the
// truth is 1/2 (the error moves rather than shrinks). Lawlor's Fig. 10 shows kirsch well below the
// hard shadow map; ours is not (docs/lawlor-table.md discusses why: the row that differs is `hard`).
TEST(Kirsch, TriangleSceneIsWorseThanPlmAndCloseToHard) {
  const auto& s = shadowTestScene("triangle");
  const double kirsch = errorAgainstReference(runTechnique("kirsch", s, {"map_size=64"}), s).rmse8;
  const double plm = errorAgainstReference(runTechnique("plm", s, {"map_size=64"}), s).rmse8;
  const double hard = errorAgainstReference(runTechnique("hard", s, {"map_size=64"}), s).rmse8;
  std::printf("[ measured ] triangle at 64^2: kirsch %.2f, plm %.2f, hard %.2f\n", kirsch, plm, hard);
  // Measured at 64^2: kirsch 20.3, plm 3.2, hard 19.0.
  EXPECT_GT(kirsch, 1.5 * plm);
  EXPECT_NEAR(kirsch / hard, 1.0, 0.25);
}

}  // namespace
}  // namespace penumbra
