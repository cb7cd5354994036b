// Tests of `plm` (src/techniques/ribbon/plm.cpp, Lawlor 2006): the paper's claims — exact along a straight
// edge under a distant disk light up to depth quantization (Sec. 4), sub-texel placement of the 50 %
// contour (Sec. 2), Appendix A's table for a limb-darkened sun — checked against the circular-segment
// closed form; its error against the reference on the paper's triangle scene; local lights through
// the perspective transform; and the light shapes it refuses. The ribbons that plm, smoothies and
// kirsch share (plm.h, rasterizeRibbons) against a brute-force rasterization of their definition.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include <cmath>
#include <cstring>
#include <limits>

#include <glm/gtc/matrix_transform.hpp>

#include "penumbra/error.h"
#include "penumbra/primitives.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "penumbra/techniques/shadow_map.h"
#include "techniques/ribbon/plm.h"
#include "techniques/shadow_map/shadow_map.h"
#include "techniques/shadow_map_fixture.h"

namespace penumbra {
namespace {

using testing::errorAgainstReference;
using testing::groundLineGBuffer;
using testing::runTechnique;
using testing::shadowTestScene;

constexpr double kPiD = 3.14159265358979323846;

// Straight-edge setup: an 8 x 8 ground at y = 0 and, kHeight above it, a horizontal rectangle
// covering x < edgeX (|z| < 3), under a directional disk light straight down.
constexpr float kHeight = 1.5f;
constexpr float kAngleDegrees = 20.0f;

Scene straightEdgeScene(float edgeX, LightProfile profile = LightProfile::Uniform) {
  return testing::straightEdgeScene(edgeX, kHeight, kAngleDegrees, profile);
}

// Exact V at signed distance d (world units, + outside the occluder) from the edge's shadow line:
// the unit disk's part left of the chord at t = d / (h tan(angle / 2)) is visible.
double exactV(double d, double u = 0.0) {
  const double t = std::clamp(d / (kHeight * std::tan(0.5 * kAngleDegrees * kPiD / 180.0)), -1.0, 1.0);
  // Blocked: the part of the unit disk beyond the chord at s = t from its centre (seen from outside
  // the shadow, d > 0, the occluder covers less than half); limb darkening integrated in closed form.
  const double s = t;
  const double area = std::acos(s) - s * std::sqrt(1.0 - s * s);
  const double blocked = (1.0 - u) * area + u * kPiD / 2.0 * (2.0 / 3.0 - s + s * s * s / 3.0);
  return 1.0 - blocked / (kPiD * (1.0 - u / 3.0));
}

constexpr float kEdgeX = 0.37f;  // not on a texel boundary of any map size

TEST(Plm, StraightEdgeIsExactAcrossThePenumbraAt32) {
  const Scene scene = straightEdgeScene(kEdgeX);
  const int n = 401;
  double worst = 0.0;
  for (float z : {-1.3f, 0.21f, 1.77f}) {  // three scan lines across the edge's shadow
    const GBuffer g = groundLineGBuffer(Vec3(kEdgeX - 0.4f, 0.0f, z), Vec3(kEdgeX + 0.4f, 0.0f, z), n);
    const Image<float> v = runTechnique("plm", scene, g, {"map_size=32"});
    for (int i = 0; i < n; ++i) {
      const double d = g.wsPosition(i, 0).x - kEdgeX;
      worst = std::max(worst, std::abs(v(i, 0) - exactV(d)));
    }
  }
  // Measured: 0.006/255 (max |error|); the bound is 2/255.
  EXPECT_LT(worst * 255.0, 2.0);
}

TEST(Plm, StraightEdgeUnderALimbDarkenedSunNeedsTheIlluminationTable) {
  const Scene scene = straightEdgeScene(kEdgeX, LightProfile::LimbDarkened);
  const int n = 401;
  const GBuffer g = groundLineGBuffer(Vec3(kEdgeX - 0.4f, 0.0f, 0.3f), Vec3(kEdgeX + 0.4f, 0.0f, 0.3f), n);
  const Image<float> withTable = runTechnique("plm", scene, g, {"map_size=32"});
  const Image<float> linear = runTechnique("plm", scene, g, {"map_size=32", "illumination_table=false"});
  double worstTable = 0.0, worstLinear = 0.0;
  for (int i = 0; i < n; ++i) {
    const double exact = exactV(g.wsPosition(i, 0).x - kEdgeX, kLimbDarkeningU);
    worstTable = std::max(worstTable, std::abs(withTable(i, 0) - exact));
    worstLinear = std::max(worstLinear, std::abs(linear(i, 0) - exact));
  }
  EXPECT_LT(worstTable * 255.0, 2.0);    // measured: 0.003/255
  EXPECT_GT(worstLinear * 255.0, 10.0);  // measured: 19.6/255 (the linear l is not V)
}

// The x where V crosses 1/2 along the scan line (linear interpolation between samples).
double halfContour(const GBuffer& g, const Image<float>& v) {
  for (int i = 1; i < v.width(); ++i)
    if ((v(i - 1, 0) - 0.5f) * (v(i, 0) - 0.5f) <= 0.0f && v(i - 1, 0) != v(i, 0)) {
      const double a = g.wsPosition(i - 1, 0).x, b = g.wsPosition(i, 0).x;
      return a + (b - a) * (0.5 - v(i - 1, 0)) / (v(i, 0) - v(i - 1, 0));
    }
  return std::nan("");
}

TEST(Plm, QuarterTexelMoveOfTheOccluderMovesTheHalfContourAQuarterTexel) {
  const float texel =
      renderLightMap(straightEdgeScene(kEdgeX), straightEdgeScene(kEdgeX).lights[0], 32).texelWorldSize(0.0f);
  const int n = 2001;
  for (float start : {0.0f, 0.1f, 0.6f}) {  // start positions within a texel
    const float x0 = -0.5f + start * texel;
    const GBuffer g = groundLineGBuffer(Vec3(x0 - 0.5f, 0.0f, 0.4f), Vec3(x0 + 0.5f + texel, 0.0f, 0.4f), n);
    const double before = halfContour(g, runTechnique("plm", straightEdgeScene(x0), g, {"map_size=32"}));
    const double after = halfContour(g, runTechnique("plm", straightEdgeScene(x0 + 0.25f * texel), g, {"map_size=32"}));
    // Measured shift: 0.25 texel; the bound is 0.25 +- 0.1.
    EXPECT_NEAR((after - before) / texel, 0.25, 0.1) << "start " << start;
  }
}

TEST(Plm, TriangleSceneIsSoftAndCloseToTheReference) {
  const auto& s = shadowTestScene("triangle");
  const ErrorStats plm = errorAgainstReference(runTechnique("plm", s, {"map_size=32"}), s);
  const ErrorStats hard = errorAgainstReference(runTechnique("hard", s, {"map_size=32"}), s);
  std::printf("[ measured ] triangle at 32^2: plm %.2f (penumbra %.2f), hard %.2f (penumbra %.2f)\n", plm.rmse8,
              plm.penumbraRmse8, hard.rmse8, hard.penumbraRmse8);
  // Measured at 32^2: plm 5.2 (penumbra 12.6), hard 24.2 (penumbra 93.6); Lawlor's Fig. 10: 9.0.
  EXPECT_LT(plm.rmse8, 9.0);
  EXPECT_LT(plm.penumbraRmse8, 0.5 * hard.penumbraRmse8);
}

TEST(Plm, SphereLightThroughThePerspectiveTransform) {
  const auto& s = shadowTestScene("crowded");
  const ErrorStats plm = errorAgainstReference(runTechnique("plm", s, {"map_size=256"}), s);
  const ErrorStats hard = errorAgainstReference(runTechnique("hard", s, {"map_size=256"}), s);
  const ErrorStats pcf = errorAgainstReference(runTechnique("pcf", s, {"map_size=256"}), s);
  std::printf("[ measured ] crowded at 256^2: plm %.2f (penumbra %.2f), hard %.2f, pcf %.2f\n", plm.rmse8,
              plm.penumbraRmse8, hard.rmse8, pcf.rmse8);
  // Measured: plm 7.7 (penumbra 18.9), hard 28.5, pcf (3x3) 15.2. What is left of plm's error is
  // mostly where several occluders' penumbrae overlap along one map ray (the hole of the raised
  // torus), one penumbra per ray being the method's stated limit (Sec. 3).
  EXPECT_LT(plm.rmse8, 10.0);
  EXPECT_LT(plm.rmse8, 0.6 * pcf.rmse8);
  EXPECT_LT(plm.rmse8, 0.5 * hard.rmse8);
}

TEST(Plm, RefusesSegmentLightsNamingTheShape) {
  Scene scene = straightEdgeScene(kEdgeX);
  scene.lights = {Light::segment(Vec3(-1.0f, 5.0f, 0.0f), Vec3(1.0f, 5.0f, 0.0f))};
  auto plm = createTechnique("plm");
  try {
    plm->prepare(scene, scene.lights[0]);
    FAIL() << "a segment light must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("segment"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("directional"), std::string::npos)
        << "names the supported shapes: " << e.what();
  }
}

// A sphere light seen from a receiver off the map's axis, along (u, 1), projects onto the map's plane as
// an ellipse: as wide as the disk across u, sqrt(1 + |u|^2) times wider along it. An edge's rate is the
// axis rate over that width across the edge: unchanged for an edge on the axis or one whose normal is
// across u, divided by sqrt(1 + |u|^2) for one whose normal lies along u (plm.h, Edge::rate).
TEST(PlmEdgeRate, ASphereLightIsAsWideAcrossAnEdgeAsItsEllipseInTheMapsPlane) {
  plm::Space space;
  space.ratePerTexel = 0.02f;
  space.sphere = true;
  LightMap map;
  map.size = 200;
  map.tanHalfFov = 1.0f;  // u runs over [-1, 1] across the map (no window offset): 0.01 a texel
  auto edgeAt = [](const Vec2& mid, const Vec2& along, const Vec2& outward) {
    plm::Edge e;
    e.a = mid - along;
    e.b = mid + along;
    e.outward = outward;
    return e;
  };
  // On the axis: the map's centre, u = 0.
  EXPECT_FLOAT_EQ(plm::edgeRate(space, map, edgeAt(Vec2(100.0f), Vec2(0.0f, 3.0f), Vec2(1.0f, 0.0f))), 0.02f);
  // At s = 175 (u = (0.75, 0)): normal along u, then across it.
  const Vec2 mid(175.0f, 100.0f);
  EXPECT_FLOAT_EQ(plm::edgeRate(space, map, edgeAt(mid, Vec2(0.0f, 3.0f), Vec2(1.0f, 0.0f))), 0.02f / 1.25f);
  EXPECT_FLOAT_EQ(plm::edgeRate(space, map, edgeAt(mid, Vec2(3.0f, 0.0f), Vec2(0.0f, 1.0f))), 0.02f);
  // t runs down the map: at t = 40, u = (0, 0.6), whose normal along u is -t.
  EXPECT_FLOAT_EQ(plm::edgeRate(space, map, edgeAt(Vec2(100.0f, 40.0f), Vec2(3.0f, 0.0f), Vec2(0.0f, -1.0f))),
                  0.02f / std::sqrt(1.36f));
  // Other lights keep the axis rate.
  space.sphere = false;
  EXPECT_EQ(plm::edgeRate(space, map, edgeAt(mid, Vec2(0.0f, 3.0f), Vec2(1.0f, 0.0f))), 0.02f);
}

// Reproducible uniform floats in [0, 1) (a linear congruential generator) for the randomized tests.
struct UniformFloats {
  uint32_t state;
  float operator()() {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
  }
};

// The ribbons of plm.h by their definition alone: every edge, in list order, at every texel within
// its width of it, through every filter, the least priority winning (ties to the first edge) — no
// tiles, no edges reordered or skipped ahead of the texels, no trimmed or skipped rows, no vector pass. The same
// operations in the same order as rasterizeRibbons' scalar path (both files are built without fused multiply-add), so
// the two agree to the bit.
Image<plm::RibbonTexel> bruteForceRibbons(const std::vector<plm::Edge>& edges, const plm::Space& space, int n,
                                          plm::RibbonSides sides, float margin, const plm::RibbonFilter& filter,
                                          const Image<float>& farthest, plm::RibbonReach reach) {
  Image<plm::RibbonTexel> out(n, n, plm::kNoRibbon);
  Image<float> best(n, n, kInfinity);
  const bool wantOuter = sides != plm::RibbonSides::Inner, wantInner = sides != plm::RibbonSides::Outer;
  const auto above = [&](float depth, float c) { return std::isfinite(depth) && space.zeta(depth) < c; };
  for (size_t k = 0; k < edges.size(); ++k) {
    const plm::Edge& e = edges[k];
    const float cMin = std::min(e.zetaA, e.zetaB);
    // The narrower reaches: the deepest surface (a far-layer texel that sees one) in the 32-texel tiles
    // of the box the map's depth range gives, capped at zeta_far (no surface there: no ribbon), and
    // for SurfacesInRange the shallowest one the map sees there where that lies above the edge; never
    // wider than the map's range.
    float width = std::max(0.0f, space.zetaFar - cMin) / e.rate;
    if (reach != plm::RibbonReach::MapDepthRange) {
      const plm::RibbonBox wide = plm::mapRangeRibbonBox(e, space, n, margin);
      constexpr int kTile = plm::kRibbonTile;
      float below = -kInfinity, from = cMin;
      for (int j = wide.j0 / kTile * kTile; j < std::min(n, (wide.j1 / kTile + 1) * kTile); ++j)
        for (int i = wide.i0 / kTile * kTile; i < std::min(n, (wide.i1 / kTile + 1) * kTile); ++i) {
          // Only the tiles where the ribbon may take a texel on the wanted sides.
          const Vec2 tileLo(static_cast<float>(i / kTile * kTile) + 0.5f, static_cast<float>(j / kTile * kTile) + 0.5f);
          const Vec2 tileHi(static_cast<float>(std::min(n, (i / kTile + 1) * kTile)) - 0.5f,
                            static_cast<float>(std::min(n, (j / kTile + 1) * kTile)) - 0.5f);
          if (!plm::ribbonMayTake(e, sides, tileLo, tileHi)) continue;
          if (farthest(i, j) < space.zetaNone) below = std::max(below, farthest(i, j));
          if (reach == plm::RibbonReach::SurfacesInRange && filter.topDepth && std::isfinite((*filter.topDepth)(i, j)))
            from = std::min(from, space.zeta((*filter.topDepth)(i, j)));
        }
      if (below == -kInfinity) continue;
      width = std::min(width, std::max(0.0f, std::min(below, space.zetaFar) - from) / e.rate);
    }
    const float h = std::min(width + margin + plm::kRibbonBorderTexels, 2.0f * static_cast<float>(n));
    const Vec2 d = e.b - e.a;
    const float invLength2 = 1.0f / glm::dot(d, d);
    // Texel centres beyond h of the segment's box are beyond h of the segment.
    const Vec2 lo = glm::min(e.a, e.b) - (h + 1.0f), hi = glm::max(e.a, e.b) + (h + 1.0f);
    for (int j = std::max(0, static_cast<int>(lo.y)); j <= std::min(n - 1, static_cast<int>(hi.y)); ++j)
      for (int i = std::max(0, static_cast<int>(lo.x)); i <= std::min(n - 1, static_cast<int>(hi.x)); ++i) {
        const float qx = static_cast<float>(i) + 0.5f, y = static_cast<float>(j) + 0.5f;
        const float aqx = qx - e.a.x, aqy = y - e.a.y;
        const float along = (aqx * d.x + aqy * d.y) * invLength2;
        const float u = std::min(std::max(along, 0.0f), 1.0f);
        const bool beforeA = along <= 0.0f, beyondB = along >= 1.0f;
        const float ox = beforeA ? aqx : (beyondB ? qx - e.b.x : aqx - u * d.x);
        const float oy = beforeA ? aqy : (beyondB ? y - e.b.y : aqy - u * d.y);
        const float distance = std::sqrt(ox * ox + oy * oy);
        const float endSide = beforeA ? e.endSideA : (beyondB ? e.endSideB : 0.0f);
        const bool outer = endSide != 0.0f ? endSide > 0.0f : aqx * e.outward.x + aqy * e.outward.y >= 0.0f;
        const float c = beforeA ? e.zetaA : (beyondB ? e.zetaB : e.zetaA + u * (e.zetaB - e.zetaA));
        const float p = c + distance * e.rate;
        if (distance > h || !(outer ? wantOuter : wantInner) || !(p < best(i, j))) continue;
        const bool ownObject = !filter.coverage || (*filter.coverage)(i, j) == e.objectId;
        if (!outer && !ownObject) continue;
        const Vec2 probe = e.a + u * d + plm::kHiddenProbeTexels * e.outward;
        const int pi = static_cast<int>(std::floor(probe.x)), pj = static_cast<int>(std::floor(probe.y));
        const bool probeInMap = pi >= 0 && pj >= 0 && pi < n && pj < n;
        if (!outer && filter.coverage && filter.footprintBorderOnly && probeInMap &&
            (*filter.coverage)(pi, pj) == e.objectId)
          continue;
        if (!(farthest(i, j) > c + plm::kBelowEdge * std::abs(c))) continue;
        if (filter.topDepth && (outer || !ownObject) && above((*filter.topDepth)(i, j), c)) continue;
        if (filter.topDepth && probeInMap && above((*filter.topDepth)(pi, pj), c)) continue;
        best(i, j) = p;
        out(i, j) = plm::RibbonTexel{c, outer ? distance : -distance, static_cast<int32_t>(k)};
      }
  }
  return out;
}

// A built-in scene's light map with its far layer, size x size under one of its lights, and the
// silhouette edges the ribbon techniques find in it.
struct RibbonScene {
  Scene scene;
  LightMap map;
  plm::Space space;
  std::vector<plm::Edge> edges;
};
RibbonScene ribbonScene(const char* name, int size, size_t lightIndex = 0) {
  RibbonScene r;
  r.scene = loadScene(name);
  const Light& sceneLight = r.scene.lights.at(lightIndex);
  createShadowMap(r.scene, sceneLight, LightMapOptions{size, LightMapFit::Tight}, r.map,
                  LightMapLayers::NearestAndFarthest);
  const Light light = lightAtMapOrigin(sceneLight, r.map);
  r.space = plm::makeSpace(r.map, light, "test");
  r.edges = plm::silhouetteEdges(r.scene, light, r.map, r.space);
  return r;
}

TEST(PlmRibbons, EveryTexelMatchesABruteForceRasterizationForEachTechniquesFilter) {
  // A perspective map over tori and boxes (sphere light), a real closed mesh (rect light), and an
  // orthographic one (directional light); map sizes that end in a partial 32-texel tile.
  for (const auto& [name, size] : {std::pair{"crowded", 200}, std::pair{"wuson", 176}, std::pair{"triangle", 72}}) {
    const RibbonScene r = ribbonScene(name, size);
    const LightMap& map = r.map;
    const plm::Space& space = r.space;
    const std::vector<plm::Edge>& edges = r.edges;
    Image<float> farthest(size, size);
    for (int j = 0; j < size; ++j)
      for (int i = 0; i < size; ++i) farthest(i, j) = plm::farthestZeta(map, space, i, j);
    struct Filter {
      const char* technique;
      plm::RibbonSides sides;
      plm::RibbonFilter filter;
      plm::RibbonReach reach;
    };
    // Each technique's filter and reach, and plm's filter with the narrower reach too.
    const Filter filters[] = {
        {"plm", plm::RibbonSides::Both, {&map.objectId, &map.lsDepth, false}, plm::RibbonReach::MapDepthRange},
        {"plm (surfaces below)",
         plm::RibbonSides::Both,
         {&map.objectId, &map.lsDepth, false},
         plm::RibbonReach::SurfacesBelow},
        {"smoothies", plm::RibbonSides::Outer, {nullptr, &map.lsDepth, false}, plm::RibbonReach::SurfacesBelow},
        {"kirsch", plm::RibbonSides::Inner, {&map.objectId, &map.lsDepth, true}, plm::RibbonReach::SurfacesInRange},
    };
    for (const Filter& f : filters) {
      SCOPED_TRACE(std::string(name) + ", " + f.technique + "'s filter");
      constexpr float kMargin = 2.0f;
      plm::RibbonImage ribbons;
      plm::rasterizeRibbons(edges, space, map, f.sides, kMargin, f.filter, ribbons, f.reach);
      const Image<plm::RibbonTexel> expected =
          bruteForceRibbons(edges, space, size, f.sides, kMargin, f.filter, farthest, f.reach);
      int covered = 0, mismatched = 0;
      for (int j = 0; j < size; ++j)
        for (int i = 0; i < size; ++i) {
          const plm::RibbonTexel &got = ribbons(i, j), &want = expected(i, j);
          covered += want.covered() ? 1 : 0;
          const bool same = got.edge == want.edge && (!want.covered() || (got.c == want.c && got.w == want.w));
          if (!same && ++mismatched <= 3)
            ADD_FAILURE() << "texel (" << i << ", " << j << "): edge " << got.edge << " c " << got.c << " w " << got.w
                          << ", expected edge " << want.edge << " c " << want.c << " w " << want.w;
        }
      EXPECT_EQ(mismatched, 0);
      EXPECT_GT(covered, 50) << edges.size() << " silhouette edges: the scene must exercise the ribbons";
    }
  }
}

// The narrower reaches give up only texels that the map-range reach gives to a ribbon beyond every
// penumbra there: SurfacesBelow (smoothies) where the winner's penumbra limit c + |w| s r lies below
// the deepest surface of the texel's tile by more than the margin and border; SurfacesInRange
// (kirsch, whose V takes the occluder's depth from the map) where the winner's width |w| s r exceeds
// the depth from the tile's shallowest surface (or the edge) to its deepest by as much. And they give
// up many on `crowded`, whose raised tori have ground 8 units below where the map's range reaches 12.
TEST(PlmRibbons, TheNarrowerReachesGiveUpOnlyTexelsBeyondEveryPenumbraThere) {
  constexpr int kSize = 256;
  constexpr float kMargin = 2.0f;
  for (const char* name : {"crowded", "wuson", "teapots"}) {
    SCOPED_TRACE(name);
    const RibbonScene r = ribbonScene(name, kSize);
    const LightMap& map = r.map;
    const plm::Space& space = r.space;
    const std::vector<plm::Edge>& edges = r.edges;
    struct Case {
      plm::RibbonSides sides;
      plm::RibbonFilter filter;
      plm::RibbonReach reach;
    };
    for (const Case& k :
         {Case{plm::RibbonSides::Outer, {nullptr, &map.lsDepth, false}, plm::RibbonReach::SurfacesBelow},
          Case{plm::RibbonSides::Inner, {&map.objectId, &map.lsDepth, true}, plm::RibbonReach::SurfacesInRange}}) {
      const bool fromTop = k.reach == plm::RibbonReach::SurfacesInRange;
      plm::RibbonImage wide, narrow;
      plm::rasterizeRibbons(edges, space, map, k.sides, kMargin, k.filter, wide, plm::RibbonReach::MapDepthRange);
      plm::rasterizeRibbons(edges, space, map, k.sides, kMargin, k.filter, narrow, k.reach);
      int given = 0, wideCovered = 0, unexplained = 0;
      for (int j = 0; j < kSize; ++j)
        for (int i = 0; i < kSize; ++i) {
          wideCovered += wide(i, j).covered();
          if (std::memcmp(&wide(i, j), &narrow(i, j), sizeof(plm::RibbonTexel)) == 0) continue;
          ++given;
          const plm::RibbonTexel& w = wide(i, j);
          if (!w.covered()) {
            ++unexplained;
            continue;
          }
          const plm::Edge& e = edges[static_cast<size_t>(w.edge)];
          // The texel's tile's deepest surface, and its shallowest where that lies above the edge.
          float deepest = -kInfinity, from = std::min(e.zetaA, e.zetaB);
          constexpr int kTile = plm::kRibbonTile;
          for (int y = j / kTile * kTile; y < std::min(kSize, (j / kTile + 1) * kTile); ++y)
            for (int x = i / kTile * kTile; x < std::min(kSize, (i / kTile + 1) * kTile); ++x) {
              if (const float z = plm::farthestZeta(map, space, x, y); z < space.zetaNone)
                deepest = std::max(deepest, z);
              if (fromTop && std::isfinite(map.lsDepth(x, y))) from = std::min(from, space.zeta(map.lsDepth(x, y)));
            }
          const float beyond = (kMargin + plm::kRibbonBorderTexels - 0.01f) * e.rate;
          unexplained += fromTop ? !(std::abs(w.w) * e.rate > deepest - from + beyond)
                                 : !(w.c + std::abs(w.w) * e.rate > deepest + beyond);
        }
      EXPECT_EQ(unexplained, 0) << given << " texels given up";
      if (std::string(name) == "crowded") {
        // Measured at 256^2: 502 of 5,790 (smoothies' outer sides), 27 of 2,310 (kirsch's inner ones, whose
        // occluders rise up to the tori's tops above their outlines).
        EXPECT_GT(given, fromTop ? 0 : wideCovered / 20) << "the narrower reach must give up texels on crowded";
      }
    }
  }
}

// The ribbon techniques rasterize their light map's far layer only in farTilesForRibbons' tiles: the
// ribbons over such a map are those over the whole layer to the bit, with a NaN left in every far
// texel outside those tiles (a read of one would drop candidates there), on a map large enough that
// the ribbons leave tiles out; a map without the far layer in a tile a ribbon reaches is refused.
TEST(PlmRibbons, AFarLayerOnlyWhereRibbonsReachGivesTheRibbonsOfTheWholeLayer) {
  for (const auto& [name, size] : {std::pair{"crowded", 512}, std::pair{"wuson", 300}, std::pair{"triangle", 200}}) {
    SCOPED_TRACE(name);
    const Scene scene = loadScene(name);
    const Light& sceneLight = scene.lights[0];
    const LightMapOptions options{size, LightMapFit::Tight};
    constexpr float kMargin = 2.0f;
    LightMap whole, part;
    createShadowMap(scene, sceneLight, options, whole, LightMapLayers::NearestAndFarthest);
    part.lsFarDepth = Image<float>(size, size, std::numeric_limits<float>::quiet_NaN());
    fitShadowMap(scene, sceneLight, options, part);
    const Light light = lightAtMapOrigin(sceneLight, part);
    const plm::Space space = plm::makeSpace(part, light, "test");
    const std::vector<plm::Edge> edges = plm::silhouetteEdges(scene, light, part, space);
    std::vector<uint8_t> tiles, bothTiles;
    plm::farTilesForRibbons(edges, space, size, kMargin, plm::RibbonSides::Both, bothTiles);
    int coveredI = -1, coveredJ = -1;  // a texel some ribbon takes
    // Each technique's sides and reach (plm, smoothies, kirsch), each with its own far tiles.
    for (const auto& [sides, reach] : {std::pair{plm::RibbonSides::Both, plm::RibbonReach::MapDepthRange},
                                       std::pair{plm::RibbonSides::Outer, plm::RibbonReach::SurfacesBelow},
                                       std::pair{plm::RibbonSides::Inner, plm::RibbonReach::SurfacesInRange}}) {
      plm::farTilesForRibbons(edges, space, size, kMargin, sides, tiles);
      rasterizeLightMap(scene, part, LightMapLayers::NearestAndFarthest, tiles);
      const auto leftOut = std::count(tiles.begin(), tiles.end(), uint8_t{0});
      if (std::string(name) == "crowded") {
        EXPECT_GT(leftOut, 0) << "the ribbons must leave tiles out";
        // One side's ribbons reach fewer tiles than both sides' (kirsch's inner sides at convex outlines).
        if (sides == plm::RibbonSides::Inner) {
          EXPECT_GT(leftOut, std::count(bothTiles.begin(), bothTiles.end(), uint8_t{0}));
        }
      }
      const bool footprint = sides == plm::RibbonSides::Inner;
      plm::RibbonImage want, got;
      plm::rasterizeRibbons(edges, space, whole, sides, kMargin,
                            plm::RibbonFilter{&whole.objectId, &whole.lsDepth, footprint}, want, reach);
      plm::rasterizeRibbons(edges, space, part, sides, kMargin,
                            plm::RibbonFilter{&part.objectId, &part.lsDepth, footprint}, got, reach);
      int covered = 0, differing = 0;
      for (int j = 0; j < size; ++j)
        for (int i = 0; i < size; ++i) {
          covered += want(i, j).covered();
          if (want(i, j).covered()) coveredI = i, coveredJ = j;
          differing += std::memcmp(&want(i, j), &got(i, j), sizeof(plm::RibbonTexel)) != 0;
        }
      EXPECT_EQ(differing, 0);
      EXPECT_GT(covered, 100);
    }
    // The tile of a texel a ribbon takes, without the far layer.
    ASSERT_GE(coveredI, 0);
    {
      std::vector<uint8_t> missing = bothTiles;
      const int perRow = (size + kFarLayerTile - 1) / kFarLayerTile;
      missing[static_cast<size_t>(coveredJ / kFarLayerTile) * perRow + coveredI / kFarLayerTile] = 0;
      rasterizeLightMap(scene, part, LightMapLayers::NearestAndFarthest, missing);
      plm::RibbonImage ribbons;
      try {
        plm::rasterizeRibbons(edges, space, part, plm::RibbonSides::Both, kMargin,
                              plm::RibbonFilter{&part.objectId, &part.lsDepth, false}, ribbons);
        ADD_FAILURE() << "a ribbon over a tile without the far layer was not refused";
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no far layer"), std::string::npos) << e.what();
      }
    }
  }
}

// A RibbonImage kept from frame to frame (as the techniques keep theirs) leaves the tiles alone that
// held no ribbon and that no ribbon reaches: frames whose ribbons reach other tiles (other scenes and
// lights at one map size), into one image, made afresh (storage of unknown content) and after
// reserveRibbons, give the ribbons of a fresh image every time, to the bit.
TEST(PlmRibbons, AnImageKeptAcrossFramesHoldsEachFramesRibbonsAlone) {
  constexpr int kSize = 256;
  constexpr float kMargin = 2.0f;
  struct Frame {
    const char* scene;
    int light;
  };
  const auto ribbonsOf = [&](const Frame& frame, plm::RibbonImage& into) {
    const RibbonScene r = ribbonScene(frame.scene, kSize, static_cast<size_t>(frame.light));
    plm::rasterizeRibbons(r.edges, r.space, r.map, plm::RibbonSides::Both, kMargin,
                          plm::RibbonFilter{&r.map.objectId, &r.map.lsDepth, false}, into);
  };
  const Frame frames[] = {{"crowded", 0}, {"triangle", 0}, {"wuson", 0},
                          {"crowded", 0}, {"spheres", 0},  {"crowded", 0}};
  plm::RibbonImage kept, reserved;
  plm::reserveRibbons(kSize, reserved);
  for (const Frame& frame : frames) {
    SCOPED_TRACE(frame.scene);
    plm::RibbonImage fresh;
    ribbonsOf(frame, fresh);
    ribbonsOf(frame, kept);
    ribbonsOf(frame, reserved);
    int covered = 0, differing = 0;
    for (int j = 0; j < kSize; ++j)
      for (int i = 0; i < kSize; ++i) {
        covered += fresh(i, j).covered();
        differing += std::memcmp(&fresh(i, j), &kept(i, j), sizeof(plm::RibbonTexel)) != 0;
        differing += std::memcmp(&fresh(i, j), &reserved(i, j), sizeof(plm::RibbonTexel)) != 0;
      }
    EXPECT_EQ(differing, 0);
    EXPECT_GT(covered, 100);
    EXPECT_LT(covered, kSize * kSize / 2) << "the frames must leave tiles empty for the test to mean something";
  }
}

// The far layer's zeta a row at a time (vector lanes and a scalar tail) is farthestZeta's to the bit, for
// both map kinds, on depths with no surface (infinite, NaN, at or behind a perspective origin) among them.
TEST(PlmRibbons, AFarLayerRowInZetaIsFarthestZetaTexelByTexel) {
  constexpr int kWidth = 37;
  UniformFloats uniform{11u};
  for (const bool orthographic : {false, true}) {
    LightMap map;
    map.orthographic = orthographic;
    map.lsFarDepth = Image<float>(kWidth, 1);
    const float special[] = {kInfinity, std::numeric_limits<float>::quiet_NaN(), 0.0f, -0.0f, -1.0f, -kInfinity,
                             1e-30f};
    for (int i = 0; i < kWidth; ++i)
      map.lsFarDepth(i, 0) = i % 3 == 0 ? special[(i / 3) % 7] : 0.1f + 20.0f * uniform();
    plm::Space space;
    space.orthographic = orthographic;
    space.zetaNone = 7.0f;
    for (int first = 0; first < 4; ++first) {
      float out[kWidth];
      plm::farthestZetaRow(map, space, map.lsFarDepth.row(0) + first, kWidth - first, out);
      for (int i = first; i < kWidth; ++i) {
        const float want = plm::farthestZeta(map, space, i, 0);
        EXPECT_EQ(std::memcmp(&want, &out[i - first], sizeof(float)), 0)
            << (orthographic ? "orthographic " : "perspective ") << i << ": " << want << " " << out[i - first];
      }
    }
  }
}

// ribbonMayTake, which leaves a tile out of an edge's one-sided ribbon, never leaves out a tile where
// the per-texel definition (the scalar span pass, every filter passing) takes a texel for that side:
// random edges with every kind of end, tiles around them, half widths up to past the tile; and it
// does leave tiles out (else it would cost without saving), only of one-sided ribbons.
TEST(PlmRibbons, ATileLeftOutOfAOneSidedRibbonHoldsNoTexelItWouldTake) {
  UniformFloats uniform{7u};
  constexpr int kTile = plm::kRibbonTile;
  float far[kTile], priority[kTile];
  std::fill_n(far, kTile, 1e30f);  // a surface below every edge
  std::fill_n(priority, kTile, kInfinity);
  int withTexels = 0, leftOut = 0;
  for (int trial = 0; trial < 6000; ++trial) {
    plm::Edge e;
    e.a = Vec2(96.0f * uniform(), 96.0f * uniform());
    e.b = e.a + Vec2(24.0f * uniform() - 12.0f, 24.0f * uniform() - 12.0f);
    const Vec2 d = e.b - e.a;
    e.outward = glm::normalize(trial % 2 ? Vec2(d.y, -d.x) : Vec2(-d.y, d.x));
    const float ends[3] = {-1.0f, 0.0f, 1.0f};
    e.endSideA = ends[trial % 3];
    e.endSideB = ends[(trial / 3) % 3];
    e.zetaA = e.zetaB = 1.0f;
    e.rate = 0.01f;
    const plm::RibbonSides sides = trial % 4 < 2 ? plm::RibbonSides::Inner : plm::RibbonSides::Outer;
    const float h = 40.0f * uniform();
    const int x0 = static_cast<int>(96.0f * uniform()), y0 = static_cast<int>(96.0f * uniform());
    const int w = 1 + trial % kTile, rows = 1 + (trial / 7) % kTile;
    plm::RibbonSpan s{};
    s.ax = e.a.x;
    s.bx = e.b.x;
    s.dx = d.x;
    s.dy = d.y;
    s.invLength2 = 1.0f / glm::dot(d, d);
    s.outX = e.outward.x;
    s.outY = e.outward.y;
    s.endSideA = e.endSideA;
    s.endSideB = e.endSideB;
    s.zetaA = e.zetaA;
    s.zetaB = e.zetaB;
    s.rate = e.rate;
    s.halfWidth = h;
    s.wantOuter = sides == plm::RibbonSides::Outer;
    s.orthographic = true;
    s.first = x0;
    s.far = far;
    s.priority = priority;
    bool takes = false;
    for (int j = y0; j < y0 + rows && !takes; ++j) {
      s.aqy = static_cast<float>(j) + 0.5f - e.a.y;
      s.by = static_cast<float>(j) + 0.5f - e.b.y;
      plm::RibbonSpanTexels texels{};
      plm::ribbonSpan(plm::SpanPath::Scalar, s, w, texels);
      takes = texels.taken != 0;
    }
    const Vec2 lo(static_cast<float>(x0) + 0.5f, static_cast<float>(y0) + 0.5f);
    const Vec2 hi = lo + Vec2(static_cast<float>(w - 1), static_cast<float>(rows - 1));
    const bool may = plm::ribbonMayTake(e, sides, lo, hi);
    if (takes) {
      ++withTexels;
      EXPECT_TRUE(may) << "trial " << trial;
    }
    leftOut += may ? 0 : 1;
    if (!plm::ribbonOneSided(e, sides)) {
      EXPECT_TRUE(may);
    }
    EXPECT_TRUE(plm::ribbonMayTake(e, plm::RibbonSides::Both, lo, hi));
  }
  EXPECT_GT(withTexels, 1000);
  EXPECT_GT(leftOut, 1000);
}

// The span pass of rasterizeRibbons through each vector path this CPU has, against the scalar
// definition, to the bit: random edges and rows around a tile, spans of every length up to a tile's
// row, ends beyond the edge on either side, both map kinds, every filter present or not, and
// priorities that tie the edge's own (taken through the scalar pass first) on some texels.
TEST(PlmRibbons, SpanPathsGiveTheScalarPassToTheBit) {
  UniformFloats uniform{2024u};
  constexpr int kTile = plm::kRibbonTile;
  float far[kTile], top[kTile], priority[kTile];
  int32_t coverage[kTile];
  int compared = 0, taken = 0, outer = 0, ties = 0;
  for (const plm::SpanPath path : {plm::SpanPath::Sse, plm::SpanPath::Avx512}) {
    if (!plm::spanPathAvailable(path)) continue;
    for (int trial = 0; trial < 20000; ++trial) {
      const Vec2 a(64.0f * uniform(), 64.0f * uniform());
      const Vec2 b = trial % 97 == 0 ? a : Vec2(64.0f * uniform(), 64.0f * uniform());  // some degenerate
      const Vec2 d = b - a;
      const float y = std::floor(64.0f * uniform()) + 0.5f;
      const bool orthographic = trial % 2 == 0;
      plm::RibbonSpan s{};
      s.ax = a.x;
      s.bx = b.x;
      s.dx = d.x;
      s.dy = d.y;
      s.aqy = y - a.y;
      s.by = y - b.y;
      s.invLength2 = 1.0f / glm::dot(d, d);
      const Vec2 n = glm::length(d) > 0.0f ? glm::normalize(Vec2(d.y, -d.x)) : Vec2(1.0f, 0.0f);
      s.outX = n.x;
      s.outY = n.y;
      const float sides[3] = {-1.0f, 0.0f, 1.0f};
      s.endSideA = sides[trial % 3];
      s.endSideB = sides[(trial / 3) % 3];
      s.zetaA = orthographic ? 2.0f + 3.0f * uniform() : -1.0f / (2.0f + 3.0f * uniform());
      s.zetaB = orthographic ? 2.0f + 3.0f * uniform() : -1.0f / (2.0f + 3.0f * uniform());
      s.rate = 0.001f + 0.05f * uniform();
      s.halfWidth = 40.0f * uniform();
      s.objectId = trial % 4;
      s.first = static_cast<int>(64.0f * uniform());
      s.bothSides = trial % 5 == 0;
      s.wantOuter = trial % 7 < 4;
      s.ties = trial % 3 != 0;
      s.orthographic = orthographic;
      const int count = 1 + trial % kTile;
      for (int m = 0; m < kTile; ++m) {
        const float depth = 1.0f + 5.0f * uniform();
        far[m] = uniform() < 0.1f ? 2.0f : (orthographic ? depth : -1.0f / depth);  // zetaNone on some
        top[m] = uniform() < 0.15f ? kInfinity : (uniform() < 0.05f ? -0.0f : depth * uniform());
        coverage[m] = static_cast<int32_t>(4.0f * uniform());
        priority[m] = uniform() < 0.3f ? kInfinity : (orthographic ? 6.0f : 0.0f) * uniform();
      }
      s.far = far;
      s.coverage = trial % 11 == 0 ? nullptr : coverage;
      s.top = trial % 13 == 0 ? nullptr : top;
      s.priority = priority;
      plm::RibbonSpanTexels want{}, got{};
      plm::ribbonSpan(plm::SpanPath::Scalar, s, count, want);
      // Ties: the edge's own priority at every third taken texel, then both passes again.
      for (int m = 0; m < count; m += 3)
        if (want.p[m] < kInfinity) {
          priority[m] = want.p[m];
          ++ties;
        }
      plm::ribbonSpan(plm::SpanPath::Scalar, s, count, want);
      plm::ribbonSpan(path, s, count, got);
      ASSERT_EQ(got.outer, want.outer) << "trial " << trial;
      ASSERT_EQ(got.taken, want.taken) << "trial " << trial;
      for (int m = 0; m < count; ++m) {
        ASSERT_EQ(std::memcmp(&got.u[m], &want.u[m], sizeof(float)), 0) << "trial " << trial << ", texel " << m;
        ASSERT_EQ(std::memcmp(&got.c[m], &want.c[m], sizeof(float)), 0) << "trial " << trial << ", texel " << m;
        ASSERT_EQ(std::memcmp(&got.distance[m], &want.distance[m], sizeof(float)), 0) << "trial " << trial;
        ASSERT_EQ(std::memcmp(&got.p[m], &want.p[m], sizeof(float)), 0) << "trial " << trial << ", texel " << m;
        taken += want.p[m] < kInfinity;
        outer += (want.outer >> m) & 1u;
        ++compared;
      }
    }
  }
  if (compared == 0) GTEST_SKIP() << "no vector path on this CPU";
  // The cases must reach every outcome for the comparison to mean something.
  EXPECT_GT(taken, compared / 50);
  EXPECT_GT(outer, compared / 10);
  EXPECT_LT(outer, compared - compared / 10);
  EXPECT_GT(ties, 1000);
}

}  // namespace
}  // namespace penumbra
