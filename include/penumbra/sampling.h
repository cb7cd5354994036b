// Deterministic sample generation. Every random decision in penumbra derives from a user seed and
// a pixel/sample index through these hashes, so a render is bit-identical for a given seed and does
// not depend on thread scheduling.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "penumbra/math.h"

namespace penumbra {

// 64 -> 32 bit hash (a variant of the splitmix64 finalizer).
inline uint32_t hash32(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  x ^= x >> 31;
  return static_cast<uint32_t>(x);
}
inline uint32_t hashCombine(uint64_t a, uint64_t b) {
  return hash32(a * 0x9e3779b97f4a7c15ull ^ (b + 0x632be59bd9b4e019ull));
}

// Correlated multi-jittered sampling (Kensler 2013, "Correlated Multi-Jittered Sampling", Pixar
// TM 13-01, Listings 5 and 6): N = m*n samples stratified on the m x n grid *and* in both 1D
// projections, so a 2D light (rect, disk) and a 1D light (segment) are both well stratified.
// `pattern` selects an independent, decorrelated sample set (one per pixel).
class CmjSampler {
 public:
  // count >= 1. When count is not a product m*n with m = floor(sqrt(count)) the grid is completed to
  // m*n >= count and the first `count` samples of a random order are used: still unbiased, with
  // slightly weaker stratification.
  explicit CmjSampler(uint32_t count) : count_(count < 1 ? 1 : count) {
    m_ = static_cast<uint32_t>(std::sqrt(static_cast<double>(count_)));
    if (m_ < 1) m_ = 1;
    n_ = (count_ + m_ - 1) / m_;
    rowMagic_ = static_cast<uint32_t>((0xffffffffull + m_) / m_);  // ceil(2^32 / m_), m_ >= 2
    exactRow_ = m_ >= 2 && static_cast<uint64_t>(m_) * n_ * m_ < (1ull << 32);
  }
  uint32_t count() const { return count_; }

  Vec2 sample(uint32_t index, uint32_t pattern) const { return sampleInStratum(stratum(index, pattern), pattern); }

  // The m x n grid the samples are stratified on: m columns in x, n rows in y.
  uint32_t columns() const { return m_; }
  uint32_t rows() const { return n_; }
  // The grid cell of sample `index` (row-major: column s % m, row s / m), and the sample of a cell:
  // sample(i, p) == sampleInStratum(stratum(i, p), p). When count == m*n every cell holds exactly one
  // sample, so a caller that needs the whole set may visit the cells in any order (the reference
  // visits them in compact tiles so that each ray packet aims at one small patch of the light).
  uint32_t stratum(uint32_t index, uint32_t pattern) const { return permute(index, m_ * n_, pattern * 0x51633e2du); }
  Vec2 sampleInStratum(uint32_t s, uint32_t pattern) const {
    const uint32_t sx = permute(s % m_, m_, pattern * kColumnScramble);
    const uint32_t sy = permute(s / m_, n_, pattern * kRowScramble);
    const float jx = randomFloat(s, pattern * 0x967a889bu);
    const float jy = randomFloat(s, pattern * 0x368cc8b7u);
    const float x = (static_cast<float>(s % m_) + (static_cast<float>(sy) + jx) / n_) / m_;
    const float y = (static_cast<float>(s / m_) + (static_cast<float>(sx) + jy) / m_) / n_;
    return Vec2(std::min(x, kOneMinusEpsilon), std::min(y, kOneMinusEpsilon));
  }
  // sampleInStratum(strata[i], patterns[i]) for the count <= 16 lanes of a ray packet, bit for bit,
  // into ux[i], uy[i]. Each step is one loop over the lanes, which the compiler vectorizes; the rare
  // permutation round that must be repeated, and a grid side that is not a power of two, finish lane
  // by lane. Always inlined, so that a caller compiled for wider vectors (a target clone) vectorizes
  // it at its own width.
  [[gnu::always_inline]] void sampleLanes(const uint32_t* strata, const uint32_t* patterns, int count, float* ux,
                                          float* uy) const {
    alignas(64) uint32_t column[16], row[16], sx[16], sy[16];
    rowsOf(strata, count, row);
    for (int i = 0; i < count; ++i) column[i] = strata[i] - row[i] * m_;
    permuteLanes(column, m_, patterns, kColumnScramble, count, sx);
    permuteLanes(row, n_, patterns, kRowScramble, count, sy);
    jitterAllLanes(strata, patterns, column, row, sx, sy, count, ux, uy);
  }

