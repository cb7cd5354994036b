// The reproduction of Lawlor 2006's Fig. 10 and Fig. 11 ("Interpolation-friendly soft shadow maps",
// CGVR, Sec. 4; docs/papers.md): RMSE8 of each
// technique row at each shadow-map size against a dense Monte Carlo truth on the `triangle` scene,
// and the row of V images and signed difference images at one map size.
//
// Rows (the paper's names): plm ("Penumbra Limit Maps"), smoothies, kirsch ("Kirsch & Doellner"),
// pcf with a 1-texel box ("Reeves Filtering": the paper notes it "always creates one-shadowmap-pixel-
// wide soft shadows"), hard ("Hard Shadow Map"), raytraced-hard ("Shadow Volumes": the exact hard
// shadow) and the reference at 16 samples per pixel with another seed than the truth ("16 Samples").
// A technique with a map_size parameter runs at every size; the others run once and their value
// stands for every size. The truth is the reference at `truthSpp` (the paper used 4,096 rays).
// "Smoothies and Kirsch and Döllner are compared with the outer and inner penumbra respectively"
// (Fig. 11): besides their rows against the full truth, smoothies and hard are measured against the
// outer half truth and kirsch and hard against the inner one (halfPenumbraTruth, metrics.h).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "penumbra/image.h"
#include "penumbra/metrics.h"
#include "penumbra/scene.h"

namespace penumbra {

struct LawlorRowSpec {
  std::string label;                 //!< the paper's row name
  std::string technique;             //!< registry name
  std::vector<std::string> params;   //!< "key=value" (map_size is added per size)
  std::vector<double> paper;         //!< Fig. 10's values at 16, 32, 64, 128 (empty: none)
  std::optional<PenumbraHalf> half;  //!< measured against this half truth; absent: the full truth
};

// Fig. 10's rows with the paper's numbers.
std::vector<LawlorRowSpec> lawlorFigure10Rows();

struct LawlorTableOptions {
  std::vector<int> mapSizes{16, 32, 64, 128};
  int width = 512, height = 512;  //!< image size, pixels
  uint32_t truthSpp = 4096;       //!< samples per pixel of the truth, >= 1
  uint64_t truthSeed = 1;
  uint64_t sampledSeed = 2;  //!< seed of the "16 Samples" row (independent of the truth)
  int figureMapSize = 32;    //!< the map size of Fig. 11's images (must be in mapSizes)
};

struct LawlorRow {
  LawlorRowSpec spec;
  bool usesMap = false;       //!< has a map_size parameter
  std::vector<double> rmse8;  //!< per map size, in LawlorTableOptions::mapSizes' order
  std::vector<double> penumbraRmse8;
  Image<float> figureV;  //!< V at figureMapSize (Fig. 11, top row)
};

struct LawlorTable {
  LawlorTableOptions options;
  std::string scene;
  std::vector<LawlorRow> rows;
  Image<float> truth;              //!< V of the truth
  Image<uint8_t> mask;             //!< the error mask
  double truthMeanStdError = 0.0;  //!< mean per-pixel standard error of the truth
  double seconds = 0.0;            //!< wall-clock time of the sweep

  //! The row of `technique` measured against the full truth, or against `half`; throws Error if absent.
  const LawlorRow& row(const std::string& technique, std::optional<PenumbraHalf> half = std::nullopt) const;
};

// Runs the sweep on the scene's first light. Throws Error for bad options.
LawlorTable runLawlorTable(const Scene& scene, const LawlorTableOptions& options = {},
                           const std::vector<LawlorRowSpec>& rows = lawlorFigure10Rows());

// The table as Markdown (ours next to the paper's) and as JSON.
std::string lawlorTableMarkdown(const LawlorTable& table);
std::string lawlorTableJson(const LawlorTable& table);
// Writes lawlor-table.md, lawlor-table.json, and Fig. 11's images: fig11-truth.png and, per row,
// fig11-<technique>.png (V) and fig11-<technique>-diff.png (V - truth: red where too bright, blue
// where too dark, full colour at |difference| 0.5), and for the half-truth rows fig11-truth-outer.png,
// fig11-truth-inner.png and fig11-<technique>-outer-diff.png / -inner-diff.png (V - half truth) into
// `directory` (created if missing).
void writeLawlorTable(const LawlorTable& table, const std::string& directory);

}  // namespace penumbra
