// Tests of the Lawlor 2006 Fig. 10 sweep (src/experiments/lawlor_table.cpp) on `triangle`: the shape the
// paper's table shows — plm the lowest row at every size, the hard shadows above it, pcf ("Reeves
// filtering", one texel wide) getting worse as the map grows — asserted at 16, 64 and 128. To
// stay fast the sweep runs at 256x256 against a 512-spp truth (the published table, docs/lawlor-
// table.md, uses 512x512 and 4096 spp, and gives the same values within 0.1); measured noise of that
// truth: mean standard error 0.00035 over the pixels that see geometry, far below the gaps asserted.
#include "experiments/lawlor_table.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "penumbra/error.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

const LawlorTable& smallTable() {
  static const LawlorTable table = [] {
    LawlorTableOptions options;
    options.mapSizes = {16, 64, 128};
    options.width = options.height = 256;
    options.truthSpp = 512;
    options.figureMapSize = 16;
    return runLawlorTable(loadScene("triangle"), options);
  }();
  return table;
}

// The paper's shape, as far as it holds here (docs/lawlor-table.md discusses the rest): plm is the
// lowest of the shadow-map rows and below the exact hard shadow at every size; the hard shadow map is
// above plm, pcf and the exact hard shadow; pcf ("one-shadowmap-pixel-wide soft shadows") gets worse
// once its texel is narrower than the penumbra (64 -> 128). Not asserted, because they do not hold:
// plm is not flat across sizes (it keeps improving), smoothies and Kirsch & Doellner sit above the
// hard shadow map from 32^2 on against the full truth (against their halves they are below it: the
// next test), pcf improves from 16^2 to 64^2, and the "16 Samples" row (our stratified reference at
// 16 spp) is far below the paper's stochastic 16 samples and below plm.
TEST(LawlorTable, ShapeOfFigure10At16To128) {
  const LawlorTable& t = smallTable();
  ASSERT_EQ(t.rows.size(), 11u);
  for (const char* name : {"plm", "smoothies", "kirsch", "pcf", "hard", "raytraced-hard", "reference"})
    std::printf("[ measured ] %-14s 16: %5.2f  64: %5.2f  128: %5.2f\n", name, t.row(name).rmse8[0],
                t.row(name).rmse8[1], t.row(name).rmse8[2]);
  // Measured (256x256, 512-spp truth), 16 / 64 / 128: plm 10.92 / 3.63 / 2.33, smoothies 35.12 / 21.31 /
  // 19.88, kirsch 33.02 / 20.58 / 18.79, pcf 23.04 / 11.26 / 12.37, hard 34.27 / 18.99 / 17.47,
  // raytraced-hard 16.06, reference (16 spp) 2.44.
  for (size_t i = 0; i < t.options.mapSizes.size(); ++i) {
    const int size = t.options.mapSizes[i];
    const double plm = t.row("plm").rmse8[i];
    for (const char* other : {"smoothies", "kirsch", "pcf", "hard", "raytraced-hard"})
      EXPECT_LT(plm, t.row(other).rmse8[i]) << other << " at " << size;
    EXPECT_GT(t.row("hard").rmse8[i], t.row("pcf").rmse8[i]) << size;
    EXPECT_GT(t.row("hard").rmse8[i], t.row("raytraced-hard").rmse8[i]) << size;
  }
  // At 16^2 plm is at the paper's level (11.3) and a third below the exact hard shadow; at 64^2 under
  // half of the next shadow-map row.
  EXPECT_LT(t.row("plm").rmse8[0], 0.8 * t.row("raytraced-hard").rmse8[0]);
  EXPECT_LT(t.row("plm").rmse8[1], 0.5 * t.row("pcf").rmse8[1]);
  // Reeves filtering turns worse as the map grows past the penumbra's width (measured +10%).
  EXPECT_GT(t.row("pcf").rmse8[2], 1.05 * t.row("pcf").rmse8[1]);
}

// Fig. 11: "Smoothies and Kirsch and Döllner are compared with the outer and inner penumbra
// respectively". Against its half truth each is below the hard shadow map against the same half, at
// every size (Fig. 10 has both below the hard shadow map).
TEST(LawlorTable, HalfPenumbraRowsBeatTheHardShadowMapAgainstTheirHalf) {
  const LawlorTable& t = smallTable();
  const PenumbraHalf outer = PenumbraHalf::Outer, inner = PenumbraHalf::Inner;
  std::printf(
      "[ measured ] half truths, 16 / 64 / 128: smoothies %.2f / %.2f / %.2f (hard %.2f / %.2f / %.2f), "
      "kirsch %.2f / %.2f / %.2f (hard %.2f / %.2f / %.2f)\n",
      t.row("smoothies", outer).rmse8[0], t.row("smoothies", outer).rmse8[1], t.row("smoothies", outer).rmse8[2],
      t.row("hard", outer).rmse8[0], t.row("hard", outer).rmse8[1], t.row("hard", outer).rmse8[2],
      t.row("kirsch", inner).rmse8[0], t.row("kirsch", inner).rmse8[1], t.row("kirsch", inner).rmse8[2],
      t.row("hard", inner).rmse8[0], t.row("hard", inner).rmse8[1], t.row("hard", inner).rmse8[2]);
  for (size_t i = 0; i < t.options.mapSizes.size(); ++i) {
    const int size = t.options.mapSizes[i];
    EXPECT_LT(t.row("smoothies", outer).rmse8[i], t.row("hard", outer).rmse8[i]) << size;
    EXPECT_LT(t.row("kirsch", inner).rmse8[i], t.row("hard", inner).rmse8[i]) << size;
  }
  EXPECT_THROW(t.row("plm", outer), Error);
}

TEST(LawlorTable, RowsWithoutAMapRunOnce) {
  const LawlorTable& t = smallTable();
  EXPECT_FALSE(t.row("raytraced-hard").usesMap);
  EXPECT_FALSE(t.row("reference").usesMap);
  EXPECT_TRUE(t.row("plm").usesMap);
  EXPECT_EQ(t.row("raytraced-hard").rmse8[0], t.row("raytraced-hard").rmse8[1]);
  EXPECT_EQ(t.row("plm").figureV.width(), 256);
}

TEST(LawlorTable, RejectsBadOptions) {
  const Scene scene = loadScene("triangle");
  LawlorTableOptions options;
  options.figureMapSize = 48;
  EXPECT_THROW(runLawlorTable(scene, options), Error);
  options = {};
  options.mapSizes.clear();
  EXPECT_THROW(runLawlorTable(scene, options), Error);
}

}  // namespace
}  // namespace penumbra
