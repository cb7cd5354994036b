// `brabec`: Brabec & Seidel 2002, "Single Sample Soft Shadows using Depth Maps" — the whole method:
// outer and inner penumbra searches with the object-id test (Sec. 3.2, 3.3), r_max derived from the
// physical light or from the paper's r_scale / r_bias / r_shrink, sub-texel distances and texel
// jitter (Sec. 4.3), the vectorized axis-aligned search (Sec. 4.2) and the adaptive block
// interpolation (Sec. 4.3); and our extension, the coverage bound (on by default). See brabec.h for
// the equations, the units and the deviations.
#include "techniques/shadow_map/brabec.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <memory>
#include <tuple>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/image_fill.h"
#include "core/target_clones.h"
#include "penumbra/error.h"
#include "penumbra/sampling.h"

namespace penumbra {

namespace brabec {
namespace {

// Key of a texel that does not qualify: the bits of +infinity, above every finite distance's.
constexpr int32_t kNoKey = std::bit_cast<int32_t>(kInfinity);

// A texel's squared distance to P' when it meets the search's criterion, +infinity otherwise: for one
// texel (F float, I int32_t) or for four at once (GCC vectors), the same operations either way. Its
// centre sc, jitter (0 without), depth and object id are given. Written as float selects, which GCC
// vectorizes in a loop over texels.
template <bool kInner, bool kIdTest, class F, class I>
inline F qualifyingDistance2(F sc, F jitterS, F jitterT, F depth, I id, float ps, float tc, float pt, float zRow,
                             float dzds, int32_t objectId, float r2) {
  const F inf = F{} + kInfinity;
  const F dx = (sc + jitterS) - ps;
  const F dy = (tc + jitterT) - pt;
  const F d2 = dx * dx + dy * dy;
  // Inner: the receiver plane's layer at this texel's centre; outer: the constant layer (dzds unused).
  F candidate;
  if constexpr (kInner)
    candidate = depth >= zRow + dzds * (sc - ps) ? d2 : inf;
  else
    candidate = depth < zRow ? d2 : inf;
  if constexpr (kIdTest) candidate = (kInner ? (id == objectId) : (id != objectId)) ? candidate : inf;
  return d2 < r2 ? candidate : inf;
}

// One texel's candidacy as an integer key: the bit pattern of its squared distance when it meets
// the criterion (non-negative floats order like their bits), kNoKey otherwise. One bit cast after
// the float selects (GCC vectorizes a select between floats, not one between a bit-cast value and an
// integer constant), so the row loop below becomes compares, blends and an integer min.
template <bool kInner, bool kIdTest, bool kJitter>
inline int32_t texelKey(const float* depth, const int32_t* id, const float* js, const float* jt, int s, float ps,
                        float tc, float pt, float zRow, float dzds, int32_t objectId, float r2) {
  return std::bit_cast<int32_t>(
      qualifyingDistance2<kInner, kIdTest>(static_cast<float>(s) + 0.5f, kJitter ? js[s] : 0.0f, kJitter ? jt[s] : 0.0f,
                                           depth[s], kIdTest ? id[s] : 0, ps, tc, pt, zRow, dzds, objectId, r2));
}

// The smallest key of texels [s0, s1] of one row: the vectorized inner loop of the search.
template <bool kInner, bool kIdTest, bool kJitter>
__attribute__((target_clones("avx2", "default"), noinline)) int32_t rowMinKey(
    const float* __restrict depth, const int32_t* __restrict id, const float* __restrict js, const float* __restrict jt,
    int s0, int s1, float ps, float tc, float pt, float zRow, float dzds, int32_t objectId, float r2) {
  int32_t best = kNoKey;
  for (int s = s0; s <= s1; ++s) {
    const int32_t key = texelKey<kInner, kIdTest, kJitter>(depth, id, js, jt, s, ps, tc, pt, zRow, dzds, objectId, r2);
    best = best < key ? best : key;
  }
  return best;
}

// The same smallest key for a short span (at most kShortSpan texels) of a row of n texels, inline: whole
// groups of four texels from a start within the row that covers [s0, s1], each texel's key from
// qualifyingDistance2 as texelKey's (the same operations lane by lane) and the texels outside [s0, s1] masked to
// kNoKey. Every span takes the same few groups and no remainder loop, where the called loop ran most of
// a short span in its scalar remainder.
constexpr int kShortSpan = 16;
template <bool kInner, bool kIdTest, bool kJitter>
inline int32_t rowMinKeyShort(const float* depth, const int32_t* id, const float* js, const float* jt, int s0, int s1,
                              int n, float ps, float tc, float pt, float zRow, float dzds, int32_t objectId, float r2) {
  using Float4 = float __attribute__((vector_size(16)));
  using Int4 = int32_t __attribute__((vector_size(16)));
  const int groups = (s1 - s0 + 4) / 4;
  const int start = std::min(s0, n - 4 * groups);  // >= 0: the caller checks n >= kShortSpan
  const Int4 lanes = {0, 1, 2, 3};
  Int4 best = {kNoKey, kNoKey, kNoKey, kNoKey};
  for (int g = 0; g < groups; ++g) {
    const int base = start + 4 * g;
    const Int4 s = base + lanes;
    Float4 d, jitterS = {0, 0, 0, 0}, jitterT = {0, 0, 0, 0};
    Int4 ids = {0, 0, 0, 0};
    __builtin_memcpy(&d, depth + base, sizeof d);
    if constexpr (kIdTest) __builtin_memcpy(&ids, id + base, sizeof ids);
    if constexpr (kJitter) {
      __builtin_memcpy(&jitterS, js + base, sizeof jitterS);
      __builtin_memcpy(&jitterT, jt + base, sizeof jitterT);
    }
    const Float4 candidate = qualifyingDistance2<kInner, kIdTest>(
        __builtin_convertvector(s, Float4) + 0.5f, jitterS, jitterT, d, ids, ps, tc, pt, zRow, dzds, objectId, r2);
    Int4 key = reinterpret_cast<Int4>(candidate);
    key = (s >= s0) & (s <= s1) ? key : kNoKey;
    best = key < best ? key : best;
  }
  return std::min(std::min(best[0], best[1]), std::min(best[2], best[3]));
}

// Whether tile (tx, ty) may hold a qualifying texel. Outer: a blocker needs depth < layer (the tile's
// nearest depth tells) and, with ids, an id other than P's (a tile all of P's object has none). Inner:
// a lit texel needs depth >= layer (the tile's farthest depth against the layer's lowest value over
// the tile, at a corner: the float layer is monotone in s and in t) and, with ids, P's id.
template <bool kInner, bool kIdTest>
bool tileMayQualify(const SearchMap& m, const SearchQuery& q, int tx, int ty) {
  // Both loads and every test combined with & and |, not && and ||: no branch and no conditional
  // load, so that the loop over a row of tiles in openTileSpan vectorizes.
  const size_t k = static_cast<size_t>(ty) * m.tilesPerRow + tx;
  if constexpr (kInner) {
    const int32_t id = m.tileObjectId[k];
    const bool idOpen = !kIdTest | (id == kMixedTile) | (id == q.objectId);
    const float sA = static_cast<float>(tx << kTileShift) + 0.5f;
    const float sB = static_cast<float>(std::min(m.size - 1, (tx << kTileShift) + kTileSize - 1)) + 0.5f;
    const float tA = static_cast<float>(ty << kTileShift) + 0.5f;
    const float tB = static_cast<float>(std::min(m.size - 1, (ty << kTileShift) + kTileSize - 1)) + 0.5f;
    const float rowA = q.zLayer + q.dzdt * (tA - q.t), rowB = q.zLayer + q.dzdt * (tB - q.t);
    const float colA = q.dzds * (sA - q.s), colB = q.dzds * (sB - q.s);
    const float lo = std::min(std::min(rowA + colA, rowA + colB), std::min(rowB + colA, rowB + colB));
    return idOpen & (m.tileMaxDepth[k] >= lo);
  } else {
    const bool idOpen = !kIdTest | (m.tileObjectId[k] != q.objectId);
    return (m.tileMinDepth[k] < q.zLayer) & idOpen;
  }
}

// The tiles a search's grid holds along each side (a radius' box of up to 24 x 24 tiles; wider boxes
// take the tiles one run at a time): three 64-bit words of one byte a tile.
constexpr int kGrid = 24;

// The first and the last of tiles tx0 .. tx0 + count - 1 (count <= kGrid) of tile row ty that may qualify,
// as offsets from tx0 (first > last: none): the tests in one loop into bytes, which the compiler
// vectorizes, then the first and the last nonzero byte found by bit scans over three 64-bit words.
template <bool kInner, bool kIdTest>
std::pair<int, int> openTileSpan(const SearchMap& m, const SearchQuery& q, int tx0, int ty, int count, int none) {
  alignas(8) uint8_t open[kGrid] = {};
  for (int i = 0; i < count; ++i) open[i] = tileMayQualify<kInner, kIdTest>(m, q, tx0 + i, ty) ? 1 : 0;
  static_assert(kGrid == 3 * 8);
  uint64_t words[3];
  std::memcpy(words, open, sizeof words);
  int first = none, last = -1;
  for (int w = 2; w >= 0; --w)
    if (words[w]) first = 8 * w + std::countr_zero(words[w]) / 8;
  for (int w = 0; w < 3; ++w)
    if (words[w]) last = 8 * w + (63 - std::countl_zero(words[w])) / 8;
  return {first, last};
}

template <bool kInner, bool kIdTest, bool kJitter>
SearchHit searchRows(const SearchMap& m, const SearchQuery& q) {
  SearchHit hit;
  const int n = m.size;
  const float r2 = q.radius * q.radius;
  const float reach = q.radius + m.maxJitter;
  const int tLo = std::max(0, static_cast<int>(std::floor(q.t - reach - 0.5f)));
  const int tHi = std::min(n - 1, static_cast<int>(std::ceil(q.t + reach - 0.5f)));
  const int sLo = std::max(0, static_cast<int>(std::floor(q.s - reach - 0.5f)));
  const int sHi = std::min(n - 1, static_cast<int>(std::ceil(q.s + reach - 0.5f)));
  if (tLo > tHi || sLo > sHi) return hit;

  // Tiles: which ones may qualify, decided once per search (a grid on the stack when the radius'
  // box spans few enough tiles), and which tile rows hold any such tile, so empty texel rows cost
  // one lookup.
  const bool tiled = m.tileMinDepth != nullptr;
  const int tx0 = sLo >> kTileShift, ty0 = tLo >> kTileShift;
  const int tilesX = (sHi >> kTileShift) - tx0 + 1, tilesY = (tHi >> kTileShift) - ty0 + 1;
  const bool gridded = tiled && tilesX <= kGrid && tilesY <= kGrid;
  // Per tile row: the first and the last tile that may qualify (first > last: none), set when the
  // search first reaches the row (kUnset before): a search that finds its texel within a few rows
  // never looks at the tile rows beyond them.
  constexpr int kUnset = kGrid + 1;
  int firstOpen[kGrid], lastOpen[kGrid];
  if (gridded) std::fill_n(firstOpen, tilesY, kUnset);

  // Lower bound of the squared distance of any texel of row t (its centre line, less the jitter).
  auto rowGap2 = [&](int t) {
    const float g = std::abs(static_cast<float>(t) + 0.5f - q.t) - m.maxJitter;
    return g > 0.0f ? g * g : 0.0f;
  };
  int32_t bestKey = kNoKey;
  if (q.seedS >= sLo && q.seedS <= sHi && q.seedT >= tLo && q.seedT <= tHi) {
    // The seed's key as its row's scan computes it: when it qualifies, it is the answer so far.
    const size_t row = static_cast<size_t>(q.seedT) * n;
    const float tc = static_cast<float>(q.seedT) + 0.5f;
    const float zRow = kInner ? q.zLayer + q.dzdt * (tc - q.t) : q.zLayer;
    const int32_t key = texelKey<kInner, kIdTest, kJitter>(
        m.lsDepth + row, m.objectId + row, kJitter ? m.jitterS + row : nullptr, kJitter ? m.jitterT + row : nullptr,
        q.seedS, q.s, tc, q.t, zRow, q.dzds, q.objectId, r2);
    if (key != kNoKey) {
      bestKey = key;
      hit = {true, std::bit_cast<float>(key), q.seedS, q.seedT};
    }
  }
  int t = std::clamp(static_cast<int>(std::floor(q.t)), tLo, tHi);
  int up = t - 1, down = t + 1;
  // When no tile of row t's tile row may qualify, or row t's chord misses the tiles that may: the tile
  // row's other rows, on either side, are passed over without a visit. Rows come nearest first, so
  // those not yet visited are at least as far as t, their chords no wider about the same s (and the
  // tile row's open tiles the same): none of them has a texel to read. The rows left keep their
  // order, and a row that would have ended the search is at least as far as the next one visited,
  // which ends it the same way.
  auto passOverTileRow = [&] {
    const int rowLo = (t >> kTileShift) << kTileShift, rowHi = rowLo + kTileSize - 1;
    if (up >= rowLo) up = rowLo - 1;
    if (down <= rowHi) down = rowHi + 1;
  };
  for (;;) {
    const float gap2 = rowGap2(t);
    // Rows come nearest first: once a row cannot hold a texel within the radius, or nearer than the
    // best so far (equal may still win the tie on t), no later row can.
    if (gap2 >= r2 || (bestKey != kNoKey && gap2 > std::bit_cast<float>(bestKey))) break;
    const int ty = t >> kTileShift;
    if (gridded && firstOpen[ty - ty0] == kUnset)
      std::tie(firstOpen[ty - ty0], lastOpen[ty - ty0]) = openTileSpan<kInner, kIdTest>(m, q, tx0, ty, tilesX, kGrid);
    if (!gridded || firstOpen[ty - ty0] <= lastOpen[ty - ty0]) {
      // The chord of the radius, or of the best distance so far once a texel is found (a texel at that
      // same distance may still win the tie); small slack so float rounding in sqrt never drops a
      // texel: the exact tests on d2 decide.
      const float bound2 = bestKey != kNoKey ? std::min(r2, std::bit_cast<float>(bestKey)) : r2;
      const float half = std::sqrt(bound2 - gap2) + m.maxJitter + 1e-3f;
      int s0 = std::max(0, static_cast<int>(std::floor(q.s - half - 0.5f)));
      int s1 = std::min(n - 1, static_cast<int>(std::ceil(q.s + half - 0.5f)));
      if (gridded) {  // one scan from the first to the last tile that may qualify
        s0 = std::max(s0, (tx0 + firstOpen[ty - ty0]) << kTileShift);
        s1 = std::min(s1, ((tx0 + lastOpen[ty - ty0]) << kTileShift) + kTileSize - 1);
      }
      if (s0 <= s1) {
        const size_t row = static_cast<size_t>(t) * n;
        const float* depth = m.lsDepth + row;
        const int32_t* id = m.objectId + row;
        const float* js = kJitter ? m.jitterS + row : nullptr;
        const float* jt = kJitter ? m.jitterT + row : nullptr;
        const float tc = static_cast<float>(t) + 0.5f;
        const float zRow = kInner ? q.zLayer + q.dzdt * (tc - q.t) : q.zLayer;
        int32_t key = kNoKey;
        if (!tiled || gridded) {
          key = s1 - s0 < kShortSpan && n >= kShortSpan
                    ? rowMinKeyShort<kInner, kIdTest, kJitter>(depth, id, js, jt, s0, s1, n, q.s, tc, q.t, zRow, q.dzds,
                                                               q.objectId, r2)
                    : rowMinKey<kInner, kIdTest, kJitter>(depth, id, js, jt, s0, s1, q.s, tc, q.t, zRow, q.dzds,
                                                          q.objectId, r2);
        } else {
          // Runs of tiles that may qualify, each scanned in one vectorized loop.
          int runStart = -1;
          for (int seg = s0; seg <= s1;) {
            const int tile = seg >> kTileShift;
            const int segEnd = std::min(s1, ((tile + 1) << kTileShift) - 1);
            const bool skip = !tileMayQualify<kInner, kIdTest>(m, q, tile, ty);
            if (!skip && runStart < 0) runStart = seg;
            if ((skip || segEnd == s1) && runStart >= 0) {
              const int runEnd = skip ? seg - 1 : segEnd;
              key = std::min(key, rowMinKey<kInner, kIdTest, kJitter>(depth, id, js, jt, runStart, runEnd, q.s, tc, q.t,
                                                                      zRow, q.dzds, q.objectId, r2));
              runStart = -1;
            }
            seg = segEnd + 1;
          }
        }
        // Equal keys: the smaller t wins, and in the same row (the seed's) the smaller s, which the scan
        // below finds first.
        if (key != kNoKey && (key < bestKey || (key == bestKey && t <= hit.t))) {
          int s = s0;
          while (texelKey<kInner, kIdTest, kJitter>(depth, id, js, jt, s, q.s, tc, q.t, zRow, q.dzds, q.objectId, r2) !=
                 key)
            ++s;
          bestKey = key;
          hit.found = true;
          hit.s = s;
          hit.t = t;
          hit.distance2 = std::bit_cast<float>(key);
        }
      } else {
        passOverTileRow();
      }
    } else {
      passOverTileRow();
    }
    const bool canUp = up >= tLo, canDown = down <= tHi;
    if (!canUp && !canDown) break;
    if (canUp &&
        (!canDown || std::abs(static_cast<float>(up) + 0.5f - q.t) <= std::abs(static_cast<float>(down) + 0.5f - q.t)))
      t = up--;
    else
      t = down++;
  }
  return hit;
}

template <bool kInner, bool kIdTest>
SearchHit searchDispatchJitter(const SearchMap& m, const SearchQuery& q) {
  return m.jitterS ? searchRows<kInner, kIdTest, true>(m, q) : searchRows<kInner, kIdTest, false>(m, q);
}

}  // namespace

SearchHit searchVectorized(const SearchMap& map, const SearchQuery& query) {
  if (!(query.radius > 0.0f) || map.size <= 0) return {};
  if (query.inner)
    return query.idTest ? searchDispatchJitter<true, true>(map, query) : searchDispatchJitter<true, false>(map, query);
  return query.idTest ? searchDispatchJitter<false, true>(map, query) : searchDispatchJitter<false, false>(map, query);
}

// The oracle: every texel of the radius' bounding box in plain row-major order, the same distance
// expression, the first strictly nearest texel kept (hence ties to the smallest (t, s)).
SearchHit searchScalar(const SearchMap& map, const SearchQuery& q) {
  SearchHit hit;
  if (!(q.radius > 0.0f) || map.size <= 0) return hit;
  const int n = map.size;
  const float r2 = q.radius * q.radius;
  const float reach = q.radius + map.maxJitter + 1.0f;
  const int tLo = std::max(0, static_cast<int>(std::floor(q.t - reach))),
            tHi = std::min(n - 1, static_cast<int>(std::ceil(q.t + reach)));
  const int sLo = std::max(0, static_cast<int>(std::floor(q.s - reach))),
            sHi = std::min(n - 1, static_cast<int>(std::ceil(q.s + reach)));
  for (int t = tLo; t <= tHi; ++t) {
    for (int s = sLo; s <= sHi; ++s) {
      const size_t i = static_cast<size_t>(t) * n + s;
      const float js = map.jitterS ? map.jitterS[i] : 0.0f;
      const float jt = map.jitterT ? map.jitterT[i] : 0.0f;
      const float sc = static_cast<float>(s) + 0.5f, tc = static_cast<float>(t) + 0.5f;
      const float dx = (sc + js) - q.s;
      const float dy = (tc + jt) - q.t;
      const float d2 = dx * dx + dy * dy;
      if (!(d2 < r2)) continue;
      const float depth = map.lsDepth[i];
      const int32_t id = map.objectId[i];
      bool ok;
      if (q.inner)
        ok = depth >= (q.zLayer + q.dzdt * (tc - q.t)) + q.dzds * (sc - q.s) && (!q.idTest || id == q.objectId);
      else
        ok = depth < q.zLayer && (!q.idTest || id != q.objectId);
      if (ok && (!hit.found || d2 < hit.distance2)) {
        hit.found = true;
        hit.distance2 = d2;
        hit.s = s;
        hit.t = t;
      }
    }
  }
  return hit;
}

float texelJitter(int s, int t, int axis, float amplitude) {
  const uint32_t h = hashCombine(hashCombine(static_cast<uint64_t>(s), static_cast<uint64_t>(t)),
                                 static_cast<uint64_t>(axis) + 0x5bd1e995u);
  const float u = static_cast<float>(h >> 8) * (1.0f / 16777216.0f);  // [0, 1)
  return amplitude * (2.0f * u - 1.0f);
}

namespace {

// Texels a, a + stride, ... <= b of one row in front of the receiver plane (depth zRow at s): the
// counting loop of the coverage bound, one compare per texel that the compiler vectorizes.
int countRowBlocked(const float* __restrict depth, int a, int b, int stride, float s, float zRow, float dzds) {
  int blocked = 0;
  if (stride == 1) {
    for (int i = a; i <= b; ++i) blocked += depth[i] < zRow + dzds * (static_cast<float>(i) + 0.5f - s);
  } else {
    for (int i = a; i <= b; i += stride) blocked += depth[i] < zRow + dzds * (static_cast<float>(i) + 0.5f - s);
  }
  return blocked;
}

// The same count over the gathered rows of a footprint (row r: depths rows[r], receiver plane zRows[r],
// its span a[r] .. b[r]), each read over the same columns, those from lo .. hi widened to whole groups
// of four within the rows' `columns`, and only the texels of its own span counted: every row runs the
// same iterations and no row has a remainder loop, where the rows' own spans (a few texels each, all
// different) mispredicted their loops' exits. Column m is texel m * stride (lattice columns when
// stride > 1). The compare is countRowBlocked's to the bit: the plane's offset at a column,
// dzds * ((m * stride + 0.5) - s), is the same for every row and computed once.
int countGatheredRowsBlocked(int rowCount, const float* const* __restrict rows, const float* __restrict zRows,
                             const int* __restrict a, const int* __restrict b, int lo, int hi, int columns, int stride,
                             float s, float dzds) {
  using Float4 = float __attribute__((vector_size(16)));
  using Int4 = int32_t __attribute__((vector_size(16)));
  constexpr int kMaxGroups = 64;
  const int groups = (hi - lo + 4) / 4;
  const int start = std::min(lo, columns - 4 * groups);
  int blocked = 0;
  if (groups > kMaxGroups || start < 0) {  // a footprint too wide for the stack, or a map under 4 columns
    for (int r = 0; r < rowCount; ++r)
      for (int m = a[r]; m <= b[r]; ++m)
        blocked += rows[r][m] < zRows[r] + dzds * (static_cast<float>(m * stride) + 0.5f - s);
    return blocked;
  }
  Float4 offset[kMaxGroups];
  Int4 column[kMaxGroups];
  const Int4 lanes = {0, 1, 2, 3};
  for (int g = 0; g < groups; ++g) {
    column[g] = start + 4 * g + lanes;
    offset[g] = dzds * (__builtin_convertvector(column[g] * stride, Float4) + 0.5f - s);
  }
  Int4 count = {0, 0, 0, 0};
  for (int r = 0; r < rowCount; ++r) {
    const float* row = rows[r] + start;
    const Float4 zRow = {zRows[r], zRows[r], zRows[r], zRows[r]};
    const Int4 ra = {a[r], a[r], a[r], a[r]}, rb = {b[r], b[r], b[r], b[r]};
    for (int g = 0; g < groups; ++g) {
      Float4 depth;
      __builtin_memcpy(&depth, row + 4 * g, sizeof depth);
      // Each compare is -1 where true: a texel counts where it lies in the row's span and in front.
      count += (column[g] >= ra) & (column[g] <= rb) & (depth < zRow + offset[g]);
    }
  }
  return -(count[0] + count[1] + count[2] + count[3]);
}

// Division by the lattice's stride k, the same for every row of a count: a multiply by 1/k and an
// exact correction instead of an integer division per row (|x| far below 2^31 / k here: map texels).
struct StrideDivider {
  explicit StrideDivider(int k) : k(k), inverse(1.0 / k) {}
  int floorDiv(int x) const {
    int q = static_cast<int>(std::floor(static_cast<double>(x) * inverse));
    if (q * k > x) --q;
    if ((q + 1) * k <= x) ++q;
    return q;
  }
  int ceilDiv(int x) const { return -floorDiv(-x); }
  int multipleAtOrAbove(int x) const { return ceilDiv(x) * k; }  //!< the smallest multiple of k >= x
  int k;
  double inverse;
};

// The count over a footprint given row by row: span(j, i0, i1) sets the texels of row j inside it
// (false: none). With stride k > 1 only texels whose s and t are multiples of k count (a lattice fixed
// in the map, so the count moves smoothly with P').
template <class Span>
Coverage countRows(const LightMap& map, const LatticeDepths* lattices, int tLo, int tHi, int stride, float s, float t,
                   float zLayer, float dzds, float dzdt, const Span& span) {
  Coverage c;
  const int n = map.size;
  const StrideDivider divider(stride);
  // The lattice of this stride, if built: row j / k starts at lattice + (j / k) * columns. Its rows and
  // columns are counted along with j and divided by the divider, never by an integer division a row.
  const float* lattice = stride > 1 && lattices ? lattices->row(stride, 0) : nullptr;
  const size_t latticeColumns = lattice ? static_cast<size_t>(lattices->columns(stride)) : 0;
  // The rows are gathered first (their spans, in the columns of the row they are read from) and counted
  // after over the columns of all of them (countGatheredRowsBlocked); a footprint of more rows than the
  // stack holds counts the rest one span at a time, as does a stride without a lattice.
  constexpr int kMaxRows = 64;
  std::array<const float*, kMaxRows> rowDepths;
  std::array<float, kMaxRows> rowZ;
  std::array<int, kMaxRows> rowA, rowB;
  int rowCount = 0, lo = n, hi = -1;
  const bool gathered = stride == 1 || lattice;
  const int jFirst = divider.multipleAtOrAbove(tLo);
  size_t latticeRow = jFirst >= 0 ? static_cast<size_t>(divider.floorDiv(jFirst)) : 0;  // used for j >= 0 only
  const int lastColumn = divider.floorDiv(n - 1);  // the last lattice column (stride 1: the last texel)
  for (int j = jFirst; j <= tHi; j += stride, latticeRow += j > 0) {
    int i0, i1;
    if (!span(j, i0, i1)) continue;
    // The row's lattice columns: texels m * stride for m0 <= m <= m1 (stride 1: the span itself).
    const int m0 = stride > 1 ? divider.ceilDiv(i0) : i0, m1 = stride > 1 ? divider.floorDiv(i1) : i1;
    if (m0 > m1) continue;
    c.total += m1 - m0 + 1;
    if (j < 0 || j >= n) continue;
    // Within the map: columns a .. b.
    const int a = std::max(m0, 0), b = std::min(m1, lastColumn);
    if (a > b) continue;
    const float zRow = zLayer + dzdt * (static_cast<float>(j) + 0.5f - t);
    if (gathered && rowCount < kMaxRows) {
      const auto r = static_cast<size_t>(rowCount++);
      rowDepths[r] = lattice ? lattice + latticeRow * latticeColumns : map.lsDepth.row(j);
      rowZ[r] = zRow;
      rowA[r] = a;
      rowB[r] = b;
      lo = std::min(lo, a);
      hi = std::max(hi, b);
    } else {
      c.blocked += countRowBlocked(map.lsDepth.row(j), a * stride, std::min(i1, n - 1), stride, s, zRow, dzds);
    }
  }
  if (rowCount > 0)
    c.blocked += countGatheredRowsBlocked(rowCount, rowDepths.data(), rowZ.data(), rowA.data(), rowB.data(), lo, hi,
                                          lastColumn + 1, stride, s, dzds);
  return c;
}

}  // namespace

void LatticeDepths::build(const LightMap& map, int maxStride) {
  size_ = map.size;
  lattices_.resize(static_cast<size_t>(std::max(maxStride + 1, 0)));
  for (int k = 2; k <= maxStride; ++k) {
    const int m = columns(k);
    std::vector<float>& lattice = lattices_[static_cast<size_t>(k)];
    lattice.resize(static_cast<size_t>(m) * m);
    tbb::parallel_for(tbb::blocked_range<int>(0, m), [&](const tbb::blocked_range<int>& rows) {
      for (int j = rows.begin(); j < rows.end(); ++j) {
        const float* depth = map.lsDepth.row(j * k);
        float* out = lattice.data() + static_cast<size_t>(j) * m;
        for (int i = 0; i < m; ++i) out[i] = depth[i * k];
      }
    });
  }
}

Coverage countBlocked(const LightMap& map, float s, float t, float zLayer, float dzds, float dzdt, float radius,
                      int stride, const LatticeDepths* lattices) {
  if (!(radius > 0.0f) || stride < 1) return {};
  const float r2 = radius * radius;
  // Row j's chord: the texel centres s_c with |s_c - s| <= sqrt(r^2 - dy^2).
  auto span = [&](int j, int& i0, int& i1) {
    const float dy = static_cast<float>(j) + 0.5f - t;
    const float rest = r2 - dy * dy;
    if (!(rest > 0.0f)) return false;
    const float half = std::sqrt(rest);
    i0 = static_cast<int>(std::ceil(s - half - 0.5f));
    i1 = static_cast<int>(std::floor(s + half - 0.5f));
    return i0 <= i1;
  };
  const int tLo = static_cast<int>(std::ceil(t - radius - 0.5f)), tHi = static_cast<int>(std::floor(t + radius - 0.5f));
  return countRows(map, lattices, tLo, tHi, stride, s, t, zLayer, dzds, dzdt, span);
}

Coverage countBlockedInPolygon(const LightMap& map, float s, float t, float zLayer, float dzds, float dzdt,
                               const std::vector<Vec2>& vertices, float scale, int stride,
                               const LatticeDepths* lattices) {
  const size_t count = vertices.size();
  if (count < 3 || !(scale > 0.0f) || stride < 1) return {};
  float area2 = 0.0f, yLo = kInfinity, yHi = -kInfinity;
  for (size_t k = 0; k < count; ++k) {
    const Vec2& a = vertices[k];
    const Vec2& b = vertices[(k + 1) % count];
    area2 += a.x * b.y - a.y * b.x;
    yLo = std::min(yLo, a.y * scale);
    yHi = std::max(yHi, a.y * scale);
  }
  const float orientation = area2 > 0.0f ? 1.0f : -1.0f;
  // Inside every edge's half-plane: orientation * cross(e, p - a) >= 0 for edge a -> a + e. A slanted
  // edge bounds x on row y at a.x + (e.x / e.y)(y - a.y), below (cx = -orientation e.y > 0) or above;
  // that is scale * offset + slope * y, set up once per count rather than divided out per row. A
  // level edge (e.y = 0) bounds the rows instead: orientation * e.x * (y - a.y) >= 0.
  struct EdgeLine {
    float slope, offset;  //!< x bound = scale * offset + slope * y; level edges: offset is a.y
    int8_t side;          //!< +1 lower bound, -1 upper bound, 0 a level edge
    float levelSign;      //!< level edges: orientation * e.x
  };
  std::array<EdgeLine, 16> local;
  std::vector<EdgeLine> heap;
  EdgeLine* lines = local.data();
  if (count > local.size()) {
    heap.resize(count);
    lines = heap.data();
  }
  for (size_t k = 0; k < count; ++k) {
    const Vec2& a = vertices[k];
    const Vec2 e = vertices[(k + 1) % count] - a;
    const float cx = -orientation * e.y;
    if (cx == 0.0f) {
      lines[k] = {0.0f, a.y * scale, 0, orientation * e.x};
    } else {
      const float slope = e.x / e.y;
      lines[k] = {slope, a.x - slope * a.y, static_cast<int8_t>(cx > 0.0f ? 1 : -1), 0.0f};
    }
  }
  auto span = [&](int j, int& i0, int& i1) {
    const float y = static_cast<float>(j) + 0.5f - t;
    float xLo = -kInfinity, xHi = kInfinity;
    for (size_t k = 0; k < count; ++k) {
      const EdgeLine& line = lines[k];
      const float bound = scale * line.offset + line.slope * y;
      if (line.side > 0)
        xLo = std::max(xLo, bound);
      else if (line.side < 0)
        xHi = std::min(xHi, bound);
      else if (line.levelSign * (y - line.offset) < 0.0f)
        return false;
    }
    if (!(xLo <= xHi)) return false;
    i0 = static_cast<int>(std::ceil(s + xLo - 0.5f));
    i1 = static_cast<int>(std::floor(s + xHi - 0.5f));
    return i0 <= i1;
  };
  const int tLo = static_cast<int>(std::ceil(t + yLo - 0.5f)), tHi = static_cast<int>(std::floor(t + yHi - 0.5f));
  return countRows(map, lattices, tLo, tHi, stride, s, t, zLayer, dzds, dzdt, span);
}

namespace {

// Samples k0 .. k0 + count - 1 of a segment's `total`: the texel each falls in (its index in the map,
// -1 outside it) and the receiver plane's depth at that texel's centre. The set-up of the count in one
// loop over samples that the compiler vectorizes; the depth reads, scattered along the segment, are
// left to countBlockedAlong's short scalar loop.
PENUMBRA_CLONES_AVX512 void segmentSamples(int k0, int count, int total, int n, float s, float t, float hx, float hy,
                                           float zLayer, float dzds, float dzdt, int32_t* __restrict index,
                                           float* __restrict layer) {
  for (int m = 0; m < count; ++m) {
    const float u = (2.0f * static_cast<float>(k0 + m) + 1.0f) / static_cast<float>(total) - 1.0f;
    const int i = static_cast<int>(std::floor(s + u * hx)), j = static_cast<int>(std::floor(t + u * hy));
    index[m] = i >= 0 && j >= 0 && i < n && j < n ? j * n + i : -1;
    layer[m] = zLayer + dzdt * (static_cast<float>(j) + 0.5f - t) + dzds * (static_cast<float>(i) + 0.5f - s);
  }
}

}  // namespace

Coverage countBlockedAlong(const LightMap& map, float s, float t, float zLayer, float dzds, float dzdt, Vec2 half) {
  Coverage c;
  const float length = 2.0f * glm::length(half);
  if (!(length > 0.0f)) return c;
  const int n = map.size;
  const float* const depth = map.lsDepth.data();
  c.total = static_cast<int>(std::ceil(length)) + 1;
  constexpr int kChunk = 64;
  int32_t index[kChunk];
  float layer[kChunk];
  for (int k0 = 0; k0 < c.total; k0 += kChunk) {
    const int count = std::min(kChunk, c.total - k0);
    segmentSamples(k0, count, c.total, n, s, t, half.x, half.y, zLayer, dzds, dzdt, index, layer);
    for (int m = 0; m < count; ++m) c.blocked += index[m] >= 0 && depth[index[m]] < layer[m];
  }
  return c;
}

void buildTiles(const LightMap& map, std::vector<float>& minDepth, std::vector<float>& maxDepth,
                std::vector<int32_t>& objectId, int& tilesPerRow) {
  const int n = map.size;
  tilesPerRow = (n + kTileSize - 1) / kTileSize;
  const size_t count = static_cast<size_t>(tilesPerRow) * tilesPerRow;
  minDepth.resize(count);
  maxDepth.resize(count);
  objectId.resize(count);
  // In parallel over rows of tiles; each tile's texels in row-major order, its summary kept in locals.
  const int tiles = tilesPerRow;
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles), [&](const tbb::blocked_range<int>& tileRows) {
    for (int ty = tileRows.begin(); ty < tileRows.end(); ++ty) {
      const int t0 = ty << kTileShift, t1 = std::min(n, t0 + kTileSize);
      for (int tx = 0; tx < tiles; ++tx) {
        const int s0 = tx << kTileShift, s1 = std::min(n, s0 + kTileSize);
        // The tile's id is its first texel's unless another texel's differs (kMixedTile): a flag over
        // the texels, where a branch per texel on the id seen so far kept the loop scalar.
        float lo = kInfinity, hi = -kInfinity;
        const int32_t first = map.objectId.row(t0)[s0];
        bool mixed = false;
        for (int t = t0; t < t1; ++t) {
          const float* depth = map.lsDepth.row(t);
          const int32_t* ids = map.objectId.row(t);
          for (int s = s0; s < s1; ++s) {
            lo = std::min(lo, depth[s]);
            hi = std::max(hi, depth[s]);
            mixed |= ids[s] != first;
          }
        }
        const size_t k = static_cast<size_t>(ty) * tiles + tx;
        minDepth[k] = lo;
        maxDepth[k] = hi;
        objectId[k] = mixed ? kMixedTile : first;
      }
    }
  });
}

