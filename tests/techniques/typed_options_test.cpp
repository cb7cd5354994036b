// The typed API (include/penumbra/techniques/*.h): every technique made from its options struct gives
// the V the registry's technique of the same name gives from parameters by name, at the defaults and
// with members changed as the matching parameters change them. The registry's schema is generated
// from these structs, so this checks that the two ways in are one.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/error.h"
#include "penumbra/primitives.h"
#include "penumbra/reference.h"
#include "penumbra/registry.h"
#include "penumbra/techniques/parker.h"
#include "penumbra/techniques/raytraced.h"
#include "penumbra/techniques/ribbon.h"
#include "penumbra/techniques/shadow_map.h"
#include "penumbra/techniques/silhouette.h"
#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

Image<float> run(ShadowTechnique& t, const Scene& scene, const GBuffer& gbuffer) {
  t.prepare(scene, scene.lights.at(0));
  Image<float> v;
  t.visibility(gbuffer, v);
  return v;
}

struct Case {
  std::string name;
  std::vector<std::string> params;  //!< as the CLI gives them
  std::function<std::unique_ptr<ShadowTechnique>()> typed;
  std::string scene = "torus";
};

std::vector<Case> cases() {
  std::vector<Case> c;
  auto add = [&](std::string name, std::vector<std::string> params, auto options, std::string scene = "torus") {
    c.push_back({name, params, [options] { return makeTechnique(options); }, scene});
  };
  add("hard", {}, HardShadowOptions{});
  HardShadowOptions hard;
  hard.lightMap.size = 256;
  hard.lightMap.fit = LightMapFit::Stable;
  hard.bias.slope = 2.0f;
  add("hard", {"map_size=256", "map_fit=stable", "bias_slope=2"}, hard);
  PcfOptions pcf;
  pcf.kernel = 5;
  add("pcf", {"kernel=5"}, pcf);
  PcssOptions pcss;
  pcss.filterSamples = 16;
  pcss.lightSize = 0.4f;
  add("pcss", {"filter_samples=16", "light_size=0.4"}, pcss);
  MultisampleOptions multisample;
  multisample.samples = 4;
  multisample.lightMap.size = 256;
  add("multisample", {"samples=4", "map_size=256"}, multisample);
  BrabecOptions brabec;
  brabec.coverageBound = false;
  brabec.lightMap.size = 512;
  add("brabec", {"coverage_bound=false", "map_size=512"}, brabec);
  add("heidrich", {}, HeidrichOptions{}, "linear");
  PlmOptions plm;
  plm.marginTexels = 3.0f;
  add("plm", {"margin=3"}, plm);
  add("smoothies", {}, SmoothiesOptions{});
  add("kirsch", {}, KirschOptions{});
  SsvOptions ssv;
  ssv.integration = SsvIntegration::Fixed8;
  add("ssv", {"integration=8x8"}, ssv, "concave");
  add("wedges", {}, WedgesOptions{}, "concave");
  ParkerOptions parker;
  parker.combine = OuterCombine::Product;
  parker.lightDiameter = 0.5f;
  add("parker", {"combine=product", "light_diameter=0.5"}, parker);
  RaytracedSoftOptions soft;
  soft.samplesPerPixel = 4;
  soft.filter.filterScale = 0.5f;
  add("raytraced-soft", {"spp=4", "filter_scale=0.5"}, soft);
  HybridOptions hybrid;
  hybrid.seed = 7;
  add("hybrid", {"seed=7"}, hybrid);
  ReferenceOptions reference;
  reference.samplesPerPixel = 8;
  add("reference", {"spp=8"}, reference);
  return c;
}

TEST(TypedOptions, EveryTechniqueFromItsStructGivesTheRegistrysV) {
  std::vector<std::string> covered;
  for (const Case& c : cases()) {
    const Scene scene = loadScene(c.scene);
    const GBuffer gbuffer = renderGBuffer(scene, 64, 64);
    ParamSet given;
    for (const std::string& kv : c.params) given.setFromKeyValue(kv, "test");
    const std::unique_ptr<ShadowTechnique> byName = createTechnique(c.name, given);
    const std::unique_ptr<ShadowTechnique> typed = c.typed();
    EXPECT_EQ(typed->name(), c.name);
    const Image<float> a = run(*byName, scene, gbuffer), b = run(*typed, scene, gbuffer);
    ASSERT_EQ(a.size(), b.size());
    size_t differ = 0;
    for (size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
    EXPECT_EQ(differ, 0u) << c.name << " with " << c.params.size() << " parameter(s)";
    covered.push_back(c.name);
  }
  // Every registered technique with options is covered (none and raytraced-hard have none).
  for (const TechniqueInfo& info : techniqueRegistry()) {
    if (!info.params.empty()) {
      EXPECT_NE(std::find(covered.begin(), covered.end(), info.name), covered.end()) << info.name;
    }
  }
}

// A member changed in the struct changes V as the parameter does (not a struct the factory ignores).
TEST(TypedOptions, ChangedMembersChangeV) {
  const Scene scene = loadScene("torus");
  const GBuffer gbuffer = renderGBuffer(scene, 64, 64);
  PcssOptions narrow;
  narrow.lightSize = 0.05f;
  PcssOptions wide;
  wide.lightSize = 1.0f;
  const auto a = makeTechnique(narrow), b = makeTechnique(wide);
  const Image<float> va = run(*a, scene, gbuffer), vb = run(*b, scene, gbuffer);
  size_t differ = 0;
  for (size_t i = 0; i < va.size(); ++i) differ += va[i] != vb[i];
  EXPECT_GT(differ, 50u);
}

// A struct filled by hand is held to the ranges of its parameters, with the registry's message.
TEST(TypedOptions, OutOfRangeMembersAreRefusedByName) {
  auto messageOf = [](auto options) -> std::string {
    try {
      makeTechnique(options);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  MultisampleOptions multisample;
  multisample.samples = -1;
  EXPECT_NE(messageOf(multisample).find("multisample.samples = -1 is not valid"), std::string::npos)
      << messageOf(multisample);
  PcssOptions pcss;
  pcss.blockerSamples = 0;
  EXPECT_NE(messageOf(pcss).find("pcss.blocker_samples = 0 is not valid"), std::string::npos) << messageOf(pcss);
  HardShadowOptions hard;
  hard.lightMap.size = 100000;
  EXPECT_NE(messageOf(hard).find("hard.map_size = 100000 is not valid"), std::string::npos) << messageOf(hard);
  RaytracedSoftOptions soft;
  soft.samplesPerPixel = 0;
  EXPECT_NE(messageOf(soft).find("raytraced-soft.spp = 0 is not valid"), std::string::npos) << messageOf(soft);
  SsvOptions ssv;
  ssv.integration = static_cast<SsvIntegration>(9);  // no such value
  EXPECT_NE(messageOf(ssv).find("ssv.integration"), std::string::npos) << messageOf(ssv);
  EXPECT_EQ(messageOf(PcssOptions{}), "");
}

}  // namespace
}  // namespace penumbra
