// Shared shadow-map stages: see shadow_map.h for the papers, the conventions and the approximations.
#include "shadow_map.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define PENUMBRA_AVX512_KERNELS 1
#endif

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "core/target_clones.h"
#include "penumbra/error.h"
#include "penumbra/motion.h"

namespace penumbra {

LightMap createShadowMap(const Scene& scene, const Light& light, const LightMapOptions& options) {
  LightMap map;
  createShadowMap(scene, light, options, map);
  return map;
}

namespace {
void checkShadowMapSize(const LightMapOptions& options) {
  if (options.size < kMinShadowMapSize || options.size > kMaxShadowMapSize)
    fail("shadow map: map_size = {} is not valid: expected an int in [{}, {}] texels", options.size, kMinShadowMapSize,
         kMaxShadowMapSize);
}
}  // namespace

void createShadowMap(const Scene& scene, const Light& light, const LightMapOptions& options, LightMap& out,
                     LightMapLayers layers) {
  checkShadowMapSize(options);
  renderLightMap(scene, light, options.size, out, options.fit, layers);
}

void fitShadowMap(const Scene& scene, const Light& light, const LightMapOptions& options, LightMap& out) {
  checkShadowMapSize(options);
  fitLightMap(scene, light, options.size, out, options.fit);
}

void reserveShadowMap(const LightMapOptions& options, LightMap& out, LightMapLayers layers) {
  reserveLightMap(out, options.size, layers);
}

Light lightAtMapOrigin(const Light& light, const LightMap& map) {
  if (light.isDirectional() || map.wsOrigin == light.center()) return light;
  return lightMovedTo(light, map.wsOrigin);
}

float minMapDepth(const LightMap& map) {
  // Rows in parallel, each row's least depth with eight independent running minima (one chain would
  // wait a compare's latency per texel). min is exact, so any split gives the same value as one pass
  // (NaN texels are skipped either way).
  const int size = map.size;
  return tbb::parallel_reduce(
      tbb::blocked_range<int>(0, size, 16), kInfinity,
      [&](const tbb::blocked_range<int>& rows, float m) {
        constexpr size_t kMinLanes = 8;
        float lane[kMinLanes];
        std::fill(lane, lane + kMinLanes, kInfinity);
        const float* d = map.lsDepth.row(rows.begin());
        const size_t n = static_cast<size_t>(rows.size()) * static_cast<size_t>(size);
        size_t i = 0;
        for (; i + kMinLanes <= n; i += kMinLanes)
          for (size_t l = 0; l < kMinLanes; ++l) lane[l] = d[i + l] < lane[l] ? d[i + l] : lane[l];
        for (; i < n; ++i) m = d[i] < m ? d[i] : m;
        for (size_t l = 0; l < kMinLanes; ++l) m = lane[l] < m ? lane[l] : m;
        return m;
      },
      [](float a, float b) { return b < a ? b : a; });
}

// The disk kernels below are also compiled for AVX2 and the receivers' loop for AVX2 and AVX-512F
// (core/target_clones.h): their vector phases run 8 or 16 lanes wide instead of 4, and every path
// rounds alike, so V is bit-identical on every CPU.
#define PENUMBRA_KERNEL_CLONES PENUMBRA_CLONES_AVX2
#define PENUMBRA_RECEIVER_CLONES PENUMBRA_CLONES_AVX512

namespace {

// What makeReceiverRow's loop reads besides the pixels: the map's frame and projection, the bias.
struct ReceiverRowConstants {
  float ox, oy, oz;                          //!< the origin of the frame the pixels are taken into
  float xx, xy, xz, yx, yy, yz, zx, zy, zz;  //!< its axes
  float mx, my, mz;                          //!< the map's origin in that frame (0 for the map's own frame)
  float size, half, halfWidth, tanHalfFov, biasConstant, biasSlope;
  float windowX, windowY;  //!< LightMap::windowOffset
  int mapSize;
};

// num / den limited to [-kMaxDepthSlope, kMaxDepthSlope] (detail::limitedRatio), as a select.
inline float limitedSelect(float num, float den) {
  const float q = den != 0.0f ? num / den : 0.0f;
  const float cap = (num < 0.0f) != (den < 0.0f) ? -kMaxDepthSlope : kMaxDepthSlope;
  return std::abs(num) <= kMaxDepthSlope * std::abs(den) ? q : cap;
}

// makeReceiver and receiverAt, operation for operation (glm's dot is (x x' + y y') + z z'), for n
// pixels. One function per projection, restrict-qualified arrays (GCC trusts restrict on parameters),
// plain floats (glm's union members keep the vectorizer from their loads), every condition a bitwise
// and of comparisons, every branch a select: the loop vectorizes.
template <bool kOrtho>
inline __attribute__((always_inline)) void receiverRowKernel(
    const ReceiverRowConstants k, size_t n, const float* __restrict position, const float* __restrict normal,
    float* __restrict s, float* __restrict t, float* __restrict z, float* __restrict dzds, float* __restrict dzdt,
    float* __restrict biasOut, float* __restrict texelWorld, float* __restrict threshold, int32_t* __restrict texel,
    int32_t* __restrict inMap) {
  for (size_t x = 0; x < n; ++x) {
    const float dx = position[3 * x] - k.ox, dy = position[3 * x + 1] - k.oy, dz = position[3 * x + 2] - k.oz;
    const float gx = normal[3 * x], gy = normal[3 * x + 1], gz = normal[3 * x + 2];
    // Minus the map's origin in the frame: exact for the map's own frame (x - 0 is x, -0 included).
    const float lx = (dx * k.xx + dy * k.xy + dz * k.xz) - k.mx;
    const float ly = (dx * k.yx + dy * k.yy + dz * k.yz) - k.my;
    const float lz = (dx * k.zx + dy * k.zy + dz * k.zz) - k.mz;
    const float nx = gx * k.xx + gy * k.xy + gz * k.xz;
    const float ny = gx * k.yx + gy * k.yy + gz * k.yz;
    const float nz = gx * k.zx + gy * k.zy + gz * k.zz;
    const bool inFront = kOrtho | (lz > 0.0f);
    const float scale = kOrtho ? 1.0f / k.halfWidth : 1.0f / (lz * k.tanHalfFov);
    const float ms = k.half * (1.0f + (lx * scale - k.windowX)), mt = k.half * (1.0f - (ly * scale - k.windowY));
    const bool inside = inFront & (ms >= 0.0f) & (ms < k.size) & (mt >= 0.0f) & (mt < k.size) &
                        (std::abs(lz) <= std::numeric_limits<float>::max());  // finite
    const float tw = 2.0f * (kOrtho ? k.halfWidth : lz * k.tanHalfFov) / k.size;
    const float nDotD = kOrtho ? nz : (nx * lx + ny * ly + nz * lz) / lz;
    const float gs = limitedSelect(-nx, nDotD), gt = limitedSelect(ny, nDotD);
    const float b = tw * (k.biasConstant + k.biasSlope * std::sqrt(gs * gs + gt * gt));
    const float fi = std::floor(ms), fj = std::floor(mt);
    const float thr = lz + gs * tw * (fi + 0.5f - ms) + gt * tw * (fj + 0.5f - mt) - b;
    // A receiver outside the map is makeReceiver's: s, t and depth where they are in front of the
    // light, the rest 0; behind a local light, all 0.
    s[x] = inFront ? ms : 0.0f;
    t[x] = inFront ? mt : 0.0f;
    z[x] = inFront ? lz : 0.0f;
    dzds[x] = inside ? gs * tw : 0.0f;
    dzdt[x] = inside ? gt * tw : 0.0f;
    biasOut[x] = inside ? b : 0.0f;
    texelWorld[x] = inside ? tw : 0.0f;
    threshold[x] = inside ? thr : 0.0f;
    // Outside the map the index is not read; clamped so that the conversion stays defined.
    const float ci = fi >= 0.0f ? (fi <= k.size - 1.0f ? fi : k.size - 1.0f) : 0.0f;
    const float cj = fj >= 0.0f ? (fj <= k.size - 1.0f ? fj : k.size - 1.0f) : 0.0f;
    texel[x] = inside ? static_cast<int32_t>(cj) * k.mapSize + static_cast<int32_t>(ci) : 0;
    inMap[x] = inside ? 1 : 0;
  }
}

// The two projections' loops, each compiled for every target of PENUMBRA_KERNEL_CLONES.
#define PENUMBRA_RECEIVER_ROW_PARAMETERS                                                                               \
  const ReceiverRowConstants k, size_t n, const float *__restrict position, const float *__restrict normal,            \
      float *__restrict s, float *__restrict t, float *__restrict z, float *__restrict dzds, float *__restrict dzdt,   \
      float *__restrict biasOut, float *__restrict texelWorld, float *__restrict threshold, int32_t *__restrict texel, \
      int32_t *__restrict inMap
PENUMBRA_RECEIVER_CLONES void receiverRowOrtho(PENUMBRA_RECEIVER_ROW_PARAMETERS) {
  receiverRowKernel<true>(k, n, position, normal, s, t, z, dzds, dzdt, biasOut, texelWorld, threshold, texel, inMap);
}
PENUMBRA_RECEIVER_CLONES void receiverRowPerspective(PENUMBRA_RECEIVER_ROW_PARAMETERS) {
  receiverRowKernel<false>(k, n, position, normal, s, t, z, dzds, dzdt, biasOut, texelWorld, threshold, texel, inMap);
}
#undef PENUMBRA_RECEIVER_ROW_PARAMETERS

}  // namespace

namespace {

void receiverRow(const LightMap& frame, const Vec3& lsOffset, const LightMap& map, const Vec3* wsPositions,
                 const Vec3* wsGeometricNormals, int count, const DepthBias& bias, ReceiverRow& out) {
  const auto n = static_cast<size_t>(std::max(count, 0));
  for (auto* field :
       {&out.s, &out.t, &out.lsDepth, &out.dzds, &out.dzdt, &out.bias, &out.texelWorld, &out.nearestThreshold})
    field->resize(n);
  out.inMap.resize(n);
  out.nearestTexel.resize(n);
  const ReceiverRowConstants k{frame.wsOrigin.x,
                               frame.wsOrigin.y,
                               frame.wsOrigin.z,
                               frame.lsFrame.x.x,
                               frame.lsFrame.x.y,
                               frame.lsFrame.x.z,
                               frame.lsFrame.y.x,
                               frame.lsFrame.y.y,
                               frame.lsFrame.y.z,
                               frame.lsFrame.z.x,
                               frame.lsFrame.z.y,
                               frame.lsFrame.z.z,
                               lsOffset.x,
                               lsOffset.y,
                               lsOffset.z,
                               static_cast<float>(map.size),
                               0.5f * static_cast<float>(map.size),
                               map.halfWidth,
                               map.tanHalfFov,
                               bias.constantTexels,
                               bias.slope,
                               map.windowOffset.x,
                               map.windowOffset.y,
                               map.size};
  static_assert(sizeof(Vec3) == 3 * sizeof(float));
  const auto* position = reinterpret_cast<const float*>(wsPositions);
  const auto* normal = reinterpret_cast<const float*>(wsGeometricNormals);
  (map.orthographic ? receiverRowOrtho : receiverRowPerspective)(
      k, n, position, normal, out.s.data(), out.t.data(), out.lsDepth.data(), out.dzds.data(), out.dzdt.data(),
      out.bias.data(), out.texelWorld.data(), out.nearestThreshold.data(), out.nearestTexel.data(), out.inMap.data());
}

}  // namespace

void makeReceiverRow(const LightMap& map, const Vec3* wsPositions, const Vec3* wsGeometricNormals, int count,
                     const DepthBias& bias, ReceiverRow& out) {
  receiverRow(map, Vec3(0.0f), map, wsPositions, wsGeometricNormals, count, bias, out);
}

void makeReceiverRowInFrame(const LightMap& frame, const Vec3& lsOffset, const LightMap& map, const Vec3* wsPositions,
                            const Vec3* wsGeometricNormals, int count, const DepthBias& bias, ReceiverRow& out) {
  receiverRow(frame, lsOffset, map, wsPositions, wsGeometricNormals, count, bias, out);
}

float pcfBox(const LightMap& map, const ShadowReceiver& r, float s, float t, float widthTexels) {
  const float half = 0.5f * widthTexels;
  const float s0 = s - half, s1 = s + half, t0 = t - half, t1 = t + half;
  const int i0 = static_cast<int>(std::floor(s0)), i1 = static_cast<int>(std::floor(s1));
  const int j0 = static_cast<int>(std::floor(t0)), j1 = static_cast<int>(std::floor(t1));
  // A box wholly inside the map (nearly every pixel's): what depends on the column alone (its weight
  // and its term of blockerThreshold) is computed once, not once per row, and no texel is
  // bounds-checked. The same values are summed in the same order as below, so V is the same to the bit.
  constexpr int kMaxColumns = 72;
  const int columns = i1 - i0 + 1;
  if (columns <= kMaxColumns && i0 >= 0 && j0 >= 0 && i1 < map.size && j1 < map.size) {
    float weight[kMaxColumns], along[kMaxColumns];
    for (int k = 0; k < columns; ++k) {
      const float fi = static_cast<float>(i0 + k);
      weight[k] = std::min(s1, fi + 1.0f) - std::max(s0, fi);
      along[k] = r.dzds * (fi + 0.5f - r.s);
    }
    float sum = 0.0f;
    for (int j = j0; j <= j1; ++j) {
      const float fj = static_cast<float>(j);
      const float wt = std::min(t1, fj + 1.0f) - std::max(t0, fj);
      const float across = r.dzdt * (fj + 0.5f - r.t);
      const float* depth = map.lsDepth.row(j) + i0;
      float row = 0.0f;
      for (int k = 0; k < columns; ++k)  // blockerThreshold: ((z + along) + across) - bias
        row += weight[k] * (depth[k] < r.lsDepth + along[k] + across - r.bias ? 0.0f : 1.0f);
      sum += wt * row;
    }
    return std::clamp(sum / (widthTexels * widthTexels), 0.0f, 1.0f);
  }
  float sum = 0.0f;
  for (int j = j0; j <= j1; ++j) {
    const float fj = static_cast<float>(j);
    const float wt = std::min(t1, fj + 1.0f) - std::max(t0, fj);
    float row = 0.0f;
    for (int i = i0; i <= i1; ++i) {
      const float fi = static_cast<float>(i);
      const float ws = std::min(s1, fi + 1.0f) - std::max(s0, fi);
      row += ws * litAtTexel(map, r, i, j);
    }
    sum += wt * row;
  }
  // The weights sum to width^2 up to rounding; keep V within [0, 1] exactly.
  return std::clamp(sum / (widthTexels * widthTexels), 0.0f, 1.0f);
}

std::vector<Vec2> vogelDisk(int n) {
  std::vector<Vec2> pattern(static_cast<size_t>(std::max(n, 0)));
  const float goldenAngle = kPi * (3.0f - std::sqrt(5.0f));
  for (int i = 0; i < n; ++i) {
    const float radius = std::sqrt((static_cast<float>(i) + 0.5f) / static_cast<float>(n));
    const float angle = static_cast<float>(i) * goldenAngle;
    pattern[static_cast<size_t>(i)] = radius * Vec2(std::cos(angle), std::sin(angle));
  }
  return pattern;
}

Vec2 pixelRotation(int x, int y) {
  const uint32_t h =
      hashCombine(static_cast<uint64_t>(static_cast<uint32_t>(x)), static_cast<uint64_t>(static_cast<uint32_t>(y)));
  const float angle = static_cast<float>(h) * (2.0f * kPi / 4294967296.0f);
  return Vec2(std::cos(angle), std::sin(angle));
}

PixelRotations::PixelRotations() : table_(kCount) {
  std::array<std::pair<uint32_t, int>, kCount> cells;
  for (int cell = 0; cell < kCount; ++cell)
    cells[static_cast<size_t>(cell)] = {
        hashCombine(static_cast<uint64_t>(cell & (kTile - 1)), static_cast<uint64_t>(cell >> kTileBits)), cell};
  std::sort(cells.begin(), cells.end());  // ties (none in practice) broken by the cell: deterministic
  for (int k = 0; k < kCount; ++k) {
    const float angle = static_cast<float>(k) * (2.0f * kPi / static_cast<float>(kCount));
    table_[static_cast<size_t>(cells[static_cast<size_t>(k)].second)] = Vec2(std::cos(angle), std::sin(angle));
  }
}

namespace {

// The disk kernels run in chunks of taps, in three phases: (1) the arithmetic of every tap (rotated
// offset, texel, weights, compare thresholds) in loops over plain arrays that GCC vectorizes, (2) the
// scattered map reads alone, (3) the compares and weights, vectorized again, summed in four lanes so
// no tap waits for the previous one's add. Phase 1 evaluates blockerThreshold's expression term by
// term in its order and phase 3's compare is exact, so a tap sees the blocker litAtTexel sees.
// Written without float selects or std::floor, which GCC vectorizes only with -fno-trapping-math (this
// file has it now, for makeReceiverRow; these kernels were written before and need it not).
constexpr size_t kTapChunk = 64;
constexpr size_t kLanes = 4;  // the partial sums below are combined as four
static_assert(kTapChunk % kLanes == 0);

// Offsets of pattern[first, first + n): each p rotated by `rotation` (cos, sin), then scaled to
// radiusTexels.
inline void rotatedOffsets(std::span<const Vec2> pattern, size_t first, size_t n, float radiusTexels,
                           const Vec2& rotation, float* __restrict ox, float* __restrict oy) {
  const Vec2* p = pattern.data() + first;
  for (size_t k = 0; k < n; ++k) {
    ox[k] = radiusTexels * (p[k].x * rotation.x - p[k].y * rotation.y);
    oy[k] = radiusTexels * (p[k].x * rotation.y + p[k].y * rotation.x);
  }
}

// std::floor(x) as an int for |x| < 2^31: truncate, then subtract one where the truncation went up,
// read from the sign bit of the difference (+ 0.0f turns the -0 of x = -0 into +0, so floor(-0) = 0).
inline int32_t floorToInt(float x) {
  const int32_t truncated = static_cast<int32_t>(x);
  const float diff = (x - static_cast<float>(truncated)) + 0.0f;
  return truncated + (std::bit_cast<int32_t>(diff) >> 31);
}

// -1 (all bits) where depth < threshold, else 0: the sign of depth - threshold, which float rounding
// cannot flip (the difference of two different floats is never rounded to zero or across it; equal
// values give +0). Depth +inf (an empty texel, or one outside the map) is never a blocker; the
// threshold is finite.
inline int32_t blockerMask(float depth, float threshold) { return std::bit_cast<int32_t>(depth - threshold) >> 31; }

// 1 where the texel lets the light through, 0 where it holds a blocker (litAtTexel's value).
inline float litValue(float depth, float threshold) { return static_cast<float>(1 + blockerMask(depth, threshold)); }

// Whether texels [iMin, iMax] x [jMin, jMax] all lie in the map.
inline bool insideMap(const DepthTexels& map, int iMin, int jMin, int iMax, int jMax) {
  return iMin >= 0 && jMin >= 0 && iMax < map.size && jMax < map.size;
}

// The depth of texel (i, j); +inf outside the map (holds nothing).
inline float depthOrEmpty(const DepthTexels& map, int i, int j) {
  return i < 0 || j < 0 || i >= map.size || j >= map.size
             ? kInfinity
             : map.depth[static_cast<size_t>(j) * map.stride + static_cast<size_t>(i)];
}

// sum of v[0, n) in kLanes interleaved partial sums; v is zero from n up to the next multiple of kLanes.
inline float laneSum(const float* __restrict v, size_t n) {
  float lane[kLanes] = {};
  for (size_t k = 0; k < n; k += kLanes)
    for (size_t l = 0; l < kLanes; ++l) lane[l] += v[k + l];
  return (lane[0] + lane[1]) + (lane[2] + lane[3]);
}

}  // namespace

namespace {

// Phases 1 and 2 of a nearest-texel disk (searchBlockers, pcfDiskNearest) for taps [first, first + n):
// the compare threshold of each tap's texel and the texel's depth (+inf outside the map).
// Inlined so each clone of its callers gets its own copy.
[[gnu::always_inline]] inline void nearestTaps(const DepthTexels& map, const ShadowReceiver& r, float radiusTexels,
                                               std::span<const Vec2> pattern, const Vec2& rotation, size_t first,
                                               size_t n, float* __restrict threshold, float* __restrict d) {
  alignas(64) float ox[kTapChunk], oy[kTapChunk];
  alignas(64) int32_t ti[kTapChunk], tj[kTapChunk], index[kTapChunk];
  rotatedOffsets(pattern, first, n, radiusTexels, rotation, ox, oy);
  // The texel's index in map.depth, in the vectorized loop. int32 is enough: taps lie within the
  // map's size of (s, t) (the callers limit the radius to it), so |i|, |j| < 2 * 8192.
  const int32_t stride = static_cast<int32_t>(map.stride);
  // A disk that lies inside the map with a texel to spare needs no per-tap bounds (|offset| <= the
  // radius up to rounding, which the spare texel covers).
  const float reach = radiusTexels + 1.0f;
  if (r.s - reach >= 0.0f && r.t - reach >= 0.0f && r.s + reach < static_cast<float>(map.size) &&
      r.t + reach < static_cast<float>(map.size)) {
    for (size_t k = 0; k < n; ++k) {
      const int32_t i = floorToInt(r.s + ox[k]), j = floorToInt(r.t + oy[k]);
      index[k] = j * stride + i;
      threshold[k] = r.lsDepth + r.dzds * (static_cast<float>(i) + 0.5f - r.s) +
                     r.dzdt * (static_cast<float>(j) + 0.5f - r.t) - r.bias;
    }
    for (size_t k = 0; k < n; ++k) d[k] = map.depth[index[k]];
    return;
  }
  int iMin = map.size, jMin = map.size, iMax = -1, jMax = -1;
  for (size_t k = 0; k < n; ++k) {
    ti[k] = floorToInt(r.s + ox[k]);
    tj[k] = floorToInt(r.t + oy[k]);
    index[k] = tj[k] * stride + ti[k];
    const float fi = static_cast<float>(ti[k]), fj = static_cast<float>(tj[k]);
    threshold[k] = r.lsDepth + r.dzds * (fi + 0.5f - r.s) + r.dzdt * (fj + 0.5f - r.t) - r.bias;
    iMin = std::min(iMin, ti[k]);
    iMax = std::max(iMax, ti[k]);
    jMin = std::min(jMin, tj[k]);
    jMax = std::max(jMax, tj[k]);
  }
  if (insideMap(map, iMin, jMin, iMax, jMax)) {
    for (size_t k = 0; k < n; ++k) d[k] = map.depth[index[k]];
  } else {
    for (size_t k = 0; k < n; ++k) d[k] = depthOrEmpty(map, ti[k], tj[k]);  // taps outside find nothing
  }
}

}  // namespace

#if PENUMBRA_AVX512_KERNELS
// GCC 12's AVX-512 intrinsics start from a deliberately undefined vector (_mm512_undefined_*), which
// its own -Wmaybe-uninitialized reports at every inlined use.
#if !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
namespace {

// The nearest-texel disks (searchBlockers, pcfDiskNearest) 16 taps to a 512-bit vector, where the CPU
// has AVX-512F and the tap count is a multiple of 16 (pcss' 16 + 32): one gather per 16 taps instead
// of GCC's 16 scalar loads, and no loop remainders. Every lane computes what the scalar kernels
// compute, with the same operations in the same order and no multiply-add, and the sums keep
// laneSum's order (four partial sums over quarters, per chunk of kTapChunk), so V is bit-identical to
// the other clones.
bool cpuHasAvx512() {
  static const bool has = __builtin_cpu_supports("avx512f");
  return has;
}

// Taps [0, 16) of p split into their x and y parts.
[[gnu::target("avx512f")]] inline void deinterleave16(const Vec2* p, __m512& px, __m512& py) {
  static_assert(sizeof(Vec2) == 2 * sizeof(float));
  const __m512 lo = _mm512_loadu_ps(&p[0].x), hi = _mm512_loadu_ps(&p[8].x);
  const __m512i even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
  const __m512i odd = _mm512_add_epi32(even, _mm512_set1_epi32(1));
  px = _mm512_permutex2var_ps(lo, even, hi);
  py = _mm512_permutex2var_ps(lo, odd, hi);
}

// Sixteen taps at pattern offsets (px, py): each tap's compare threshold and its texel's depth (+inf
// outside the map).
[[gnu::target("avx512f")]] inline void nearestTaps16(const DepthTexels& map, const ShadowReceiver& r,
                                                     float radiusTexels, __m512 px, __m512 py, const Vec2& rotation,
                                                     bool diskInsideMap, __m512& threshold, __m512& depth) {
  const __m512 cosA = _mm512_set1_ps(rotation.x), sinA = _mm512_set1_ps(rotation.y);
  const __m512 radius = _mm512_set1_ps(radiusTexels);
  const __m512 ox = _mm512_mul_ps(radius, _mm512_sub_ps(_mm512_mul_ps(px, cosA), _mm512_mul_ps(py, sinA)));
  const __m512 oy = _mm512_mul_ps(radius, _mm512_add_ps(_mm512_mul_ps(px, sinA), _mm512_mul_ps(py, cosA)));
  const __m512 s = _mm512_set1_ps(r.s), t = _mm512_set1_ps(r.t);
  // floor as an int (floorToInt's value for every |x| < 2^31).
  constexpr int kFloor = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;
  const __m512i i = _mm512_cvt_roundps_epi32(_mm512_add_ps(s, ox), kFloor);
  const __m512i j = _mm512_cvt_roundps_epi32(_mm512_add_ps(t, oy), kFloor);
  const __m512 half = _mm512_set1_ps(0.5f);
  const __m512 a = _mm512_mul_ps(_mm512_set1_ps(r.dzds), _mm512_sub_ps(_mm512_add_ps(_mm512_cvtepi32_ps(i), half), s));
  const __m512 b = _mm512_mul_ps(_mm512_set1_ps(r.dzdt), _mm512_sub_ps(_mm512_add_ps(_mm512_cvtepi32_ps(j), half), t));
  threshold = _mm512_sub_ps(_mm512_add_ps(_mm512_add_ps(_mm512_set1_ps(r.lsDepth), a), b), _mm512_set1_ps(r.bias));
  const __m512i index = _mm512_add_epi32(_mm512_mullo_epi32(j, _mm512_set1_epi32(static_cast<int32_t>(map.stride))), i);
  if (diskInsideMap) {
    depth = _mm512_i32gather_ps(index, map.depth, 4);
    return;
  }
  const __m512i zero = _mm512_setzero_si512(), size = _mm512_set1_epi32(map.size);
  const __mmask16 inside = _mm512_cmpge_epi32_mask(i, zero) & _mm512_cmpge_epi32_mask(j, zero) &
                           _mm512_cmplt_epi32_mask(i, size) & _mm512_cmplt_epi32_mask(j, size);
  depth = _mm512_mask_i32gather_ps(_mm512_set1_ps(kInfinity), inside, index, map.depth, 4);
}

// laneSum of one chunk's values, given as its quarters' running sum: (l0 + l1) + (l2 + l3).
[[gnu::target("avx512f")]] inline float quarterLanes(__m128 lanes) {
  alignas(16) float l[4];
  _mm_store_ps(l, lanes);
  return (l[0] + l[1]) + (l[2] + l[3]);
}

// lanes += the four quarters of v, in order (laneSum's partial sums, four taps at a time).
[[gnu::target("avx512f")]] inline __m128 addQuarters(__m128 lanes, __m512 v) {
  lanes = _mm_add_ps(lanes, _mm512_castps512_ps128(v));
  lanes = _mm_add_ps(lanes, _mm512_extractf32x4_ps(v, 1));
  lanes = _mm_add_ps(lanes, _mm512_extractf32x4_ps(v, 2));
  return _mm_add_ps(lanes, _mm512_extractf32x4_ps(v, 3));
}

// Whether a disk of radiusTexels around (s, t) lies inside the map with a texel to spare (nearestTaps).
inline bool diskInside(const DepthTexels& map, const ShadowReceiver& r, float radiusTexels) {
  const float reach = radiusTexels + 1.0f;
  return r.s - reach >= 0.0f && r.t - reach >= 0.0f && r.s + reach < static_cast<float>(map.size) &&
         r.t + reach < static_cast<float>(map.size);
}

// One group of 16 search taps at pattern offsets (px, py): adds its blocked taps to `blockers` and their
// depths to the running quarter sums `lanes` (laneSum's order).
[[gnu::target("avx512f")]] inline void blockerTaps16(const DepthTexels& map, const ShadowReceiver& r,
                                                     float radiusTexels, __m512 px, __m512 py, const Vec2& rotation,
                                                     bool diskInsideMap, int& blockers, __m128& lanes) {
  __m512 threshold, d;
  nearestTaps16(map, r, radiusTexels, px, py, rotation, diskInsideMap, threshold, d);
  const __mmask16 blocked = _mm512_cmp_ps_mask(d, threshold, _CMP_LT_OQ);
  blockers += std::popcount(static_cast<unsigned>(blocked));
  lanes = addQuarters(lanes, _mm512_maskz_mov_ps(blocked, d));
}

// A search's result from its blocked taps and the sum of their depths.
inline BlockerSearch blockerResult(int blockers, float depthSum) {
  BlockerSearch result;
  result.blockers = blockers;
  if (blockers > 0) result.meanDepth = depthSum / static_cast<float>(blockers);
  return result;
}

[[gnu::target("avx512f")]] BlockerSearch searchBlockers16(const DepthTexels& map, const ShadowReceiver& r,
                                                          float radiusTexels, std::span<const Vec2> pattern,
                                                          const Vec2& rotation) {
  const bool inside = diskInside(map, r, radiusTexels);
  int blockers = 0;
  float depthSum = 0.0f;
  for (size_t first = 0; first < pattern.size(); first += kTapChunk) {
    const size_t n = std::min(kTapChunk, pattern.size() - first);
    __m128 lanes = _mm_setzero_ps();
    for (size_t k = 0; k < n; k += 16) {
      __m512 px, py;
      deinterleave16(pattern.data() + first + k, px, py);
      blockerTaps16(map, r, radiusTexels, px, py, rotation, inside, blockers, lanes);
    }
    depthSum += quarterLanes(lanes);
  }
  return blockerResult(blockers, depthSum);
}

// searchBlockersRow with 16 taps (pcss' default search): the pattern split once per row, the receivers
// read from the row, each pixel's search searchBlockers16's, operation for operation.
[[gnu::target("avx512f")]] void searchBlockersRow16(const DepthTexels& map, const ReceiverRow& receivers,
                                                    std::span<const int32_t> pixels, const float* radiusTexels,
                                                    const Vec2* rotations, std::span<const Vec2> pattern,
                                                    BlockerSearch* out) {
  __m512 px, py;
  deinterleave16(pattern.data(), px, py);
  for (const int32_t x : pixels) {
    const ShadowReceiver r = receivers[x];
    const auto i = static_cast<size_t>(x);
    int blockers = 0;
    __m128 lanes = _mm_setzero_ps();
    blockerTaps16(map, r, radiusTexels[i], px, py, rotations[i], diskInside(map, r, radiusTexels[i]), blockers, lanes);
    // searchBlockers16's sum starts from 0: 0 + s is s for the non-negative sums here.
    out[i] = blockerResult(blockers, quarterLanes(lanes));
  }
}

[[gnu::target("avx512f")]] inline float pcfDiskNearest16(const DepthTexels& map, const ShadowReceiver& r,
                                                         float radiusTexels, std::span<const Vec2> pattern,
                                                         const Vec2& rotation) {
  const bool inside = diskInside(map, r, radiusTexels);
  const __m512 one = _mm512_set1_ps(1.0f);
  float sum = 0.0f;
  for (size_t first = 0; first < pattern.size(); first += kTapChunk) {
    const size_t n = std::min(kTapChunk, pattern.size() - first);
    __m128 lanes = _mm_setzero_ps();
    for (size_t k = 0; k < n; k += 16) {
      __m512 threshold, d;
      __m512 px, py;
      deinterleave16(pattern.data() + first + k, px, py);
      nearestTaps16(map, r, radiusTexels, px, py, rotation, inside, threshold, d);
      const __mmask16 lit = _mm512_cmp_ps_mask(d, threshold, _CMP_NLT_UQ);
      lanes = addQuarters(lanes, _mm512_maskz_mov_ps(lit, one));
    }
    sum += quarterLanes(lanes);
  }
  return sum / static_cast<float>(pattern.size());
}

// pcfDisk's taps 16 at a time (AVX-512F), as the scalar loop computes them.
[[gnu::target("avx512f")]] inline float pcfDisk16(const DepthTexels& map, const ShadowReceiver& r, float radiusTexels,
                                                  std::span<const Vec2> pattern, const Vec2& rotation) {
  // Each tap reads texels up to 1.5 texels beyond the disk (its 1-texel box, and floor's texel).
  const bool inside = diskInside(map, r, radiusTexels + 1.0f);
  const __m512i even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
  const __m512i odd = _mm512_add_epi32(even, _mm512_set1_epi32(1));
  const __m512 cosA = _mm512_set1_ps(rotation.x), sinA = _mm512_set1_ps(rotation.y);
  const __m512 radius = _mm512_set1_ps(radiusTexels), half = _mm512_set1_ps(0.5f), one = _mm512_set1_ps(1.0f);
  const __m512 s = _mm512_set1_ps(r.s), t = _mm512_set1_ps(r.t), lsDepth = _mm512_set1_ps(r.lsDepth);
  const __m512 dzds = _mm512_set1_ps(r.dzds), dzdt = _mm512_set1_ps(r.dzdt), bias = _mm512_set1_ps(r.bias);
  const __m512i stride = _mm512_set1_epi32(static_cast<int32_t>(map.stride)), size = _mm512_set1_epi32(map.size);
  const __m512i zero = _mm512_setzero_si512(), unit = _mm512_set1_epi32(1);
  const __m512 empty = _mm512_set1_ps(kInfinity);
  constexpr int kFloor = _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC;
  float sum = 0.0f;
  for (size_t first = 0; first < pattern.size(); first += kTapChunk) {
    const size_t n = std::min(kTapChunk, pattern.size() - first);
    __m128 lanes = _mm_setzero_ps();
    for (size_t k = 0; k < n; k += 16) {
      const Vec2* p = pattern.data() + first + k;
      const __m512 lo = _mm512_loadu_ps(&p[0].x), hi = _mm512_loadu_ps(&p[8].x);
      const __m512 px = _mm512_permutex2var_ps(lo, even, hi), py = _mm512_permutex2var_ps(lo, odd, hi);
      const __m512 ox = _mm512_mul_ps(radius, _mm512_sub_ps(_mm512_mul_ps(px, cosA), _mm512_mul_ps(py, sinA)));
      const __m512 oy = _mm512_mul_ps(radius, _mm512_add_ps(_mm512_mul_ps(px, sinA), _mm512_mul_ps(py, cosA)));
      const __m512 sc = _mm512_sub_ps(_mm512_add_ps(s, ox), half), tc = _mm512_sub_ps(_mm512_add_ps(t, oy), half);
      const __m512i i = _mm512_cvt_roundps_epi32(sc, kFloor), j = _mm512_cvt_roundps_epi32(tc, kFloor);
      const __m512 fs = _mm512_cvtepi32_ps(i), ft = _mm512_cvtepi32_ps(j);
      const __m512 ws = _mm512_sub_ps(sc, fs), wt = _mm512_sub_ps(tc, ft);
      const __m512 a0 = _mm512_mul_ps(dzds, _mm512_sub_ps(_mm512_add_ps(fs, half), s));
      const __m512 a1 = _mm512_mul_ps(dzds, _mm512_sub_ps(_mm512_add_ps(fs, _mm512_set1_ps(1.5f)), s));
      const __m512 b0 = _mm512_mul_ps(dzdt, _mm512_sub_ps(_mm512_add_ps(ft, half), t));
      const __m512 b1 = _mm512_mul_ps(dzdt, _mm512_sub_ps(_mm512_add_ps(ft, _mm512_set1_ps(1.5f)), t));
      const __m512 t00 = _mm512_sub_ps(_mm512_add_ps(_mm512_add_ps(lsDepth, a0), b0), bias);
      const __m512 t10 = _mm512_sub_ps(_mm512_add_ps(_mm512_add_ps(lsDepth, a1), b0), bias);
      const __m512 t01 = _mm512_sub_ps(_mm512_add_ps(_mm512_add_ps(lsDepth, a0), b1), bias);
      const __m512 t11 = _mm512_sub_ps(_mm512_add_ps(_mm512_add_ps(lsDepth, a1), b1), bias);
      const __m512i index = _mm512_add_epi32(_mm512_mullo_epi32(j, stride), i);
      __m512 d00, d10, d01, d11;
      if (inside) {
        d00 = _mm512_i32gather_ps(index, map.depth, 4);
        d10 = _mm512_i32gather_ps(_mm512_add_epi32(index, unit), map.depth, 4);
        d01 = _mm512_i32gather_ps(_mm512_add_epi32(index, stride), map.depth, 4);
        d11 = _mm512_i32gather_ps(_mm512_add_epi32(index, _mm512_add_epi32(stride, unit)), map.depth, 4);
      } else {
        const __m512i i1 = _mm512_add_epi32(i, unit), j1 = _mm512_add_epi32(j, unit);
        const __mmask16 col0 = _mm512_cmpge_epi32_mask(i, zero) & _mm512_cmplt_epi32_mask(i, size);
        const __mmask16 col1 = _mm512_cmpge_epi32_mask(i1, zero) & _mm512_cmplt_epi32_mask(i1, size);
        const __mmask16 row0 = _mm512_cmpge_epi32_mask(j, zero) & _mm512_cmplt_epi32_mask(j, size);
        const __mmask16 row1 = _mm512_cmpge_epi32_mask(j1, zero) & _mm512_cmplt_epi32_mask(j1, size);
        d00 = _mm512_mask_i32gather_ps(empty, col0 & row0, index, map.depth, 4);
        d10 = _mm512_mask_i32gather_ps(empty, col1 & row0, _mm512_add_epi32(index, unit), map.depth, 4);
        d01 = _mm512_mask_i32gather_ps(empty, col0 & row1, _mm512_add_epi32(index, stride), map.depth, 4);
        d11 = _mm512_mask_i32gather_ps(empty, col1 & row1, _mm512_add_epi32(index, _mm512_add_epi32(stride, unit)),
                                       map.depth, 4);
      }
      const __m512 l00 = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(d00, t00, _CMP_NLT_UQ), one);
      const __m512 l10 = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(d10, t10, _CMP_NLT_UQ), one);
      const __m512 l01 = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(d01, t01, _CMP_NLT_UQ), one);
      const __m512 l11 = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(d11, t11, _CMP_NLT_UQ), one);
      const __m512 top = _mm512_add_ps(l00, _mm512_mul_ps(ws, _mm512_sub_ps(l10, l00)));
      const __m512 bottom = _mm512_add_ps(l01, _mm512_mul_ps(ws, _mm512_sub_ps(l11, l01)));
      lanes = addQuarters(lanes, _mm512_add_ps(top, _mm512_mul_ps(wt, _mm512_sub_ps(bottom, top))));
    }
    sum += quarterLanes(lanes);
  }
  return std::clamp(sum / static_cast<float>(pattern.size()), 0.0f, 1.0f);
}

