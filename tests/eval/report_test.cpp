// Tests of src/eval/report.cpp and src/eval/html_report.cpp: the JSON report parses back to the
// values it was given, the baseline ratio is total / baseline total, the text formats hold every
// row, and the HTML page shows the JSON's numbers (table cells, plot points, profile), escapes
// names, refers to nothing outside its directory, and joins only non-dominated points on its front.
#include "penumbra/report.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include "eval/html_table.h"
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
    EXPECT_NE(s.find("12.50"), std::string::npos);  // RMSE8
    EXPECT_NE(s.find("40.25"), std::string::npos);  // penumbra RMSE8
    EXPECT_NE(s.find("5.00"), std::string::npos);   // ratio of the reference
    EXPECT_NE(s.find("mean_std_error=0.004"), std::string::npos);
  }
  EXPECT_NE(md.find("| technique |"), std::string::npos);
  EXPECT_NE(md.find("built-in:torus"), std::string::npos);
}

// parker's true spheres against the reference's tessellated ones: every writer says so, and only when
// a row traced one.
TEST(Report, EveryWriterNotesARowThatTracedTrueSpheres) {
  Report r = sampleReport();
  EXPECT_TRUE(reportNotes(r).empty());
  EXPECT_EQ(reportToJson(r).find("\"notes\""), std::string::npos);
  ReportRow parker;
  parker.technique = "parker";
  parker.stats = {{"analytic_spheres", 5.0}, {"rays", 100.0}};
  r.rows.push_back(parker);
  const std::vector<std::string> notes = reportNotes(r);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("parker traced 5 sphere objects as true spheres"), std::string::npos) << notes[0];
  const nlohmann::json j = nlohmann::json::parse(reportToJson(r));
  EXPECT_EQ(j.at("notes").at(0).get<std::string>(), notes[0]);
  EXPECT_NE(reportToMarkdown(r).find("- " + notes[0]), std::string::npos);
  EXPECT_NE(reportToText(r).find("note: " + notes[0]), std::string::npos);
  EXPECT_NE(reportToHtml(r).find("<ul id=\"notes\"><li>parker traced 5 sphere objects as true spheres"),
            std::string::npos);
}

// A compare report with a profile, a map-size sweep and error maps.
Report richReport() {
  Report r = sampleReport();
  r.rows[1].mapSizeVaries = false;
  ReportRow map;
  map.technique = "hard";
  map.error = ErrorStats{20.125, 60.5, 0.75, 100, 10, 7, 3};
  map.timings.add("prepare", 0.25);
  map.timings.add("visibility", 0.5);
  map.images = {{"shaded", "t_hard.png"}, {"visibility", "t_hard_v.png"}, {"error", "t_hard_err.png"}};
  r.rows.push_back(map);
  r.mapSizes = {16, 64};
  r.rows[0].mapSizeSweep = {{16, *r.rows[0].error, r.rows[0].timings}, {64, *r.rows[0].error, r.rows[0].timings}};
  r.rows[1].mapSizeSweep = {{16, *r.rows[1].error, r.rows[1].timings}, {64, *r.rows[1].error, r.rows[1].timings}};
  r.rows[2].mapSizeVaries = true;
  r.rows[2].mapSizeSweep = {{16, ErrorStats{31.5, 70, 1, 100, 10}, map.timings}, {64, *map.error, map.timings}};
  ScanProfile profile;
  profile.row = 3;
  profile.choice = "--profile-row";
  profile.reference = {1.0f, 0.5f, 0.123456f, 0.0f};
  profile.mask = {0, 1, 1, 1};
  r.profile = profile;
  for (ReportRow& row : r.rows) row.profile = {1.0f, 0.25f, 0.0f, 0.0f};
  r.errorMapRange = 0.5;
  r.truth = r.rows[0];
  r.truth->images = {{"shaded", "t_truth.png"}, {"visibility", "t_truth_v.png"}};
  r.command = "penumbra compare --scene torus";
  fillBaselineRatios(r);
  return r;
}

std::map<std::string, std::vector<std::string>> tableValues(const std::string& html) {
  return testing::htmlTableValues(html);
}