// Inline: the table's build merges every entry of every level three times (out of line, a call each).
[[gnu::always_inline]] inline TileNearestTable::Entry TileNearestTable::merge(const Entry& a, const Entry& b) {
  const Entry& first = b.nearest < a.nearest ? b : a;
  const Entry& second = b.nearest < a.nearest ? a : b;
  // Every tile of `second` lies at or beyond second.nearest; those with an id other than first.id
  // are all of them when second's nearest tile has another id, else its own `other`.
  return {first.nearest, first.id, std::min(first.other, second.id == first.id ? second.other : second.nearest)};
}

void TileNearestTable::build(const std::vector<float>& tileMinDepth, const std::vector<int32_t>& tileObjectId,
                             int tilesPerRow) {
  n_ = tilesPerRow;
  const size_t count = static_cast<size_t>(n_) * n_;
  int levelCount = 1;
  while ((1 << levelCount) <= n_) ++levelCount;
  levels_.resize(static_cast<size_t>(levelCount));
  levels_[0].resize(count);
  for (size_t k = 0; k < count; ++k) levels_[0][k] = {tileMinDepth[k], tileObjectId[k], kInfinity};
  for (int level = 1; level < levelCount; ++level) {
    const std::vector<Entry>& below = levels_[static_cast<size_t>(level - 1)];
    std::vector<Entry>& here = levels_[static_cast<size_t>(level)];
    here.resize(count);
    const int half = 1 << (level - 1);
    // Squares that would reach past the grid are never read (queries fit their level's size).
    const int last = n_ - (1 << level);
    if (last < 0) continue;
    tbb::parallel_for(tbb::blocked_range<int>(0, last + 1, 8), [&](const tbb::blocked_range<int>& rows) {
      for (int ty = rows.begin(); ty < rows.end(); ++ty)
        for (int tx = 0; tx <= last; ++tx) {
          auto at = [&](int x, int y) -> const Entry& { return below[static_cast<size_t>(y) * n_ + x]; };
          here[static_cast<size_t>(ty) * n_ + tx] =
              merge(merge(at(tx, ty), at(tx + half, ty)), merge(at(tx, ty + half), at(tx + half, ty + half)));
        }
    });
  }
}

