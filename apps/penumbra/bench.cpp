// `penumbra bench`: per-pass wall-clock times (steady frames: median over the --repeat runs after the
// first; the first frame's total apart, as first_frame_ms) of techniques on one
// scene, with the time relative to a baseline measured in the same run (the machines are shared
// and noisy, so only same-run ratios are comparable; docs/architecture.md, "Conventions"). Micro-benchmarks
// of individual kernels live in bench/ (Google Benchmark).
#include <algorithm>
#include <cstdio>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "cli.h"
#include "core/image_fill.h"
#include "penumbra/error.h"
#include "penumbra/motion.h"
#include "penumbra/raster.h"
#include "penumbra/report.h"

namespace penumbra::cli {

namespace {

struct BenchOptions {
  FrameOptions frame;
  std::vector<std::string> techniques;
  std::string baseline;
  std::optional<int> repeat;  //!< runs per technique (default 5); a sequence runs each frame once
  std::string jsonPath;
  MotionOptions motion;
};

// The frames of a motion, one instance of each technique across them, as a renderer runs it; each
// frame's G-buffer is rendered once (into the same buffer) and timed. A row's timings are each pass's
// median over the frames after the first (steady frames); the first frame's total, which builds what
// the others reuse, is its `first_frame_ms`. Rows in `names`' order; a technique that cannot take a
// frame leaves the sequence with its reason. Every technique writes its V into `target`.
std::vector<ReportRow> benchSequence(const Setup& setup, const Motion& motion, const std::vector<std::string>& names,
                                     const std::vector<ParamSet>& given, NotRunTechniques& notRun,
                                     std::vector<double>& gbufferMs, Image<float>& target) {
  std::vector<std::unique_ptr<ShadowTechnique>> instances(names.size());
  std::vector<std::optional<ReportRow>> rows(names.size(), ReportRow{});
  std::vector<std::vector<PassTimings>> steady(names.size());
  std::vector<double> firstFrameMs(names.size(), 0.0), setupMs(names.size(), 0.0);
  GBuffer gbuffer;
  for (int k = 0; k < motion.frames; ++k) {
    Setup frame = setup;
    frame.scene = sceneAtFrame(setup.scene, motion, k);
    Timer timer;
    renderGBuffer(frame.scene, setup.width, setup.height, gbuffer);
    gbufferMs.push_back(timer.elapsedMs());
    for (size_t i = 0; i < names.size(); ++i) {
      if (!rows[i]) continue;
      const TechniqueInfo& info = findTechnique(names[i]);
      try {
        TechniqueRun run = runTechnique(frame, gbuffer, info, given[i], 1, &instances[i], &target);
        if (k == 0) {
          rows[i]->technique = info.name;
          rows[i]->params = describeParams(run.params);
          firstFrameMs[i] = run.timings.total();
          setupMs[i] = run.setupMs;
        } else {
          steady[i].push_back(std::move(run.timings));
        }
        rows[i]->stats = std::move(run.stats);  // the last frame's
      } catch (const std::exception& e) {
        notRun.add(info.name, e.what());
        rows[i].reset();
      }
    }
  }
  std::vector<ReportRow> out;
  for (size_t i = 0; i < names.size(); ++i) {
    if (!rows[i]) continue;
    rows[i]->timings = medianOverFrames(steady[i]);
    rows[i]->stats.emplace_back("first_frame_ms", firstFrameMs[i]);
    rows[i]->stats.emplace_back("setup_ms", setupMs[i]);
    out.push_back(std::move(*rows[i]));
  }
  return out;
}

int runBench(const BenchOptions& options) {
  ThreadLimit threads(options.frame.threads);
  std::vector<std::string> names = techniqueList(options.techniques);
  const std::string baseline = options.baseline.empty() ? defaultBaseline() : options.baseline;
  findTechnique(baseline);
  if (std::find(names.begin(), names.end(), baseline) == names.end()) names.push_back(baseline);
  checkPrefixedParams(options.frame.params, names);

  const Setup setup = loadSetup(options.frame);
  const std::optional<Motion> motion = runMotion(options.motion, setup);
  if (motion && options.repeat)
    fail("--repeat is for a still scene; over a sequence each of the {} frames runs once", motion->frames);
  const int repeat = motion ? motion->frames : options.repeat.value_or(5);
  if (!options.jsonPath.empty()) refuseInputOverwrite(setup, options.jsonPath);
  std::vector<ParamSet> given;
  std::vector<PlannedRun> planned;
  for (const std::string& name : names) {
    const TechniqueInfo& info = findTechnique(name);
    given.push_back(gatherParams(setup, info, options.frame, true));
    planned.push_back({&info, resolveParams(info.name, info.params, given.back()), repeat});
  }
  checkResources(setup, planned, 1, options.frame.force);
  if (!options.jsonPath.empty()) checkWritableFolderOf(options.jsonPath);

  fmt::print("{}\n", describeSetup(setup));
  std::vector<double> gbufferMs;
  double gbufferFirstMs = 0.0, gbufferSetupMs = 0.0;
  GBuffer gbuffer;
  if (motion) {
    fmt::print("{} frames: {}\n", motion->frames, describeMotion(*motion));
  } else {
    // The G-buffer's images made, and their pages touched, for the image size before any frame is
    // timed, as a renderer makes its render targets when its window is sized: every frame, the first
    // included, renders into storage that persists. Their making is reported apart (gbuffer_setup_ms).
    const Timer setupTimer;
    resetGBuffer(gbuffer, setup.width, setup.height);
    gbufferSetupMs = setupTimer.elapsedMs();
    for (int r = 0; r < repeat; ++r) {  // into the same G-buffer, as a renderer does frame to frame
      Timer timer;
      renderGBuffer(setup.scene, setup.width, setup.height, gbuffer);
      gbufferMs.push_back(timer.elapsedMs());
    }
    // The first frame builds the rasterizer's scratch: reported apart, the median is the steady one.
    gbufferFirstMs = gbufferMs.front();
    if (gbufferMs.size() > 1) gbufferMs.erase(gbufferMs.begin());
  }

  const SharedBuildMs shared = buildSharedCaches(setup.scene, names);
  Report report = beginReport("bench", setup, baseline);
  // The G-buffer's time is reported once all runs are in (over a sequence, every frame renders its own).
  report.settings = {{motion ? "frames" : "repeat", fmt::format("{}", repeat)},
                     {"statistic", motion ? "median over frames 2 to N of one technique instance (steady frames); "
                                            "first_frame_ms: frame 1, which builds what the others reuse; "
                                            "setup_ms: the instance's storage made before frame 1 (reserve)"
                                          : "median over repeats 2 to N of one technique instance (steady frames; "
                                            "repeat 1: the first); first_frame_ms: repeat 1, which builds what the "
                                            "others reuse and faults in what fresh memory reserve did not make; "
                                            "setup_ms: the instance's storage made before repeat 1 (reserve)"}};
  // As in compare: a technique that cannot take this scene costs its row, and fails the run only when named.
  NotRunTechniques notRun(report, !options.techniques.empty(), options.baseline);
  // The techniques' output, made (and its pages touched) before any is timed and kept across them and
  // across a sequence's frames, as a renderer keeps its render target (runTechnique).
  Image<float> target;
  resetInParallel(target, setup.width, setup.height, 1.0f);
  if (motion) report.rows = benchSequence(setup, *motion, names, given, notRun, gbufferMs, target);
  for (size_t i = 0; i < names.size() && !motion; ++i) {
    const TechniqueInfo& info = findTechnique(names[i]);
    std::optional<TechniqueRun> attempt;
    try {
      attempt = runTechnique(setup, gbuffer, info, given[i], repeat, nullptr, &target);
    } catch (const std::exception& e) {
      notRun.add(info.name, e.what());
      continue;
    }
    const TechniqueRun& run = *attempt;
    ReportRow row;
    row.technique = info.name;
    row.params = describeParams(run.params);
    row.timings = run.timings;
    row.stats = run.stats;
    row.stats.emplace_back("first_frame_ms", run.firstFrameMs);
    row.stats.emplace_back("setup_ms", run.setupMs);
    report.rows.push_back(std::move(row));
  }
  report.settings.emplace_back("gbuffer_ms", fmt::format("{:.3f}", median(gbufferMs)));
  if (shared.rayScene) report.settings.emplace_back("ray_scene_ms", fmt::format("{:.3f}", *shared.rayScene));
  if (shared.meshEdges) report.settings.emplace_back("mesh_edges_ms", fmt::format("{:.3f}", *shared.meshEdges));
  if (!motion) {
    report.settings.emplace_back("gbuffer_first_ms", fmt::format("{:.3f}", gbufferFirstMs));
    report.settings.emplace_back("gbuffer_setup_ms", fmt::format("{:.3f}", gbufferSetupMs));
  }
  addFrameSettings(report.settings, options.frame);
  fillBaselineRatios(report);
  // The Embree scene and the meshes' edge adjacency are built once for the scene before any technique
  // (buildSharedCaches).
  const std::string sharedBuilt =
      (shared.rayScene ? fmt::format("; Embree scene {:.2f} ms, built once, shared", *shared.rayScene)
                       : std::string()) +
      (shared.meshEdges ? fmt::format("; mesh edges {:.2f} ms, built once, shared", *shared.meshEdges) : std::string());
  if (motion)
    fmt::print("G-buffer raster {:.2f} ms (median of {}){}\n\n{}", median(gbufferMs), gbufferMs.size(), sharedBuilt,
               reportToText(report));
  else
    fmt::print(
        "G-buffer raster {:.2f} ms steady (median of {}), {:.2f} ms first; its storage made at setup {:.2f} ms{}\n\n{}",
        median(gbufferMs), gbufferMs.size(), gbufferFirstMs, gbufferSetupMs, sharedBuilt, reportToText(report));
  if (!options.jsonPath.empty()) {
    writeTextFile(options.jsonPath, reportToJson(report));
    fmt::print("wrote {}\n", options.jsonPath);
  }
  return notRun.exitCode("table");
}

}  // namespace

Command addBenchCommand(CLI::App& parent) {
  auto options = std::make_shared<BenchOptions>();
  CLI::App* app = parent.add_subcommand(
      "bench", "time techniques per pass (steady frames, the first apart) relative to a baseline");
  app->add_option("--techniques,-t", options->techniques,
                  "comma-separated technique names (default: every registered technique)")
      ->delimiter(',');
  app->add_option("--baseline", options->baseline,
                  "technique the ratios are relative to, measured in the same run (default: hard if registered, "
                  "else raytraced-hard)");
  app->add_option("--repeat", options->repeat,
                  "runs per technique: the median of runs 2 to N is reported (steady frames), the first run's total as "
                  "first_frame_ms (default 5; not with a motion)")
      ->check(CLI::Range(1, 1000));
  app->add_option("--json", options->jsonPath, "also write the table as JSON to this file");
  addFrameOptions(
      *app, options->frame,
      "technique parameter technique.key=value, e.g. reference.spp=64, or *.key=value for every technique that has "
      "the key, e.g. *.map_fit=stable (repeatable; overrides the scene file; a technique's own key overrides *)");
  addMotionOptions(*app, options->motion);
  return {app, [options] { return runBench(*options); }};
}

}  // namespace penumbra::cli
