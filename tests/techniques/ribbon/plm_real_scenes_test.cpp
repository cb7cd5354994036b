// Tests of `plm` (src/techniques/ribbon/plm.cpp, Lawlor 2006) and of `kirsch` and `smoothies`, which share
// its silhouette ribbons (plm.h), on the scenes where plm shattered (lit holes and specks in umbrae,
// spikes radiating from penumbrae, ragged outlines) and kirsch fell far behind the hard shadow: real
// meshes from Debian's assimp-testmodels (WusonOBJ, a closed scanned mesh of 3,732 triangles;
// 2CylinderEngine, 121,496 triangles with fins) on a ground plane under rect, disk, sphere and
// directional lights; `crowded` at a small size; a finely tessellated sphere under a sphere light.
// Each technique is measured against the reference over the error mask by RMSE8, by its umbra leaks
// (pixels the reference has at V < 0.05 and the technique above 1/2) and by its speckle (pixels whose
// V differs from the median of their 3x3 neighbourhood by more than 1/4 where the reference's
// differs by less than 0.05), and compared with `hard` on the same pixels. Small images (160^2, the
// sphere 128^2) and a 128-spp reference keep the file fast; every technique runs at its default
// 1024^2 map.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "penumbra/error.h"
#include "penumbra/metrics.h"
#include "penumbra/raster.h"
#include "penumbra/reference.h"
#include "penumbra/scene_io.h"
#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

using testing::runTechnique;

const std::filesystem::path kTestModels = "/usr/share/assimp/models";
constexpr uint32_t kReferenceSpp = 128;
constexpr int kMeshImageSize = 160;

// The four lights of the mesh scenes, all of radius 0.5 (directional: the same angular size) about
// 5.4 units from the model, off to one side so the shadow falls beside it.
const char* const kLights[] = {
    R"({"type": "rect", "center": [2, 5, 0.5], "u": [0.5, 0, 0], "v": [0, 0, 0.5]})",
    R"({"type": "disk", "center": [2, 5, 0.5], "normal": [0, -1, 0], "radius": 0.5})",
    R"({"type": "sphere", "center": [2, 5, 0.5], "radius": 0.5})",
    R"({"type": "directional", "direction": [2, 5, 0.5], "angular_diameter": 11.42})",
};
const char* const kLightNames[] = {"rect", "disk", "sphere", "directional"};

// An 8 x 8 ground and `mesh` (a file of assimp-testmodels) placed by `transform`, seen from above on
// the side of its shadow, under light `light` of kLights. The file is read once per process.
Scene meshScene(const std::string& mesh, const std::string& transform, const std::string& camera, int light) {
  static std::map<std::string, Scene> parsed;  // test-only cache: every light of one mesh
  auto it = parsed.find(mesh);
  if (it == parsed.end()) {
    const std::filesystem::path path = kTestModels / mesh;
    if (!std::filesystem::exists(path))
      throw Error(path.string() +
                  " is missing: install Debian's test models with `sudo apt-get install assimp-testmodels`");
    std::string lights;
    for (const char* l : kLights) lights += std::string(lights.empty() ? "" : ", ") + l;
    const std::string text = R"({"camera": )" + camera + R"(, "lights": [)" + lights +
                             R"(], "objects": [{"name": "ground", "primitive": {"type": "plane", "size": 8}},
                                 {"name": "model", "mesh": ")" +
                             path.string() + R"(", "transform": )" + transform + "}]}";
    it = parsed.emplace(mesh, parseScene(text, mesh + ".json")).first;
  }
  Scene scene = it->second;
  scene.lights = {it->second.lights.at(static_cast<size_t>(light))};
  return scene;
}

Scene wusonScene(int light) {
  // The model stands on the ground (its lowest vertex is at y = -0.000566).
  return meshScene("OBJ/WusonOBJ.obj", R"({"translate": [0, 0.0006, 0]})",
                   R"({"position": [-1, 6.5, 3.5], "look_at": [-0.8, 0, -0.1], "fov_y": 38})", light);
}