float TileNearestTable::nearest(int tx0, int tx1, int ty0, int ty1, int32_t objectId, bool idTest) const {
  const int w = tx1 - tx0 + 1, h = ty1 - ty0 + 1;
  int level = 0;
  while ((2 << level) <= std::min(w, h)) ++level;
  const int side = 1 << level;
  const std::vector<Entry>& entries = levels_[static_cast<size_t>(level)];
  float result = kInfinity;
  // Squares at tx0, tx0 + side, ... and one flush with tx1 (likewise in t): they cover the rectangle.
  for (int y = ty0;; y = std::min(y + side, ty1 - side + 1)) {
    for (int x = tx0;; x = std::min(x + side, tx1 - side + 1)) {
      const Entry& e = entries[static_cast<size_t>(y) * n_ + x];
      result = std::min(result, idTest && e.id == objectId ? e.other : e.nearest);
      if (x == tx1 - side + 1) break;
    }
    if (y == ty1 - side + 1) break;
  }
  return result;
}

}  // namespace brabec

BrabecTechnique::BrabecTechnique(const BrabecOptions& options) : options_(options) {
  const int given = int(options.rScale.has_value()) + int(options.rBias.has_value()) + int(options.rShrink.has_value());
  if (given != 0 && given != 3) {
    std::string missing;
    for (const auto& [name, value] : {std::pair{"r_scale", options.rScale}, std::pair{"r_bias", options.rBias},
                                      std::pair{"r_shrink", options.rShrink}})
      if (!value) missing += missing.empty() ? name : std::string(", ") + name;
    fail(
        "brabec: r_scale, r_bias and r_shrink are the paper's knobs and replace the physically derived r_max "
        "together; give all three or none (missing: {})",
        missing);
  }
  if (!(options.meet >= 0.0f && options.meet <= 1.0f))
    fail("brabec: meet = {} is not valid: expected a float in [0, 1]", options.meet);
  if (options.maxRadius < 1)
    fail("brabec: max_radius = {} is not valid: expected an int >= 1 (texels)", options.maxRadius);
  if (!(options.interpolateMaxStep >= 0.0f && options.interpolateMaxStep <= 1.0f))
    fail("brabec: interpolate_max_step = {} is not valid: expected a float in [0, 1]", options.interpolateMaxStep);
  if (!(options.interpolateMaxAngle >= 0.0f && options.interpolateMaxAngle <= 180.0f))
    fail("brabec: interpolate_max_angle = {} is not valid: expected a float in [0, 180] (degrees)",
         options.interpolateMaxAngle);
  if (options.coverageMinTexels < 1)
    fail("brabec: coverage_min_texels = {} is not valid: expected an int >= 1 (texels)", options.coverageMinTexels);
  if (options.coverageSamples < 16)
    fail("brabec: coverage_samples = {} is not valid: expected an int >= 16 (texels)", options.coverageSamples);
  if (!(options.jitter >= 0.0f && options.jitter <= 0.5f))
    fail("brabec: jitter = {} is not valid: expected a float in [0, 0.5] (texels)", options.jitter);
}

