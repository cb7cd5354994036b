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
// light); the light's per-point set-up is done once per pixel (Light::samplerAt); the hot loop
// allocates nothing; rows run in parallel with oneTBB.
#include "penumbra/reference.h"

#include <algorithm>
#include <atomic>
#include <cmath>

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

  std::atomic<int> rowsDone{0};
  std::atomic<int64_t> hitPixels{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
    uint32_t strata[16];
    Vec2 us[16];
    LightSample lightSamples[16];
    Ray packet[16];
    bool occluded[16];
    float weights[16];
    int64_t localHits = 0;
    for (int y = range.begin(); y < range.end(); ++y) {
      for (int x = 0; x < width; ++x) {
        if (!gbuffer.hit(x, y)) continue;
        ++localHits;
        const Vec3 wsP = gbuffer.wsPosition(x, y);
        const Vec3 wsNg = gbuffer.wsGeometricNormal(x, y);
        const Vec3 wsOrigin = rt::offsetOrigin(wsP, wsNg, rt::lightSide(light, wsP, wsNg), epsilon);
        const uint32_t pattern = hashCombine(seed, static_cast<uint64_t>(y) * width + x);
        // The light's per-point set-up (a sphere's silhouette frame) once per pixel, not per ray.
        const Light::Sampler lightSampler = light.samplerAt(wsP);
        // Sums in double: with millions of samples a float sum would lose the low bits of V.
        double sumW = 0.0, sumWVis = 0.0, sumW2 = 0.0, sumW2Vis = 0.0;
        int count = 0;
        auto trace = [&] {
          // The sample points first, in a loop of their own: each is a long chain of dependent integer
          // hashes, and only independent iterations back to back let the CPU overlap them.
          for (int i = 0; i < count; ++i) us[i] = sampler.sampleInStratum(strata[i], pattern);
          lightSampler.sample(us, count, lightSamples);
          for (int i = 0; i < count; ++i) {
            // Copied member by member: a whole-struct copy made the compiler assemble the ray in a
            // stack temporary with narrow stores and reload it with 16-byte loads: a store-forwarding
            // stall in the hottest loop.
            const Ray ray =
                rt::shadowRay(wsP, wsOrigin, lightSamples[i].wsDirection, lightSamples[i].distance, epsilon);
            packet[i].origin = ray.origin;
            packet[i].direction = ray.direction;
            packet[i].tMin = ray.tMin;
            packet[i].tMax = ray.tMax;
            weights[i] = lightSamples[i].weight;
          }
          rays.occluded16(packet, count, occluded);
          for (int i = 0; i < count; ++i) {
            const double w = weights[i];
            const double vis = occluded[i] ? 0.0 : 1.0;
            sumW += w;
            sumWVis += w * vis;
            sumW2 += w * w;
            sumW2Vis += w * w * vis;
          }
          count = 0;
        };
        if (fullGrid) {
          for (uint32_t ty = 0; ty < rows; ty += 4)
            for (uint32_t tx = 0; tx < columns; tx += 4)
              for (uint32_t cy = ty; cy < std::min(ty + 4, rows); ++cy)
                for (uint32_t cx = tx; cx < std::min(tx + 4, columns); ++cx) {
                  strata[count++] = cy * columns + cx;
                  if (count == 16) trace();
                }
        } else {
          for (uint32_t i = 0; i < spp; ++i) {
            strata[count++] = sampler.stratum(i, pattern);
            if (count == 16) trace();
          }
        }
        if (count > 0) trace();
        const double V = sumW > 0.0 ? sumWVis / sumW : 1.0;
        double se = 0.0;
        if (spp > 1 && sumW > 0.0) {
          // sum (w (vis - V))^2 with vis in {0, 1}: sum w^2 vis (1 - 2V) + V^2 sum w^2.
          const double ss = std::max(0.0, sumW2Vis * (1.0 - 2.0 * V) + V * V * sumW2);
          const double meanW = sumW / spp;
          se = std::sqrt(ss / (spp - 1)) / meanW / std::sqrt(static_cast<double>(spp));
        }
        v(x, y) = static_cast<float>(V);
        stdError_(x, y) = static_cast<float>(se);
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
