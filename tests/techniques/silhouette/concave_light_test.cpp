// Concave polygon lights in the silhouette techniques (ssv, wedges: src/techniques/silhouette/convex_parts.h,
// Rouf 2007, Section 5.2.5) and in the others:
//  - under a straight edge parallel to the sides of an L, where ssv and wedges are exact for each
//    convex part (rectangles, as the partition cuts them), the combination by area is exact too:
//    both match the closed form, the lit fraction of the L's area;
//  - the combination is the area-weighted mean of the technique run on each part alone, bit for
//    bit, and a convex light runs unsplit (no "light_parts" stat);
//  - the L light of the built-in `concave` scene (light 4) over its U slab: RMSE8 and penumbra
//    RMSE8 of ssv, wedges, pcss and raytraced-hard against the reference (printed), ssv and wedges
//    below thresholds and far below the hard shadow.
// That every registered technique runs on an L- or U-shaped light or refuses it naming the shape is
// tests/techniques/registry_test.cpp's EveryTechniqueHandlesEveryLightShape.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "penumbra/error.h"
#include "penumbra/metrics.h"
#include "penumbra/primitives.h"
#include "penumbra/reference.h"
#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

using testing::groundLineGBuffer;

// The L of `concave`: the square [-0.6, 0.6]^2 (x, z) at height 4 without its +x +z quarter.
Light lLight() { return loadScene("concave").lights.at(4); }