void BrabecTechnique::reserveImpl(int width, int height) {
  reserveShadowMap(options_.lightMap, map_);
  if (!options_.interpolate) return;  // the interpolation's per-pixel buffers (visibilityImpl)
  const size_t count = static_cast<size_t>(width) * height;
  scratchClass_.resize(count);
  scratchKey_.resize(count);
  scratchKnown_.resize(count);
  scratchDirection_.resize(2 * count);
}

void BrabecTechnique::prepareImpl(const Scene& scene, const Light& sceneLight) {
  createShadowMap(scene, sceneLight, options_.lightMap, map_);
  light_ = lightAtMapOrigin(sceneLight, map_);  // a receiver's facing is told from the map's origin
  setHorizonClamp(options_.lightMap.horizon, *light_);
  const Light& light = *light_;
  lightRadius_ = light.extent();
  // A segment's footprint is a segment along its direction in the map (its component across the
  // light's axis; t runs against light-space y).
  segmentLight_ = light.shape() == LightShape::Segment;
  auto mapDirection = [&](const Vec3& wsOffset) {
    const Vec3 h = map_.lsFrame.toLocal(wsOffset);
    return Vec2(h.x, -h.y) / lightRadius_;
  };
  if (segmentLight_) segmentAxis_ = mapDirection(light.b() - light.center());
  polygon_.clear();
  polygonArea_ = 0.0f;
  if (light.shape() == LightShape::Rect || light.shape() == LightShape::Polygon) {
    for (const Vec3& vertex : light.vertices()) polygon_.push_back(mapDirection(vertex - light.center()));
    for (size_t k = 0; k < polygon_.size(); ++k) {
      const Vec2& a = polygon_[k];
      const Vec2& b = polygon_[(k + 1) % polygon_.size()];
      polygonArea_ += 0.5f * (a.x * b.y - a.y * b.x);
    }
    polygonArea_ = std::abs(polygonArea_);
  }
  minDepth_ = minMapDepth(map_);
  brabec::buildTiles(map_, tileMinDepth_, tileMaxDepth_, tileObjectId_, tilesPerRow_);
  if (options_.accelerate) tileNearest_.build(tileMinDepth_, tileObjectId_, tilesPerRow_);
  if (options_.coverageBound && !segmentLight_) {
    // The largest stride boundByCoverage can ask for: its footprint is at most max_radius texels.
    const float radius = static_cast<float>(options_.maxRadius);
    const float area = radius * radius * (polygon_.empty() ? 3.14159265f : polygonArea_);
    const float samples = static_cast<float>(options_.coverageSamples);
    lattices_.build(map_, area > samples ? static_cast<int>(std::ceil(std::sqrt(area / samples))) : 1);
  } else {
    lattices_.build(map_, 1);
  }
  if (options_.jitter > 0.0f) {
    const int n = map_.size;
    jitterS_ = Image<float>(n, n);
    jitterT_ = Image<float>(n, n);
    for (int t = 0; t < n; ++t)
      for (int s = 0; s < n; ++s) {
        jitterS_(s, t) = brabec::texelJitter(s, t, 0, options_.jitter);
        jitterT_(s, t) = brabec::texelJitter(s, t, 1, options_.jitter);
      }
  } else {
    jitterS_ = {};
    jitterT_ = {};
  }
}