Scene engineScene(int light) {
  // 743 x 273 x 268 units, turned so its long axis runs across the shadow, scaled to 3 units long and
  // set on the ground (its lowest vertex is at y = -180.97).
  return meshScene("glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb",
                   R"({"scale": 0.004, "rotate": [0, 90, 0], "translate": [0, 0.725, 0]})",
                   R"({"position": [-0.6, 6, 3], "look_at": [-0.7, 0, 0], "fov_y": 36})", light);
}

// A ground and a sphere of 96 x 48 segments (radius 0.5, centre 1.2 above the ground) under a sphere
// light of radius 0.8 off to one side: its silhouette seen from the light is a folded polyline.
Scene sphereScene() {
  return parseScene(R"({"camera": {"position": [0, 6, 4], "look_at": [0, 0, 0], "fov_y": 40},
      "lights": [{"type": "sphere", "center": [2, 4, 1], "radius": 0.8}],
      "objects": [{"name": "ground", "primitive": {"type": "plane", "size": 6}},
                  {"name": "ball", "primitive": {"type": "sphere", "radius": 0.5, "segments": 96, "rings": 48},
                   "transform": {"translate": [0, 1.2, 0]}}]})",
                    "sphere.json");
}

struct SceneSetup {
  Scene scene;
  GBuffer gbuffer;
  Image<uint8_t> mask;
  Image<float> reference;
};

// The G-buffer, mask and reference of a scene, computed once per process and key.
const SceneSetup& setup(const std::string& key, const std::function<Scene()>& make, int size) {
  static std::map<std::string, std::unique_ptr<SceneSetup>> cache;  // test-only cache
  auto it = cache.find(key);
  if (it != cache.end()) return *it->second;
  auto s = std::make_unique<SceneSetup>();
  s->scene = make();
  s->gbuffer = renderGBuffer(s->scene, size, size);
  s->mask = errorMask(s->gbuffer, s->scene.lights.at(0));
  ReferenceTechnique reference(ReferenceOptions{kReferenceSpp, 1});
  reference.prepare(s->scene, s->scene.lights.at(0));
  reference.visibility(s->gbuffer, s->reference);
  return *cache.emplace(key, std::move(s)).first->second;
}

float median3x3(const Image<float>& v, int x, int y) {
  float values[9];
  int n = 0;
  for (int j = -1; j <= 1; ++j)
    for (int i = -1; i <= 1; ++i)
      values[n++] = v(std::clamp(x + i, 0, v.width() - 1), std::clamp(y + j, 0, v.height() - 1));
  std::nth_element(values, values + 4, values + 9);
  return values[4];
}

struct Measured {
  double rmse8 = 0.0;
  size_t leaks = 0;    //!< reference V < 0.05, technique V > 0.5
  size_t speckle = 0;  //!< |V - median3x3(V)| > 0.25 where |Vref - median3x3(Vref)| < 0.05
};

Measured measure(const SceneSetup& s, const Image<float>& v) {
  Measured m;
  m.rmse8 = compareVisibility(v, s.reference, s.mask).rmse8;
  for (int y = 0; y < v.height(); ++y)
    for (int x = 0; x < v.width(); ++x) {
      if (!s.mask(x, y)) continue;
      if (s.reference(x, y) < 0.05f && v(x, y) > 0.5f) ++m.leaks;
      if (std::abs(v(x, y) - median3x3(v, x, y)) > 0.25f &&
          std::abs(s.reference(x, y) - median3x3(s.reference, x, y)) < 0.05f)
        ++m.speckle;
    }
  return m;
}

Measured measure(const SceneSetup& s, const std::string& technique) {
  return measure(s, runTechnique(technique, s.scene, s.gbuffer));
}

