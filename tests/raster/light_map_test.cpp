// Tests of renderLightMap and LightMap's projections (src/raster/light_map.cpp). The oracle is
// Embree ray casting from the light: through each texel centre, from the centre sample (local
// lights) or along the light's axis (directional), the first hit's object id and light-space depth
// must agree with the map, except on a small measured fraction of texels on silhouettes. Also the
// fit (every bounds corner lands in the map), the 150-degree clamp for a light inside the scene,
// project/unproject round trips, texel sizes, and bad input. The stable fit: it holds the scene at
// every frame of long light paths, agrees with rays, and does not change at all while the light moves
// within one cell of its lattice.
#include <gtest/gtest.h>

#include <algorithm>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include "penumbra/error.h"
#include "penumbra/motion.h"
#include "penumbra/raster.h"
#include "raster_test_scenes.h"
#include "rt/ray_scene.h"

namespace penumbra {
namespace {

struct MapComparison {
  int texels = 0, hits = 0, idMismatch = 0;
  int depthOutliers = 0;          // texels further off than the snapping allows
  double maxInteriorError = 0.0;  // relative depth error where the ray hits well inside a triangle
};

// The ray through texel (s, t)'s centre from the map's origin (orthographic: along its axis), with
// t measured in light-space depth.
Ray texelRay(const LightMap& m, int s, int t) {
  const float sc = static_cast<float>(s) + 0.5f, tc = static_cast<float>(t) + 0.5f;
  Ray ray;
  if (m.orthographic) {
    ray.origin = m.unproject(sc, tc, 0.0f);
    ray.direction = m.lsFrame.z;
  } else {
    ray.origin = m.wsOrigin;
    ray.direction = m.unproject(sc, tc, 1.0f) - m.wsOrigin;  // light-space z = 1: t is the depth
    ray.tMin = m.zNear;
  }
  return ray;
}

MapComparison compareWithRays(const Scene& scene, const LightMap& m) {
  const RayScene rays(scene);
  MapComparison c;
  for (int t = 0; t < m.size; ++t)
    for (int s = 0; s < m.size; ++s) {
      ++c.texels;
      Ray ray = texelRay(m, s, t);
      const std::optional<RayHit> hit = rays.intersect(ray);
      const int32_t id = hit ? hit->objectId : kNoObject;
      if (id != m.objectId(s, t)) {
        ++c.idMismatch;
        continue;
      }
      if (!hit) {
        EXPECT_EQ(m.lsDepth(s, t), kInfinity);
        continue;
      }
      ++c.hits;
      const float error = std::abs(m.lsDepth(s, t) - hit->t);
      const Vec2 b = hit->barycentrics;
      if (std::min({b.x, b.y, 1.0f - b.x - b.y}) > 0.02f)
        c.maxInteriorError = std::max(c.maxInteriorError, double(error / hit->t));
      // Near a shared edge the rasterizer's 1/512-texel snapping may pick the neighbouring
      // triangle: allow that much offset along the surface, stretched by the slope seen from the light.
      const float cosine = std::abs(glm::dot(hit->wsGeometricNormal, glm::normalize(ray.direction)));
      if (error > 1e-5f * hit->t + 0.01f * m.texelWorldSize(hit->t) / std::max(cosine, 1e-3f)) ++c.depthOutliers;
    }
  return c;
}

void expectMatchesRays(const Scene& scene, const LightMap& m, int minHits) {
  const MapComparison c = compareWithRays(scene, m);
  SCOPED_TRACE(::testing::Message() << "idMismatch " << c.idMismatch << " of " << c.texels << ", interior depth "
                                    << c.maxInteriorError << ", outliers " << c.depthOutliers << ", hits " << c.hits);
  if (std::getenv("PENUMBRA_PRINT_MEASURED"))
    std::printf("light map: idMismatch %d of %d, interior %.3g, outliers %d, hits %d\n", c.idMismatch, c.texels,
                c.maxInteriorError, c.depthOutliers, c.hits);
  EXPECT_GT(c.hits, minHits);
  // Measured (PENUMBRA_PRINT_MEASURED=1): no texel changes object in these maps; interior depths
  // agree to 3.8e-6 relative, and no texel is off by more than the snapping allows.
  EXPECT_LE(c.idMismatch, std::max(2, c.texels / 5000));
  EXPECT_LT(c.maxInteriorError, 1e-5);
  EXPECT_EQ(c.depthOutliers, 0);
}

void expectCornersInside(const Scene& scene, const LightMap& m) {
  const Bounds3 b = scene.bounds();
  for (int i = 0; i < 8; ++i) {
    const Vec3 corner((i & 1) ? b.upper.x : b.lower.x, (i & 2) ? b.upper.y : b.lower.y,
                      (i & 4) ? b.upper.z : b.lower.z);
    const Vec3 p = m.project(corner);
    EXPECT_GE(p.x, 0.0f);
    EXPECT_LE(p.x, static_cast<float>(m.size));
    EXPECT_GE(p.y, 0.0f);
    EXPECT_LE(p.y, static_cast<float>(m.size));
    EXPECT_GE(p.z, m.zNear);
    EXPECT_LE(p.z, m.zFar * 1.0001f);
  }
}

TEST(LightMap, SphereLightMatchesRaysFromTheCentreSample) {
  const Scene scene = rastertest::objectsScene();
  const Light light = Light::sphere(Vec3(1.0f, 6.0f, 2.0f), 0.3f);
  const LightMap m = renderLightMap(scene, light, 256);
  EXPECT_FALSE(m.orthographic);
  EXPECT_EQ(m.wsOrigin, light.center());
  EXPECT_NEAR(glm::dot(m.lsFrame.z, glm::normalize(scene.bounds().center() - light.center())), 1.0f, 1e-6f);
  expectCornersInside(scene, m);
  // The fit is tight: some corner lies within 1% of the map's border.
  const Bounds3 b = scene.bounds();
  float outermost = 0.0f;
  for (int i = 0; i < 8; ++i) {
    const Vec3 corner((i & 1) ? b.upper.x : b.lower.x, (i & 2) ? b.upper.y : b.lower.y,
                      (i & 4) ? b.upper.z : b.lower.z);
    const Vec3 p = m.project(corner);
    outermost = std::max({outermost, std::abs(p.x - 128.0f), std::abs(p.y - 128.0f)});
  }
  EXPECT_GT(outermost, 128.0f * 0.99f);
  expectMatchesRays(scene, m, 9000);  // measured: 10412 hits
}

// Two maps equal field for field and texel for texel.
void expectSameMap(const LightMap& a, const LightMap& b) {
  EXPECT_EQ(a.size, b.size);
  EXPECT_EQ(a.orthographic, b.orthographic);
  EXPECT_EQ(a.wsOrigin, b.wsOrigin);
  EXPECT_EQ(a.lsFrame.x, b.lsFrame.x);
  EXPECT_EQ(a.lsFrame.y, b.lsFrame.y);
  EXPECT_EQ(a.lsFrame.z, b.lsFrame.z);
  EXPECT_EQ(a.halfWidth, b.halfWidth);
  EXPECT_EQ(a.tanHalfFov, b.tanHalfFov);
  EXPECT_EQ(a.windowOffset, b.windowOffset);
  EXPECT_EQ(a.zNear, b.zNear);
  EXPECT_EQ(a.zFar, b.zFar);
  EXPECT_TRUE(std::equal(a.lsDepth.begin(), a.lsDepth.end(), b.lsDepth.begin(), b.lsDepth.end()));
  EXPECT_TRUE(std::equal(a.objectId.begin(), a.objectId.end(), b.objectId.begin(), b.objectId.end()));
}

// Rendering into a map that held another (larger, perspective) gives a fresh render's map, field for
// field and texel for texel, and then the other way round.
TEST(LightMap, RenderingIntoAUsedMapEqualsAFreshRender) {
  const Scene scene = rastertest::objectsScene();
  const Light sphere = Light::sphere(Vec3(1.0f, 6.0f, 2.0f), 0.3f);
  const Light sun = Light::directional(Vec3(0.4f, 1.0f, -0.3f), radians(0.53f));
  LightMap reused = renderLightMap(scene, sphere, 256);
  renderLightMap(scene, sun, 128, reused);
  expectSameMap(reused, renderLightMap(scene, sun, 128));
  renderLightMap(scene, sphere, 200, reused);
  expectSameMap(reused, renderLightMap(scene, sphere, 200));
  // Maps that see nothing clear what was there: an empty scene, a scene wholly behind the light.
  renderLightMap(Scene{}, sphere, 200, reused);
  expectSameMap(reused, renderLightMap(Scene{}, sphere, 200));
  renderLightMap(scene, sphere, 200, reused);
  const Light below = Light::disk(Vec3(0.0f, -50.0f, 0.0f), Vec3(0.0f, -1.0f, 0.0f), 0.5f);
  renderLightMap(scene, below, 200, reused);
  expectSameMap(reused, renderLightMap(scene, below, 200));
}

// LightMapLayers::NearestDepth: the depths of the map with ids, to the bit, and no ids; a map rendered
// with ids into it afterwards equals a fresh one.
TEST(LightMap, DepthOnlyMapHasTheSameDepthsAndNoIds) {
  const Scene scene = rastertest::objectsScene();
  for (const Light& light :
       {Light::sphere(Vec3(1.0f, 6.0f, 2.0f), 0.3f), Light::directional(Vec3(0.4f, 1.0f, -0.3f), radians(0.53f))}) {
    const LightMap withIds = renderLightMap(scene, light, 200);
    LightMap depthOnly;
    renderLightMap(scene, light, 200, depthOnly, LightMapFit::Tight, LightMapLayers::NearestDepth);
    EXPECT_EQ(depthOnly.objectId.size(), 0u);
    ASSERT_EQ(depthOnly.lsDepth.size(), withIds.lsDepth.size());
    size_t differing = 0, covered = 0;
    for (size_t i = 0; i < withIds.lsDepth.size(); ++i) {
      differing += std::memcmp(&depthOnly.lsDepth[i], &withIds.lsDepth[i], sizeof(float)) != 0;
      covered += std::isfinite(withIds.lsDepth[i]);
    }
    EXPECT_EQ(differing, 0u);
    EXPECT_GT(covered, 2000u) << "the map must hold surfaces for the comparison to mean something";
    renderLightMap(scene, light, 200, depthOnly);
    expectSameMap(depthOnly, withIds);
  }
}

// LightMapLayers::NearestDepthAndFarthest: both depth layers of NearestAndFarthest, to the bit, and no
// ids.
TEST(LightMap, DepthLayersWithoutIdsAreTheDepthsOfTheMapWithIds) {
  const Scene scene = rastertest::objectsScene();
  for (const Light& light :
       {Light::sphere(Vec3(1.0f, 6.0f, 2.0f), 0.3f), Light::directional(Vec3(0.4f, 1.0f, -0.3f), radians(0.53f))}) {
    LightMap withIds, depthsOnly;
    renderLightMap(scene, light, 200, withIds, LightMapFit::Tight, LightMapLayers::NearestAndFarthest);
    renderLightMap(scene, light, 200, depthsOnly, LightMapFit::Tight, LightMapLayers::NearestDepthAndFarthest);
    EXPECT_EQ(depthsOnly.objectId.size(), 0u);
    ASSERT_EQ(depthsOnly.lsDepth.size(), withIds.lsDepth.size());
    ASSERT_EQ(depthsOnly.lsFarDepth.size(), withIds.lsFarDepth.size());
    size_t differing = 0, between = 0;
    for (size_t i = 0; i < withIds.lsDepth.size(); ++i) {
      differing += std::memcmp(&depthsOnly.lsDepth[i], &withIds.lsDepth[i], sizeof(float)) != 0;
      differing += std::memcmp(&depthsOnly.lsFarDepth[i], &withIds.lsFarDepth[i], sizeof(float)) != 0;
      between += std::isfinite(withIds.lsDepth[i]) && withIds.lsFarDepth[i] > withIds.lsDepth[i];
    }
    EXPECT_EQ(differing, 0u);
    EXPECT_GT(between, 200u) << "the layers must differ at many texels for the comparison to mean something";
  }
}

// fitLightMap then rasterizeLightMap with a far layer in some tiles only: the near layer, the ids and
// the far layer in those tiles are renderLightMap's to the bit, the other tiles' far texels are not
// touched (a NaN put in their storage stays), farTiles records the tiles, and a mask of the wrong
// size is refused. A scene with nothing in it has an empty far layer in every tile asked for.
TEST(LightMap, FarLayerInSomeTilesIsTheWholeMapsThereAndLeavesTheRestAlone) {
  const Scene scene = rastertest::objectsScene();
  constexpr int kSize = 200;  // 4 x 4 tiles of 64, the last ones partial
  const int tiles = (kSize + kFarLayerTile - 1) / kFarLayerTile;
  std::vector<uint8_t> mask(static_cast<size_t>(tiles) * tiles);
  for (size_t k = 0; k < mask.size(); ++k) mask[k] = (k * 7 + k / tiles) % 3 == 0 ? 1 : 0;  // a scattered third
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Light& light :
       {Light::sphere(Vec3(1.0f, 6.0f, 2.0f), 0.3f), Light::directional(Vec3(0.4f, 1.0f, -0.3f), radians(0.53f))}) {
    LightMap whole, part;
    renderLightMap(scene, light, kSize, whole, LightMapFit::Tight, LightMapLayers::NearestAndFarthest);
    part.lsFarDepth = Image<float>(kSize, kSize, nan);
    fitLightMap(scene, light, kSize, part);
    rasterizeLightMap(scene, part, LightMapLayers::NearestAndFarthest, mask);
    expectSameMap(part, whole);
    EXPECT_EQ(part.farTiles, mask);
    EXPECT_TRUE(whole.farTiles.empty());
    int kept = 0, left = 0, surfaces = 0;
    for (int j = 0; j < kSize; ++j)
      for (int i = 0; i < kSize; ++i) {
        const bool inTile = mask[static_cast<size_t>(j / kFarLayerTile) * tiles + i / kFarLayerTile] != 0;
        if (inTile) {
          kept += std::memcmp(&part.lsFarDepth(i, j), &whole.lsFarDepth(i, j), sizeof(float)) == 0;
          surfaces += std::isfinite(whole.lsFarDepth(i, j));
        } else {
          left += std::isnan(part.lsFarDepth(i, j));
        }
      }
    EXPECT_GT(surfaces, 1000) << "the tiles asked for must hold surfaces for the comparison to mean something";
    EXPECT_EQ(kept + left, kSize * kSize) << "kept " << kept << ", left " << left;
    EXPECT_GT(left, 0);
    EXPECT_THROW(
        rasterizeLightMap(scene, part, LightMapLayers::NearestAndFarthest, std::vector<uint8_t>(mask.size() - 1, 1)),
        Error);
  }
  LightMap empty;
  empty.lsFarDepth = Image<float>(kSize, kSize, nan);
  fitLightMap(Scene{}, Light::sphere(Vec3(0.0f, 5.0f, 0.0f), 0.5f), kSize, empty);
  rasterizeLightMap(Scene{}, empty, LightMapLayers::NearestDepthAndFarthest, mask);
  for (int j = 0; j < kSize; ++j)
    for (int i = 0; i < kSize; ++i)
      if (mask[static_cast<size_t>(j / kFarLayerTile) * tiles + i / kFarLayerTile]) {
        ASSERT_EQ(empty.lsFarDepth(i, j), kInfinity) << i << "," << j;
      }
}

// The far layer (LightMapLayers::NearestAndFarthest) against the last hit along each texel's ray,
// found by tracing on past every hit; the nearest layer is the same as without it, bit for bit.
TEST(LightMap, FarLayerMatchesTheLastHitAlongEachTexelsRay) {
  const Scene scene = rastertest::objectsScene();
  const RayScene rays(scene);
  for (const Light& light :
       {Light::sphere(Vec3(1.0f, 6.0f, 2.0f), 0.3f), Light::directional(Vec3(0.4f, 1.0f, -0.3f), radians(0.53f))}) {
    LightMap m;
    renderLightMap(scene, light, 128, m, LightMapFit::Tight, LightMapLayers::NearestAndFarthest);
    expectSameMap(m, renderLightMap(scene, light, 128));
    ASSERT_EQ(m.lsFarDepth.size(), m.lsDepth.size());
    int hits = 0, outliers = 0, behindNearest = 0;
    for (int t = 0; t < m.size; ++t)
      for (int s = 0; s < m.size; ++s) {
        Ray ray = texelRay(m, s, t);
        std::optional<RayHit> last;
        for (int step = 0; step < 32; ++step) {
          const std::optional<RayHit> hit = rays.intersect(ray);
          if (!hit) break;
          last = hit;
          ray.tMin = hit->t * (1.0f + 1e-5f);
        }
        const float far = m.lsFarDepth(s, t);
        if (m.lsDepth(s, t) == kInfinity) {
          EXPECT_EQ(far, kInfinity) << s << "," << t;
          continue;
        }
        behindNearest += !(far >= m.lsDepth(s, t));
        if (!last) {
          ++outliers;
          continue;
        }
        ++hits;
        // As the nearest layer: a texel by a silhouette may see the neighbouring triangle.
        const float cosine = std::abs(glm::dot(last->wsGeometricNormal, glm::normalize(ray.direction)));
        outliers +=
            std::abs(far - last->t) > 1e-5f * last->t + 0.01f * m.texelWorldSize(last->t) / std::max(cosine, 1e-3f);
      }
    EXPECT_GT(hits, m.size * m.size / 8);
    EXPECT_EQ(behindNearest, 0);
    // Measured: none of the 2599 (sphere light) and 7656 (directional) hits; a texel whose ray grazes a
    // silhouette may see the neighbouring triangle, as in the nearest layer.
    EXPECT_LE(outliers, 2) << "hits " << hits;
  }
}

TEST(LightMap, RectLightUsesItsNormalAsTheAxis) {
  const Scene scene = rastertest::objectsScene();
  // Facing up, away from the scene: light space turns its axis to face the scene.
  const Light light = Light::rect(Vec3(-1.0f, 5.0f, 0.5f), Vec3(0.5f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, -0.4f));
  const LightMap m = renderLightMap(scene, light, 200);
  EXPECT_NEAR(m.lsFrame.z.y, -1.0f, 1e-6f);
  expectCornersInside(scene, m);
  expectMatchesRays(scene, m, 7500);  // measured: 8000 hits (the ground plane, 100 x 80 texels)
}

TEST(LightMap, DirectionalLightIsOrthographicFromBehindTheScene) {
  const Scene scene = rastertest::objectsScene();
  const Light light = Light::directional(Vec3(0.4f, 1.0f, -0.3f), radians(0.53f));
  const LightMap m = renderLightMap(scene, light, 256);
  EXPECT_TRUE(m.orthographic);
  EXPECT_NEAR(glm::dot(m.lsFrame.z, -light.direction()), 1.0f, 1e-6f);
  EXPECT_GT(m.zNear, 0.0f);
  expectCornersInside(scene, m);
  // The texel size is the same everywhere, and the map is no wider than the bounds need.
  EXPECT_FLOAT_EQ(m.texelWorldSize(1.0f), m.texelWorldSize(9.0f));
  EXPECT_LE(m.halfWidth, scene.bounds().radius() * 1.001f);
  expectMatchesRays(scene, m, 30000);
}

TEST(LightMap, LightInsideTheSceneClampsTheFieldOfView) {
  const Scene scene = rastertest::roomScene();
  const Light light = Light::sphere(Vec3(-1.0f, 2.0f, 1.0f), 0.2f);  // inside the room
  const LightMap m = renderLightMap(scene, light, 160);
  EXPECT_NEAR(m.tanHalfFov, std::tan(radians(75.0f)), 1e-5f);
  EXPECT_GT(m.zNear, 0.0f);
  // Whatever the clamped frustum holds agrees with rays; the room's walls fill every texel.
  for (int32_t id : m.objectId) ASSERT_NE(id, kNoObject);
  expectMatchesRays(scene, m, 25000);
}

// Where no world axis serves (the light inside the room, below the floor's level, or level with the
// scene) the aligned fit is the stable one, and every map it makes is finite and holds what it can.
TEST(LightMap, AlignedFitFallsBackToTheStableOneWhereNoWorldAxisServes) {
  const Scene room = rastertest::roomScene();
  const Light inside = Light::sphere(Vec3(-1.0f, 2.0f, 1.0f), 0.2f);
  const LightMap a = renderLightMap(room, inside, 160, LightMapFit::Aligned);
  const LightMap b = renderLightMap(room, inside, 160, LightMapFit::Stable);
  expectSameMap(a, b);
  const Scene objects = rastertest::objectsScene();
  for (const Vec3& p :
       {Vec3(0.3f, 0.5f, 9.0f), Vec3(0.2f, -6.0f, 0.4f), Vec3(8.0f, 1.0f, 0.0f), Vec3(0.0f, 30.0f, 0.0f)}) {
    SCOPED_TRACE(::testing::Message() << "light at " << p.x << " " << p.y << " " << p.z);
    const LightMap m = renderLightMap(objects, Light::sphere(p, 0.3f), 128, LightMapFit::Aligned);
    EXPECT_TRUE(std::isfinite(m.tanHalfFov) && std::isfinite(m.windowOffset.x) && std::isfinite(m.windowOffset.y));
    expectCornersInside(objects, m);
  }
}

TEST(LightMap, ProjectInvertsUnprojectAndTexelSizesAreConsistent) {
  const Scene scene = rastertest::objectsScene();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> st(0.0f, 512.0f), depth(0.5f, 12.0f);
  for (const Light& light :
       {Light::sphere(Vec3(1.0f, 6.0f, 2.0f), 0.3f), Light::directional(Vec3(0.4f, 1.0f, -0.3f), 0.01f)}) {
    const LightMap m = renderLightMap(scene, light, 512);
    for (int i = 0; i < 200; ++i) {
      const float s = st(rng), t = st(rng), z = depth(rng);
      const Vec3 p = m.project(m.unproject(s, t, z));
      EXPECT_NEAR(p.x, s, 2e-3f);
      EXPECT_NEAR(p.y, t, 2e-3f);
      EXPECT_NEAR(p.z, z, 1e-5f * z);
      // One texel step in s or t moves the world point by texelWorldSize(z).
      const Vec3 w = m.unproject(s, t, z);
      EXPECT_NEAR(glm::length(m.unproject(s + 1.0f, t, z) - w), m.texelWorldSize(z), 1e-4f * m.texelWorldSize(z));
      EXPECT_NEAR(glm::length(m.unproject(s, t + 1.0f, z) - w), m.texelWorldSize(z), 1e-4f * m.texelWorldSize(z));
    }
  }
}

// Light positions along a closed loop over the scene: a circle of radius `radius` at height y around
// (cx, cz), bobbing up and down by 0.5, `frames` frames.
std::vector<Vec3> loop(float cx, float cz, float radius, float y, int frames) {
  std::vector<Vec3> path;
  for (int k = 0; k < frames; ++k) {
    const float a = 2.0f * kPi * static_cast<float>(k) / static_cast<float>(frames);
    path.emplace_back(cx + radius * std::cos(a), y + 0.5f * std::sin(3.0f * a), cz + radius * std::sin(a));
  }
  return path;
}

TEST(LightMap, StableFitHoldsTheSceneAtEveryFrameOfALongPath) {
  const Scene scene = rastertest::objectsScene();
  const Light sphere = Light::sphere(Vec3(0.0f), 0.3f);
  const Light rect = Light::rect(Vec3(0.0f), Vec3(0.5f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, -0.4f));
  const Light sun = Light::directional(Vec3(0.4f, 1.0f, -0.3f), radians(0.53f));
  int frame = 0;
  for (const Vec3& p : loop(0.5f, 0.5f, 3.0f, 8.0f, 400)) {
    SCOPED_TRACE(::testing::Message() << "frame " << frame);
    // A light that passes over the scene, one whose axis is its own, and a sun that circles the sky
    // (map sizes vary so that the lattice steps do).
    const int size = 64 + 8 * (frame % 7);
    for (const Light& light : {lightMovedTo(sphere, p), lightMovedTo(rect, p), lightMovedTo(sun, p)})
      for (const LightMapFit fit : {LightMapFit::Stable, LightMapFit::Aligned}) {
        const LightMap m = renderLightMap(scene, light, size, fit);
        expectCornersInside(scene, m);
        // The origin is at most half a lattice diagonal from the centre sample: a texel at the scene.
        if (!light.isDirectional()) {
          EXPECT_LT(glm::distance(m.wsOrigin, light.center()), m.texelWorldSize(m.zFar));
        }
      }
    ++frame;
  }
}

TEST(LightMap, StableMapMatchesRaysFromItsOrigin) {
  const Scene scene = rastertest::objectsScene();
  const LightMap sphere = renderLightMap(scene, Light::sphere(Vec3(1.3f, 6.1f, 2.2f), 0.3f), 256, LightMapFit::Stable);
  expectCornersInside(scene, sphere);
  expectMatchesRays(scene, sphere, 8500);  // measured: 8995 hits (coarser texels than the tight map's)
  const LightMap sun =
      renderLightMap(scene, Light::directional(Vec3(0.4f, 1.0f, -0.3f), 0.01f), 256, LightMapFit::Stable);
  expectCornersInside(scene, sun);
  expectMatchesRays(scene, sun, 26000);  // measured: 28264
}

// An Aligned map of a light above the scene looks straight down, its window centred on the scene off
// its axis: the rasterized map agrees with rays through its texels (the window's offset is the same in
// the rasterizer's clip space and in project/unproject), and it holds the scene.
TEST(LightMap, AlignedMapLooksAlongAWorldAxisAndMatchesRaysFromItsOrigin) {
  const Scene scene = rastertest::objectsScene();
  const LightMap m = renderLightMap(scene, Light::sphere(Vec3(1.3f, 6.1f, 2.2f), 0.3f), 256, LightMapFit::Aligned);
  EXPECT_EQ(m.lsFrame.z, Vec3(0.0f, -1.0f, 0.0f));
  EXPECT_NE(m.windowOffset, Vec2(0.0f));  // the light is off the scene's centre
  expectCornersInside(scene, m);
  expectMatchesRays(scene, m, 8500);
  // unproject inverts project, window included.
  const Vec3 p(0.7f, 0.2f, -1.9f);
  const Vec3 stz = m.project(p);
  const Vec3 back = m.unproject(stz.x, stz.y, stz.z);
  EXPECT_LT(glm::distance(back, p), 1e-4f);
  // A light far to the side (more than 30 degrees from every world axis) keeps Stable's axis.
  const Light side = Light::sphere(Vec3(7.0f, 5.0f, 6.5f), 0.3f);
  EXPECT_EQ(renderLightMap(scene, side, 128, LightMapFit::Aligned).lsFrame.z,
            renderLightMap(scene, side, 128, LightMapFit::Stable).lsFrame.z);
}

// Why Aligned: at a lattice step the floor keeps its texels. A floor point's map position moves by whole
// texels (up to the reference depth's quantization, 2^(1/16) of the floor's depth: 0.044 of a texel)
// as the light moves across the scene, where a Stable map's tilted axis leaves the floor at depths on
// both sides of its reference and moves its points by fractions of a texel.
TEST(LightMap, AlignedMapMovesTheFloorByWholeTexels) {
  const Scene scene = rastertest::objectsScene();  // its floor: the plane y = 0
  const Vec3 floorPoints[] = {Vec3(-3.5f, 0.0f, -2.5f), Vec3(0.4f, 0.0f, 1.3f), Vec3(3.8f, 0.0f, 2.9f)};
  double worstAligned = 0.0, worstStable = 0.0;
  int stepsAligned = 0;
  for (const LightMapFit fit : {LightMapFit::Aligned, LightMapFit::Stable}) {
    std::optional<LightMap> before;
    for (int k = 0; k <= 60; ++k) {
      const Light light = Light::sphere(Vec3(0.5f + 0.01f * static_cast<float>(k), 8.0f, -1.0f), 0.8f);
      LightMap m = renderLightMap(scene, light, 512, fit);
      if (before && before->wsOrigin != m.wsOrigin && before->tanHalfFov == m.tanHalfFov &&
          before->lsFrame.z == m.lsFrame.z) {
        stepsAligned += fit == LightMapFit::Aligned;
        for (const Vec3& q : floorPoints) {
          const Vec3 a = before->project(q), b = m.project(q);
          for (const float d : {b.x - a.x, b.y - a.y}) {
            const double off = std::abs(d - std::round(d));
            (fit == LightMapFit::Aligned ? worstAligned : worstStable) =
                std::max(fit == LightMapFit::Aligned ? worstAligned : worstStable, off);
          }
        }
      }
      before = std::move(m);
    }
  }
  std::printf("[ measured ] floor's shift off whole texels at a lattice step: aligned %.4f, stable %.4f (%d steps)\n",
              worstAligned, worstStable, stepsAligned);
  EXPECT_GT(stepsAligned, 5);
  EXPECT_LT(worstAligned, 0.05);
  EXPECT_GT(worstStable, 0.05);
}

TEST(LightMap, StableExtentAndAxisStayWithinTheirQuantizationOfTheTightFit) {
  const Scene scene = rastertest::objectsScene();
  for (const Vec3& p : loop(0.5f, 0.5f, 3.0f, 6.0f, 40)) {
    const Light light = Light::sphere(p, 0.3f);
    const LightMap tight = renderLightMap(scene, light, 512);
    const LightMap stable = renderLightMap(scene, light, 512, LightMapFit::Stable);
    // Axis within half a cell's diagonal of the tight axis (cells 2/31 wide in the octahedral square:
    // a few degrees across).
    const float tilt = std::acos(std::min(1.0f, glm::dot(tight.lsFrame.z, stable.lsFrame.z)));
    EXPECT_LT(tilt, radians(8.0f));
    // Half-angle: the tight one, turned by the tilt, widened by one step of 2^(1/16), the snap's
    // texel a side and at most one more step for the snapped origin (under 3 degrees at these
    // angles). A turned axis may also centre the scene better: the tight axis aims at the bounds'
    // centre, not at the best-fitting direction.
    EXPECT_LT(std::atan(stable.tanHalfFov), std::atan(tight.tanHalfFov) + tilt + radians(3.0f));
  }
}

TEST(LightMap, StableMapDoesNotChangeWhileTheLightMovesWithinALatticeCell) {
  const Scene scene = rastertest::objectsScene();
  for (const Light& light : {Light::sphere(Vec3(1.3f, 6.1f, 2.2f), 0.3f),
                             Light::rect(Vec3(-1.1f, 5.2f, 0.6f), Vec3(0.5f, 0.0f, 0.0f), Vec3(0.0f, 0.0f, -0.4f))}) {
    for (const LightMapFit fit : {LightMapFit::Stable, LightMapFit::Aligned}) {
      const LightMap m = renderLightMap(scene, light, 300, fit);
      ASSERT_NE(m.wsOrigin, light.center());  // the snap moved it (else the test shows nothing)
      // A hundredth of the way towards the lattice point the light still rounds to it (and stays
      // within its cell of axes and extents, which a larger move might cross).
      const Vec3 moved = light.center() + 0.01f * (m.wsOrigin - light.center());
      expectSameMap(renderLightMap(scene, lightMovedTo(light, moved), 300, fit), m);
    }
    const LightMap m = renderLightMap(scene, light, 300, LightMapFit::Stable);
    const Vec3 moved = light.center() + 0.01f * (m.wsOrigin - light.center());
    // The tight fit refits to the moved light: its origin follows it.
    EXPECT_EQ(renderLightMap(scene, lightMovedTo(light, moved), 300).wsOrigin, moved);
  }
  // A directional map's origin snaps across its axis only: onto the lattice of whole texels, within
  // half a texel of the axis through the bounds' centre.
  const Light sun = Light::directional(Vec3(0.4f, 1.0f, -0.3f), 0.01f);
  const LightMap m = renderLightMap(scene, sun, 256, LightMapFit::Stable);
  const float texel = m.texelWorldSize(1.0f);
  const Vec3 c = scene.bounds().center();
  for (const Vec3& axis : {m.lsFrame.x, m.lsFrame.y}) {
    const double onLattice = glm::dot(m.wsOrigin, axis) / texel;
    EXPECT_NEAR(onLattice, std::round(onLattice), 1e-3);
    EXPECT_LE(std::abs(glm::dot(m.wsOrigin - c, axis)), 0.5f * texel * 1.001f);
  }
}

TEST(LightMap, EmptySceneAndBadSizes) {
  const Scene empty;
  const LightMap m = renderLightMap(empty, Light::sphere(Vec3(0.0f, 3.0f, 0.0f), 0.5f), 32);
  EXPECT_EQ(m.size, 32);
  for (float z : m.lsDepth) ASSERT_EQ(z, kInfinity);
  for (int32_t id : m.objectId) ASSERT_EQ(id, kNoObject);
  const Scene scene = rastertest::objectsScene();
  EXPECT_THROW(renderLightMap(scene, Light::sphere(Vec3(0.0f, 5.0f, 0.0f), 0.5f), 0), Error);
  EXPECT_THROW(renderLightMap(scene, Light::sphere(Vec3(0.0f, 5.0f, 0.0f), 0.5f), 100000), Error);
}

}  // namespace
}  // namespace penumbra
