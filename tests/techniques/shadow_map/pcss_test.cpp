// Tests of the `pcss` technique (src/techniques/shadow_map/pcss.cpp) on `torus` and `crowded` at 512x512 with
// a 256x256 map: the error against the reference (thresholds: measured values plus a margin,
// printed), clearly below the hard shadow's; contact hardening — on `crowded`, the penumbra of an
// object resting on the floor is much narrower than that of an object floating high, as in the
// reference (a fixed-kernel filter fails this, see pcf_test.cpp); a larger light_size widens the
// penumbra; directional lights (orthographic variant) against the reference; determinism; the
// vectorized disk kernels of shadow_map.cpp (searchBlockers, pcfDisk, pcfDiskNearest) against
// plain scalar loops over litAtTexel / blockerThreshold on the real `crowded` map, including
// receivers whose disks reach past the map's border; wide filters with nearest-texel taps stay
// within a small margin of all-bilinear ones.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "techniques/shadow_map/shadow_map.h"
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
    EXPECT_EQ(std::vector<float>(v.begin(), v.end()), [&] {
      const Image<float> w = runTechnique("pcss", s, {"map_size=256"});
      return std::vector<float>(w.begin(), w.end());
    }());
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
  std::printf("[ measured ] transition widths (samples of 0.005): pcss low %d high %d; reference low %d high %d\n",
              pcss.low, pcss.high, reference.low, reference.high);
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
  std::printf(
      "[ measured ] torus under a 10-degree sun: pcss RMSE8 %.2f, penumbra %.2f; multisample %.2f, %.2f; hard %.2f, "
      "%.2f\n",
      pcss.rmse8, pcss.penumbraRmse8, multi.rmse8, multi.penumbraRmse8, hard.rmse8, hard.penumbraRmse8);
  EXPECT_LT(pcss.penumbraRmse8, 0.5 * hard.penumbraRmse8);
  EXPECT_LT(multi.penumbraRmse8, 0.5 * hard.penumbraRmse8);
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

// Scalar oracles: the kernels as the plain loops the header describes.
BlockerSearch oracleSearch(const LightMap& m, const ShadowReceiver& r, float radius, const std::vector<Vec2>& disk,
                           const Vec2& rot) {
  BlockerSearch b;
  double sum = 0.0;
  for (const Vec2& p : disk) {
    const float ox = radius * (p.x * rot.x - p.y * rot.y), oy = radius * (p.x * rot.y + p.y * rot.x);
    const int i = static_cast<int>(std::floor(r.s + ox)), j = static_cast<int>(std::floor(r.t + oy));
    if (litAtTexel(m, r, i, j) == 0.0f) {
      ++b.blockers;
      sum += m.lsDepth(i, j);
    }
  }
  if (b.blockers > 0) b.meanDepth = static_cast<float>(sum / b.blockers);
  return b;
}

double oraclePcf(const LightMap& m, const ShadowReceiver& r, float radius, const std::vector<Vec2>& disk,
                 const Vec2& rot, bool bilinear) {
  double sum = 0.0;
  for (const Vec2& p : disk) {
    const float ox = radius * (p.x * rot.x - p.y * rot.y), oy = radius * (p.x * rot.y + p.y * rot.x);
    if (!bilinear) {
      sum += litAtTexel(m, r, static_cast<int>(std::floor(r.s + ox)), static_cast<int>(std::floor(r.t + oy)));
      continue;
    }
    const float sc = r.s + ox - 0.5f, tc = r.t + oy - 0.5f;
    const int i = static_cast<int>(std::floor(sc)), j = static_cast<int>(std::floor(tc));
    const double ws = sc - std::floor(sc), wt = tc - std::floor(tc);
    sum += (1 - wt) * ((1 - ws) * litAtTexel(m, r, i, j) + ws * litAtTexel(m, r, i + 1, j)) +
           wt * ((1 - ws) * litAtTexel(m, r, i, j + 1) + ws * litAtTexel(m, r, i + 1, j + 1));
  }
  return sum / static_cast<double>(disk.size());
}