void print(const std::string& what, const std::string& technique, const Measured& m) {
  std::printf("[ measured ] %-28s %-9s RMSE8 %5.2f  leaks %4zu  speckle %4zu\n", what.c_str(), technique.c_str(),
              m.rmse8, m.leaks, m.speckle);
}

// The helpers count what they should: a lit pixel in the reference's umbra is a leak, an isolated
// pixel a speckle, and neither is counted outside the mask or where the reference changes as fast.
TEST(PlmRealScenes, LeakAndSpeckleCountsOnAHandMadeImage) {
  SceneSetup s;
  s.reference.reset(8, 8, 0.0f);
  s.mask.reset(8, 8, 1);
  for (int y = 0; y < 8; ++y)
    for (int x = 4; x < 8; ++x) s.reference(x, y) = 1.0f;  // umbra on the left half, lit on the right
  Image<float> v = s.reference;
  EXPECT_EQ(measure(s, v).leaks, 0u);
  EXPECT_EQ(measure(s, v).speckle, 0u);
  v(1, 1) = 0.6f;  // a lit speck in the umbra: a leak and a speckle
  v(6, 6) = 0.6f;  // a dark speck in the light: a speckle
  v(1, 6) = 0.6f;
  s.mask(1, 6) = 0;  // outside the mask: neither
  const Measured m = measure(s, v);
  EXPECT_EQ(m.leaks, 1u);
  EXPECT_EQ(m.speckle, 2u);
}

// crowded at a small size (Brabec & Seidel's scene): the spikes that radiated from the raised tori's
// penumbrae and the white lines across their umbrae are speckle; plm has less of it than hard's
// stair-stepped outlines, no more umbra leaks, and under half its error.
TEST(PlmRealScenes, CrowdedAtASmallSizeHasNoSpikesOrLines) {
  const SceneSetup& s = setup(
      "crowded", [] { return loadScene("crowded"); }, kMeshImageSize);
  const Measured plm = measure(s, "plm"), hard = measure(s, "hard");
  print("crowded 160^2", "plm", plm);
  print("crowded 160^2", "hard", hard);
  // Measured: plm 6.51 / 1 / 8, hard 26.59 / 11 / 20.
  EXPECT_LE(plm.speckle, hard.speckle);
  EXPECT_LE(plm.leaks, hard.leaks);
  EXPECT_LT(plm.rmse8, 0.5 * hard.rmse8);
}

// Behind a sphere under a sphere light the inner penumbra is wide: inside the exact hard shadow the
// reference's mean V is about 0.2. plm's must be within 0.05 of it (Equation 1 along the nearest
// edge of a curved silhouette is darker than the truth, by 0.03 here).
TEST(PlmRealScenes, SphereOccluderUnderASphereLightKeepsItsInnerPenumbra) {
  const SceneSetup& s = setup("sphere", sphereScene, 128);
  const Image<float> plm = runTechnique("plm", s.scene, s.gbuffer);
  const Image<float> hardTruth = runTechnique("raytraced-hard", s.scene, s.gbuffer);
  double sumPlm = 0.0, sumReference = 0.0;
  size_t n = 0;
  for (int y = 0; y < plm.height(); ++y)
    for (int x = 0; x < plm.width(); ++x)
      if (s.mask(x, y) && hardTruth(x, y) == 0.0f) {
        sumPlm += plm(x, y);
        sumReference += s.reference(x, y);
        ++n;
      }
  ASSERT_GT(n, 500u);
  const Measured plmCounts = measure(s, plm), hard = measure(s, "hard");
  const double meanPlm = sumPlm / static_cast<double>(n), meanReference = sumReference / static_cast<double>(n);
  std::printf("[ measured ] sphere occluder: mean V inside the hard shadow, plm %.3f, reference %.3f (%zu px)\n",
              meanPlm, meanReference, n);
  EXPECT_NEAR(meanPlm, meanReference, 0.05);
  print("sphere occluder 128^2", "plm", plmCounts);
  print("sphere occluder 128^2", "hard", hard);
  // Measured: plm 0.178 against 0.205; plm 4.92 / 1 / 1, hard 23.93 / 2 / 7 (RMSE8 / leaks / speckle).
  EXPECT_LE(plmCounts.speckle, hard.speckle) << "spikes in the inner penumbra";
  EXPECT_LE(plmCounts.leaks, hard.leaks);
  EXPECT_LT(plmCounts.rmse8, 0.5 * hard.rmse8);
}