// pcfDiskRow and pcfDiskNearestRow with a 16-tap kernel (pcfDisk16 or pcfDiskNearest16, inlined here):
// each pixel's filter the per-pixel call's.
template <float (*kKernel)(const DepthTexels&, const ShadowReceiver&, float, std::span<const Vec2>, const Vec2&)>
[[gnu::target("avx512f")]] void filterRow16(const DepthTexels& map, const ReceiverRow& receivers,
                                            std::span<const int32_t> pixels, const float* radiusTexels,
                                            const Vec2* rotations, std::span<const Vec2> pattern, float* out) {
  for (const int32_t x : pixels) {
    const auto i = static_cast<size_t>(x);
    out[i] = kKernel(map, receivers[x], radiusTexels[i], pattern, rotations[i]);
  }
}

}  // namespace
#if !defined(__clang__)
#pragma GCC diagnostic pop
#endif
#endif

namespace {

// A kernel over a row's listed pixels (..Row16 below), and one pixel's (searchBlockers, pcfDisk, ...).
template <class Out>
using RowKernel = void (*)(const DepthTexels&, const ReceiverRow&, std::span<const int32_t>, const float*, const Vec2*,
                           std::span<const Vec2>, Out*);
template <class Out>
using PixelKernel = Out (*)(const DepthTexels&, const ShadowReceiver&, float, std::span<const Vec2>, const Vec2&);

// Runs `row16` over the listed pixels where it is given, `vectors` (the pattern suits it) and the CPU
// has AVX-512F; else `perPixel` (which dispatches itself) at each pixel.
template <class Out>
void runRow(RowKernel<Out> row16, bool vectors, PixelKernel<Out> perPixel, const DepthTexels& map,
            const ReceiverRow& receivers, std::span<const int32_t> pixels, const float* radiusTexels,
            const Vec2* rotations, std::span<const Vec2> pattern, Out* out) {
#if PENUMBRA_AVX512_KERNELS
  if (row16 && vectors && cpuHasAvx512()) {
    row16(map, receivers, pixels, radiusTexels, rotations, pattern, out);
    return;
  }
#else
  (void)row16;
  (void)vectors;
#endif
  for (const int32_t x : pixels) {
    const auto i = static_cast<size_t>(x);
    out[i] = perPixel(map, receivers[x], radiusTexels[i], pattern, rotations[i]);
  }
}

#if PENUMBRA_AVX512_KERNELS
constexpr RowKernel<BlockerSearch> kSearchBlockersRow16 = searchBlockersRow16;
constexpr RowKernel<float> kPcfDiskRow16 = filterRow16<pcfDisk16>;
constexpr RowKernel<float> kPcfDiskNearestRow16 = filterRow16<pcfDiskNearest16>;
#else
constexpr RowKernel<BlockerSearch> kSearchBlockersRow16 = nullptr;
constexpr RowKernel<float> kPcfDiskRow16 = nullptr, kPcfDiskNearestRow16 = nullptr;
#endif

}  // namespace