  // For many samples of one pattern (a pixel that fills ray packets alone): sampleInStratum's two
  // permutations tabulated once, sx of every column (columns() entries) and sy of every row (rows()
  // entries), so that each sample then costs its jitter alone.
  void tabulatePermutations(uint32_t pattern, uint32_t* columnSx, uint32_t* rowSy) const {
    for (uint32_t c = 0; c < m_; ++c) columnSx[c] = permute(c, m_, pattern * kColumnScramble);
    for (uint32_t r = 0; r < n_; ++r) rowSy[r] = permute(r, n_, pattern * kRowScramble);
  }
  // sampleLanes for count <= 16 lanes that all take `pattern`, through its tables
  // (tabulatePermutations): the same points, bit for bit.
  [[gnu::always_inline]] void sampleLanesOfOnePattern(const uint32_t* strata, uint32_t pattern,
                                                      const uint32_t* columnSx, const uint32_t* rowSy, int count,
                                                      float* ux, float* uy) const {
    alignas(64) uint32_t column[16], row[16], sx[16], sy[16], patterns[16];
    rowsOf(strata, count, row);
    for (int i = 0; i < count; ++i) {
      column[i] = strata[i] - row[i] * m_;
      sx[i] = columnSx[column[i]];
      sy[i] = rowSy[row[i]];
      patterns[i] = pattern;
    }
    jitterAllLanes(strata, patterns, column, row, sx, sy, count, ux, uy);
  }

 private:
  static constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;
  // The pattern's multipliers for the permutations of a stratum's column and of its row.
  static constexpr uint32_t kColumnScramble = 0x68bc21ebu, kRowScramble = 0x02e5be93u;

