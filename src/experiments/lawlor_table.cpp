// The Fig. 10 / Fig. 11 sweep of Lawlor 2006: see src/experiments/lawlor_table.h.
#include "experiments/lawlor_table.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "penumbra/error.h"
#include "penumbra/image_io.h"
#include "penumbra/metrics.h"
#include "penumbra/raster.h"
#include "penumbra/reference.h"
#include "penumbra/registry.h"
#include "penumbra/timer.h"

namespace penumbra {

std::vector<LawlorRowSpec> lawlorFigure10Rows() {
  // smoothies and kirsch as their papers read their buffers: at the texel holding the pixel.
  return {
      {"Penumbra Limit Maps", "plm", {}, {11.3, 9.0, 9.2, 8.8}, std::nullopt},
      {"Smoothies", "smoothies", {"sub_texel=false"}, {24.7, 17.8, 16.4, 15.3}, std::nullopt},
      {"Kirsch & Doellner", "kirsch", {"sub_texel=false"}, {37.2, 23.0, 15.6, 10.9}, std::nullopt},
      {"Reeves Filtering", "pcf", {"kernel=1"}, {25.7, 26.8, 28.5, 30.3}, std::nullopt},
      {"Hard Shadow Map", "hard", {}, {45.5, 39.3, 35.1, 34.2}, std::nullopt},
      {"Shadow Volumes", "raytraced-hard", {}, {33.5, 33.5, 33.5, 33.5}, std::nullopt},
      {"16 Samples", "reference", {"spp=16"}, {12.0, 12.0, 12.0, 12.0}, std::nullopt},
      // Fig. 11's comparison of the two half-penumbra techniques, with hard against the same halves.
      {"Smoothies, outer penumbra", "smoothies", {"sub_texel=false"}, {24.7, 17.8, 16.4, 15.3}, PenumbraHalf::Outer},
      {"Hard Shadow Map, outer penumbra", "hard", {}, {}, PenumbraHalf::Outer},
      {"Kirsch & Doellner, inner penumbra",
       "kirsch",
       {"sub_texel=false"},
       {37.2, 23.0, 15.6, 10.9},
       PenumbraHalf::Inner},
      {"Hard Shadow Map, inner penumbra", "hard", {}, {}, PenumbraHalf::Inner},
  };
}

const LawlorRow& LawlorTable::row(const std::string& technique, std::optional<PenumbraHalf> half) const {
  for (const LawlorRow& r : rows)
    if (r.spec.technique == technique && r.spec.half == half) return r;
  fail("Lawlor table: no row for technique '{}'{}", technique,
       !half                          ? ""
       : *half == PenumbraHalf::Outer ? " against the outer penumbra"
                                      : " against the inner penumbra");
}

LawlorTable runLawlorTable(const Scene& scene, const LawlorTableOptions& options,
                           const std::vector<LawlorRowSpec>& rows) {
  if (scene.lights.empty()) fail("Lawlor table: scene '{}' has no light", scene.name);
  if (options.mapSizes.empty()) fail("Lawlor table: mapSizes is empty; expected map sizes such as 16,32,64,128");
  if (options.truthSpp < 1) fail("Lawlor table: truthSpp = 0; expected >= 1 samples per pixel");
  if (std::find(options.mapSizes.begin(), options.mapSizes.end(), options.figureMapSize) == options.mapSizes.end())
    fail("Lawlor table: figureMapSize = {} is not one of the map sizes", options.figureMapSize);
  Timer timer;
  LawlorTable table;
  table.options = options;
  table.scene = scene.name;
  const Light& light = scene.lights.front();
  const GBuffer gbuffer = renderGBuffer(scene, options.width, options.height);
  table.mask = errorMask(gbuffer, light);
  {
    ReferenceTechnique truth(ReferenceOptions{options.truthSpp, options.truthSeed});
    truth.prepare(scene, light);
    truth.visibility(gbuffer, table.truth);
    for (const auto& [key, value] : truth.stats())
      if (key == "mean_std_error") table.truthMeanStdError = value;
  }
  const Image<float> outerTruth = halfPenumbraTruth(table.truth, PenumbraHalf::Outer);
  const Image<float> innerTruth = halfPenumbraTruth(table.truth, PenumbraHalf::Inner);
  for (const LawlorRowSpec& spec : rows) {
    const Image<float>& truth = !spec.half ? table.truth : *spec.half == PenumbraHalf::Outer ? outerTruth : innerTruth;
    LawlorRow row;
    row.spec = spec;
    const TechniqueInfo& info = findTechnique(spec.technique);
    row.usesMap = info.hasParam("map_size");
    const auto run = [&](int mapSize) {
      ParamSet given;
      for (const std::string& kv : spec.params) given.setFromKeyValue(kv, "Lawlor table row " + spec.label);
      if (spec.technique == "reference") given.set("seed", int64_t(options.sampledSeed), "Lawlor table");
      if (row.usesMap) given.set("map_size", int64_t{mapSize}, "Lawlor table");
      // The paper's V: no technique of Fig. 10 clamps to the receiver's horizon.
      if (info.hasParam("horizon")) given.setFromKeyValue("horizon=off", "Lawlor table");
      auto technique = createTechnique(spec.technique, given);
      technique->prepare(scene, light);
      Image<float> v;
      technique->visibility(gbuffer, v);
      return v;
    };
    if (row.usesMap) {
      for (int size : options.mapSizes) {
        Image<float> v = run(size);
        const ErrorStats e = compareVisibility(v, truth, table.mask);
        row.rmse8.push_back(e.rmse8);
        row.penumbraRmse8.push_back(e.penumbraRmse8);
        if (size == options.figureMapSize) row.figureV = std::move(v);
      }
    } else {
      row.figureV = run(0);
      const ErrorStats e = compareVisibility(row.figureV, truth, table.mask);
      row.rmse8.assign(options.mapSizes.size(), e.rmse8);
      row.penumbraRmse8.assign(options.mapSizes.size(), e.penumbraRmse8);
    }
    table.rows.push_back(std::move(row));
  }
  table.seconds = timer.elapsedMs() / 1000.0;
  return table;
}

std::string lawlorTableMarkdown(const LawlorTable& table) {
  std::string md = fmt::format(
      "RMSE8 (x255) on `{}` at {}x{}, truth: reference at {} spp (mean standard error {:.4f})\n\n", table.scene,
      table.options.width, table.options.height, table.options.truthSpp, table.truthMeanStdError);
  md += "| technique |";
  for (int size : table.options.mapSizes) md += fmt::format(" {} ours | {} paper |", size, size);
  md += "\n|---|";
  for (size_t i = 0; i < table.options.mapSizes.size(); ++i) md += "---:|---:|";
  md += "\n";
  for (const LawlorRow& row : table.rows) {
    md += fmt::format("| {} (`{}`) |", row.spec.label, row.spec.technique);
    for (size_t i = 0; i < table.options.mapSizes.size(); ++i) {
      const int size = table.options.mapSizes[i];
      const int paperIndex = size == 16 ? 0 : size == 32 ? 1 : size == 64 ? 2 : size == 128 ? 3 : -1;
      const std::string paper = paperIndex >= 0 && static_cast<size_t>(paperIndex) < row.spec.paper.size()
                                    ? fmt::format("{:.1f}", row.spec.paper[static_cast<size_t>(paperIndex)])
                                    : "—";
      md += fmt::format(" {:.1f} | {} |", row.rmse8[i], paper);
    }
    md += "\n";
  }
  return md;
}

std::string lawlorTableJson(const LawlorTable& table) {
  nlohmann::json j;
  j["scene"] = table.scene;
  j["width"] = table.options.width;
  j["height"] = table.options.height;
  j["truth_spp"] = table.options.truthSpp;
  j["truth_mean_std_error"] = table.truthMeanStdError;
  j["map_sizes"] = table.options.mapSizes;
  j["seconds"] = table.seconds;
  for (const LawlorRow& row : table.rows) {
    nlohmann::json r;
    r["label"] = row.spec.label;
    r["technique"] = row.spec.technique;
    r["truth"] = !row.spec.half ? "full" : *row.spec.half == PenumbraHalf::Outer ? "outer penumbra" : "inner penumbra";
    r["params"] = row.spec.params;
    r["uses_map"] = row.usesMap;
    r["rmse8"] = row.rmse8;
    r["penumbra_rmse8"] = row.penumbraRmse8;
    r["paper_rmse8"] = row.spec.paper;
    j["rows"].push_back(r);
  }
  return j.dump(2) + "\n";
}

namespace {

Image<Vec3> signedDifference(const Image<float>& v, const Image<float>& truth, const Image<uint8_t>& mask) {
  Image<Vec3> out(v.width(), v.height(), Vec3(0.0f));
  for (size_t i = 0; i < v.size(); ++i) {
    if (!mask[i]) continue;
    const float d = std::clamp(2.0f * (v[i] - truth[i]), -1.0f, 1.0f);
    out[i] = d > 0.0f ? Vec3(d, 0.0f, 0.0f) : Vec3(0.0f, 0.0f, -d);
  }
  return out;
}

void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream file(path);
  if (!file) fail("Lawlor table: cannot write '{}'; check that the directory is writable", path.string());
  file << text;
}

}  // namespace