void pcfDiskRow(const DepthTexels& map, const ReceiverRow& receivers, std::span<const int32_t> pixels,
                const float* radiusTexels, const Vec2* rotations, std::span<const Vec2> pattern, float* out) {
  runRow<float>(kPcfDiskRow16, !pattern.empty() && pattern.size() % 16 == 0, pcfDisk, map, receivers, pixels,
                radiusTexels, rotations, pattern, out);
}

void pcfDiskNearestRow(const DepthTexels& map, const ReceiverRow& receivers, std::span<const int32_t> pixels,
                       const float* radiusTexels, const Vec2* rotations, std::span<const Vec2> pattern, float* out) {
  runRow<float>(kPcfDiskNearestRow16, !pattern.empty() && pattern.size() % 16 == 0, pcfDiskNearest, map, receivers,
                pixels, radiusTexels, rotations, pattern, out);
}

PENUMBRA_KERNEL_CLONES
BlockerSearch searchBlockers(const DepthTexels& map, const ShadowReceiver& r, float radiusTexels,
                             std::span<const Vec2> pattern, const Vec2& rotation) {
#if PENUMBRA_AVX512_KERNELS
  if (pattern.size() % 16 == 0 && cpuHasAvx512()) return searchBlockers16(map, r, radiusTexels, pattern, rotation);
#endif
  alignas(64) float threshold[kTapChunk], d[kTapChunk], blockerDepth[kTapChunk];
  int blockers = 0;
  float depthSum = 0.0f;
  for (size_t first = 0; first < pattern.size(); first += kTapChunk) {
    const size_t n = std::min(kTapChunk, pattern.size() - first);
    nearestTaps(map, r, radiusTexels, pattern, rotation, first, n, threshold, d);
    const size_t padded = (n + kLanes - 1) / kLanes * kLanes;
    for (size_t k = n; k < padded; ++k) blockerDepth[k] = 0.0f;
    for (size_t k = 0; k < n; ++k) {
      const int32_t mask = blockerMask(d[k], threshold[k]);
      blockers -= mask;
      blockerDepth[k] = std::bit_cast<float>(std::bit_cast<int32_t>(d[k]) & mask);
    }
    depthSum += laneSum(blockerDepth, padded);
  }
  BlockerSearch result;
  result.blockers = blockers;
  if (blockers > 0) result.meanDepth = depthSum / static_cast<float>(blockers);
  return result;
}