TEST(Report, HtmlTableHoldsTheJsonNumbers) {
  const Report r = richReport();
  const nlohmann::json j = nlohmann::json::parse(reportToJson(r));
  const auto table = tableValues(reportToHtml(r));
  ASSERT_EQ(table.size(), j["techniques"].size());
  const char* keys[] = {"rmse8",      "penumbra_rmse8", "max_abs_error", "umbra_leaks",      "speckle",
                        "prepare_ms", "visibility_ms",  "total_ms",      "ratio_to_baseline"};
  for (const auto& row : j["techniques"]) {
    const auto it = table.find(row["label"].get<std::string>());
    ASSERT_NE(it, table.end()) << row["label"];
    ASSERT_EQ(it->second.size(), 1 + std::size(keys));
    EXPECT_EQ(it->second[0], row["label"].get<std::string>());
    for (size_t k = 0; k < std::size(keys); ++k)
      EXPECT_DOUBLE_EQ(std::stod(it->second[k + 1]), row[keys[k]].get<double>()) << row["label"] << " " << keys[k];
  }
}

// A technique that could not take the scene keeps a row with its reason in every writer, outside the
// sorted table body; characters that would break a Markdown table stay inside their cell.
TEST(Report, TechniquesNotRunKeepARowWithTheReason) {
  Report r = richReport();
  r.skipped = {{"ssv", "ssv: a sphere light is not supported | needs a polygon\nlight"}};
  const std::string md = reportToMarkdown(r);
  EXPECT_NE(md.find("| ssv | - |"), std::string::npos) << md;
  EXPECT_NE(md.find("not run here: ssv: a sphere light is not supported \\| needs a polygon light |"),
            std::string::npos)
      << md;
  const std::string text = reportToText(r);
  EXPECT_NE(text.find("not run here: ssv: a sphere light"), std::string::npos) << text;
  const std::string html = reportToHtml(r);
  EXPECT_NE(html.find("<tbody id=\"not-run\">\n<tr data-not-run=\"ssv\"><td>ssv</td><td colspan=\"10\" "
                      "class=\"not-run\">not run here: ssv: a sphere light is not supported | needs a polygon\nlight"),
            std::string::npos);
  EXPECT_EQ(tableValues(html).size(), r.rows.size());  // the sorted body holds the rows that ran
  const nlohmann::json j = nlohmann::json::parse(reportToJson(r));
  EXPECT_EQ(j["skipped"][0]["name"], "ssv");
}

// A scene's name is free text from a file: in Markdown it cannot open raw HTML or end the heading.
TEST(Report, MarkdownEscapesNamesFromFiles) {
  Report r = richReport();
  r.scene = "evil\n# injected <script>alert(1)</script>";
  const std::string md = reportToMarkdown(r);
  EXPECT_EQ(md.find("<script>"), std::string::npos) << md;
  EXPECT_EQ(md.find("\n# injected"), std::string::npos) << md;
  EXPECT_EQ(md.rfind("# penumbra compare: evil # injected &lt;script&gt;alert(1)&lt;/script&gt;\n", 0), 0u) << md;
}