BrabecTechnique::Pixel BrabecTechnique::classify(const GBuffer& gbuffer, int x, int y) const {
  if (!gbuffer.hit(x, y)) return Pixel{};
  return classify(gbuffer, x, y,
                  makeReceiver(map_, gbuffer.wsPosition(x, y), gbuffer.wsGeometricNormal(x, y), options_.bias));
}

BrabecTechnique::Pixel BrabecTechnique::classify(const GBuffer& gbuffer, int x, int y, const ShadowReceiver& r) const {
  Pixel p;
  if (!gbuffer.hit(x, y)) return p;
  p.objectId = p.key = gbuffer.objectId(x, y);
  const Vec3 wsP = gbuffer.wsPosition(x, y);
  const Vec3 wsNg = gbuffer.wsGeometricNormal(x, y);
  if (facesAwayFromLight(wsP, wsNg)) {
    p.cls = Pixel::BackFacing;
    return p;
  }
  const int i = static_cast<int>(std::floor(r.s)), j = static_cast<int>(std::floor(r.t));
  if (!r.inMap || i < 0 || j < 0 || i >= map_.size || j >= map_.size) {
    p.cls = Pixel::OutOfMap;
    return p;
  }
  p.s = r.s;
  p.t = r.t;
  p.lsDepth = r.lsDepth;
  p.zLayer = r.lsDepth - r.bias;
  p.dzds = r.dzds;
  p.dzdt = r.dzdt;
  p.texelWorld = r.texelWorld;
  if (hardShadow(map_, r) == 0.0f) {
    p.cls = Pixel::Blocked;
    p.key = map_.objectId(i, j);
    p.blockerDepth = map_.lsDepth(i, j);
  } else {
    p.cls = Pixel::Lit;
  }
  return p;
}