namespace {

// listSearchingPixels' pixels [from, width), added to `result`.
inline void listSearchingPixelsFrom(int from, const int32_t* ids, const ReceiverRow& receivers, int width, float scale,
                                    float zMin, float maxRadius, int32_t* pixels, float* radius, uint8_t* clamped,
                                    float* out, SearchingPixels& result) {
  for (int x = from; x < width; ++x) {
    const auto i = static_cast<size_t>(x);
    const float r = searchRadiusTexels(receivers, i, scale, zMin);
    clamped[i] = r > maxRadius;
    radius[i] = std::min(r, maxRadius);
    out[i] = 1.0f;
    const bool hit = ids[i] != kNoObject;
    const bool search = hit && searchesForBlockers(receivers, i, zMin);
    pixels[result.count] = x;  // kept when the pixel searches: no branch
    result.count += search;
    result.hits += hit;
    result.clamped += search && clamped[i];
  }
}

#if PENUMBRA_AVX512_KERNELS
// listSearchingPixels 16 pixels at a time: the lanes' tests and radii as the scalar loop computes them
// (min(maxRadius, r) is std::min(r, maxRadius), NaN included), the searching lanes compressed into
// the list. The maskz forms, all lanes set, because GCC 12 warns of the plain forms' undefined source.
[[gnu::target("avx512f")]] SearchingPixels listSearchingPixels16(const int32_t* ids, const ReceiverRow& receivers,
                                                                 int width, float scale, float zMin, float maxRadius,
                                                                 int32_t* pixels, float* radius, uint8_t* clamped,
                                                                 float* out) {
  SearchingPixels result;
  const __m512 vScale = _mm512_set1_ps(scale), vZMin = _mm512_set1_ps(zMin), vMax = _mm512_set1_ps(maxRadius);
  const __m512 one = _mm512_set1_ps(1.0f);
  const __m512i none = _mm512_set1_epi32(kNoObject), zero = _mm512_setzero_si512();
  const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const float* lsDepth = receivers.lsDepth.data();
  const float* texelWorld = receivers.texelWorld.data();
  const int32_t* inMap = receivers.inMap.data();
  int x = 0;
  for (; x + 16 <= width; x += 16) {
    const __m512 z = _mm512_loadu_ps(lsDepth + x);
    const __m512 r = _mm512_div_ps(_mm512_mul_ps(vScale, _mm512_sub_ps(z, vZMin)), _mm512_loadu_ps(texelWorld + x));
    const __mmask16 cut = _mm512_cmp_ps_mask(r, vMax, _CMP_GT_OQ);
    _mm512_storeu_ps(radius + x, _mm512_maskz_min_ps(0xFFFF, vMax, r));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(clamped + x),
                     _mm512_maskz_cvtepi32_epi8(0xFFFF, _mm512_maskz_set1_epi32(cut, 1)));
    _mm512_storeu_ps(out + x, one);
    const __mmask16 hit = _mm512_cmpneq_epi32_mask(_mm512_loadu_si512(ids + x), none);
    const __mmask16 search =
        hit & _mm512_cmpneq_epi32_mask(_mm512_loadu_si512(inMap + x), zero) & _mm512_cmp_ps_mask(z, vZMin, _CMP_GT_OQ);
    _mm512_mask_compressstoreu_epi32(pixels + result.count, search, _mm512_add_epi32(_mm512_set1_epi32(x), lane));
    result.count += std::popcount(static_cast<unsigned>(search));
    result.hits += std::popcount(static_cast<unsigned>(hit));
    result.clamped += std::popcount(static_cast<unsigned>(search & cut));
  }
  listSearchingPixelsFrom(x, ids, receivers, width, scale, zMin, maxRadius, pixels, radius, clamped, out, result);
  return result;
}
#endif

}  // namespace