TEST(Report, HtmlPlotsAreDrawnFromTheJsonNumbers) {
  const Report r = richReport();
  const std::string html = reportToHtml(r);
  const nlohmann::json j = nlohmann::json::parse(reportToJson(r));
  // Error against time: one point per row, at the row's total ms and RMSE8.
  const std::regex pointRe("data-technique=\"([^\"]*)\" data-ms=\"([^\"]*)\" data-rmse8=\"([^\"]*)\"");
  size_t points = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), pointRe); it != std::sregex_iterator(); ++it) {
    ++points;
    bool found = false;
    for (const auto& row : j["techniques"])
      if (row["label"] == (*it)[1].str()) {
        found = true;
        EXPECT_DOUBLE_EQ(std::stod((*it)[2]), row["total_ms"].get<double>());
        EXPECT_DOUBLE_EQ(std::stod((*it)[3]), row["rmse8"].get<double>());
      }
    EXPECT_TRUE(found) << (*it)[1];
  }
  EXPECT_EQ(points, r.rows.size());
  // Map-size plot: a marker per size for the technique whose error varies with it.
  const std::regex sizeRe("data-technique=\"hard\" data-map-size=\"(\\d+)\" data-rmse8=\"([^\"]*)\"");
  std::vector<std::pair<int, double>> sizes;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), sizeRe); it != std::sregex_iterator(); ++it)
    sizes.emplace_back(std::stoi((*it)[1]), std::stod((*it)[2]));
  ASSERT_EQ(sizes.size(), 2u);
  for (size_t s = 0; s < 2; ++s) {
    EXPECT_EQ(sizes[s].first, j["techniques"][2]["map_size_sweep"][s]["map_size"].get<int>());
    EXPECT_DOUBLE_EQ(sizes[s].second, j["techniques"][2]["map_size_sweep"][s]["rmse8"].get<double>());
  }
  // The profile: the JSON holds the rounded values the page plots, one vertex per pixel.
  EXPECT_DOUBLE_EQ(j["profile"]["reference"][2].get<double>(), 0.1235);
  EXPECT_EQ(j["profile"]["row"], 3);
  const std::regex truthRe("data-technique=\"truth\" stroke=\"[^\"]*\" points=\"([^\"]*)\"");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(html, m, truthRe));
  const std::string vertices = m[1];
  EXPECT_EQ(std::count(vertices.begin(), vertices.end(), ','), 4);
  EXPECT_NE(html.find("id=\"plot-error-time\""), std::string::npos);
  EXPECT_NE(html.find("id=\"plot-map-size\""), std::string::npos);
  EXPECT_NE(html.find("id=\"plot-profile\""), std::string::npos);
  EXPECT_NE(html.find("id=\"error-legend\""), std::string::npos);
  EXPECT_NE(html.find("&#177;0.5"), std::string::npos);  // the legend states the symmetric range
}

// Every marker inside the plotting frame (x in [64, 700], y in [16, 348] of the 720 x 400 view box):
// an axis that stopped at the last round tick below the largest error would cut it off.
TEST(Report, HtmlPlotPointsLieInsideTheFrame) {
  const std::string html = reportToHtml(richReport());
  const std::regex circleRe("<circle class=\"point\"[^>]* cx=\"([^\"]*)\" cy=\"([^\"]*)\"");
  size_t count = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), circleRe); it != std::sregex_iterator(); ++it) {
    ++count;
    const double cx = std::stod((*it)[1]), cy = std::stod((*it)[2]);
    EXPECT_GE(cx, 64.0 - 1e-6);
    EXPECT_LE(cx, 700.0 + 1e-6);
    EXPECT_GE(cy, 16.0 - 1e-6) << (*it)[0];
    EXPECT_LE(cy, 348.0 + 1e-6) << (*it)[0];
  }
  EXPECT_EQ(count, 3u + 2u);  // three on the error-time plot, two sizes of `hard` on the map-size plot
}

// The profile plot zooms to where anything is shadowed, with a margin of max(8, span / 4) pixels.
TEST(Report, HtmlProfileZoomsToTheShadowedColumns) {
  Report r = richReport();
  r.profile->reference.assign(200, 1.0f);
  r.profile->mask.assign(200, 1);
  for (int x = 100; x < 110; ++x) r.profile->reference[static_cast<size_t>(x)] = 0.5f;
  for (ReportRow& row : r.rows) row.profile.assign(200, 1.0f);
  r.rows[1].profile[105] = 0.0f;
  const std::string html = reportToHtml(r);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(html, m, std::regex("data-technique=\"truth\" stroke=\"[^\"]*\" points=\"([^\"]*)\"")));
  const std::string vertices = m[1];
  EXPECT_EQ(std::count(vertices.begin(), vertices.end(), ','), 118 - 92);
  EXPECT_NE(html.find("columns 92 to 117 of 200"), std::string::npos);
  // The JSON keeps the whole row.
  EXPECT_EQ(nlohmann::json::parse(reportToJson(r))["profile"]["reference"].size(), 200u);
}