namespace {

// classifyRow's loop over raw rows: every test computed for every pixel and the class picked by
// selects, so that it vectorizes (the map's texels gathered; a pixel outside the map reads texel 0).
// towardLight is the light's direction for a directional light, else its centre, from which each
// pixel's own direction is taken as facesAwayFromLight takes it.
template <bool kDirectional>
inline void classifyPixelsLoop(int width, const int32_t* __restrict ids, const Vec3* __restrict positions,
                               const Vec3* __restrict normals, const int32_t* __restrict inMap,
                               const int32_t* __restrict nearestTexel, const float* __restrict nearestThreshold,
                               const float* __restrict depth, const int32_t* __restrict mapIds, float lx, float ly,
                               float lz, uint8_t* __restrict cls, int32_t* __restrict key) {
  for (int x = 0; x < width; ++x) {
    const int32_t id = ids[x];
    const Vec3 light(lx, ly, lz);
    const Vec3 toLight = kDirectional ? light : light - positions[x];
    const bool away = glm::dot(normals[x], toLight) <= 0.0f;
    const auto texel = static_cast<size_t>(nearestTexel[x]);
    const bool blocked = depth[texel] < nearestThreshold[x];  // hardShadow's compare
    const int32_t blocker = mapIds[texel];
    // classify's tests in its order: a hit, the side of the light's centre, the map's bounds, the hard
    // test (in the map, floor(s) and floor(t) lie in [0, size)).
    const bool hit = id != kNoObject, in = inMap[x] != 0;
    int32_t c = blocked ? brabec::Blocked : brabec::Lit;
    c = in ? c : brabec::OutOfMap;
    c = away ? brabec::BackFacing : c;
    c = hit ? c : brabec::Miss;
    cls[x] = static_cast<uint8_t>(c);
    // The blocker's id where the hard test blocks a hit facing the light in the map, else the pixel's
    // own (as selects: a condition of several parts joined by & becomes branches, which do not vectorize).
    int32_t k = blocked ? blocker : id;
    k = in ? k : id;
    k = away ? id : k;
    key[x] = hit ? k : id;
  }
}

PENUMBRA_CLONES_AVX512 void classifyPixels(int width, const int32_t* __restrict ids, const Vec3* __restrict positions,
                                           const Vec3* __restrict normals, const int32_t* __restrict inMap,
                                           const int32_t* __restrict nearestTexel,
                                           const float* __restrict nearestThreshold, const float* __restrict depth,
                                           const int32_t* __restrict mapIds, bool directional, float lx, float ly,
                                           float lz, uint8_t* __restrict cls, int32_t* __restrict key) {
  if (directional)
    classifyPixelsLoop<true>(width, ids, positions, normals, inMap, nearestTexel, nearestThreshold, depth, mapIds, lx,
                             ly, lz, cls, key);
  else
    classifyPixelsLoop<false>(width, ids, positions, normals, inMap, nearestTexel, nearestThreshold, depth, mapIds, lx,
                              ly, lz, cls, key);
}

}  // namespace

void BrabecTechnique::classifyRow(const GBuffer& gbuffer, int y, const ReceiverRow& receivers, uint8_t* cls,
                                  int32_t* key) const {
  const bool directional = light_->isDirectional();
  const Vec3 towardLight = directional ? light_->direction() : light_->center();
  classifyPixels(gbuffer.width(), gbuffer.objectId.row(y), gbuffer.wsPosition.row(y), gbuffer.wsGeometricNormal.row(y),
                 receivers.inMap.data(), receivers.nearestTexel.data(), receivers.nearestThreshold.data(),
                 map_.lsDepth.data(), map_.objectId.data(), directional, towardLight.x, towardLight.y, towardLight.z,
                 cls, key);
}