PENUMBRA_KERNEL_CLONES
SearchingPixels listSearchingPixels(const int32_t* ids, const ReceiverRow& receivers, int width, float scale,
                                    float zMin, float maxRadius, int32_t* pixels, float* radius, uint8_t* clamped,
                                    float* out) {
#if PENUMBRA_AVX512_KERNELS
  if (cpuHasAvx512())
    return listSearchingPixels16(ids, receivers, width, scale, zMin, maxRadius, pixels, radius, clamped, out);
#endif
  SearchingPixels result;
  listSearchingPixelsFrom(0, ids, receivers, width, scale, zMin, maxRadius, pixels, radius, clamped, out, result);
  return result;
}

void searchBlockersRow(const DepthTexels& map, const ReceiverRow& receivers, std::span<const int32_t> pixels,
                       const float* radiusTexels, const Vec2* rotations, std::span<const Vec2> pattern,
                       BlockerSearch* out) {
  runRow<BlockerSearch>(kSearchBlockersRow16, pattern.size() == 16, searchBlockers, map, receivers, pixels,
                        radiusTexels, rotations, pattern, out);
}

PENUMBRA_KERNEL_CLONES
float pcfDiskNearest(const DepthTexels& map, const ShadowReceiver& r, float radiusTexels, std::span<const Vec2> pattern,
                     const Vec2& rotation) {
  if (pattern.empty()) return 1.0f;
#if PENUMBRA_AVX512_KERNELS
  if (pattern.size() % 16 == 0 && cpuHasAvx512()) return pcfDiskNearest16(map, r, radiusTexels, pattern, rotation);
#endif
  alignas(64) float threshold[kTapChunk], d[kTapChunk], lit[kTapChunk];
  float sum = 0.0f;
  for (size_t first = 0; first < pattern.size(); first += kTapChunk) {
    const size_t n = std::min(kTapChunk, pattern.size() - first);
    nearestTaps(map, r, radiusTexels, pattern, rotation, first, n, threshold, d);
    const size_t padded = (n + kLanes - 1) / kLanes * kLanes;
    for (size_t k = n; k < padded; ++k) lit[k] = 0.0f;
    for (size_t k = 0; k < n; ++k) lit[k] = litValue(d[k], threshold[k]);
    sum += laneSum(lit, padded);
  }
  return sum / static_cast<float>(pattern.size());  // a count over a count: within [0, 1] exactly
}