TEST(Report, HtmlFrontJoinsOnlyNonDominatedPoints) {
  Report r;
  r.kind = "compare";
  r.width = r.height = 4;
  const std::tuple<const char*, double, double> rows[] = {
      {"fast", 1.0, 10.0}, {"dominated", 2.0, 20.0}, {"accurate", 10.0, 5.0}, {"slow-bad", 50.0, 8.0}};
  for (const auto& [name, ms, err] : rows) {
    ReportRow row;
    row.technique = name;
    row.error = ErrorStats{err, err, 0.1, 10, 1};
    row.timings.add("visibility", ms);
    r.rows.push_back(row);
  }
  const std::string html = reportToHtml(r);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(html, m, std::regex("<polyline class=\"front\" points=\"([^\"]*)\"")));
  const std::string front = m[1];
  EXPECT_EQ(std::count(front.begin(), front.end(), ','), 2) << front;  // fast, accurate
}

TEST(Report, HtmlEscapesNamesAndStaysOnDisk) {
  Report r = richReport();
  r.rows[1].label = "<b>bold</b> & \"quoted\"";
  r.light = "sphere <script>alert(1)</script>";
  const std::string html = reportToHtml(r);
  EXPECT_EQ(html.find("<b>bold</b>"), std::string::npos);
  EXPECT_EQ(html.find("<script>alert"), std::string::npos);
  EXPECT_NE(html.find("&lt;b&gt;bold&lt;/b&gt; &amp; &quot;quoted&quot;"), std::string::npos);
  // Self-contained: no stylesheet, script or image from elsewhere; the only URL is SVG's namespace name.
  for (const char* forbidden : {"<link", "@import", "src=\"http", "href=\"http", "url(http", "//cdn", "src=\"/"})
    EXPECT_EQ(html.find(forbidden), std::string::npos) << forbidden;
  const std::regex srcRe("src=\"([^\"]*)\"");
  size_t images = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), srcRe); it != std::sregex_iterator(); ++it) {
    ++images;
    EXPECT_EQ((*it)[1].str().find('/'), std::string::npos) << (*it)[1];  // beside the page
  }
  EXPECT_GT(images, 0u);
  EXPECT_NE(html.find("t_hard_err.png"), std::string::npos);
  EXPECT_NE(html.find("t_truth.png"), std::string::npos);
}

TEST(Report, MarkdownHasTheMapSizeTable) {
  const std::string md = reportToMarkdown(richReport());
  EXPECT_NE(md.find("| technique | 16 | 64 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| hard | 31.50 | 20.12 |"), std::string::npos) << md;  // 20.125 (exact in binary) rounds to even
  EXPECT_NE(md.find("| raytraced-hard (no map) | 12.50 | 12.50 |"), std::string::npos) << md;
  EXPECT_NE(md.find("scan-line profile: row 3"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(reportToJson(richReport()));
  EXPECT_EQ(j["map_sizes"], nlohmann::json::array({16, 64}));
  EXPECT_FALSE(j["techniques"][1]["map_size_varies"].get<bool>());
  EXPECT_TRUE(j["techniques"][2]["map_size_varies"].get<bool>());
  EXPECT_DOUBLE_EQ(j["error_map_range"].get<double>(), 0.5);
  EXPECT_EQ(j["truth"]["images"]["shaded"], "t_truth.png");
}

TEST(Report, DescribeLightNamesShapeAndValues) {
  EXPECT_EQ(describeLight(Light::sphere(Vec3(0.0f, 4.0f, 0.0f), 0.5f)),
            "sphere center (0, 4, 0) radius 0.5, intensity 1");
}

TEST(Report, WriteTextFileFailsWithThePath) {
  const std::string bad = "/nonexistent-penumbra-dir/report.json";
  try {
    writeTextFile(bad, "x");
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
  }
  const auto path =
      std::filesystem::temp_directory_path() / ("penumbra_report_test_" + std::to_string(getpid()) + ".md");
  writeTextFile(path.string(), "hello\n");
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(), "hello\n");
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace penumbra