// WusonOBJ under each light: plm below hard's RMSE8, with no more umbra leaks and no more speckle.
TEST(PlmRealScenes, WusonUnderEachLightBeatsHardWithoutLeaksOrSpeckle) {
  for (int light = 0; light < 4; ++light) {
    const std::string what = std::string("WusonOBJ ") + kLightNames[light];
    const SceneSetup& s = setup(
        what, [light] { return wusonScene(light); }, kMeshImageSize);
    const Measured plm = measure(s, "plm"), hard = measure(s, "hard");
    print(what, "plm", plm);
    print(what, "hard", hard);
    // Measured (rect, disk, sphere, directional): plm 10.59/11/9, 9.06/11/15, 9.59/11/12,
    // 5.82/3/9; hard 25.85/64/25, 24.50/64/25, 25.77/68/57, 15.94/5/25.
    EXPECT_LT(plm.rmse8, hard.rmse8) << what;
    EXPECT_LE(plm.leaks, hard.leaks) << what;
    EXPECT_LE(plm.speckle, hard.speckle) << what;
  }
}

// 2CylinderEngine under a rect and a directional light (the two measured worst of the four): plm
// below hard's RMSE8 with less speckle. Its umbra leaks are one or two pixels (of 25,600) above
// hard's: receivers on the engine seen almost edge-on from the light, under a part of it a texel or
// less away, which the slope-scaled bias lifts above that part where the fetch is split per texel
// (one ribbon does not hold a stack of fins), and receivers shadowed by a part that the texel's ray
// passes beside, which the fit of b does not see (plm.cpp).
TEST(PlmRealScenes, CylinderEngineBeatsHardWithLessSpeckle) {
  for (int light : {0, 3}) {
    const std::string what = std::string("2CylinderEngine ") + kLightNames[light];
    const SceneSetup& s = setup(
        what, [light] { return engineScene(light); }, kMeshImageSize);
    const Measured plm = measure(s, "plm"), hard = measure(s, "hard");
    print(what, "plm", plm);
    print(what, "hard", hard);
    // Measured (rect, directional): plm 10.95/12/28, 7.22/10/17; hard 23.66/12/64, 16.36/10/25.
    EXPECT_LT(plm.rmse8, 0.6 * hard.rmse8) << what;
    EXPECT_LE(plm.speckle, hard.speckle) << what;
    EXPECT_LE(plm.leaks, hard.leaks + 2) << what;
  }
}

// What the fit of b repairs (plm.cpp, "b"): without it (fit_lower_limit=false: b unset, the map of
// Sec. 3.1's steps 1 and 2) the receivers under the engine's fins and body take the penumbra of the
// ribbon above them, and the umbra is lit: many times hard's and the fitted map's leaks, RMSE8 above
// hard's. With it, the bar of the test above.
TEST(PlmRealScenes, WithoutTheFitOfBTheEnginesUmbraIsLit) {
  const std::string what = std::string("2CylinderEngine ") + kLightNames[0];
  const SceneSetup& s = setup(
      what, [] { return engineScene(0); }, kMeshImageSize);
  const Measured fitted = measure(s, "plm");
  const Measured unfitted = measure(s, runTechnique("plm", s.scene, s.gbuffer, {"fit_lower_limit=false"}));
  const Measured hard = measure(s, "hard");
  print(what, "plm", fitted);
  print(what + " no fit", "plm", unfitted);
  print(what, "hard", hard);
  // Measured: fitted 10.95/12/28, unfitted 31.20/660/31, hard 23.66/12/64 (RMSE8/leaks/speckle).
  EXPECT_GT(unfitted.leaks, 5 * hard.leaks) << what;
  EXPECT_GT(unfitted.leaks, 5 * fitted.leaks) << what;
  EXPECT_GT(unfitted.rmse8, 1.5 * fitted.rmse8) << what;
}