double overlap1D(double a0, double a1, double b0, double b1) {
  return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

// Lit fraction of the L (bar [-0.6, 0.6] x [-0.6, 0] plus arm [-0.6, 0] x [0, 0.6]) where the light
// plane is hidden for x < s (edge along z) or z < s (edge along x).
double lLitFraction(double s, bool alongZ) {
  if (alongZ) return (0.6 * overlap1D(s, 1e9, -0.6, 0.6) + 0.6 * overlap1D(s, 1e9, -0.6, 0.0)) / 1.08;
  return (1.2 * overlap1D(s, 1e9, -0.6, 0.0) + 0.6 * overlap1D(s, 1e9, 0.0, 0.6)) / 1.08;
}

Scene lScene(const Light& light, std::vector<Object> occluders) {
  Scene scene;
  scene.objects.push_back(testing::makeObject(0, makePlane(20.0f, 20.0f)));
  for (Object& o : occluders) scene.objects.push_back(std::move(o));
  scene.lights.push_back(light);
  scene.camera.position = Vec3(0.0f, 8.0f, 6.0f);
  scene.camera.lookAt = Vec3(0.0f);
  return scene;
}

TEST(ConcaveLight, SsvAndWedgesAreExactUnderAStraightEdgeParallelToTheLsSides) {
  // A 10 x 10 plate 0.002 thick, its top at h = 2 (half-way to the light), one edge through
  // x = 0.1 (or z = 0.1) and the rest of it on the negative side: from ground point p it hides the
  // light's plane where x < p.x + (0.1 - p.x) * 4 / 2.
  const Light light = lLight();
  ASSERT_FALSE(light.convex());
  const float h = 2.0f, thick = 0.002f;
  for (const bool alongZ : {true, false}) {
    SCOPED_TRACE(alongZ ? "edge along z" : "edge along x");
    const Vec3 centre = alongZ ? Vec3(0.1f - 5.0f, h - 0.5f * thick, 0.0f) : Vec3(0.0f, h - 0.5f * thick, 0.1f - 5.0f);
    Object plate = testing::makeObject(1, makeBox(Vec3(10.0f, thick, 10.0f)));
    transformMesh(plate.mesh, glm::translate(Mat4(1.0f), centre));
    const Scene scene = lScene(light, {plate});
    const Vec3 a = alongZ ? Vec3(-1.0f, 0.0f, 0.05f) : Vec3(0.05f, 0.0f, -1.0f);
    const Vec3 b = alongZ ? Vec3(1.2f, 0.0f, 0.05f) : Vec3(0.05f, 0.0f, 1.2f);
    const GBuffer g = groundLineGBuffer(a, b, 221);
    for (const std::vector<std::string>& kv :
         {std::vector<std::string>{}, std::vector<std::string>{"edge_visibility=area"}}) {
      for (const char* name : {"ssv", "wedges"}) {
        if (std::string(name) == "wedges" && !kv.empty()) continue;
        const Image<float> v = testing::runTechnique(name, scene, g, kv);
        double maxErr = 0.0, minV = 1.0, maxV = 0.0;
        for (int i = 0; i < g.width(); ++i) {
          const Vec3 p = g.wsPosition(i, 0);
          const double q = alongZ ? p.x : p.z;
          const double truth = lLitFraction(q + (0.1 - q) * 4.0 / h, alongZ);
          maxErr = std::max(maxErr, std::abs(v(i, 0) - truth));
          minV = std::min(minV, double(v(i, 0)));
          maxV = std::max(maxV, double(v(i, 0)));
        }
        std::printf("[ measured ] L under a straight edge (%s), %s %s: max |V - exact| %.4f\n",
                    alongZ ? "along z" : "along x", name, kv.empty() ? "" : kv[0].c_str(), maxErr);
        EXPECT_LT(maxErr, 0.01) << name;  // the plate's 0.002 thickness and float rounding
        EXPECT_EQ(minV, 0.0f) << name;    // the line runs from the umbra ...
        EXPECT_EQ(maxV, 1.0f) << name;    // ... to full light
      }
    }
  }
}

TEST(ConcaveLight, PartsAreCombinedByAreaAndAConvexLightIsNotSplit) {
  Scene scene = loadScene("concave");
  const Light light = lLight();
  scene.lights = {light};
  const GBuffer g = renderGBuffer(scene, 64, 64);
  const std::vector<std::vector<Vec3>> parts = light.convexParts();
  ASSERT_EQ(parts.size(), 2u);
  for (const char* name : {"ssv", "wedges"}) {
    auto technique = createTechnique(name);
    technique->prepare(scene, light);
    Image<float> v;
    technique->visibility(g, v);
    const auto stats = technique->stats();
    EXPECT_NE(std::find(stats.begin(), stats.end(), std::pair<std::string, double>{"light_parts", 2.0}), stats.end())
        << name;
    // Each part alone, then their mean weighted by area, in the order convex_parts.cpp sums them.
    std::vector<Image<float>> vs;
    std::vector<double> areas;
    double total = 0.0;
    for (const auto& part : parts) {
      const Light piece = Light::polygon(part);
      Scene one = scene;
      one.lights = {piece};
      vs.push_back(testing::runTechnique(name, one, g));
      areas.push_back(piece.area());
      total += piece.area();
    }
    size_t differ = 0, partial = 0;
    for (size_t i = 0; i < v.size(); ++i) {
      double hidden = 0.0;
      for (size_t k = 0; k < vs.size(); ++k) hidden += areas[k] / total * (1.0 - static_cast<double>(vs[k][i]));
      const bool allHidden = std::all_of(vs.begin(), vs.end(), [&](const Image<float>& x) { return x[i] == 0.0f; });
      const float expected = allHidden ? 0.0f : static_cast<float>(std::clamp(1.0 - hidden, 0.0, 1.0));
      differ += v[i] != expected;
      partial += v[i] > 0.0f && v[i] < 1.0f;
    }
    EXPECT_EQ(differ, 0u) << name;
    EXPECT_GT(partial, 100u) << name << ": the image holds penumbrae";
    // A convex light (the scene's square) runs unsplit.
    auto convex = createTechnique(name);
    Scene square = loadScene("concave");
    convex->prepare(square, square.lights.at(0));
    for (const auto& [key, value] : convex->stats()) EXPECT_NE(key, "light_parts") << name;
  }
}

TEST(ConcaveLight, LShapedLightOnConcaveAgainstTheReference) {
  // The U slab of `concave` under its L light (light 4), at 256 x 256 against a 256-spp reference.
  Scene scene = loadScene("concave");
  ASSERT_EQ(scene.lights.size(), 5u);
  const Light light = scene.lights[4];
  scene.lights = {light};
  const GBuffer g = renderGBuffer(scene, 256, 256);
  const Image<uint8_t> mask = errorMask(g, light);
  ReferenceTechnique reference(ReferenceOptions{256, 1});
  reference.prepare(scene, light);
  Image<float> vr;
  reference.visibility(g, vr);
  const auto measure = [&](const std::string& name, const std::vector<std::string>& kv = {}) {
    return compareVisibility(testing::runTechnique(name, scene, g, kv), vr, mask);
  };
  const ErrorStats ssv = measure("ssv"), ssvArea = measure("ssv", {"edge_visibility=area"}), wedges = measure("wedges");
  const ErrorStats pcss = measure("pcss"), hard = measure("raytraced-hard");
  std::printf(
      "[ measured ] concave, L light: RMSE8 / penumbra RMSE8: ssv %.2f / %.2f, ssv edge_visibility=area %.2f / %.2f, "
      "wedges %.2f / %.2f, pcss %.2f / %.2f, raytraced-hard %.2f / %.2f\n",
      ssv.rmse8, ssv.penumbraRmse8, ssvArea.rmse8, ssvArea.penumbraRmse8, wedges.rmse8, wedges.penumbraRmse8,
      pcss.rmse8, pcss.penumbraRmse8, hard.rmse8, hard.penumbraRmse8);
  // Thresholds about 1.1 x the measured values: ssv 4.54 / 8.34, edge_visibility=area 2.10 / 3.88,
  // wedges 4.98 / 9.47 (pcss 13.24 / 23.15, raytraced-hard 35.48 / 67.79). ssv is below wedges
  // here, unlike under the square light of the same scene (ssv_test.cpp): wedges' error lies on the
  // slab's notch walls (its single silhouette, wedges_test.cpp), and most of it comes from the L's
  // 1.2 x 0.6 part, whose centre is off the slab's. Run alone as lights, that part measures ssv
  // 6.91, wedges 7.32 and the 0.6 x 0.6 part ssv 5.34, wedges 1.61.
  EXPECT_LT(ssv.rmse8, 5.0);
  EXPECT_LT(ssv.penumbraRmse8, 9.2);
  EXPECT_LT(ssvArea.rmse8, 2.4);
  EXPECT_LT(ssvArea.penumbraRmse8, 4.3);
  EXPECT_LT(wedges.rmse8, 5.5);
  EXPECT_LT(wedges.penumbraRmse8, 10.5);
  for (const ErrorStats& e : {ssv, ssvArea, wedges}) EXPECT_LT(e.rmse8, 0.2 * hard.rmse8);
}

}  // namespace
}  // namespace penumbra