float BrabecTechnique::evaluate(const Pixel& p, Vec2* toTexel, bool* raised, SearchSeeds* seeds) const {
  if (toTexel) *toTexel = Vec2(0.0f);
  if (raised) *raised = false;
  switch (p.cls) {
    case Pixel::Miss:
    case Pixel::OutOfMap:
      return 1.0f;
    case Pixel::BackFacing:
      return 0.0f;
    default:
      break;
  }
  const bool inner = p.cls == Pixel::Blocked;
  const bool physical = !options_.rScale;
  const bool orthographic = map_.orthographic;
  // Physical half penumbra width in texels for a blocker at depth zb (brabec.h): R (z_r - z_b) / z_b
  // world units, divided by the texel size at the receiver.
  const float texelsPerWorld = lightRadius_ / p.texelWorld;
  auto widthTexels = [&](float zb) {
    const float dz = p.lsDepth - zb;
    return dz > 0.0f ? texelsPerWorld * dz / (orthographic ? 1.0f : zb) : 0.0f;
  };
  const float cap = static_cast<float>(options_.maxRadius);
  float radius;
  if (physical)
    radius = std::min(cap, widthTexels(inner ? p.blockerDepth : minDepth_));
  else
    radius = std::min(cap, *options_.rScale * std::abs(p.lsDepth) + *options_.rBias);
  if (physical && !inner && radius > 0.0f && options_.accelerate) {
    // The nearest possible blocker near P rather than in the whole map: the nearest depth of the
    // tiles within the radius that may hold a blocker. A texel beyond w_tex of that depth gives
    // r >= r_max, V = 1, exactly as no texel does, so the smaller radius changes no result — only
    // the cost (and no such tile means no search at all).
    const float reach = radius + options_.jitter;
    const int tx0 = std::max(0, static_cast<int>(std::floor(p.s - reach - 0.5f))) >> brabec::kTileShift;
    const int tx1 = std::min(map_.size - 1, static_cast<int>(std::ceil(p.s + reach - 0.5f))) >> brabec::kTileShift;
    const int ty0 = std::max(0, static_cast<int>(std::floor(p.t - reach - 0.5f))) >> brabec::kTileShift;
    const int ty1 = std::min(map_.size - 1, static_cast<int>(std::ceil(p.t + reach - 0.5f))) >> brabec::kTileShift;
    // The nearest of the tiles that are not P's own object's alone: below the layer it is the
    // nearest tile that may block, else no tile may.
    const float nearest = tileNearest_.nearest(tx0, tx1, ty0, ty1, p.objectId, options_.idTest);
    radius = nearest < p.zLayer ? std::min(radius, widthTexels(nearest)) : 0.0f;
  }

  brabec::SearchMap m;
  m.size = map_.size;
  m.lsDepth = map_.lsDepth.data();
  m.objectId = map_.objectId.data();
  if (!jitterS_.empty()) {
    m.jitterS = jitterS_.data();
    m.jitterT = jitterT_.data();
    m.maxJitter = options_.jitter;
  }
  if (options_.accelerate) {
    m.tilesPerRow = tilesPerRow_;
    m.tileMinDepth = tileMinDepth_.data();
    m.tileMaxDepth = tileMaxDepth_.data();
    m.tileObjectId = tileObjectId_.data();
  }
  brabec::SearchQuery q;
  q.s = p.s;
  q.t = p.t;
  q.zLayer = p.zLayer;
  q.dzds = p.dzds;
  q.dzdt = p.dzdt;
  q.objectId = p.objectId;
  q.inner = inner;
  q.idTest = options_.idTest;
  q.radius = radius;
  SearchSeeds::Texel* seed = seeds ? (inner ? &seeds->inner : &seeds->outer) : nullptr;
  if (seed) {
    q.seedS = seed->s;
    q.seedT = seed->t;
  }
  const brabec::SearchHit hit = options_.scalarSearch ? brabec::searchScalar(m, q) : brabec::searchVectorized(m, q);
  if (seed && hit.found) *seed = {hit.s, hit.t};
  if (!hit.found) {
    if (!inner) return 1.0f;
    if (!options_.coverageBound) return 0.0f;
    const float bounded = boundByCoverage(p, 0.0f, p.blockerDepth);
    if (raised) *raised = bounded > 0.0f;
    return bounded;
  }
  if (toTexel) {
    // The texel's position as the distance measured it (centre + jitter).
    const size_t i = static_cast<size_t>(hit.t) * map_.size + hit.s;
    const Vec2 d(static_cast<float>(hit.s) + 0.5f + (m.jitterS ? m.jitterS[i] : 0.0f) - p.s,
                 static_cast<float>(hit.t) + 0.5f + (m.jitterT ? m.jitterT[i] : 0.0f) - p.t);
    const float length = glm::length(d);
    if (length > 0.0f) *toTexel = d / length;
  }

  const float found = map_.lsDepth(hit.s, hit.t);
  float rMax;
  if (physical) {
    rMax = widthTexels(inner ? p.blockerDepth : found);
  } else {
    // Sec. 3.3 verbatim: r_max *= r_shrink * (depth difference between P' and the texel found).
    const float dz = inner ? found - p.lsDepth : p.lsDepth - found;
    rMax = (*options_.rScale * std::abs(p.lsDepth) + *options_.rBias) * *options_.rShrink * dz;
  }
  const float r = std::sqrt(hit.distance2);
  const float c = rMax > 0.0f ? std::min(r / rMax, 1.0f) : 1.0f;
  const float meet = options_.meet;
  const float v = inner ? meet * (1.0f - c) : meet + (1.0f - meet) * c;
  if (!options_.coverageBound) return v;
  // The blocker plane of the bound: the blocker's silhouette as the map sees it, on the edge between
  // blocked and lit texels nearest to P'. Outer: the blocker texel found lies on it. Inner: the
  // deepest blocker texel next to the lit texel found (the texel over P is the top of the blocker,
  // whose footprint is wider than the silhouette's).
  float zb = found;
  if (inner) {
    zb = -kInfinity;
    for (int j = std::max(0, hit.t - 1); j <= std::min(map_.size - 1, hit.t + 1); ++j)
      for (int i = std::max(0, hit.s - 1); i <= std::min(map_.size - 1, hit.s + 1); ++i) {
        const float z = map_.lsDepth(i, j);
        const float tc = static_cast<float>(j) + 0.5f, sc = static_cast<float>(i) + 0.5f;
        if (z < p.zLayer + p.dzdt * (tc - p.t) + p.dzds * (sc - p.s)) zb = std::max(zb, z);
      }
    if (zb == -kInfinity) zb = p.blockerDepth;
  }
  const float bounded = boundByCoverage(p, v, zb);
  if (raised) *raised = bounded > v;
  return bounded;
}

float BrabecTechnique::boundByCoverage(const Pixel& p, float v, float zb) const {
  // Not for a receiver in the shadow of its own object: the part of the object that the map does not
  // see (below its silhouette from the light's centre) reaches down towards the receiver and covers
  // more of the light than one blocker plane at zb does.
  if (v >= 1.0f || (p.cls == Pixel::Blocked && p.key == p.objectId)) return v;
  // The footprint's size: the physical penumbra width at zb (brabec.h, r_max), within max_radius.
  const float dz = p.lsDepth - zb;
  const float width = dz > 0.0f ? lightRadius_ / p.texelWorld * dz / (map_.orthographic ? 1.0f : zb) : 0.0f;
  const float footprint = std::min(static_cast<float>(options_.maxRadius), width);
  // A wide footprint is counted on a lattice of every stride-th texel in s and t, about
  // coverage_samples texels at most (the cost of a count, which grows with the footprint's area).
  const float area = footprint * footprint * (polygon_.empty() ? 3.14159265f : polygonArea_);
  const float samples = static_cast<float>(options_.coverageSamples);
  const int stride = area > samples ? static_cast<int>(std::ceil(std::sqrt(area / samples))) : 1;
  const brabec::Coverage c =
      segmentLight_ ? brabec::countBlockedAlong(map_, p.s, p.t, p.zLayer, p.dzds, p.dzdt, footprint * segmentAxis_)
      : !polygon_.empty()
          ? brabec::countBlockedInPolygon(map_, p.s, p.t, p.zLayer, p.dzds, p.dzdt, polygon_, footprint, stride,
                                          &lattices_)
          : brabec::countBlocked(map_, p.s, p.t, p.zLayer, p.dzds, p.dzdt, footprint, stride, &lattices_);
  // A footprint of few texels cannot resolve how much of it the blockers cover (contact shadows,
  // small maps): the paper's V stands there.
  if (c.total * stride * stride < options_.coverageMinTexels) return v;
  return std::max(v, 1.0f - static_cast<float>(c.blocked) / static_cast<float>(c.total));
}

namespace brabec {

int interpolationBlock(int option, int width, int height) {
  if (option > 0) return option;
  int block = 4;  // the paper's, up to 1023 pixels on the longer side
  for (int side = std::max(width, height); side >= 1024; side /= 2) block *= 2;
  return block;
}

}  // namespace brabec

namespace {

// Sec. 4.3 group refinement along one line of pixels (a column or a row): `at(i)` is pixel i's
// index. Borders a and b are solved (searched unless already known); the pixels between are
// interpolated when the borders pass `smooth` (the extra criteria: step, kinks) and the whole group
// shares class and key, else the middle one is searched and both halves are refined. Groups of 5
// split into two of 3, as in the paper's Figure 5. `fill(k, from)` interpolates pixel k, `from` being
// its nearer interpolant (whose id and direction it keeps).
template <class Solve, class Smooth, class Same, class Fill, class At>
void refineGroup(int a, int b, const Solve& solve, const Smooth& smooth, const Same& same, const Fill& fill,
                 const At& at, float* v, const uint8_t* known) {
  solve(at(a));
  solve(at(b));
  if (b - a < 2) return;
  bool uniform = smooth(at(a), at(b));
  for (int i = a + 1; i <= b && uniform; ++i) uniform = same(at(a), at(i));
  if (uniform) {
    const float va = v[at(a)], vb = v[at(b)];
    for (int i = a + 1; i < b; ++i) {
      const size_t k = at(i);
      if (known[k]) continue;
      const float f = static_cast<float>(i - a) / static_cast<float>(b - a);
      v[k] = va + f * (vb - va);
      fill(k, i - a <= b - i ? at(a) : at(b));
    }
    return;
  }
  const int mid = (a + b) / 2;
  refineGroup(a, mid, solve, smooth, same, fill, at, v, known);
  refineGroup(mid, b, solve, smooth, same, fill, at, v, known);
}

// Group borders along a line of `length` pixels: every `block`-th pixel and the last one.
std::vector<int> groupBorders(int length, int block) {
  std::vector<int> borders;
  for (int i = 0; i < length; i += block) borders.push_back(i);
  if (borders.back() != length - 1) borders.push_back(length - 1);
  return borders;
}

}  // namespace