// kirsch and smoothies on the real meshes (rect light). Each draws half of every penumbra from the
// hard shadow's outline, where the truth is 1/2: Lawlor (Sec. 4) notes they "perform acceptably at
// higher resolutions when taking into account that they only compute one half of the penumbra", and
// the half they draw is off by up to 1/2 over the whole band, as the hard shadow is, and more where
// the disk's profile bends (kirsch_test.cpp). So neither beats hard's RMSE8 by design; what is
// asserted is that they stay within a quarter of it (a shadow-width map fed by the silhouettes inside
// the footprint put kirsch at twice and three times hard's), and that smoothies, whose umbra is the
// hard shadow's, leaks no more than hard.
TEST(PlmRealScenes, KirschAndSmoothiesStayNearHardOnRealMeshes) {
  for (int model = 0; model < 2; ++model) {
    const std::string what = model == 0 ? "WusonOBJ rect" : "2CylinderEngine rect";
    const SceneSetup& s = model == 0 ? setup(
                                           what, [] { return wusonScene(0); }, kMeshImageSize)
                                     : setup(
                                           what, [] { return engineScene(0); }, kMeshImageSize);
    const Measured kirsch = measure(s, "kirsch"), smoothies = measure(s, "smoothies"), hard = measure(s, "hard");
    print(what, "kirsch", kirsch);
    print(what, "smoothies", smoothies);
    print(what, "hard", hard);
    // Measured (Wuson, engine): kirsch 25.46/71/19, 27.81/40/19; smoothies 30.04/63/8,
    // 26.06/12/16; hard 25.85/64/25, 23.66/12/64.
    EXPECT_LT(kirsch.rmse8, 1.25 * hard.rmse8) << what;
    EXPECT_LT(smoothies.rmse8, 1.25 * hard.rmse8) << what;
    EXPECT_LE(smoothies.leaks, hard.leaks) << what;
    EXPECT_LE(kirsch.speckle, hard.speckle) << what;
    EXPECT_LE(smoothies.speckle, hard.speckle) << what;
  }
}

// smoothies fades every hard shadow outwards: on crowded, where the exact hard shadow is lit and the
// reference is in the outer penumbra (V in [0.1, 0.9]), smoothies must be below 0.99 at most pixels.
// Its strips are as wide as the widest penumbra in the map; kept by depth, a raised object's strip
// would cover the lower objects' strips around it and their fades would vanish (smoothies.cpp).
TEST(PlmRealScenes, SmoothiesFadesOutsideEveryHardShadowOnCrowded) {
  const SceneSetup& s = setup(
      "crowded", [] { return loadScene("crowded"); }, kMeshImageSize);
  const Image<float> smoothies = runTechnique("smoothies", s.scene, s.gbuffer);
  const Image<float> hardTruth = runTechnique("raytraced-hard", s.scene, s.gbuffer);
  size_t outer = 0, faded = 0;
  for (int y = 0; y < smoothies.height(); ++y)
    for (int x = 0; x < smoothies.width(); ++x)
      if (s.mask(x, y) && hardTruth(x, y) == 1.0f && s.reference(x, y) >= 0.1f && s.reference(x, y) <= 0.9f) {
        ++outer;
        if (smoothies(x, y) < 0.99f) ++faded;
      }
  ASSERT_GT(outer, 300u);
  const double share = static_cast<double>(faded) / static_cast<double>(outer);
  std::printf("[ measured ] crowded 160^2: smoothies fades %.3f of the outer penumbra's %zu px\n", share, outer);
  EXPECT_GT(share, 0.8);
}

}  // namespace
}  // namespace penumbra
