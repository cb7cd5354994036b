// The penumbra-aware filter of penumbra_filter.h.
#include "penumbra_filter.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image_fill.h"

namespace penumbra::raytraced {
namespace {

// 1 / k for the tap offsets k <= 64 (taps_per_side's largest).
constexpr std::array<float, 65> kInverse = [] {
  std::array<float, 65> t{};
  for (int k = 1; k <= 64; ++k) t[static_cast<size_t>(k)] = 1.0f / static_cast<float>(k);
  return t;
}();

// x^n by squaring: a handful of multiplies where std::pow is a library call per tap.
inline float integerPower(float x, int n) {
  float result = 1.0f;
  for (; n > 0; n >>= 1, x *= x)
    if (n & 1) result *= x;
  return result;
}

// Pixels whose set-up is computed together.
constexpr int kChunk = 32;

// One separable pass along (dx, dy) over the active tiles: writes `out` at their pixels of radius
// >= 1 from `in`. The second pass reads the first pass's result inside the active tiles and the
// unfiltered input around them: `in` holds both (filterPenumbrae copies the input into it first).
// kPower: options.normalPower when it is one of the exponents instantiated below (so that the normal
// weight's squarings unroll: the same multiplies as the loop's), 0 otherwise.
template <int kPower>
void filterPassWith(const GBuffer& g, const PenumbraFilterInput& input, const PenumbraFilterOptions& options,
                    const Image<float>& in, int dx, int dy, Image<float>& out) {
  const int width = g.width(), height = g.height();
  const Image<float>& radius = *input.radius;
  const Image<float>& reach = *input.reach;
  const int tileSize = input.activeTiles ? input.tileSize : std::max(width, height);
  const int tilesX = input.activeTiles ? input.tilesX : 1;
  const int tilesY = (height + tileSize - 1) / tileSize;
  // The images' storage, read through raw pointers: the taps' loads index them with one linear offset
  // (every image is the G-buffer's size), and the compiler keeps the pointers in registers, where
  // through the images it reloaded each one at every tap.
  assert(in.width() == width && in.height() == height);
  assert(reach.width() == width && reach.height() == height && out.width() == width && out.height() == height);
  const int32_t* const ids = g.objectId.data();
  const Vec3* const positions = g.wsPosition.data();
  const Vec3* const normals = g.wsNormal.data();
  const float* const reaches = reach.data();
  const float* const ins = in.data();
  // Pixels along the pass: the tap offsets run over [0, extent) in the pass's coordinate.
  const int extent = dx != 0 ? width : height;
  const ptrdiff_t pitch = dx != 0 ? 1 : width;  // linear offset of one pixel along the pass
  tbb::parallel_for(tbb::blocked_range<int>(0, tilesX * tilesY), [&](const tbb::blocked_range<int>& range) {
    for (int tile = range.begin(); tile < range.end(); ++tile) {
      if (input.activeTiles && !input.activeTiles[static_cast<size_t>(tile)]) continue;  // row-major, as `tile` counts
      const int x0 = (tile % tilesX) * tileSize, y0 = (tile / tilesX) * tileSize;
      const int x1 = std::min(x0 + tileSize, width);
      for (int y = y0; y < std::min(y0 + tileSize, height); ++y)
        for (int xChunk = x0; xChunk < x1; xChunk += kChunk) {
          // The per-pixel set-up of up to kChunk pixels in one loop the compiler vectorizes (its
          // divisions, floors and ceil lane by lane, the same operations as one pixel at a time).
          // taps is int(r) / stride, and the taps' range inside the image -floor(c / stride) ..
          // floor((extent - 1 - c) / stride) for the pixel's coordinate c along the pass, each taken
          // as the floor of the float quotient: exact for integers below 2^24.
          const int count = std::min(kChunk, x1 - xChunk);
          alignas(64) float invToleranceOf[kChunk], invR2Of[kChunk], invStrideOf[kChunk];
          alignas(64) int strideOf[kChunk], firstTapOf[kChunk], lastTapOf[kChunk];
          const float* radii = radius.row(y) + xChunk;
          const float* depths = g.csDepth.row(y) + xChunk;
          for (int i = 0; i < count; ++i) {
            const float ri = radii[i];
            // A radius is at most max_radius (256); one below 1 or not a number is a pixel left as it
            // is, whose set-up is not read.
            const float r = ri >= 1.0f && ri <= 1e6f ? ri : 1.0f;
            invToleranceOf[i] = 1.0f / (options.planeTolerance * pixelFootprint(depths[i], input.tanHalfFovY, height));
            const int stride = std::max(1, static_cast<int>(std::ceil(r / static_cast<float>(options.tapsPerSide))));
            const float strideF = static_cast<float>(stride);
            strideOf[i] = stride;
            const int taps = static_cast<int>(std::floor(static_cast<float>(static_cast<int>(r)) / strideF));
            const int c = dx != 0 ? xChunk + i : y;
            firstTapOf[i] = std::max(-taps, -static_cast<int>(std::floor(static_cast<float>(c) / strideF)));
            lastTapOf[i] = std::min(taps, static_cast<int>(std::floor(static_cast<float>(extent - 1 - c) / strideF)));
            invR2Of[i] = 1.0f / (r * r);
            invStrideOf[i] = 1.0f / strideF;
          }
          for (int i = 0; i < count; ++i) {
            const int x = xChunk + i;
            const ptrdiff_t pixel = static_cast<ptrdiff_t>(y) * width + x;
            const int32_t id = ids[pixel];
            if (!(radii[i] >= 1.0f) || id == kNoObject) {
              out(x, y) = ins[pixel];
              continue;
            }
            const Vec3 p = positions[pixel];
            const Vec3 n = normals[pixel];
            // Tolerated distance from p's tangent plane per pixel of screen distance.
            const float invTolerance = invToleranceOf[i];
            const int stride = strideOf[i];
            const float invR2 = invR2Of[i];
            const float invStride = invStrideOf[i];
            const ptrdiff_t step = stride * pitch;
            float sum = ins[pixel], weightSum = 1.0f;
            for (int k = firstTapOf[i]; k <= lastTapOf[i]; ++k) {
              if (k == 0) continue;
              const ptrdiff_t q = pixel + k * step;
              if (ids[q] != id) continue;  // also drops pixels that see nothing
              const float d = static_cast<float>(std::abs(k) * stride);
              if (reaches[q] < d) continue;
              const float plane = std::abs(glm::dot(n, positions[q] - p));
              // 1 - plane / (tolerance d), with reciprocals: no division per tap.
              const float planeWeight = 1.0f - plane * invTolerance * invStride * kInverse[std::abs(k)];
              if (!(planeWeight > 0.0f)) continue;
              const float cosine = glm::dot(n, normals[q]);
              if (!(cosine > 0.0f)) continue;
              const float normalWeight = integerPower(cosine, kPower > 0 ? kPower : options.normalPower);
              // Biweight in screen distance: smooth, compact (zero at the radius), no exp per tap.
              const float s = 1.0f - d * d * invR2;
              const float w = s * s * planeWeight * normalWeight;
              sum += w * ins[q];
              weightSum += w;
            }
            out(x, y) = sum / weightSum;
          }
        }
    }
  });
}

void filterPass(const GBuffer& g, const PenumbraFilterInput& input, const PenumbraFilterOptions& options,
                const Image<float>& in, int dx, int dy, Image<float>& out) {
  switch (options.normalPower) {
    case 16:  // the few-ray techniques' default
      return filterPassWith<16>(g, input, options, in, dx, dy, out);
    case 8:
      return filterPassWith<8>(g, input, options, in, dx, dy, out);
    default:
      return filterPassWith<0>(g, input, options, in, dx, dy, out);
  }
}

}  // namespace

void filterPenumbrae(const GBuffer& gbuffer, const PenumbraFilterInput& input, const PenumbraFilterOptions& options,
                     Image<float>& scratch, Image<float>& out) {
  const Image<float>& noisy = *input.noisy;
  const int width = gbuffer.width(), height = gbuffer.height();
  // Pixels outside the active tiles keep their input; both passes write only inside them. `scratch`
  // starts as the input too, so that the second pass reads the first's result inside the active tiles
  // and the input around them from one image (no test of a tap's tile).
  scratch.resizeForOverwrite(width, height);
  out.resizeForOverwrite(width, height);
  tbb::parallel_for(tbb::blocked_range<int>(0, height, 32), [&](const tbb::blocked_range<int>& rows) {
    const size_t n = static_cast<size_t>(rows.size()) * static_cast<size_t>(width);
    std::copy(noisy.row(rows.begin()), noisy.row(rows.begin()) + n, out.row(rows.begin()));
    std::copy(noisy.row(rows.begin()), noisy.row(rows.begin()) + n, scratch.row(rows.begin()));
  });
  filterPass(gbuffer, input, options, noisy, 1, 0, scratch);
  filterPass(gbuffer, input, options, scratch, 0, 1, out);
}

}  // namespace penumbra::raytraced
