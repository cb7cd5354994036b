// Deterministic sample generation. Every random decision in penumbra derives from a user seed and
// a pixel/sample index through these hashes, so a render is bit-identical for a given seed and does
// not depend on thread scheduling.
#pragma once

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
    const uint32_t sx = permute(s % m_, m_, pattern * 0x68bc21ebu);
    const uint32_t sy = permute(s / m_, n_, pattern * 0x02e5be93u);
    const float jx = randomFloat(s, pattern * 0x967a889bu);
    const float jy = randomFloat(s, pattern * 0x368cc8b7u);
    const float x = (static_cast<float>(s % m_) + (static_cast<float>(sy) + jx) / n_) / m_;
    const float y = (static_cast<float>(s / m_) + (static_cast<float>(sx) + jy) / m_) / n_;
    return Vec2(std::min(x, kOneMinusEpsilon), std::min(y, kOneMinusEpsilon));
  }

 private:
  static constexpr float kOneMinusEpsilon = 0x1.fffffep-1f;

  // A random permutation of [0, l) indexed by i, selected by p (Kensler, Listing 3).
  static uint32_t permute(uint32_t i, uint32_t l, uint32_t p) {
    if (l <= 1) return 0;
    uint32_t w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    do {
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
    } while (i >= l);
    return (i + p) % l;
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