void writeLawlorTable(const LawlorTable& table, const std::string& directory) {
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  if (ec) fail("Lawlor table: cannot create directory '{}': {}", directory, ec.message());
  const std::filesystem::path dir(directory);
  writeText(dir / "lawlor-table.md", lawlorTableMarkdown(table));
  writeText(dir / "lawlor-table.json", lawlorTableJson(table));
  writePngGray((dir / "fig11-truth.png").string(), table.truth);
  const Image<float> outerTruth = halfPenumbraTruth(table.truth, PenumbraHalf::Outer);
  const Image<float> innerTruth = halfPenumbraTruth(table.truth, PenumbraHalf::Inner);
  writePngGray((dir / "fig11-truth-outer.png").string(), outerTruth);
  writePngGray((dir / "fig11-truth-inner.png").string(), innerTruth);
  for (const LawlorRow& row : table.rows) {
    if (row.spec.half) {
      // The V image is the full-truth row's; only the difference to the half truth is new.
      const bool outer = *row.spec.half == PenumbraHalf::Outer;
      writePng((dir / fmt::format("fig11-{}-{}-diff.png", row.spec.technique, outer ? "outer" : "inner")).string(),
               signedDifference(row.figureV, outer ? outerTruth : innerTruth, table.mask));
      continue;
    }
    writePngGray((dir / fmt::format("fig11-{}.png", row.spec.technique)).string(), row.figureV);
    writePng((dir / fmt::format("fig11-{}-diff.png", row.spec.technique)).string(),
             signedDifference(row.figureV, table.truth, table.mask));
  }
}

}  // namespace penumbra