  // sampleInStratum's last step for the lanes: the jitter inside each cell. The integers are below
  // 2^31, so they convert to float as signed ones (one instruction; an unsigned conversion is several).
  // jitterLanes, dividing by a power-of-two grid's sides as multiplying by their reciprocals (bit for
  // bit the same, and much cheaper).
  [[gnu::always_inline]] void jitterAllLanes(const uint32_t* strata, const uint32_t* patterns, const uint32_t* column,
                                             const uint32_t* row, const uint32_t* sx, const uint32_t* sy, int count,
                                             float* ux, float* uy) const {
    if (((m_ & (m_ - 1)) | (n_ & (n_ - 1))) == 0)
      jitterLanes<true>(strata, patterns, column, row, sx, sy, count, ux, uy);
    else
      jitterLanes<false>(strata, patterns, column, row, sx, sy, count, ux, uy);
  }
  template <bool kPowersOfTwo>
  [[gnu::always_inline]] void jitterLanes(const uint32_t* strata, const uint32_t* patterns, const uint32_t* column,
                                          const uint32_t* row, const uint32_t* sx, const uint32_t* sy, int count,
                                          float* ux, float* uy) const {
    const float m = static_cast<float>(m_), n = static_cast<float>(n_);
    const float invM = 1.0f / m, invN = 1.0f / n;
    auto f = [](uint32_t i) { return static_cast<float>(static_cast<int32_t>(i)); };
    for (int i = 0; i < count; ++i) {
      const uint32_t s = strata[i], p = patterns[i];
      const float jx = randomFloat(s, p * 0x967a889bu), jy = randomFloat(s, p * 0x368cc8b7u);
      const float x =
          kPowersOfTwo ? (f(column[i]) + (f(sy[i]) + jx) * invN) * invM : (f(column[i]) + (f(sy[i]) + jx) / n) / m;
      const float y =
          kPowersOfTwo ? (f(row[i]) + (f(sx[i]) + jy) * invM) * invN : (f(row[i]) + (f(sx[i]) + jy) / m) / n;
      ux[i] = std::min(x, kOneMinusEpsilon);
      uy[i] = std::min(y, kOneMinusEpsilon);
    }
  }
  // A random permutation of [0, l) indexed by i, selected by p (Kensler, Listing 3): rounds of a
  // hash on the bits of l - 1 until the result falls below l (cycle walking), then a rotation by p.
  static uint32_t permute(uint32_t i, uint32_t l, uint32_t p) {
    if (l <= 1) return 0;
    const uint32_t w = bitMask(l);
    do i = permuteRound(i, w, p);
    while (i >= l);
    return (i + p) % l;
  }
  // The smallest 2^k - 1 >= l - 1.
  static uint32_t bitMask(uint32_t l) {
    uint32_t w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    return w;
  }
  static uint32_t permuteRound(uint32_t i, uint32_t w, uint32_t p) {
    i ^= p;
    i *= 0xe170893du;
    i ^= p >> 16;
    i ^= (i & w) >> 4;
    i ^= p >> 8;
    i *= 0x0929eb3fu;
    i ^= p >> 23;
    i ^= (i & w) >> 1;
    i *= 1u | p >> 27;
    i *= 0x6935fa69u;
    i ^= (i & w) >> 11;
    i *= 0x74dcb303u;
    i ^= (i & w) >> 2;
    i *= 0x9e501cc3u;
    i ^= (i & w) >> 2;
    i *= 0xc860a3dfu;
    i &= w;
    i ^= i >> 5;
    return i;
  }
  // out[i] = permute(index[i], l, patterns[i] * salt) for count lanes: the first round for every
  // lane at once, the further rounds (when a round lands at or above l) lane by lane.
  [[gnu::always_inline]] static void permuteLanes(const uint32_t* index, uint32_t l, const uint32_t* patterns,
                                                  uint32_t salt, int count, uint32_t* out) {
    if (l <= 1) {
      for (int i = 0; i < count; ++i) out[i] = 0;
      return;
    }
    const uint32_t w = bitMask(l);
    for (int i = 0; i < count; ++i) out[i] = permuteRound(index[i], w, patterns[i] * salt);
    if (w + 1 == l) {  // a power of two: every round lands below l, and % l is a mask
      for (int i = 0; i < count; ++i) out[i] = (out[i] + patterns[i] * salt) & w;
      return;
    }
    for (int i = 0; i < count; ++i) {
      const uint32_t p = patterns[i] * salt;
      while (out[i] >= l) out[i] = permuteRound(out[i], w, p);
      out[i] = (out[i] + p) % l;
    }
  }
  // s / m_ by a multiply: exact while s m_ < 2^32 (for s < m_ n_, true up to about 2^21 samples),
  // otherwise a division.
  uint32_t rowOf(uint32_t s) const {
    return exactRow_ ? static_cast<uint32_t>((static_cast<uint64_t>(s) * rowMagic_) >> 32) : s / m_;
  }
  // rowOf for lanes [0, count): one column (m = 1, one sample a pixel) without the division, which
  // does not vectorize.
  [[gnu::always_inline]] void rowsOf(const uint32_t* strata, int count, uint32_t* row) const {
    if (m_ == 1) {
      for (int i = 0; i < count; ++i) row[i] = strata[i];
      return;
    }
    for (int i = 0; i < count; ++i) row[i] = rowOf(strata[i]);
  }
  // A float in [0, 1) from (i, p) (Kensler, Listing 4).
  static float randomFloat(uint32_t i, uint32_t p) {
    i ^= p;
    i ^= i >> 17;
    i ^= i >> 10;
    i *= 0xb36534e5u;
    i ^= i >> 12;
    i ^= i >> 21;
    i *= 0x93fc4795u;
    i ^= 0xdf6e307fu;
    i ^= i >> 17;
    i *= 1u | p >> 18;
    return static_cast<float>(i) * (1.0f / 4294967808.0f);
  }

  uint32_t count_, m_, n_;
  uint32_t rowMagic_ = 0;
  bool exactRow_ = false;
};

// Shirley–Chiu concentric map of [0,1)^2 onto the unit disk: preserves stratification and area.
inline Vec2 concentricDisk(const Vec2& u) {
  const Vec2 o = 2.0f * u - Vec2(1.0f);
  if (o.x == 0.0f && o.y == 0.0f) return Vec2(0.0f);
  float r, theta;
  if (std::abs(o.x) > std::abs(o.y)) {
    r = o.x;
    theta = (kPi / 4.0f) * (o.y / o.x);
  } else {
    r = o.y;
    theta = (kPi / 2.0f) - (kPi / 4.0f) * (o.x / o.y);
  }
  return r * Vec2(std::cos(theta), std::sin(theta));
}

// Uniform point on a triangle as barycentrics (b0, b1) (Heitz 2019, low-distortion square-to-triangle).
inline Vec2 uniformTriangle(const Vec2& u) {
  float b0, b1;
  if (u.x < u.y) {
    b0 = u.x / 2.0f;
    b1 = u.y - b0;
  } else {
    b1 = u.y / 2.0f;
    b0 = u.x - b1;
  }
  return Vec2(b0, b1);
}

}  // namespace penumbra
