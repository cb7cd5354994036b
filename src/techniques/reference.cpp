// `reference`: the ground truth every technique is measured against (docs/architecture.md, "Reference").
// V(p) is estimated by Monte Carlo over the light's emitting area: spp points from Light::sample with
// correlated multi-jittered samples (Kensler 2013; stratified in 2D and in both 1D projections), one
// Embree occlusion ray to each, V = sum(w_i vis_i) / sum(w_i) with the light's profile weights w_i.
// The ratio form is exact when nothing is occluded (V = 1 bit for bit) and unbiased in the limit.
//
// Determinism: pixel i uses the sample pattern hashCombine(seed, i), so its rays do not depend on
// which thread traces it or in which order; the output is bit-identical for a seed at any thread count.
//
// Standard error: the delta-method error of the ratio estimate, sqrt(sum (w_i (vis_i - V))^2 / (n-1))
// / mean(w) / sqrt(n), which is the sample standard deviation of vis over sqrt(n) for a uniform
// light. It treats the samples as independent; stratification makes the true error smaller, so the
// estimate is conservative.
//
// Speed: a pixel's rays share an origin and aim at one light, so they are traced as coherent
// 16-ray Embree packets, each aimed at one 4 x 4 tile of the sample grid (a small patch of the
// light); at up to 16 spp a packet holds 16 / spp whole neighbouring pixels of a row instead, so its lanes
// are not left idle (each pixel's samples are summed in the same order, so V does not depend on the
// packing); the light's per-point set-up is done once per pixel (Light::samplerAt); the hot loop
// allocates nothing (one strata buffer per range of rows); rows run in parallel with oneTBB.
#include "penumbra/reference.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/sampling.h"
#include "rt/shadow_ray.h"

