// Tests of the deterministic samplers (include/penumbra/sampling.h): correlated multi-jittered
// samples are stratified on the m x n grid and in both 1D projections (exactly one sample per cell
// and per 1D stratum when count = m * n), deterministic per (index, pattern), different per pattern;
// a sample decomposes into its grid cell and the sample of that cell; the disk and triangle maps
// stay inside their domains and preserve area.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

#include "penumbra/sampling.h"

namespace penumbra {
namespace {

// m x n of the sampler for a count (its documented choice: m = floor(sqrt(count)), n = ceil(count / m)).
std::pair<uint32_t, uint32_t> grid(uint32_t count) {
  const uint32_t m = static_cast<uint32_t>(std::sqrt(static_cast<double>(count)));
  return {m, (count + m - 1) / m};
}

TEST(CmjSampler, StratifiedIn2DAndInBoth1DProjections) {
  for (const uint32_t count : {1u, 4u, 12u, 16u, 48u, 64u, 100u, 256u, 1024u}) {
    const auto [m, n] = grid(count);
    ASSERT_EQ(m * n, count);
    const CmjSampler sampler(count);
    for (const uint32_t pattern : {0u, 1u, 77u, 0xdeadbeefu}) {
      SCOPED_TRACE(::testing::Message() << "count " << count << " pattern " << pattern);
      std::vector<int> cells(count, 0), xStrata(count, 0), yStrata(count, 0);
      for (uint32_t i = 0; i < count; ++i) {
        const Vec2 u = sampler.sample(i, pattern);
        ASSERT_GE(u.x, 0.0f);
        ASSERT_LT(u.x, 1.0f);
        ASSERT_GE(u.y, 0.0f);
        ASSERT_LT(u.y, 1.0f);
        // m columns in x, n rows in y.
        ++cells[static_cast<uint32_t>(u.y * n) * m + static_cast<uint32_t>(u.x * m)];
        ++xStrata[static_cast<uint32_t>(u.x * count)];
        ++yStrata[static_cast<uint32_t>(u.y * count)];
      }
      for (uint32_t k = 0; k < count; ++k) {
        EXPECT_EQ(cells[k], 1) << "cell " << k;
        EXPECT_EQ(xStrata[k], 1) << "x stratum " << k;
        EXPECT_EQ(yStrata[k], 1) << "y stratum " << k;
      }
    }
  }
}

TEST(CmjSampler, LanesAreTheSamplesBitForBit) {
  // sampleLanes is sampleInStratum for a packet's lanes, each lane with its own pattern: the same
  // floats, whatever the grid (square or not, sides powers of two or not: 3 x 3 cycle-walks its
  // permutations), the lane count and the pattern, including the rare lanes that need a second round.
  for (const uint32_t count : {1u, 2u, 3u, 4u, 9u, 12u, 16u, 48u, 100u, 1024u, 4096u}) {
    const CmjSampler sampler(count);
    const uint32_t cells = sampler.columns() * sampler.rows();
    SCOPED_TRACE(::testing::Message() << "count " << count);
    for (int lanes = 1; lanes <= 16; lanes += 5) {
      for (uint32_t trial = 0; trial < 200; ++trial) {
        uint32_t strata[16], patterns[16];
        float ux[16], uy[16];
        for (int i = 0; i < lanes; ++i) {
          strata[i] = hash32(trial * 64 + static_cast<uint32_t>(i)) % cells;
          patterns[i] = hash32(0x9e37u + trial * 64 + static_cast<uint32_t>(i));
        }
        sampler.sampleLanes(strata, patterns, lanes, ux, uy);
        for (int i = 0; i < lanes; ++i) {
          const Vec2 u = sampler.sampleInStratum(strata[i], patterns[i]);
          ASSERT_EQ(ux[i], u.x) << "stratum " << strata[i] << " pattern " << patterns[i];
          ASSERT_EQ(uy[i], u.y) << "stratum " << strata[i] << " pattern " << patterns[i];
        }
      }
    }
  }
}

TEST(CmjSampler, OnePatternLanesAreTheLanesBitForBit) {
  // sampleLanesOfOnePattern (the permutations tabulated once for a pattern) gives the floats
  // sampleLanes gives for lanes that all take that pattern, on every grid the reference uses.
  for (const uint32_t count : {17u, 48u, 64u, 100u, 256u, 1000u, 1024u, 4096u}) {
    const CmjSampler sampler(count);
    const uint32_t cells = sampler.columns() * sampler.rows();
    SCOPED_TRACE(::testing::Message() << "count " << count);
    std::vector<uint32_t> columnSx(sampler.columns()), rowSy(sampler.rows());
    for (uint32_t trial = 0; trial < 50; ++trial) {
      const uint32_t pattern = hash32(0x51u + trial);
      sampler.tabulatePermutations(pattern, columnSx.data(), rowSy.data());
      for (int lanes = 1; lanes <= 16; lanes += 3) {
        uint32_t strata[16], patterns[16];
        float ux[16], uy[16], oneX[16], oneY[16];
        for (int i = 0; i < lanes; ++i) {
          strata[i] = hash32(trial * 64 + static_cast<uint32_t>(i)) % cells;
          patterns[i] = pattern;
        }
        sampler.sampleLanes(strata, patterns, lanes, ux, uy);
        sampler.sampleLanesOfOnePattern(strata, pattern, columnSx.data(), rowSy.data(), lanes, oneX, oneY);
        for (int i = 0; i < lanes; ++i) {
          ASSERT_EQ(oneX[i], ux[i]) << "stratum " << strata[i] << " pattern " << pattern;
          ASSERT_EQ(oneY[i], uy[i]) << "stratum " << strata[i] << " pattern " << pattern;
        }
      }
    }
  }
}

TEST(CmjSampler, StrataDecomposeTheSample) {
  // sample(i) is the sample of cell stratum(i); stratum() is a permutation of the cells when count
  // == m * n, and sampleInStratum(s) lies in cell (s % m, s / m) of the m x n grid.
  for (const uint32_t count : {16u, 48u, 256u}) {
    const CmjSampler sampler(count);
    const uint32_t m = sampler.columns(), n = sampler.rows();
    ASSERT_EQ(std::make_pair(m, n), grid(count));
    std::set<uint32_t> seen;
    for (uint32_t i = 0; i < count; ++i) {
      const uint32_t s = sampler.stratum(i, 21);
      ASSERT_LT(s, m * n);
      seen.insert(s);
      EXPECT_EQ(sampler.sample(i, 21), sampler.sampleInStratum(s, 21));
      const Vec2 u = sampler.sampleInStratum(s, 21);
      EXPECT_EQ(static_cast<uint32_t>(u.x * m), s % m);
      EXPECT_EQ(static_cast<uint32_t>(u.y * n), s / m);
    }
    EXPECT_EQ(seen.size(), count);
  }
}

TEST(CmjSampler, NonRectangularCountsUseDistinctCells) {
  for (const uint32_t count : {2u, 5u, 10u, 17u, 250u}) {
    const auto [m, n] = grid(count);
    const CmjSampler sampler(count);
    EXPECT_EQ(sampler.count(), count);
    std::set<uint32_t> cells;
    for (uint32_t i = 0; i < count; ++i) {
      const Vec2 u = sampler.sample(i, 5);
      ASSERT_LT(u.x, 1.0f);
      ASSERT_LT(u.y, 1.0f);
      cells.insert(static_cast<uint32_t>(u.y * n) * m + static_cast<uint32_t>(u.x * m));
    }
    EXPECT_EQ(cells.size(), count);
  }
  EXPECT_EQ(CmjSampler(0).count(), 1u);  // documented: count >= 1
}

TEST(CmjSampler, DeterministicAndDecorrelatedAcrossPatterns) {
  const CmjSampler a(64), b(64);
  int same = 0;
  for (uint32_t i = 0; i < 64; ++i) {
    EXPECT_EQ(a.sample(i, 9), b.sample(i, 9));
    same += a.sample(i, 9) == a.sample(i, 10);
  }
  EXPECT_EQ(same, 0);
  // The mean of a stratified set is close to the centre, for any pattern.
  for (uint32_t pattern = 0; pattern < 8; ++pattern) {
    Vec2 mean(0.0f);
    for (uint32_t i = 0; i < 256; ++i) mean += a.sample(i % 64, pattern) / 256.0f;
    EXPECT_NEAR(mean.x, 0.5f, 1.0f / 64.0f);
    EXPECT_NEAR(mean.y, 0.5f, 1.0f / 64.0f);
  }
}

TEST(Hashes, DeterministicAndSpread) {
  EXPECT_EQ(hash32(12345), hash32(12345));
  EXPECT_NE(hash32(1), hash32(2));
  EXPECT_NE(hashCombine(1, 2), hashCombine(2, 1));
  std::set<uint32_t> values;
  for (uint64_t i = 0; i < 10000; ++i) values.insert(hashCombine(7, i));
  EXPECT_EQ(values.size(), 10000u);  // no collisions among neighbouring pixel indices
}

TEST(ConcentricDisk, InsideTheDiskAndAreaPreserving) {
  const CmjSampler sampler(4096);
  int inner = 0;
  for (uint32_t i = 0; i < 4096; ++i) {
    const Vec2 d = concentricDisk(sampler.sample(i, 3));
    EXPECT_LE(glm::length(d), 1.0f + 1e-6f);
    inner += glm::length(d) < 0.5f;
  }
  // The disk of radius 1/2 holds a quarter of the area; stratification keeps the count within a few.
  EXPECT_NEAR(inner, 1024, 20);
  EXPECT_EQ(concentricDisk(Vec2(0.5f)), Vec2(0.0f));
  EXPECT_NEAR(glm::length(concentricDisk(Vec2(1.0f, 0.5f))), 1.0f, 1e-6f);
}

TEST(UniformTriangle, InsideAndUniform) {
  const CmjSampler sampler(4096);
  int nearVertex0 = 0;  // b0 > 1/2: the corner triangle with a quarter of the area
  for (uint32_t i = 0; i < 4096; ++i) {
    const Vec2 b = uniformTriangle(sampler.sample(i, 8));
    EXPECT_GE(b.x, 0.0f);
    EXPECT_GE(b.y, 0.0f);
    EXPECT_LE(b.x + b.y, 1.0f + 1e-6f);
    nearVertex0 += b.x > 0.5f;
  }
  EXPECT_NEAR(nearVertex0, 1024, 40);
}

}  // namespace
}  // namespace penumbra
