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
// packing); the rays' origins, the sample patterns and points and the rays are made sixteen at a
// time in vector form (rt::offsetOrigins, patternLanes, CmjSampler::sampleLanes,
// rt::buildShadowRays), compiled for AVX2 and AVX-512F too (core/target_clones.h). Above 16 spp, where
// a pixel fills its packets alone, what depends on the pixel only is made once per pixel, not per
// packet: its lanes' origins and pattern, its pattern's permutations of the sample grid
// (CmjSampler::tabulatePermutations) and a sphere light's silhouette disk (rt::buildShadowRaysFromOnePoint).
// Under unit weights (every light but a limb-darkened sun) a packet's visible lanes are counted, not
// summed one by one, and V and its error are read from a table by that count. Each gives the same
// floats as the direct form, bit for bit. The hot loop allocates nothing; rows run in parallel with
// oneTBB. The Embree scene is built by the first prepare
// and kept by later ones while every object's id, positions and triangles are the same (a light or
// camera moving over a static scene).
#include "penumbra/reference.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/target_clones.h"
#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "penumbra/sampling.h"
#include "rt/ray_scene.h"
#include "rt/shadow_packet.h"

namespace penumbra {
namespace {

// Lanes [0, count): the sample pattern hashCombine(seed, pixel) of each lane's pixel, in one vector
// loop (compiled for AVX2 and AVX-512F too).
PENUMBRA_CLONES_AVX512 void patternLanes(uint64_t seed, int count, const uint64_t* __restrict pixel,
                                         uint32_t* __restrict pattern) {
  for (int i = 0; i < count; ++i) pattern[i] = hashCombine(seed, pixel[i]);
}

// CmjSampler::sampleLanes, compiled for AVX2 and AVX-512F too (its hashes' unsigned conversions are
// one instruction there).
PENUMBRA_CLONES_AVX512 void sampleLanes(const CmjSampler& sampler, const uint32_t* __restrict strata,
                                        const uint32_t* __restrict patterns, int count, float* __restrict ux,
                                        float* __restrict uy) {
  sampler.sampleLanes(strata, patterns, count, ux, uy);
}

// Sixteen consecutive x, y, z triples (a G-buffer row's run of points or normals) into three lane
// arrays: a fixed-count strided copy the compiler turns into vector shuffles (AVX2 and AVX-512F clones
// too), where the lane-by-lane copy cost half the pass's own work at one sample a pixel.
PENUMBRA_CLONES_AVX512 void deinterleave16(const float* __restrict xyz, float* __restrict x, float* __restrict y,
                                           float* __restrict z) {
  for (int i = 0; i < 16; ++i) {
    x[i] = xyz[3 * i];
    y[i] = xyz[3 * i + 1];
    z[i] = xyz[3 * i + 2];
  }
}

// Whether the sixteen pixels from `objectIds` on all see geometry (a vector compare).
bool allSeeGeometry16(const int32_t* __restrict objectIds) {
  bool all = true;
  for (int i = 0; i < 16; ++i) all &= objectIds[i] != kNoObject;
  return all;
}

// CmjSampler::sampleLanesOfOnePattern, compiled for AVX2 and AVX-512F too.
PENUMBRA_CLONES_AVX512 void sampleLanesOfOnePattern(const CmjSampler& sampler, const uint32_t* __restrict strata,
                                                    uint32_t pattern, const uint32_t* __restrict columnSx,
                                                    const uint32_t* __restrict rowSy, int count, float* __restrict ux,
                                                    float* __restrict uy) {
  sampler.sampleLanesOfOnePattern(strata, pattern, columnSx, rowSy, count, ux, uy);
}

}  // namespace

ReferenceTechnique::~ReferenceTechnique() = default;

ReferenceTechnique::ReferenceTechnique(const ReferenceOptions& options) : options_(options) {
  if (options_.samplesPerPixel < 1) fail("reference: spp must be >= 1 (got {})", options_.samplesPerPixel);
}

void ReferenceTechnique::setOptions(const ReferenceOptions& options) {
  if (options.samplesPerPixel < 1) fail("reference: spp must be >= 1 (got {})", options.samplesPerPixel);
  options_ = options;
}

void ReferenceTechnique::prepareImpl(const Scene& scene, const Light& light) {
  // Every light shape offers Light::sample, so every shape is supported.
  if (!raysCache_) raysCache_ = std::make_unique<RaySceneCache>();
  rays_ = nullptr;
  rays_ = &raysCache_->get(scene);
  light_ = light;
  epsilon_ = shadowRayEpsilon(raysCache_->bounds());
}

void ReferenceTechnique::visibilityImpl(const GBuffer& gbuffer, Image<float>& v) {
  if (!rays_ || !light_) fail("reference: visibility() called before prepare(); call prepare(scene, light) first");
  const int width = gbuffer.width(), height = gbuffer.height();
  // Every pixel is written by the row loop below (1 and error 0 where nothing is seen), in place:
  // fresh pages every frame cost a fault each.
  v.resizeForOverwrite(width, height);
  stdError_.resizeForOverwrite(width, height);
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

  // That order of the cells, the same for every pixel (at most 16 spp: the grid's row-major order).
  std::vector<uint32_t> gridOrder;
  if (fullGrid)
    for (uint32_t ty = 0; ty < rows; ty += 4)
      for (uint32_t tx = 0; tx < columns; tx += 4)
        for (uint32_t cy = ty; cy < std::min(ty + 4, rows); ++cy)
          for (uint32_t cx = tx; cx < std::min(tx + 4, columns); ++cx) gridOrder.push_back(cy * columns + cx);
  // At up to 16 spp a packet holds the samples of 16 / spp whole neighbouring pixels of a row (one at 9
  // to 16), so its lanes are not left idle; each pixel's samples are still traced and summed in the
  // same order, so V is the same as with one pixel a packet. Above 16 spp a pixel fills packets alone.
  const bool wholePixels = spp <= 16;
  const int pixelsPerPacket = wholePixels ? static_cast<int>(16 / spp) : 1;

  // A pixel's V and the standard error of its estimate from its sums.
  auto estimate = [spp](const auto& sums, float& V, float& error) {
    const double v = sums.w > 0.0 ? sums.wVis / sums.w : 1.0;
    double se = 0.0;
    if (spp > 1 && sums.w > 0.0) {
      // sum (w (vis - V))^2 with vis in {0, 1}: sum w^2 vis (1 - 2V) + V^2 sum w^2.
      const double ss = std::max(0.0, sums.w2Vis * (1.0 - 2.0 * v) + v * v * sums.w2);
      const double meanW = sums.w / spp;
      se = std::sqrt(ss / (spp - 1)) / meanW / std::sqrt(static_cast<double>(spp));
    }
    V = static_cast<float>(v);
    error = static_cast<float>(se);
  };
  // With unit weights (Sums::whole) the sums are {spp, k, spp, k} for k visible samples, so V and its
  // error take spp + 1 values: tabulated once (up to 2^16 spp), the same floats estimate() gives, where
  // per pixel two square roots and three divisions cost a fifth of the pass at 4 spp.
  std::vector<float> wholeV, wholeError;
  if (spp <= (1u << 16)) {
    wholeV.resize(spp + 1);
    wholeError.resize(spp + 1);
    struct {
      double w, wVis, w2, w2Vis;
    } whole{static_cast<double>(spp), 0.0, static_cast<double>(spp), 0.0};
    for (uint32_t k = 0; k <= spp; ++k) {
      whole.wVis = whole.w2Vis = static_cast<double>(k);
      estimate(whole, wholeV[k], wholeError[k]);
    }
  }
  std::atomic<int> rowsDone{0};
  std::atomic<int64_t> hitPixels{0};
  // Each row's sum and maximum of the standard error, summed over the rows in order afterwards (the
  // same sum at any thread count).
  std::vector<double> rowErrorSum(static_cast<size_t>(height), 0.0);
  std::vector<float> rowErrorMax(static_cast<size_t>(height), 0.0f);
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& range) {
    rt::ShadowLanes lanes;
    RayPacket16 packet;
    float weights[16];
    int xs[16];
    int64_t localHits = 0;
    // Sums in double: with millions of samples a float sum would lose the low bits of V. While every
    // weight so far is 1 (every light but a limb-darkened sun), the sums are whole numbers, exact in
    // a double in any order: a packet's lanes are then counted rather than summed one by one (a chain
    // of dependent additions that cost a third of the pass at high spp), the same sums to the bit.
    struct Sums {
      double w = 0.0, wVis = 0.0, w2 = 0.0, w2Vis = 0.0;
      bool whole = true;  //!< every weight added so far was 1
    };
    auto add = [&](Sums& sums, int first, int count) {
      bool unitWeights = sums.whole;
      int visible = 0;
      for (int i = first; i < first + count; ++i) {
        unitWeights &= weights[i] == 1.0f;
        visible += packet.blocked(i) ? 0 : 1;
      }
      if (unitWeights) {
        sums.w += count;
        sums.wVis += visible;
        sums.w2 += count;
        sums.w2Vis += visible;
        return;
      }
      sums.whole = false;
      // In locals: summed through the struct, each step went through memory.
      double sw = sums.w, swVis = sums.wVis, sw2 = sums.w2, sw2Vis = sums.w2Vis;
      for (int i = first; i < first + count; ++i) {
        const double w = weights[i];
        const double vis = packet.blocked(i) ? 0.0 : 1.0;
        sw += w;
        swVis += w * vis;
        sw2 += w * w;
        sw2Vis += w * w * vis;
      }
      sums = {sw, swVis, sw2, sw2Vis, false};
    };
    // The row being traced: its images' rows and its error sum and maximum, kept in locals and
    // stored once per row (through the vectors, every pixel's update went through memory).
    float* vRow = nullptr;
    float* errorRow = nullptr;
    double errorSum = 0.0;
    float errorMax = 0.0f;
    auto finish = [&](const Sums& sums, int x) {
      float V, error;
      if (sums.whole && !wholeV.empty()) {  // V and its error tabulated by the count of visible samples
        const auto visible = static_cast<size_t>(sums.wVis);
        V = wholeV[visible];
        error = wholeError[visible];
      } else {
        estimate(sums, V, error);
      }
      vRow[x] = V;
      errorRow[x] = error;
      errorSum += error;
      errorMax = std::max(errorMax, error);
    };
    alignas(64) uint32_t laneStrata[16], lanePatterns[16];
    if (wholePixels && fullGrid)
      for (int lane = 0; lane < 16; ++lane) laneStrata[lane] = gridOrder[static_cast<size_t>(lane) % spp];
    std::vector<uint32_t> columnSx(wholePixels ? 0 : columns), rowSy(wholePixels ? 0 : rows);
    alignas(64) uint64_t pixelIndices[16];
    // Lanes [0, group n): lane i is a sample of pixel xs[i / n] of row y. Every lane holds its pixel's
    // point, normal and sample pattern (hashed once per pixel from its index); with `origins` the ray
    // origins are made for all of them in one vector loop (for each sample where n > 1, which costs less
    // than a pixel-by-pixel set-up), without it the rays' builder makes them
    // (rt::buildShadowRaysAndOrigins).
    const Vec3* positionRow = nullptr;
    const Vec3* normalRow = nullptr;
    auto fillSurfaces = [&](int y, int group, int n, bool origins) {
      const uint64_t rowStart = static_cast<uint64_t>(y) * width;
      if (n == 1 && group == 16 && xs[15] - xs[0] == 15) {  // sixteen neighbouring pixels: a run of the row
        static_assert(sizeof(Vec3) == 3 * sizeof(float));
        deinterleave16(reinterpret_cast<const float*>(positionRow + xs[0]), lanes.px, lanes.py, lanes.pz);
        deinterleave16(reinterpret_cast<const float*>(normalRow + xs[0]), lanes.nx, lanes.ny, lanes.nz);
        for (int j = 0; j < 16; ++j) pixelIndices[j] = rowStart + static_cast<uint64_t>(xs[0] + j);
        if (origins) rt::offsetOrigins(light, epsilon, 16, lanes);
        patternLanes(seed, 16, pixelIndices, lanePatterns);
        return 16;
      }
      // The pixels' patterns hashed once each, then every lane takes its pixel's.
      alignas(64) uint32_t pixelPatterns[16];
      for (int j = 0; j < group; ++j) pixelIndices[j] = rowStart + static_cast<uint64_t>(xs[j]);
      patternLanes(seed, group, pixelIndices, pixelPatterns);
      for (int j = 0; j < group; ++j) {
        const Vec3 p = positionRow[xs[j]], ng = normalRow[xs[j]];
        for (int lane = j * n; lane < (j + 1) * n; ++lane) {
          lanes.setSurface(lane, p, ng);
          lanePatterns[lane] = pixelPatterns[j];
        }
      }
      const int count = group * n;
      if (origins) rt::offsetOrigins(light, epsilon, count, lanes);
      return count;
    };
    for (int y = range.begin(); y < range.end(); ++y) {
      vRow = v.row(y);
      errorRow = stdError_.row(y);
      positionRow = gbuffer.wsPosition.row(y);
      normalRow = gbuffer.wsGeometricNormal.row(y);
      const int32_t* objectRow = gbuffer.objectId.row(y);
      errorSum = 0.0;
      errorMax = 0.0f;
      int x = 0;
      while (x < width) {
        // The next pixelsPerPacket pixels of the row that see geometry; a pixel that sees nothing is lit.
        int group = 0;
        if (pixelsPerPacket == 16 && x + 16 <= width && allSeeGeometry16(objectRow + x)) {
          for (int j = 0; j < 16; ++j) xs[j] = x + j;
          group = 16;
          x += 16;
        } else {
          for (; x < width && group < pixelsPerPacket; ++x) {
            if (objectRow[x] != kNoObject) {
              xs[group++] = x;
            } else {
              vRow[x] = 1.0f;
              errorRow[x] = 0.0f;
            }
          }
        }
        if (group == 0) break;
        localHits += group;
        if (wholePixels) {
          // Lane j n + k takes sample k of pixel xs[j]: on a full grid the same cells for every packet.
          const int n = static_cast<int>(spp);
          const int count = fillSurfaces(y, group, n, group == 1);
          if (!fullGrid)
            for (int j = 0; j < group; ++j)
              for (int k = 0; k < n; ++k)
                laneStrata[j * n + k] = sampler.stratum(static_cast<uint32_t>(k), lanePatterns[j * n]);
          sampleLanes(sampler, laneStrata, lanePatterns, count, lanes.ux, lanes.uy);
          // A pixel alone in its packet (9 to 16 spp): the light's per-point set-up once, the same rays.
          if (group == 1)
            rt::buildShadowRaysFromOnePoint(light, lanes, count, epsilon, packet, weights);
          else
            rt::buildShadowRaysAndOrigins(light, lanes, count, epsilon, packet, weights);
          rays.occluded16(packet, count);
          if (n == 1) {
            // One sample: V = w vis / w is vis itself (w > 0; 1 where w = 0) and its error 0, the sums'
            // values without them.
            for (int j = 0; j < group; ++j) {
              vRow[xs[j]] = weights[j] > 0.0f && packet.blocked(j) ? 0.0f : 1.0f;
              errorRow[xs[j]] = 0.0f;
            }
            continue;
          }
          for (int j = 0; j < group; ++j) {
            Sums sums;
            add(sums, j * n, n);
            finish(sums, xs[j]);
          }
          continue;
        }
        // The pixel fills every packet: its lanes' point, origin and pattern, and its pattern's
        // permutations of the grid's columns and rows, are made once.
        fillSurfaces(y, 1, 16, true);
        const uint32_t pattern = lanePatterns[0];
        sampler.tabulatePermutations(pattern, columnSx.data(), rowSy.data());
        Sums sums;
        for (uint32_t first = 0; first < spp; first += 16) {
          const int count = static_cast<int>(std::min<uint32_t>(16, spp - first));
          for (int lane = 0; lane < count; ++lane) {
            const uint32_t index = first + static_cast<uint32_t>(lane);
            laneStrata[lane] = fullGrid ? gridOrder[index] : sampler.stratum(index, pattern);
          }
          sampleLanesOfOnePattern(sampler, laneStrata, pattern, columnSx.data(), rowSy.data(), count, lanes.ux,
                                  lanes.uy);
          rt::buildShadowRaysFromOnePoint(light, lanes, count, epsilon, packet, weights);
          rays.occluded16(packet, count);
          add(sums, 0, count);
        }
        finish(sums, xs[0]);
      }
      rowErrorSum[static_cast<size_t>(y)] = errorSum;
      rowErrorMax[static_cast<size_t>(y)] = errorMax;
      // About a hundred progress reports per pass, whatever the image height.
      const int done = ++rowsDone;
      if (done * 100 / height != (done - 1) * 100 / height) reportProgress(static_cast<double>(done) / height);
    }
    hitPixels += localHits;
  });

  rayCount_ = static_cast<double>(hitPixels.load()) * spp;
  double sum = 0.0, mx = 0.0;
  for (int y = 0; y < height; ++y) {
    sum += rowErrorSum[static_cast<size_t>(y)];
    mx = std::max(mx, static_cast<double>(rowErrorMax[static_cast<size_t>(y)]));
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

std::unique_ptr<ShadowTechnique> makeTechnique(const ReferenceOptions& o) {
  validateOptions("reference", o);

  return std::make_unique<ReferenceTechnique>(o);
}

TechniqueInfo referenceTechniqueInfo() {
  TechniqueInfo info;
  info.name = "reference";
  info.summary = "stratified Monte Carlo ray tracing over the light's emitting area (Embree occlusion rays)";
  info.source = "ground truth";
  info.tracesRays = true;
  info.setOptions<ReferenceOptions>([](const ReferenceOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
