// Tests of src/eval/report.cpp: the JSON report parses back to the values it was given, the
// baseline ratio is total / baseline total, and the text formats hold every row.
#include "penumbra/report.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "penumbra/error.h"

namespace penumbra {
namespace {

Report sampleReport() {
  Report r;
  r.kind = "compare";
  r.version = "9.9.9";
  r.scene = "torus";
  r.sceneSource = "built-in:torus";
  r.lightIndex = 0;
  r.light = describeLight(Light::sphere(Vec3(0.0f, 4.0f, 0.0f), 0.5f));
  r.width = 32;
  r.height = 16;
  r.baseline = "raytraced-hard";
  r.settings = {{"spp", "4"}};
  ReportRow ref;
  ref.technique = "reference";
  ref.params = {{"spp", "4"}, {"seed", "auto"}};
  ref.error = ErrorStats{0.0, 0.0, 0.0, 100, 10};
  ref.timings.add("prepare", 1.0);
  ref.timings.add("visibility", 9.0);
  ref.stats = {{"mean_std_error", 0.004}};
  ReportRow hard;
  hard.technique = "raytraced-hard";
  hard.error = ErrorStats{12.5, 40.25, 1.0, 100, 10};
  hard.timings.add("prepare", 0.5);
  hard.timings.add("visibility", 1.5);
  hard.images = {{"shaded", "torus_raytraced-hard.png"}};
  r.rows = {ref, hard};
  return r;
}

TEST(Report, BaselineRatioIsTotalOverBaselineTotal) {
  Report r = sampleReport();
  fillBaselineRatios(r);
  ASSERT_TRUE(r.rows[0].ratioToBaseline.has_value());
  EXPECT_DOUBLE_EQ(*r.rows[0].ratioToBaseline, 10.0 / 2.0);
  EXPECT_DOUBLE_EQ(*r.rows[1].ratioToBaseline, 1.0);
  r.baseline = "hard";  // not among the rows: no ratio rather than a made-up one
  fillBaselineRatios(r);
  EXPECT_FALSE(r.rows[0].ratioToBaseline.has_value());
}

TEST(Report, JsonHoldsEveryField) {
  Report r = sampleReport();
  fillBaselineRatios(r);
  const nlohmann::json j = nlohmann::json::parse(reportToJson(r));
  EXPECT_EQ(j["kind"], "compare");
  EXPECT_EQ(j["penumbra_version"], "9.9.9");
  EXPECT_EQ(j["scene"]["name"], "torus");
  EXPECT_EQ(j["image"]["width"], 32);
  EXPECT_EQ(j["baseline"], "raytraced-hard");
  EXPECT_EQ(j["settings"]["spp"], "4");
  ASSERT_EQ(j["techniques"].size(), 2u);
  const auto& hard = j["techniques"][1];
  EXPECT_EQ(hard["name"], "raytraced-hard");
  EXPECT_DOUBLE_EQ(hard["rmse8"].get<double>(), 12.5);
  EXPECT_DOUBLE_EQ(hard["penumbra_rmse8"].get<double>(), 40.25);
  EXPECT_DOUBLE_EQ(hard["max_abs_error"].get<double>(), 1.0);
  EXPECT_EQ(hard["mask_pixels"], 100);
  EXPECT_DOUBLE_EQ(hard["prepare_ms"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(hard["visibility_ms"].get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(hard["total_ms"].get<double>(), 2.0);
  EXPECT_EQ(hard["images"]["shaded"], "torus_raytraced-hard.png");
  const auto& ref = j["techniques"][0];
  EXPECT_EQ(ref["params"]["seed"], "auto");
  EXPECT_DOUBLE_EQ(ref["stats"]["mean_std_error"].get<double>(), 0.004);
  EXPECT_DOUBLE_EQ(ref["ratio_to_baseline"].get<double>(), 5.0);
}

TEST(Report, BenchRowsWithoutErrorOmitErrorFields) {
  Report r = sampleReport();
  r.kind = "bench";
  for (ReportRow& row : r.rows) row.error.reset();
  const nlohmann::json j = nlohmann::json::parse(reportToJson(r));
  EXPECT_FALSE(j["techniques"][0].contains("rmse8"));
  EXPECT_EQ(reportToText(r).find("RMSE8"), std::string::npos);
}

TEST(Report, TextAndMarkdownListEveryRow) {
  Report r = sampleReport();
  fillBaselineRatios(r);
  const std::string text = reportToText(r);
  const std::string md = reportToMarkdown(r);
  for (const std::string& s : {text, md}) {
    EXPECT_NE(s.find("reference"), std::string::npos);
    EXPECT_NE(s.find("raytraced-hard"), std::string::npos);
    EXPECT_NE(s.find("12.50"), std::string::npos);   // RMSE8
    EXPECT_NE(s.find("40.25"), std::string::npos);   // penumbra RMSE8
    EXPECT_NE(s.find("5.00"), std::string::npos);    // ratio of the reference
    EXPECT_NE(s.find("mean_std_error=0.004"), std::string::npos);
  }
  EXPECT_NE(md.find("| technique |"), std::string::npos);
  EXPECT_NE(md.find("built-in:torus"), std::string::npos);
}

TEST(Report, DescribeLightNamesShapeAndValues) {
  EXPECT_EQ(describeLight(Light::sphere(Vec3(0.0f, 4.0f, 0.0f), 0.5f)), "sphere center (0, 4, 0) radius 0.5, intensity 1");
}

TEST(Report, WriteTextFileFailsWithThePath) {
  const std::string bad = "/nonexistent-penumbra-dir/report.json";
  try {
    writeTextFile(bad, "x");
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
  }
  const auto path = std::filesystem::temp_directory_path() / ("penumbra_report_test_" + std::to_string(getpid()) + ".md");
  writeTextFile(path.string(), "hello\n");
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), "hello\n");
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace penumbra