TEST(Pcss, DiskKernelsMatchScalarLoopsOnTheCrowdedMap) {
  const Scene scene = loadScene("crowded");
  const LightMap m = createShadowMap(scene, scene.lights.at(0), LightMapOptions{256});
  const GBuffer& g = testing::shadowTestScene("crowded").gbuffer;
  const PixelRotations rotations;
  // 16 and 32 taps as pcss uses them, and 77: more than one 64-tap chunk, not a multiple of 4.
  for (int taps : {16, 32, 77}) {
    const std::vector<Vec2> disk = vogelDisk(taps);
    int checked = 0, blocked = 0, nearBorder = 0;
    for (int y = 0; y < g.height(); y += 7) {
      for (int x = 0; x < g.width(); x += 7) {
        if (!g.hit(x, y)) continue;
        const ShadowReceiver r = makeReceiver(m, g.wsPosition(x, y), g.wsGeometricNormal(x, y), DepthBias{});
        if (!r.inMap) continue;
        const Vec2 rot = rotations(x, y);
        // Radii from a texel to far past the map's border (texels outside hold nothing).
        const float radius = 0.7f + static_cast<float>((x * 31 + y * 17) % 400) * 0.25f;
        nearBorder += r.s - radius < 0.0f || r.t - radius < 0.0f || r.s + radius > 256.0f || r.t + radius > 256.0f;
        const BlockerSearch fast = searchBlockers(m, r, radius, disk, rot);
        const BlockerSearch slow = oracleSearch(m, r, radius, disk, rot);
        ASSERT_EQ(fast.blockers, slow.blockers) << x << "," << y << " taps " << taps;
        EXPECT_NEAR(fast.meanDepth, slow.meanDepth, 1e-5f * slow.meanDepth) << x << "," << y;
        blocked += fast.blockers > 0;
        EXPECT_NEAR(pcfDisk(m, r, radius, disk, rot), oraclePcf(m, r, radius, disk, rot, true), 1e-5) << x << "," << y;
        EXPECT_EQ(pcfDiskNearest(m, r, radius, disk, rot),
                  static_cast<float>(oraclePcf(m, r, radius, disk, rot, false)))
            << x << "," << y;
        ++checked;
      }
    }
    // The sample reaches what the test is about: blockers, and disks that cross the border.
    EXPECT_GT(checked, 2000);
    EXPECT_GT(blocked, checked / 10);
    EXPECT_GT(nearBorder, checked / 40);  // measured: 208 of 3930
  }
}

TEST(Pcss, NearestTapsForWideFiltersCostLittleQuality) {
  // At map 1024 most filter disks are wider than bilinear_max_radius (4 texels): the default against
  // all-bilinear taps (bilinear_max_radius = 8192), on crowded and torus.
  for (const char* name : {"torus", "crowded"}) {
    const testing::ShadowTestScene& s = testing::shadowTestScene(name);
    const ErrorStats mixed = testing::errorAgainstReference(testing::runTechnique("pcss", s, {"map_size=1024"}), s);
    const ErrorStats bilinear = testing::errorAgainstReference(
        testing::runTechnique("pcss", s, {"map_size=1024", "bilinear_max_radius=8192"}), s);
    std::printf("[ measured ] %s pcss map 1024: RMSE8 %.2f, penumbra %.2f; all bilinear %.2f, %.2f\n", name,
                mixed.rmse8, mixed.penumbraRmse8, bilinear.rmse8, bilinear.penumbraRmse8);
    EXPECT_LT(mixed.rmse8, bilinear.rmse8 + 0.5) << name;
    EXPECT_LT(mixed.penumbraRmse8, bilinear.penumbraRmse8 + 1.5) << name;
  }
}

}  // namespace
}  // namespace penumbra

namespace penumbra::testing {
namespace {

// A light far wider than its distance to the occluders (light_size at the top of its range): the
// receiver plane's slope, extrapolated over a search as wide as the map, counts texels behind the
// receiver as blockers and made the estimated width negative; the filter then read outside the map.
TEST(Pcss, LightsWiderThanTheSceneStayInsideTheMap) {
  const Scene scene = loadScene("torus");
  const GBuffer gbuffer = renderGBuffer(scene, 64, 64);
  for (const char* size : {"light_size=50", "light_size=100", "light_size=1000000"}) {
    SCOPED_TRACE(size);
    const Image<float> v = runTechnique("pcss", scene, gbuffer, {size, "map_size=256"});
    for (size_t i = 0; i < v.size(); ++i) ASSERT_TRUE(v[i] >= 0.0f && v[i] <= 1.0f) << i << " " << v[i];
  }
  // The clamp is the documented rule, and the run says how often it applied (stat frac_clamped_to_map).
  const auto clampedFraction = [&](const char* size) {
    auto pcss = createTechnique("pcss", [&] {
      ParamSet given;
      given.setFromKeyValue(size, "test");
      given.setFromKeyValue("map_size=256", "test");
      return given;
    }());
    Image<float> v;
    pcss->prepare(scene, scene.lights[0]);
    pcss->visibility(gbuffer, v);
    for (const auto& [name, value] : pcss->stats())
      if (name == "frac_clamped_to_map") return value;
    return -1.0;
  };
  EXPECT_GT(clampedFraction("light_size=1000000"), 0.5);
  EXPECT_EQ(clampedFraction("light_size=0.5"), 0.0);
}

}  // namespace
}  // namespace penumbra::testing
