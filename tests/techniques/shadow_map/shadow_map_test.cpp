// Tests of the shared shadow-map stages (src/techniques/shadow_map/shadow_map.cpp) on small hand-made light
// maps whose content is known in closed form: the exact PCF box against the covered fraction of a
// half-plane of blockers, the receiver plane against the analytic depth of a tilted plane
// (orthographic: exact; perspective: first order, checked against ray-plane intersections), the
// blocker search's mean depth, the nearest-blocker ring search against a brute-force scan, the
// disk patterns, and the rejection of bad map sizes and kernels.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <utility>

#include "penumbra/error.h"
#include "penumbra/raster.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"
#include "techniques/shadow_map/shadow_map.h"

namespace penumbra {
namespace {

// An orthographic 16x16 map looking down +z from the origin: texel size 1, s = 8 + x, t = 8 - y.
LightMap orthoMap(int size = 16, float fill = kInfinity) {
  LightMap m;
  m.size = size;
  m.orthographic = true;
  m.halfWidth = 0.5f * static_cast<float>(size);
  m.zNear = 0.0f;
  m.zFar = 100.0f;
  m.lsDepth = Image<float>(size, size, fill);
  m.objectId = Image<int32_t>(size, size, kNoObject);
  return m;
}

const Vec3 kFacingLight(0.0f, 0.0f, -1.0f);  // a receiver facing a light that looks down +z

TEST(ShadowMap, OrthoMapProjectsAsDocumented) {
  const LightMap m = orthoMap();
  const Vec3 stz = m.project(Vec3(1.25f, -2.5f, 7.0f));
  EXPECT_NEAR(stz.x, 9.25f, 1e-5f);
  EXPECT_NEAR(stz.y, 10.5f, 1e-5f);
  EXPECT_NEAR(stz.z, 7.0f, 1e-5f);
  EXPECT_NEAR(m.texelWorldSize(7.0f), 1.0f, 1e-6f);
}

TEST(ShadowMap, PcfBoxIsTheCoveredFractionOfAHalfPlane) {
  LightMap m = orthoMap();
  for (int j = 0; j < m.size; ++j)
    for (int i = 0; i < 8; ++i) m.lsDepth(i, j) = 1.0f;  // blockers where s < 8
  for (float width : {1.0f, 3.0f, 5.0f}) {
    for (float x = -4.0f; x <= 4.0f; x += 0.137f) {
      const ShadowReceiver r = makeReceiver(m, Vec3(x, 0.3f, 5.0f), kFacingLight, DepthBias{});
      ASSERT_TRUE(r.inMap);
      const float s = 8.0f + x;
      const float exact = std::clamp((s + 0.5f * width - 8.0f) / width, 0.0f, 1.0f);
      EXPECT_NEAR(pcfBox(m, r, r.s, r.t, width), exact, 1e-5f) << "width " << width << " s " << s;
    }
  }
  // The hard compare is the step at s = 8.
  EXPECT_EQ(hardShadow(m, makeReceiver(m, Vec3(-0.01f, 0.0f, 5.0f), kFacingLight, DepthBias{})), 0.0f);
  EXPECT_EQ(hardShadow(m, makeReceiver(m, Vec3(0.01f, 0.0f, 5.0f), kFacingLight, DepthBias{})), 1.0f);
  // A blocker behind the receiver does not shadow it.
  EXPECT_EQ(hardShadow(m, makeReceiver(m, Vec3(-3.0f, 0.0f, 0.5f), kFacingLight, DepthBias{})), 1.0f);
}

TEST(ShadowMap, ReceiverPlaneMatchesATiltedPlaneExactlyInAnOrthoMap) {
  LightMap m = orthoMap(64);
  // A plane at 60 degrees to the light's axis through (0, 0, 20), rendered into the map analytically.
  const Vec3 n =
      glm::normalize(Vec3(std::sin(radians(60.0f)) * 0.8f, std::sin(radians(60.0f)) * 0.6f, -std::cos(radians(60.0f))));
  const Vec3 p0(0.0f, 0.0f, 20.0f);
  auto planeDepth = [&](float x, float y) { return (glm::dot(n, p0) - n.x * x - n.y * y) / n.z; };
  for (int j = 0; j < m.size; ++j)
    for (int i = 0; i < m.size; ++i) {
      const Vec3 w = m.unproject(static_cast<float>(i) + 0.5f, static_cast<float>(j) + 0.5f, 1.0f);
      m.lsDepth(i, j) = planeDepth(w.x, w.y);
    }
  const Vec3 p(1.3f, -0.7f, planeDepth(1.3f, -0.7f));
  const ShadowReceiver exact = makeReceiver(m, p, n, DepthBias{0.0f, 0.0f});
  ASSERT_TRUE(exact.inMap);
  EXPECT_NEAR(exact.dzds, -n.x / n.z, 1e-5f);  // texel size 1; x grows with s
  EXPECT_NEAR(exact.dzdt, n.y / n.z, 1e-5f);   // y falls with t
  const int ci = static_cast<int>(exact.s), cj = static_cast<int>(exact.t);
  for (int dj = -7; dj <= 7; ++dj)
    for (int di = -7; di <= 7; ++di)
      EXPECT_NEAR(blockerThreshold(exact, ci + di, cj + dj), m.lsDepth(ci + di, cj + dj), 2e-5f * 20.0f);
  // With the default bias a 15-texel kernel on the steep plane sees no blocker at all...
  const ShadowReceiver biased = makeReceiver(m, p, n, DepthBias{});
  EXPECT_EQ(pcfBox(m, biased, biased.s, biased.t, 15.0f), 1.0f);
  // ... while comparing against the receiver's own depth (a flat receiver) shadows about half of it.
  const ShadowReceiver flat = makeReceiver(m, p, kFacingLight, DepthBias{});
  EXPECT_NEAR(pcfBox(m, flat, flat.s, flat.t, 15.0f), 0.5f, 0.1f);
}

// A receiver seen edge-on from the light whose normal lies along a map axis (a wall parallel to the
// light's direction): its depth does not change along the other axis (slope 0, where 0 / 0 gave NaN
// and made every compare with its plane false), and along its normal the slope is the limit.
TEST(ShadowMap, AnEdgeOnReceiverHasFiniteSlopes) {
  const LightMap m = orthoMap(64, 30.0f);  // a blocker at depth 30 everywhere, beyond the receiver
  const DepthBias bias{};
  for (const Vec3& normal : {Vec3(1, 0, 0), Vec3(0, -1, 0)}) {
    const Vec3 p(0.3f, -0.2f, 10.0f);
    const ShadowReceiver r = makeReceiver(m, p, normal, bias);
    ASSERT_TRUE(r.inMap);
    EXPECT_TRUE(std::isfinite(r.dzds) && std::isfinite(r.dzdt) && std::isfinite(r.bias));
    EXPECT_EQ(normal.x != 0.0f ? r.dzdt : r.dzds, 0.0f);
    EXPECT_EQ(std::abs(normal.x != 0.0f ? r.dzds : r.dzdt), kMaxDepthSlope);
    ReceiverRow row;
    makeReceiverRow(m, &p, &normal, 1, bias, row);
    EXPECT_EQ(row[0].dzds, r.dzds);
    EXPECT_EQ(row[0].dzdt, r.dzdt);
    // The blocker lies behind the receiver at its own texel: lit.
    EXPECT_EQ(hardShadow(m, r), 1.0f);
  }
}

TEST(ShadowMap, ReceiverPlaneIsFirstOrderExactInAPerspectiveMap) {
  LightMap m;
  m.size = 64;
  m.orthographic = false;
  m.tanHalfFov = 1.0f;
  m.zNear = 0.1f;
  m.zFar = 100.0f;
  m.lsDepth = Image<float>(m.size, m.size, kInfinity);
  const Vec3 n = glm::normalize(Vec3(0.5f, -0.4f, -0.7f));
  const Vec3 p(1.0f, 0.5f, 10.0f);
  // Exact depth of the plane through p along the ray through map position (s, t).
  auto exactDepth = [&](float s, float t) {
    const Vec3 d = m.unproject(s, t, 1.0f);  // the point of depth 1 on the ray: (a, b, 1)
    return glm::dot(n, p) / glm::dot(n, d);
  };
  const ShadowReceiver r = makeReceiver(m, p, n, DepthBias{0.0f, 0.0f});
  ASSERT_TRUE(r.inMap);
  EXPECT_NEAR(r.lsDepth, 10.0f, 1e-4f);
  const float h = 0.01f;
  EXPECT_NEAR(r.dzds, (exactDepth(r.s + h, r.t) - exactDepth(r.s - h, r.t)) / (2 * h), 2e-3f);
  EXPECT_NEAR(r.dzdt, (exactDepth(r.s, r.t + h) - exactDepth(r.s, r.t - h)) / (2 * h), 2e-3f);
  // At a texel centre the exact depth is z0 / (1 + e) with e = n.d(texel) / n.d(receiver) - 1; the
  // linear extrapolation must be its first-order part z0 (1 - e), exactly.
  const int ci = static_cast<int>(r.s), cj = static_cast<int>(r.t);
  const float nDotD0 = glm::dot(n, m.unproject(r.s, r.t, 1.0f));
  for (int dj = -3; dj <= 3; ++dj)
    for (int di = -3; di <= 3; ++di) {
      const Vec3 d = m.unproject(static_cast<float>(ci + di) + 0.5f, static_cast<float>(cj + dj) + 0.5f, 1.0f);
      const float e = glm::dot(n, d) / nDotD0 - 1.0f;
      EXPECT_NEAR(blockerThreshold(r, ci + di, cj + dj), r.lsDepth * (1.0f - e), 1e-4f * r.lsDepth);
    }
}

TEST(ShadowMap, ReceiversOutsideTheMapAreLit) {
  const LightMap m = orthoMap(16, 1.0f);  // blockers everywhere
  const ShadowReceiver outside = makeReceiver(m, Vec3(20.0f, 0.0f, 5.0f), kFacingLight, DepthBias{});
  EXPECT_FALSE(outside.inMap);
  EXPECT_EQ(hardShadow(m, outside), 1.0f);
  const ShadowReceiver inside = makeReceiver(m, Vec3(2.0f, 0.0f, 5.0f), kFacingLight, DepthBias{});
  EXPECT_TRUE(inside.inMap);
  EXPECT_EQ(hardShadow(m, inside), 0.0f);
  LightMap persp = m;
  persp.orthographic = false;
  EXPECT_FALSE(makeReceiver(persp, Vec3(0.0f, 0.0f, -5.0f), kFacingLight, DepthBias{}).inMap);  // behind the light
}

// makeReceiverRow is makeReceiver, vectorized: field for field, to the bit, on real G-buffers under a
// perspective map (a sphere light) and an orthographic one (a directional light), receivers outside the
// map and behind the light included; and its nearest-texel threshold is hardShadow's compare.
TEST(ShadowMap, ReceiverRowIsMakeReceiverToTheBit) {
  const auto bits = [](float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
  };
  for (const char* name : {"crowded", "triangle", "teapots"}) {
    const Scene scene = loadScene(name);
    // A small map, so that many receivers fall outside it, and the image wider than the scene's view.
    for (const Light& light : scene.lights) {
      for (const int mapSize : {64, 1024}) {
        // The fitted map; one a quarter as wide (receivers outside it); one looking from the scene's
        // centre (a perspective map's receivers behind it).
        const LightMap fitted = renderLightMap(scene, light, mapSize);
        LightMap narrow = fitted;
        narrow.halfWidth *= 0.25f;
        narrow.tanHalfFov *= 0.25f;
        LightMap inside = fitted;
        inside.wsOrigin = scene.bounds().center();
        const GBuffer gbuffer = renderGBuffer(scene, 96, 64);
        for (const LightMap* mapVariant :
             {&fitted, static_cast<const LightMap*>(&narrow), static_cast<const LightMap*>(&inside)}) {
          const LightMap& map = *mapVariant;
          const DepthBias bias{0.7f, 1.3f};
          ReceiverRow row;
          int outside = 0, checked = 0;
          for (int y = 0; y < gbuffer.height(); ++y) {
            makeReceiverRow(map, gbuffer.wsPosition.row(y), gbuffer.wsGeometricNormal.row(y), gbuffer.width(), bias,
                            row);
            for (int x = 0; x < gbuffer.width(); ++x) {
              const ShadowReceiver want =
                  makeReceiver(map, gbuffer.wsPosition(x, y), gbuffer.wsGeometricNormal(x, y), bias);
              const ShadowReceiver got = row[x];
              const std::string where = std::string(name) + " light " + std::string(toString(light.shape())) + " map " +
                                        std::to_string(mapSize) + " pixel " + std::to_string(x) + "," +
                                        std::to_string(y);
              ASSERT_EQ(got.inMap, want.inMap) << where;
              for (const auto& [a, b] : {std::pair{got.s, want.s},
                                         {got.t, want.t},
                                         {got.lsDepth, want.lsDepth},
                                         {got.dzds, want.dzds},
                                         {got.dzdt, want.dzdt},
                                         {got.bias, want.bias},
                                         {got.texelWorld, want.texelWorld}})
                ASSERT_EQ(bits(a), bits(b)) << where << ": " << a << " vs " << b;
              if (want.inMap) {
                const int i = static_cast<int>(std::floor(want.s)), j = static_cast<int>(std::floor(want.t));
                ASSERT_EQ(row.nearestTexel[static_cast<size_t>(x)], j * map.size + i) << where;
                ASSERT_EQ(bits(row.nearestThreshold[static_cast<size_t>(x)]), bits(blockerThreshold(want, i, j)))
                    << where;
              } else {
                ++outside;
              }
              ++checked;
            }
          }
          EXPECT_GT(checked, 0);
          if (mapVariant == &narrow) {
            EXPECT_GT(outside, 0) << name;
          }
        }
      }
    }
  }
}

// pcfBox against its definition, texel by texel with litAtTexel (the path it takes at the map's border),
// on a real map at random receivers, widths and positions: the same V to the bit.
TEST(ShadowMap, PcfBoxIsItsTexelByTexelSumToTheBit) {
  const Scene scene = loadScene("crowded");
  const LightMap map = renderLightMap(scene, scene.lights[0], 256);
  const GBuffer gbuffer = renderGBuffer(scene, 64, 64);
  uint64_t state = 12345;
  const auto uniform = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<float>(state >> 40) / static_cast<float>(1 << 24);
  };
  int checked = 0;
  for (int y = 0; y < gbuffer.height(); ++y)
    for (int x = 0; x < gbuffer.width(); ++x) {
      if (!gbuffer.hit(x, y)) continue;
      const ShadowReceiver r = makeReceiver(map, gbuffer.wsPosition(x, y), gbuffer.wsGeometricNormal(x, y), {});
      if (!r.inMap) continue;
      const float width = 1.0f + 20.0f * uniform();
      const float s = r.s + 8.0f * (uniform() - 0.5f), t = r.t + 8.0f * (uniform() - 0.5f);
      const float half = 0.5f * width;
      float sum = 0.0f;
      for (int j = static_cast<int>(std::floor(t - half)); j <= static_cast<int>(std::floor(t + half)); ++j) {
        const float fj = static_cast<float>(j);
        const float wt = std::min(t + half, fj + 1.0f) - std::max(t - half, fj);
        float row = 0.0f;
        for (int i = static_cast<int>(std::floor(s - half)); i <= static_cast<int>(std::floor(s + half)); ++i) {
          const float fi = static_cast<float>(i);
          row += (std::min(s + half, fi + 1.0f) - std::max(s - half, fi)) * litAtTexel(map, r, i, j);
        }
        sum += wt * row;
      }
      const float want = std::clamp(sum / (width * width), 0.0f, 1.0f);
      ASSERT_EQ(pcfBox(map, r, s, t, width), want) << "pixel " << x << "," << y << " width " << width;
      ++checked;
    }
  EXPECT_GT(checked, 1000);
}

TEST(ShadowMap, BlockerSearchAveragesTheBlockersItFinds) {
  LightMap m = orthoMap(64, 3.0f);
  const std::vector<Vec2> disk = vogelDisk(64);
  const ShadowReceiver r = makeReceiver(m, Vec3(0.2f, 0.1f, 10.0f), kFacingLight, DepthBias{});
  BlockerSearch all = searchBlockers(m, r, 6.0f, disk, Vec2(1, 0));
  EXPECT_EQ(all.blockers, 64);
  EXPECT_FLOAT_EQ(all.meanDepth, 3.0f);
  // Blockers at depth 2 left of the receiver only: about half the disk finds them, all at depth 2.
  for (int j = 0; j < m.size; ++j)
    for (int i = 0; i < m.size; ++i) m.lsDepth(i, j) = i < 32 ? 2.0f : kInfinity;
  const ShadowReceiver atEdge = makeReceiver(m, Vec3(0.0f, 0.0f, 10.0f), kFacingLight, DepthBias{});
  BlockerSearch half = searchBlockers(m, atEdge, 6.0f, disk, pixelRotation(3, 4));
  EXPECT_NEAR(half.blockers, 32, 5);
  EXPECT_FLOAT_EQ(half.meanDepth, 2.0f);
  // Nothing in front of a receiver nearer than every blocker.
  const ShadowReceiver near = makeReceiver(m, Vec3(0.0f, 0.0f, 1.0f), kFacingLight, DepthBias{});
  EXPECT_EQ(searchBlockers(m, near, 6.0f, disk, Vec2(1, 0)).blockers, 0);
}

// The vectorized disk kernels (every CPU path: the AVX-512 kernels take tap counts that are
// multiples of 16, the other clones the rest) against a scalar oracle built from litAtTexel: the same
// taps, the same compare and the same order of sums, so every result must be equal — V does not
// depend on the CPU. Half the receivers are placed so that one tap lands exactly on a texel border,
// where one rounding more or less (a fused multiply-add in one path) moves it to the next texel.
// The row kernels (pcss' searches and filters a row at a time) are searchBlockers, pcfDisk and
// pcfDiskNearest at each listed pixel, to the bit: on real G-buffers and maps, with radii from under a
// texel to wider than the map, disks straddling the map's border, every pixel or every third listed, and
// patterns the 16-tap row paths take and others.
TEST(ShadowMap, DiskKernelRowsAreThePerPixelKernelsToTheBit) {
  const auto bits = [](float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
  };
  uint32_t state = 777u;
  const auto uniform = [&] {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
  };
  int searched = 0, partial = 0;
  for (const char* name : {"crowded", "teapots"}) {
    const Scene scene = loadScene(name);
    const LightMap map = renderLightMap(scene, scene.lights.front(), 256);
    const GBuffer gbuffer = renderGBuffer(scene, 120, 80);
    for (const int taps : {16, 7, 32}) {
      const std::vector<Vec2> pattern = vogelDisk(taps);
      ReceiverRow row;
      std::vector<float> radius(static_cast<size_t>(gbuffer.width()));
      std::vector<Vec2> rotation(radius.size());
      std::vector<BlockerSearch> got(radius.size());
      std::vector<float> box(radius.size()), nearest(radius.size());
      std::vector<int32_t> pixels;
      for (int y = 0; y < gbuffer.height(); ++y) {
        makeReceiverRow(map, gbuffer.wsPosition.row(y), gbuffer.wsGeometricNormal.row(y), gbuffer.width(), DepthBias{},
                        row);
        pixels.clear();
        for (int x = 0; x < gbuffer.width(); ++x) {
          if (!row.inMap[static_cast<size_t>(x)] || (y % 2 == 1 && x % 3 != 0)) continue;
          radius[static_cast<size_t>(x)] = uniform() < 0.05f ? 300.0f : 0.2f + 40.0f * uniform();
          rotation[static_cast<size_t>(x)] = pixelRotation(x, y);
          pixels.push_back(x);
        }
        searchBlockersRow(depthTexels(map), row, pixels, radius.data(), rotation.data(), pattern, got.data());
        pcfDiskRow(depthTexels(map), row, pixels, radius.data(), rotation.data(), pattern, box.data());
        pcfDiskNearestRow(depthTexels(map), row, pixels, radius.data(), rotation.data(), pattern, nearest.data());
        for (const int32_t x : pixels) {
          const auto i = static_cast<size_t>(x);
          const BlockerSearch want = searchBlockers(map, row[x], radius[i], pattern, rotation[i]);
          ASSERT_EQ(got[i].blockers, want.blockers) << name << " " << taps << " taps, pixel " << x << "," << y;
          ASSERT_EQ(bits(got[i].meanDepth), bits(want.meanDepth)) << name << " " << taps << " taps, pixel " << x;
          ASSERT_EQ(bits(box[i]), bits(pcfDisk(map, row[x], radius[i], pattern, rotation[i])))
              << name << " " << taps << " taps, pixel " << x << "," << y;
          ASSERT_EQ(bits(nearest[i]), bits(pcfDiskNearest(map, row[x], radius[i], pattern, rotation[i])))
              << name << " " << taps << " taps, pixel " << x << "," << y;
          ++searched;
          partial += want.blockers > 0 && want.blockers < taps;
        }
      }
    }
  }
  EXPECT_GT(searched, 20000);
  EXPECT_GT(partial, 1000) << "the searches must find some blockers, not all, for the depth sums to be compared";
}

// listSearchingPixels (16 pixels to a vector where the CPU has AVX-512F, a scalar tail) against its
// definition, pixel by pixel: the list, every radius to the bit, the cut flags and the counts. A row
// of 120 pixels (seven vectors and a tail), a zMin that leaves some receivers in front of it, a
// maxRadius that cuts some radii, and a NaN depth and a zero texel size among the receivers.
TEST(ShadowMap, SearchingPixelsAreTheirDefinition) {
  const auto bits = [](float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
  };
  size_t listed = 0, skipped = 0, cut = 0;
  for (const char* name : {"crowded", "teapots"}) {
    const Scene scene = loadScene(name);
    const LightMap map = renderLightMap(scene, scene.lights.front(), 256);
    const GBuffer gbuffer = renderGBuffer(scene, 120, 80);
    const float zMin = minMapDepth(map) * 1.3f, scale = 0.55f / zMin, maxRadius = 2.0f;
    ReceiverRow row;
    const size_t n = static_cast<size_t>(gbuffer.width());
    std::vector<int32_t> pixels(n);
    std::vector<float> radius(n), out(n, 0.0f);
    std::vector<uint8_t> clamped(n);
    for (int y = 0; y < gbuffer.height(); ++y) {
      makeReceiverRow(map, gbuffer.wsPosition.row(y), gbuffer.wsGeometricNormal.row(y), gbuffer.width(), DepthBias{},
                      row);
      if (y == 40) {
        row.lsDepth[33] = std::numeric_limits<float>::quiet_NaN();
        row.texelWorld[34] = 0.0f;
      }
      const int32_t* ids = gbuffer.objectId.row(y);
      const SearchingPixels got = listSearchingPixels(ids, row, gbuffer.width(), scale, zMin, maxRadius, pixels.data(),
                                                      radius.data(), clamped.data(), out.data());
      SearchingPixels want;
      for (size_t i = 0; i < n; ++i) {
        const float r = scale * (row.lsDepth[i] - zMin) / row.texelWorld[i];
        ASSERT_EQ(bits(radius[i]), bits(std::min(r, maxRadius))) << name << " pixel " << i << "," << y;
        ASSERT_EQ(clamped[i] != 0, r > maxRadius) << name << " pixel " << i << "," << y;
        ASSERT_EQ(out[i], 1.0f) << name << " pixel " << i << "," << y;
        const bool hit = ids[i] != kNoObject;
        want.hits += hit;
        if (!(hit && row.inMap[i] && row.lsDepth[i] > zMin)) {
          skipped += hit;
          continue;
        }
        ASSERT_LT(want.count, got.count) << name << " row " << y;
        ASSERT_EQ(pixels[static_cast<size_t>(want.count)], static_cast<int32_t>(i)) << name << " row " << y;
        ++want.count;
        want.clamped += r > maxRadius;
      }
      ASSERT_EQ(got.count, want.count) << name << " row " << y;
      ASSERT_EQ(got.hits, want.hits) << name << " row " << y;
      ASSERT_EQ(got.clamped, want.clamped) << name << " row " << y;
      listed += static_cast<size_t>(got.count);
      cut += static_cast<size_t>(got.clamped);
    }
  }
  std::printf("[ measured ] listed %zu, skipped %zu, cut %zu\n", listed, skipped, cut);
  EXPECT_GT(listed, 2000u);
  EXPECT_GT(skipped, 200u) << "some receivers must lie in front of zMin";
  EXPECT_GT(cut, 500u) << "some radii must be cut";
  EXPECT_LT(cut, listed / 2);
}

// minMapDepth (rows in parallel): the least finite depth of the map, NaN and empty texels skipped, kInfinity
// for a map with none; on odd sizes, whose rows do not fill its eight lanes.
TEST(ShadowMap, MinMapDepthIsTheLeastDepth) {
  for (const int size : {1, 7, 130, 1024}) {
    LightMap m = orthoMap(size);
    uint32_t state = static_cast<uint32_t>(size);
    float want = kInfinity;
    for (float& d : m.lsDepth) {
      state = state * 1664525u + 1013904223u;
      const uint32_t r = state >> 8;
      d = r % 7 == 0 ? kInfinity : r % 11 == 0 ? std::numeric_limits<float>::quiet_NaN() : 1.0f + (r % 100003) * 1e-3f;
      if (std::isfinite(d)) want = std::min(want, d);
    }
    EXPECT_EQ(minMapDepth(m), want) << size;
    std::fill(m.lsDepth.begin(), m.lsDepth.end(), kInfinity);
    EXPECT_EQ(minMapDepth(m), kInfinity) << size;
  }
}

TEST(ShadowMap, DiskKernelsMatchAScalarOracleTapForTap) {
  LightMap m = orthoMap(1024);
  uint32_t state = 12345u;
  const auto uniform = [&] {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
  };
  for (int j = 0; j < m.size; ++j)
    for (int i = 0; i < m.size; ++i) m.lsDepth(i, j) = uniform() < 0.2f ? kInfinity : 5.0f + 10.0f * uniform();
  const auto offset = [](const Vec2& p, float radius, const Vec2& rotation) {
    return Vec2(radius * (p.x * rotation.x - p.y * rotation.y), radius * (p.x * rotation.y + p.y * rotation.x));
  };
  int cases = 0, blockedTaps = 0;
  for (int n : {1, 7, 16, 17, 32, 48, 64, 80, 128, 130}) {
    const std::vector<Vec2> disk = vogelDisk(n);
    for (int trial = 0; trial < 2000; ++trial) {
      ShadowReceiver r;
      r.inMap = true;
      r.s = -20.0f + 1064.0f * uniform();  // some disks straddle the map's border, some leave it
      r.t = -20.0f + 1064.0f * uniform();
      r.lsDepth = 6.0f + 8.0f * uniform();
      r.dzds = 0.02f * (uniform() - 0.5f);
      r.dzdt = 0.02f * (uniform() - 0.5f);
      r.bias = 0.01f;
      const float radius = 0.5f + 40.0f * uniform();
      const Vec2 rotation = pixelRotation(trial, n);
      if (trial % 2 == 1) {
        // Tap k's t lands on the border of a texel row, or a float away from it: the nearest taps'
        // border (t + o) or the 1-texel boxes' (t + o - 1/2).
        const Vec2 o = offset(disk[static_cast<size_t>(trial / 4) % disk.size()], radius, rotation);
        r.t = std::floor(r.t) + (trial % 4 == 1 ? 0.0f : 0.5f) - o.y;
      }
      int blockers = 0, lit = 0;
      // The kernels' sum order: four partial sums over the taps of each chunk of 64.
      float depthSum = 0.0f, lanes[4] = {};
      for (size_t k = 0; k < disk.size(); ++k) {
        const Vec2 o = offset(disk[k], radius, rotation);
        const int i = static_cast<int>(std::floor(r.s + o.x)), j = static_cast<int>(std::floor(r.t + o.y));
        if (litAtTexel(m, r, i, j) == 0.0f) {
          ++blockers;
          lanes[k % 4] += m.lsDepth(i, j);
        } else {
          ++lit;
        }
        if (k % 64 == 63 || k + 1 == disk.size()) {
          depthSum += (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
          lanes[0] = lanes[1] = lanes[2] = lanes[3] = 0.0f;
        }
      }
      // pcfDisk: a 1-texel box (bilinear weights of four compares) at every tap.
      float boxSum = 0.0f, boxLanes[4] = {};
      for (size_t k = 0; k < disk.size(); ++k) {
        const Vec2 o = offset(disk[k], radius, rotation);
        const float sc = r.s + o.x - 0.5f, tc = r.t + o.y - 0.5f;
        const int i = static_cast<int>(std::floor(sc)), j = static_cast<int>(std::floor(tc));
        const float ws = sc - static_cast<float>(i), wt = tc - static_cast<float>(j);
        const float l00 = litAtTexel(m, r, i, j), l10 = litAtTexel(m, r, i + 1, j);
        const float l01 = litAtTexel(m, r, i, j + 1), l11 = litAtTexel(m, r, i + 1, j + 1);
        const float top = l00 + ws * (l10 - l00), bottom = l01 + ws * (l11 - l01);
        boxLanes[k % 4] += top + wt * (bottom - top);
        if (k % 64 == 63 || k + 1 == disk.size()) {
          boxSum += (boxLanes[0] + boxLanes[1]) + (boxLanes[2] + boxLanes[3]);
          boxLanes[0] = boxLanes[1] = boxLanes[2] = boxLanes[3] = 0.0f;
        }
      }
      ASSERT_EQ(pcfDisk(m, r, radius, disk, rotation), std::clamp(boxSum / static_cast<float>(n), 0.0f, 1.0f))
          << "n " << n << " trial " << trial;
      const BlockerSearch search = searchBlockers(m, r, radius, disk, rotation);
      ASSERT_EQ(search.blockers, blockers) << "n " << n << " trial " << trial;
      if (blockers > 0) {
        ASSERT_EQ(search.meanDepth, depthSum / static_cast<float>(blockers)) << "n " << n << " trial " << trial;
      }
      ASSERT_EQ(pcfDiskNearest(m, r, radius, disk, rotation), static_cast<float>(lit) / static_cast<float>(n))
          << "n " << n << " trial " << trial;
      ++cases;
      blockedTaps += blockers;
    }
  }
  EXPECT_GT(blockedTaps, cases * 5);  // the compares went both ways: measured 386044 blocked taps in 20000 cases
}

TEST(ShadowMap, PcfDiskOfAHalfPlaneIsAboutHalfLit) {
  LightMap m = orthoMap(64);
  for (int j = 0; j < m.size; ++j)
    for (int i = 0; i < 32; ++i) m.lsDepth(i, j) = 2.0f;
  const std::vector<Vec2> disk = vogelDisk(256);
  const ShadowReceiver r = makeReceiver(m, Vec3(0.0f, 0.0f, 10.0f), kFacingLight, DepthBias{});
  EXPECT_NEAR(pcfDisk(m, r, 8.0f, disk, Vec2(1, 0)), 0.5f, 0.02f);
  // Moved by half the radius into the lit side: the lit part of the disk is the disk minus a
  // circular segment at distance d = R/2 from the centre: 1 - (acos(d/R) - (d/R) sqrt(1 - (d/R)^2)) / pi.
  const ShadowReceiver lit = makeReceiver(m, Vec3(4.0f, 0.0f, 10.0f), kFacingLight, DepthBias{});
  const double q = 0.5;
  const double exact = 1.0 - (std::acos(q) - q * std::sqrt(1.0 - q * q)) / 3.14159265358979323846;
  EXPECT_NEAR(pcfDisk(m, lit, 8.0f, disk, Vec2(1, 0)), exact, 0.02);
}

TEST(ShadowMap, VogelDiskSpreadsUniformlyOverTheUnitDisk) {
  const std::vector<Vec2> disk = vogelDisk(32);
  ASSERT_EQ(disk.size(), 32u);
  Vec2 mean(0.0f);
  int inner = 0;
  for (const Vec2& p : disk) {
    EXPECT_LT(glm::length(p), 1.0f);
    mean += p / 32.0f;
    inner += glm::length(p) < 0.5f ? 1 : 0;
  }
  EXPECT_LT(glm::length(mean), 0.05f);
  EXPECT_EQ(inner, 8);  // a quarter of the area holds a quarter of the points
  EXPECT_EQ(vogelDisk(32), disk);
  const Vec2 rot = pixelRotation(17, 5);
  EXPECT_NEAR(glm::length(rot), 1.0f, 1e-5f);
  EXPECT_EQ(rot, pixelRotation(17, 5));
  EXPECT_NE(rot, pixelRotation(18, 5));
}

TEST(ShadowMap, RejectsBadSizesAndKernels) {
  Scene empty;
  const Light light = Light::sphere(Vec3(0, 5, 0), 0.5f);
  EXPECT_THROW(createShadowMap(empty, light, LightMapOptions{8}), Error);
  EXPECT_THROW(createShadowMap(empty, light, LightMapOptions{9000}), Error);
  for (const char* technique : {"hard", "pcf", "pcss", "multisample"}) {
    ParamSet bad;
    bad.set("map_size", int64_t{8}, "scene.json: techniques.x.map_size");
    try {
      createTechnique(technique, bad);
      ADD_FAILURE() << technique << " accepted map_size = 8";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("map_size"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("scene.json"), std::string::npos) << e.what();
    }
    ParamSet negativeBias;
    negativeBias.set("bias_constant", -1.0, "command line");
    EXPECT_THROW(createTechnique(technique, negativeBias), Error) << technique;
  }
  ParamSet even;
  even.set("kernel", int64_t{4}, "command line");
  try {
    createTechnique("pcf", even);
    ADD_FAILURE() << "pcf accepted kernel = 4";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("odd"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace penumbra