namespace penumbra {

ReferenceTechnique::ReferenceTechnique(const ReferenceOptions& options) : options_(options) {
  if (options_.samplesPerPixel < 1) fail("reference: spp must be >= 1 (got {})", options_.samplesPerPixel);
}

void ReferenceTechnique::prepareImpl(const Scene& scene, const Light& light) {
  // Every light shape offers Light::sample, so every shape is supported.
  rays_ = std::make_unique<RayScene>(scene);
  light_ = light;
  epsilon_ = shadowRayEpsilon(scene.bounds());
}

void ReferenceTechnique::visibilityImpl(const GBuffer& gbuffer, Image<float>& v) {
  if (!rays_ || !light_) fail("reference: visibility() called before prepare(); call prepare(scene, light) first");
  const int width = gbuffer.width(), height = gbuffer.height();
  v.reset(width, height, 1.0f);
  stdError_ = Image<float>(width, height, 0.0f);
  const Light& light = *light_;
  const RayScene& rays = *rays_;
  const float epsilon = epsilon_;
  const uint32_t spp = options_.samplesPerPixel;
  const uint64_t seed = options_.seed;
  const CmjSampler sampler(spp);

  // When spp fills the sampler's m x n grid, every cell holds one sample and the cells are visited in
  // 4 x 4 tiles, so each 16-ray packet aims at one small patch of the light: a narrow frustum that
  // Embree traverses faster than 16 rays spread over the whole light. Otherwise the samples are taken
  // in index order. Either way the set of samples, and so V up to the order of the sums, is the one
  // sample(i, pattern) gives for i < spp.
  const uint32_t columns = sampler.columns(), rows = sampler.rows();
  const bool fullGrid = columns * rows == spp;

  // A pixel's strata in the order its samples are traced: the 4 x 4 tiles of the grid when spp fills
  // it (at most 16 spp: the grid's row-major order), index order otherwise.
  auto pixelStrata = [&](uint32_t pattern, uint32_t* out) {
    uint32_t n = 0;
    if (fullGrid) {
      for (uint32_t ty = 0; ty < rows; ty += 4)
        for (uint32_t tx = 0; tx < columns; tx += 4)
          for (uint32_t cy = ty; cy < std::min(ty + 4, rows); ++cy)
            for (uint32_t cx = tx; cx < std::min(tx + 4, columns); ++cx) out[n++] = cy * columns + cx;
    } else {
      for (uint32_t i = 0; i < spp; ++i) out[n++] = sampler.stratum(i, pattern);
    }
  };
  // At up to 16 spp a packet holds the samples of 16 / spp whole neighbouring pixels of a row (one at 9
  // to 16), so its lanes are not left idle; each pixel's samples are still traced and summed in the
  // same order, so V is the same as with one pixel a packet. Above 16 spp a pixel fills packets alone.
  const bool wholePixels = spp <= 16;
  const int pixelsPerPacket = wholePixels ? static_cast<int>(16 / spp) : 1;

  std::atomic<int> rowsDone{0};
  std::atomic<int64_t> hitPixels{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
    Vec2 us[16];
    LightSample lightSamples[16];
    Ray packet[16];
    bool occluded[16];
    float weights[16];
    int xs[16];
    int64_t localHits = 0;
    // Sums in double: with millions of samples a float sum would lose the low bits of V.
    struct Sums {
      double w = 0.0, wVis = 0.0, w2 = 0.0, w2Vis = 0.0;
    };
    auto add = [&](Sums& sums, int first, int count) {
      for (int i = first; i < first + count; ++i) {
        const double w = weights[i];
        const double vis = occluded[i] ? 0.0 : 1.0;
        sums.w += w;
        sums.wVis += w * vis;
        sums.w2 += w * w;
        sums.w2Vis += w * w * vis;
      }
    };
    auto finish = [&](const Sums& sums, int x, int y) {
      const double V = sums.w > 0.0 ? sums.wVis / sums.w : 1.0;
      double se = 0.0;
      if (spp > 1 && sums.w > 0.0) {
        // sum (w (vis - V))^2 with vis in {0, 1}: sum w^2 vis (1 - 2V) + V^2 sum w^2.
        const double ss = std::max(0.0, sums.w2Vis * (1.0 - 2.0 * V) + V * V * sums.w2);
        const double meanW = sums.w / spp;
        se = std::sqrt(ss / (spp - 1)) / meanW / std::sqrt(static_cast<double>(spp));
      }
      v(x, y) = static_cast<float>(V);
      stdError_(x, y) = static_cast<float>(se);
    };
    // Rays of `count` samples of one pixel into packet slots [first, first + count).
    auto makeRays = [&](const Light::Sampler& lightSampler, const Vec3& wsP, const Vec3& wsOrigin, uint32_t pattern,
                        const uint32_t* cells, int first, int count) {
      // The sample points first, in a loop of their own: each is a long chain of dependent integer
      // hashes, and only independent iterations back to back let the CPU overlap them.
      for (int i = 0; i < count; ++i) us[first + i] = sampler.sampleInStratum(cells[i], pattern);
      lightSampler.sample(us + first, count, lightSamples + first);
      for (int i = first; i < first + count; ++i) {
        // Stored member by member (rt::storeRay): a whole-struct copy stalls on store forwarding.
        rt::storeRay(packet[i],
                     rt::shadowRay(wsP, wsOrigin, lightSamples[i].wsDirection, lightSamples[i].distance, epsilon));
        weights[i] = lightSamples[i].weight;
      }
    };
    std::vector<uint32_t> allStrata(spp);
    // One pixel's set-up: its point, the shadow rays' origin, its sample pattern and (into allStrata)
    // its strata in tracing order. Returns the light's sampler at the point (the per-point set-up, a
    // sphere's silhouette frame, once per pixel, not per ray).
    auto setUp = [&](int px, int y, Vec3& wsP, Vec3& wsOrigin, uint32_t& pattern) {
      wsP = gbuffer.wsPosition(px, y);
      const Vec3 wsNg = gbuffer.wsGeometricNormal(px, y);
      wsOrigin = rt::offsetOrigin(wsP, wsNg, rt::lightSide(light, wsP, wsNg), epsilon);
      pattern = hashCombine(seed, static_cast<uint64_t>(y) * width + px);
      pixelStrata(pattern, allStrata.data());
      return light.samplerAt(wsP);
    };
    for (int y = range.begin(); y < range.end(); ++y) {
      int x = 0;
      while (x < width) {
        // The next pixelsPerPacket pixels of the row that see geometry.
        int group = 0;
        for (; x < width && group < pixelsPerPacket; ++x)
          if (gbuffer.hit(x, y)) xs[group++] = x;
        if (group == 0) break;
        localHits += group;
        Vec3 wsP, wsOrigin;
        uint32_t pattern = 0;
        if (wholePixels) {
          const int n = static_cast<int>(spp);
          for (int j = 0; j < group; ++j) {
            const Light::Sampler lightSampler = setUp(xs[j], y, wsP, wsOrigin, pattern);
            makeRays(lightSampler, wsP, wsOrigin, pattern, allStrata.data(), j * n, n);
          }
          rays.occluded16(packet, group * n, occluded);
          for (int j = 0; j < group; ++j) {
            Sums sums;
            add(sums, j * n, n);
            finish(sums, xs[j], y);
          }
          continue;
        }
        const Light::Sampler lightSampler = setUp(xs[0], y, wsP, wsOrigin, pattern);
        Sums sums;
        for (uint32_t first = 0; first < spp; first += 16) {
          const int count = static_cast<int>(std::min<uint32_t>(16, spp - first));
          makeRays(lightSampler, wsP, wsOrigin, pattern, allStrata.data() + first, 0, count);
          rays.occluded16(packet, count, occluded);
          add(sums, 0, count);
        }
        finish(sums, xs[0], y);
      }
      // About a hundred progress reports per pass, whatever the image height.
      const int done = ++rowsDone;
      if (done * 100 / height != (done - 1) * 100 / height) reportProgress(static_cast<double>(done) / height);
    }
    hitPixels += localHits;
  });

  rayCount_ = static_cast<double>(hitPixels.load()) * spp;
  // Error statistics over the pixels that hit geometry, in a fixed order (deterministic sums).
  double sum = 0.0, mx = 0.0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (gbuffer.hit(x, y)) {
        sum += stdError_(x, y);
        mx = std::max(mx, static_cast<double>(stdError_(x, y)));
      }
  meanStdError_ = hitPixels.load() > 0 ? sum / static_cast<double>(hitPixels.load()) : 0.0;
  maxStdError_ = mx;
}

std::vector<std::pair<std::string, double>> ReferenceTechnique::stats() const {
  const double seconds = timings().get("visibility") / 1000.0;
  return {{"rays", rayCount_},
          {"rays_per_second", seconds > 0.0 ? rayCount_ / seconds : 0.0},
          {"mean_std_error", meanStdError_},
          {"max_std_error", maxStdError_}};
}

TechniqueInfo referenceTechniqueInfo() {
  TechniqueInfo info;
  info.name = "reference";
  info.summary = "stratified Monte Carlo ray tracing over the light's emitting area (Embree occlusion rays)";
  info.source = "ground truth";
  info.setOptions<ReferenceOptions>([](const ReferenceOptions& o) { return std::make_unique<ReferenceTechnique>(o); });
  return info;
}

}  // namespace penumbra