PENUMBRA_KERNEL_CLONES
float pcfDisk(const DepthTexels& map, const ShadowReceiver& r, float radiusTexels, std::span<const Vec2> pattern,
              const Vec2& rotation) {
  if (pattern.empty()) return 1.0f;
#if PENUMBRA_AVX512_KERNELS
  if (pattern.size() % 16 == 0 && cpuHasAvx512()) return pcfDisk16(map, r, radiusTexels, pattern, rotation);
#endif
  const float* depth = map.depth;
  const size_t stride = map.stride;
  alignas(64) float ox[kTapChunk], oy[kTapChunk], ws[kTapChunk], wt[kTapChunk], tap[kTapChunk];
  alignas(64) float t00[kTapChunk], t10[kTapChunk], t01[kTapChunk], t11[kTapChunk];
  alignas(64) float d00[kTapChunk], d10[kTapChunk], d01[kTapChunk], d11[kTapChunk];
  alignas(64) int32_t ti[kTapChunk], tj[kTapChunk], index[kTapChunk];
  const int32_t stride32 = static_cast<int32_t>(stride);
  float sum = 0.0f;
  for (size_t first = 0; first < pattern.size(); first += kTapChunk) {
    const size_t n = std::min(kTapChunk, pattern.size() - first);
    rotatedOffsets(pattern, first, n, radiusTexels, rotation, ox, oy);
    int iMin = map.size, jMin = map.size, iMax = -1, jMax = -1;
    for (size_t k = 0; k < n; ++k) {
      // A 1-texel box at (s, t) + o: the four texels around it, bilinear weights.
      const float sc = r.s + ox[k] - 0.5f, tc = r.t + oy[k] - 0.5f;
      ti[k] = floorToInt(sc);
      tj[k] = floorToInt(tc);
      index[k] = tj[k] * stride32 + ti[k];  // int32 is enough: see nearestTaps
      const float fs = static_cast<float>(ti[k]), ft = static_cast<float>(tj[k]);
      ws[k] = sc - fs;
      wt[k] = tc - ft;
      // blockerThreshold of texels (i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1).
      const float a0 = r.dzds * (fs + 0.5f - r.s), a1 = r.dzds * (fs + 1.5f - r.s);
      const float b0 = r.dzdt * (ft + 0.5f - r.t), b1 = r.dzdt * (ft + 1.5f - r.t);
      t00[k] = r.lsDepth + a0 + b0 - r.bias;
      t10[k] = r.lsDepth + a1 + b0 - r.bias;
      t01[k] = r.lsDepth + a0 + b1 - r.bias;
      t11[k] = r.lsDepth + a1 + b1 - r.bias;
      iMin = std::min(iMin, ti[k]);
      iMax = std::max(iMax, ti[k]);
      jMin = std::min(jMin, tj[k]);
      jMax = std::max(jMax, tj[k]);
    }
    if (insideMap(map, iMin, jMin, iMax + 1, jMax + 1)) {
      for (size_t k = 0; k < n; ++k) {
        const float* p = depth + index[k];
        d00[k] = p[0];
        d10[k] = p[1];
        d01[k] = p[stride];
        d11[k] = p[stride + 1];
      }
    } else {
      for (size_t k = 0; k < n; ++k) {
        d00[k] = depthOrEmpty(map, ti[k], tj[k]);
        d10[k] = depthOrEmpty(map, ti[k] + 1, tj[k]);
        d01[k] = depthOrEmpty(map, ti[k], tj[k] + 1);
        d11[k] = depthOrEmpty(map, ti[k] + 1, tj[k] + 1);
      }
    }
    const size_t padded = (n + kLanes - 1) / kLanes * kLanes;
    for (size_t k = n; k < padded; ++k) tap[k] = 0.0f;
    for (size_t k = 0; k < n; ++k) {
      const float l00 = litValue(d00[k], t00[k]), l10 = litValue(d10[k], t10[k]);
      const float l01 = litValue(d01[k], t01[k]), l11 = litValue(d11[k], t11[k]);
      // Lerps written as a + w (b - a): four lit (blocked) texels give exactly 1 (0).
      const float top = l00 + ws[k] * (l10 - l00);
      const float bottom = l01 + ws[k] * (l11 - l01);
      tap[k] = top + wt[k] * (bottom - top);
    }
    sum += laneSum(tap, padded);
  }
  return std::clamp(sum / static_cast<float>(pattern.size()), 0.0f, 1.0f);  // rounding of the weights
}

}  // namespace penumbra
