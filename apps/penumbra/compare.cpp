// `penumbra compare`: every chosen technique against the ray-traced reference on the same
// G-buffer (DESIGN.md, "Data flow"). The reference runs first; each technique's V is compared
// with it over the error mask (metrics.h), timed, and written out; the table goes to the terminal,
// DIR/compare.json and DIR/compare.md. Time ratios are to a baseline measured in the same run.
#include <algorithm>

#include <fmt/format.h>

#include "cli.h"
#include "penumbra/error.h"
#include "penumbra/image_io.h"
#include "penumbra/metrics.h"
#include "penumbra/raster.h"
#include "penumbra/report.h"
#include "penumbra/shade.h"

namespace penumbra::cli {

namespace {

constexpr const char* kReference = "reference";

struct CompareOptions {
  FrameOptions frame;
  std::vector<std::string> techniques;
  std::string baseline;
  std::string outDir = "out";
};

int runCompare(const CompareOptions& options) {
  ThreadLimit threads(options.frame.threads);
  // The reference first (it is the truth every row is measured against), then the requested
  // techniques, then the baseline if it was not requested (ratios need it measured in this run).
  std::vector<std::string> names = {kReference};
  for (const std::string& name : techniqueList(options.techniques))
    if (name != kReference) names.push_back(name);
  const std::string baseline = options.baseline.empty() ? defaultBaseline() : options.baseline;
  findTechnique(baseline);
  if (std::find(names.begin(), names.end(), baseline) == names.end()) names.push_back(baseline);
  checkPrefixedParams(options.frame.params, names);

  const Setup setup = loadSetup(options.frame);
  const Light& light = setupLight(setup);
  // Resolve every technique's parameters before the (long) reference runs, so a typo fails fast.
  std::vector<ParamSet> given;
  for (const std::string& name : names) {
    const TechniqueInfo& info = findTechnique(name);
    given.push_back(gatherParams(setup, info, options.frame, true));
    resolveParams(info.name, info.params, given.back());
  }
  std::vector<std::string> files = {"compare.json", "compare.md"};
  for (const std::string& name : names)
    for (const char* suffix : {".png", "_v.exr", "_v.png"}) files.push_back(setup.scene.name + "_" + name + suffix);
  for (const std::string& file : files) outputPath(setup, options.outDir, file);
  makeOutputDir(options.outDir);

  fmt::print("scene {} ({}), {}x{}, light {}: {}\n", setup.scene.name, setup.scene.source, setup.width, setup.height,
             setup.lightIndex, describeLight(light));
  Timer gbufferTimer;
  const GBuffer gbuffer = renderGBuffer(setup.scene, setup.width, setup.height);
  const double gbufferMs = gbufferTimer.elapsedMs();
  const Image<uint8_t> mask = errorMask(gbuffer, light);

  Report report = beginReport("compare", setup, baseline);
  report.settings = {{"gbuffer_ms", fmt::format("{:.2f}", gbufferMs)},
                     {"threads", options.frame.threads > 0 ? fmt::format("{}", options.frame.threads) : "all"}};
  if (options.frame.spp) report.settings.emplace_back("spp", fmt::format("{}", *options.frame.spp));
  if (options.frame.seed) report.settings.emplace_back("seed", fmt::format("{}", *options.frame.seed));

  Image<float> vReference;
  for (size_t i = 0; i < names.size(); ++i) {
    const TechniqueInfo& info = findTechnique(names[i]);
    TechniqueRun run = runTechnique(setup, gbuffer, info, given[i]);
    if (i == 0) vReference = run.v;
    ReportRow row;
    row.technique = info.name;
    row.params = describeParams(run.params);
    row.error = compareVisibility(run.v, vReference, mask);
    row.timings = run.timings;
    row.stats = run.stats;
    const std::string base = setup.scene.name + "_" + info.name;
    writePng(outputPath(setup, options.outDir, base + ".png"), shade(setup.scene, light, gbuffer, run.v));
    writeExr(outputPath(setup, options.outDir, base + "_v.exr"), run.v);
    writePngGray(outputPath(setup, options.outDir, base + "_v.png"), run.v);
    row.images = {{"shaded", base + ".png"}, {"visibility", base + "_v.png"}, {"visibility_exr", base + "_v.exr"}};
    report.rows.push_back(std::move(row));
  }
  fillBaselineRatios(report);

  const std::string jsonPath = outputPath(setup, options.outDir, "compare.json");
  const std::string mdPath = outputPath(setup, options.outDir, "compare.md");
  writeTextFile(jsonPath, reportToJson(report));
  writeTextFile(mdPath, reportToMarkdown(report));
  fmt::print("G-buffer {:.2f} ms; error mask: {} pixels\n\n{}\nwrote {}, {} and images to {}\n", gbufferMs,
             report.rows.front().error->maskPixels, reportToText(report), jsonPath, mdPath, options.outDir);
  return 0;
}

}  // namespace

Command addCompareCommand(CLI::App& parent) {
  auto options = std::make_shared<CompareOptions>();
  CLI::App* app = parent.add_subcommand(
      "compare", "compare techniques with the ray-traced reference: error, timings, images, compare.json/.md");
  app->add_option("--techniques,-t", options->techniques,
                  "comma-separated technique names (default: every registered technique)")
      ->delimiter(',');
  app->add_option("--baseline", options->baseline,
                  "technique the time ratios are relative to (default: hard if registered, else raytraced-hard)");
  addFrameOptions(*app, options->frame,
                  "technique parameter technique.key=value, e.g. reference.spp=64 (repeatable; overrides the scene file)");
  app->add_option("--out,-o", options->outDir, "output directory (created if missing)")->capture_default_str();
  return {app, [options] { return runCompare(*options); }};
}

}  // namespace penumbra::cli