void BrabecTechnique::visibilityImpl(const GBuffer& gbuffer, Image<float>& v) {
  if (!light_) fail("brabec: visibility() called before prepare(); call prepare(scene, light) first");
  const int width = gbuffer.width(), height = gbuffer.height();
  // Every pixel is written below (the interpolation's groups cover the image), in parallel.
  v.resizeForOverwrite(width, height);
  searches_ = 0.0;
  hitPixels_ = 0.0;
  if (width == 0 || height == 0) return;

  std::atomic<int64_t> hits{0}, searches{0};
  auto searched = [](const Pixel& p) { return p.cls == Pixel::Lit || p.cls == Pixel::Blocked; };
  float* out = v.data();
  if (!options_.interpolate) {
    forEachReceiverRow(gbuffer, map_, options_.bias, [&](int y, const ReceiverRow& receivers) {
      int64_t hitCount = 0, searchCount = 0;
      for (int x = 0; x < width; ++x) {
        const Pixel p = classify(gbuffer, x, y, receivers[x]);
        out[static_cast<size_t>(y) * width + x] = evaluate(p);
        hitCount += p.cls != Pixel::Miss;
        searchCount += searched(p);
      }
      hits += hitCount;
      searches += searchCount;
    });
  } else {
    // The hard test and the interpolation id of every pixel, kept compact (5 bytes a pixel); the
    // few pixels that are searched are classified again in full.
    const size_t count = static_cast<size_t>(width) * height;
    scratchClass_.resize(count);
    scratchKey_.resize(count);
    scratchKnown_.assign(count, 0);
    std::vector<uint8_t>& cls = scratchClass_;
    std::vector<uint8_t>& known = scratchKnown_;
    std::vector<int32_t>& key = scratchKey_;
    forEachReceiverRow(gbuffer, map_, options_.bias, [&](int y, const ReceiverRow& receivers) {
      const size_t row = static_cast<size_t>(y) * width;
      classifyRow(gbuffer, y, receivers, cls.data() + row, key.data() + row);
      int64_t hitCount = 0;
      for (int x = 0; x < width; ++x) hitCount += cls[row + static_cast<size_t>(x)] != Pixel::Miss;
      hits += hitCount;
    });
    // The lambdas below take the buffers as raw pointers, by value: through the vectors, captured by
    // reference, every byte stored to `known` or `direction` (char types, which may alias anything)
    // made the compiler reload each vector's data pointer before the next read.
    const uint8_t* const clsOf = cls.data();
    const int32_t* const keyOf = key.data();
    uint8_t* const knownOf = known.data();
    auto same = [clsOf, keyOf](size_t a, size_t b) { return clsOf[a] == clsOf[b] && keyOf[a] == keyOf[b]; };
    // known[k]: kKnown once pixel k is solved or interpolated, with kRaised when the coverage bound
    // raised its V (an interpolated pixel takes its nearer interpolant's).
    constexpr uint8_t kKnown = 1, kRaised = 2;
    // Per known pixel: the direction to its texel as two snorm8 components (0, 0: none), 2 bytes a
    // pixel; written before it is read (a pixel is known once solved or interpolated).
    scratchDirection_.resize(2 * count);
    int8_t* const direction = scratchDirection_.data();
    auto storeDirection = [direction](size_t k, const Vec2& d) {
      direction[2 * k] = static_cast<int8_t>(std::lround(d.x * 127.0f));
      direction[2 * k + 1] = static_cast<int8_t>(std::lround(d.y * 127.0f));
    };
    // V at the end of the penumbra (r >= r_max, or no texel within the radius): the clamp's kink.
    auto atEnd = [clsOf, out](size_t k) {
      return clsOf[k] == Pixel::Lit ? out[k] == 1.0f : clsOf[k] == Pixel::Blocked ? out[k] == 0.0f : true;
    };
    const float maxStep = options_.interpolateMaxStep;
    const bool kinks = options_.interpolateKinks;
    // cos of the largest angle, in the snorm8 units of the dot product (127^2).
    const float minDot = std::cos(radians(options_.interpolateMaxAngle)) * 127.0f * 127.0f;
    auto smooth = [out, maxStep, kinks, knownOf, atEnd, direction, minDot](size_t a, size_t b) {
      if (std::abs(out[a] - out[b]) > maxStep) return false;
      if (!kinks) return true;
      // The coverage bound's kink: V' = max(V, 1 - f) switches from one to the other between them.
      if ((knownOf[a] ^ knownOf[b]) & kRaised) return false;
      const bool endA = atEnd(a), endB = atEnd(b);
      if (endA != endB) return false;
      if (endA) return true;
      const int dot = direction[2 * a] * direction[2 * b] + direction[2 * a + 1] * direction[2 * b + 1];
      return static_cast<float>(dot) >= minDot;
    };
    auto fill = [knownOf, direction](size_t k, size_t from) {
      knownOf[k] = static_cast<uint8_t>(kKnown | (knownOf[from] & kRaised));
      direction[2 * k] = direction[2 * from];
      direction[2 * k + 1] = direction[2 * from + 1];
    };
    const int block = brabec::interpolationBlock(options_.interpolateBlock, width, height);
    const std::vector<int> columns = groupBorders(width, block), rowBorders = groupBorders(height, block);
    // A task's solves: they count its searches, and each search starts from the texel its task's last
    // search of that kind found (`seeds`, the task's own), as the task's next pixels lie near its last.
    auto makeSolve = [&](int64_t& searchCount, SearchSeeds& seeds) {
      return [this, &gbuffer, knownOf, out, width, storeDirection, searched, searchCountPtr = &searchCount,
              seedsPtr = &seeds](size_t k) {
        if (knownOf[k]) return;
        const Pixel p = classify(gbuffer, static_cast<int>(k % width), static_cast<int>(k / width));
        Vec2 toTexel;
        bool raised = false;
        out[k] = evaluate(p, &toTexel, &raised, seedsPtr);
        storeDirection(k, toTexel);
        knownOf[k] = static_cast<uint8_t>(kKnown | (raised ? kRaised : 0));
        *searchCountPtr += searched(p);
      };
    };
    // Columns first (every 4th and the last), then every row between those columns. A pixel's
    // solution depends on no other pixel, so the order is free: the corners where border rows cross
    // border columns are solved first, then each group of rows is refined along every border column
    // at once (its few rows stay in cache, where a column at a time reads a new line per pixel).
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rowBorders.size()), [&](const tbb::blocked_range<size_t>& range) {
      int64_t searchCount = 0;
      SearchSeeds seeds;
      const auto solve = makeSolve(searchCount, seeds);
      for (size_t r = range.begin(); r < range.end(); ++r)
        for (const int x : columns) solve(static_cast<size_t>(rowBorders[r]) * width + x);
      searches += searchCount;
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rowBorders.size() - 1),
                      [&](const tbb::blocked_range<size_t>& range) {
                        int64_t searchCount = 0;
                        SearchSeeds seeds;
                        const auto solve = makeSolve(searchCount, seeds);
                        for (size_t g = range.begin(); g < range.end(); ++g)
                          for (const int x : columns) {
                            auto at = [width, x](int y) { return static_cast<size_t>(y) * width + x; };
                            refineGroup(rowBorders[g], rowBorders[g + 1], solve, smooth, same, fill, at, out, knownOf);
                          }
                        searches += searchCount;
                      });
    // The last pass: a pixel it interpolates is never a group's border, so nothing reads its flags or
    // direction again, and they are not written.
    auto fillNothing = [](size_t, size_t) {};
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
      int64_t searchCount = 0;
      SearchSeeds seeds;
      const auto solve = makeSolve(searchCount, seeds);
      for (int y = rows.begin(); y < rows.end(); ++y) {
        const size_t rowStart = static_cast<size_t>(y) * width;
        auto at = [rowStart](int x) { return rowStart + x; };
        for (size_t g = 0; g + 1 < columns.size(); ++g)
          refineGroup(columns[g], columns[g + 1], solve, smooth, same, fillNothing, at, out, knownOf);
      }
      searches += searchCount;
    });
  }
  searches_ = static_cast<double>(searches.load());
  hitPixels_ = static_cast<double>(hits.load());
}

std::vector<std::pair<std::string, double>> BrabecTechnique::stats() const {
  return {{"searches", searches_},
          {"search_fraction", hitPixels_ > 0.0 ? searches_ / hitPixels_ : 0.0},
          {"map_min_depth", minDepth_}};
}

std::unique_ptr<ShadowTechnique> makeTechnique(const BrabecOptions& o) {
  validateOptions("brabec", o);
  return std::make_unique<BrabecTechnique>(o);
}

TechniqueInfo brabecTechniqueInfo() {
  TechniqueInfo info;
  info.name = "brabec";
  info.summary =
      "single-sample soft shadows: nearest blocker / lit texel search in a depth + object-id map, inner and outer "
      "penumbra";
  info.source = "Brabec & Seidel 2002, Single sample soft shadows using depth maps";
  info.setOptions<BrabecOptions>([](const BrabecOptions& o) { return makeTechnique(o); });
  return info;
}

}  // namespace penumbra
