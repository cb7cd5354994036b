// `penumbra compare`: every chosen technique against the ray-traced reference on the same
// G-buffer (docs/architecture.md, "Data flow"), written as a report a person opens to choose a technique:
// DIR/report/index.html (sortable table, plots, images beside it), compare.json (every number of
// the page), compare.md, and per technique the shaded image (PNG), V (EXR and PNG) and the signed
// error map against the reference (PNG).
//
// The truth is the `reference` technique with the scene's parameters and --spp/--seed; it is cached
// under DIR/cache (reference_cache.cpp) so a second compare of the same setup does not trace it
// again. `reference` named among the techniques is a row like any other, with its own
// --param reference.*, measured against the truth (rendered once when its parameters equal the
// truth's). With --map-sizes every technique that has a `map_size` parameter also runs at each
// size (the others once); a scan line through the penumbra (--profile-row, or the row with the
// most penumbra pixels in the truth) is kept for the profile plot. Time ratios are to a baseline
// measured in the same run.
//
// Outputs: file names start with the scene's name (or --name) made a safe file name; DIR is locked
// for the run (a second compare into it is refused, not mixed in), and the report is written into a
// fresh folder swapped in for DIR/report only when complete (StagedReport), so an interrupted run
// leaves the previous report whole.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "cli.h"
#include "eval/report_figures.h"
#include "penumbra/error.h"
#include "penumbra/image_io.h"
#include "penumbra/metrics.h"
#include "penumbra/motion.h"
#include "penumbra/raster.h"
#include "penumbra/report.h"
#include "penumbra/scene_io.h"
#include "penumbra/shade.h"
#include "penumbra/temporal_metrics.h"

namespace penumbra::cli {

namespace {

namespace fs = std::filesystem;

constexpr const char* kReference = "reference";
constexpr const char* kMapSize = "map_size";

struct CompareOptions {
  FrameOptions frame;
  std::vector<std::string> techniques;
  std::string baseline;
  std::string outDir = "out";
  std::vector<int> mapSizes;
  std::optional<int> profileRow;
  double errorRange = 0.5;
  std::string cacheDir;  //!< empty: DIR/cache
  bool noCache = false;
  MotionOptions motion;
};

// A row's shown name: techniques with a sample count say it, so a cheap reference row is not
// mistaken for the truth.
std::string rowLabel(const TechniqueInfo& info, const Params& params) {
  if (!info.hasParam("spp")) return info.name;
  return fmt::format("{} ({} spp)", info.name, params.getInt("spp"));
}

std::string joinParams(const KeyValues& params) {
  std::string s;
  for (const auto& [k, v] : params) s += fmt::format("{}{}={}", s.empty() ? "" : " ", k, v);
  return s;
}

bool sameParams(const Params& a, const Params& b) { return describeParams(a) == describeParams(b); }

std::vector<float> rowOf(const Image<float>& v, int y) { return {v.row(y), v.row(y) + v.width()}; }

std::string shellQuote(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./,=:+") ==
                        std::string::npos)
    return s;
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// A command line that renders the same report (the scene as it was named; scene.json beside the
// page is a copy of it).
std::string reproduceCommand(const CompareOptions& options, const Setup& setup, const std::vector<std::string>& names,
                             const std::string& baseline) {
  std::vector<std::string> args = {"penumbra", "compare",
                                   "--scene",  options.frame.scene,
                                   "--width",  std::to_string(setup.width),
                                   "--height", std::to_string(setup.height)};
  if (setup.lightIndex != 0) args.insert(args.end(), {"--light", std::to_string(setup.lightIndex)});
  if (options.frame.spp) args.insert(args.end(), {"--spp", std::to_string(*options.frame.spp)});
  if (options.frame.seed) args.insert(args.end(), {"--seed", std::to_string(*options.frame.seed)});
  args.insert(args.end(), {"--techniques", fmt::format("{}", fmt::join(names, ","))});
  if (!options.baseline.empty()) args.insert(args.end(), {"--baseline", baseline});
  for (const std::string& p : options.frame.params) args.insert(args.end(), {"--param", p});
  if (!options.mapSizes.empty())
    args.insert(args.end(), {"--map-sizes", fmt::format("{}", fmt::join(options.mapSizes, ","))});
  if (options.profileRow) args.insert(args.end(), {"--profile-row", std::to_string(*options.profileRow)});
  if (!options.motion.path.empty())
    args.insert(args.end(), {"--motion-moves", options.motion.moves, "--motion-path", options.motion.path});
  if (options.motion.frames) args.insert(args.end(), {"--frames", std::to_string(*options.motion.frames)});
  args.insert(args.end(), {"--error-range", fmt::format("{:g}", options.errorRange), "--out", options.outDir});
  std::string command;
  for (const std::string& a : args) command += (command.empty() ? "" : " ") + shellQuote(a);
  return command;
}

// The report is written into a fresh folder beside DIR/report and swapped in whole once complete,
// so a failed or interrupted run leaves the previous report as it was (and a folder named
// .report-partial-* that says what it holds), never a page of one run beside images of another.
class StagedReport {
 public:
  StagedReport(const std::string& outDir, const Setup& setup)
      : outDir_(outDir), final_((fs::path(outDir) / "report").string()) {
    struct stat st {};
    if (::lstat(final_.c_str(), &st) == 0 && !S_ISDIR(st.st_mode))
      fail("cannot write the report into '{}': it exists and is not a folder", final_);
    // The swap replaces the whole folder: an input there would be lost with it.
    const fs::path finalCanonical = fs::weakly_canonical(final_);
    for (const std::string& input : setup.scene.inputFiles) {
      const fs::path in = fs::weakly_canonical(input);
      if (std::mismatch(finalCanonical.begin(), finalCanonical.end(), in.begin(), in.end()).first ==
          finalCanonical.end())
        fail(
            "refusing to replace '{}': it holds the input '{}', and a new report replaces the whole folder; copy the "
            "input elsewhere or choose another --out",
            final_, input);
    }
    std::string pattern = (fs::path(outDir) / ".report-partial-XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
      fail("cannot create a folder in '{}': {} (check that it is writable)", outDir, std::strerror(errno));
    staging_ = pattern;
    ::chmod(staging_.c_str(), 0755);  // mkdtemp makes it private; a report is as readable as any folder
  }
  ~StagedReport() {
    std::error_code ec;
    if (!committed_) fs::remove_all(staging_, ec);
  }
  StagedReport(const StagedReport&) = delete;
  StagedReport& operator=(const StagedReport&) = delete;

  const std::string& dir() const { return staging_; }
  const std::string& finalDir() const { return final_; }

  void commit() {
    std::string old;
    if (fs::exists(final_)) {
      old = (fs::path(outDir_) / ".report-old-XXXXXX").string();
      if (!::mkdtemp(old.data()) || ::rename(final_.c_str(), old.c_str()) != 0)
        fail("cannot move the previous report '{}' aside: {}", final_, std::strerror(errno));
    }
    if (::rename(staging_.c_str(), final_.c_str()) != 0)
      fail("cannot move the new report into '{}': {} (it is complete in '{}')", final_, std::strerror(errno), staging_);
    committed_ = true;
    std::error_code ec;
    if (!old.empty()) fs::remove_all(old, ec);
  }

 private:
  std::string outDir_, final_, staging_;
  bool committed_ = false;
};

// The techniques to compare (the baseline appended when not named), after the checks that need
// no scene: the baseline exists, and every prefixed --param names one of them.
std::vector<std::string> comparedTechniques(const CompareOptions& options, const std::string& baseline) {
  std::vector<std::string> names = techniqueList(options.techniques);
  findTechnique(baseline);
  if (std::find(names.begin(), names.end(), baseline) == names.end()) names.push_back(baseline);
  const bool referenceRow = std::find(names.begin(), names.end(), kReference) != names.end();
  for (const std::string& kv : options.frame.params)
    if (kv.rfind(std::string(kReference) + ".", 0) == 0 && !referenceRow)
      fail(
          "command line: parameter '{}' is for a `reference` row, but reference is not among --techniques; the "
          "truth's samples are set by --spp (and --seed)",
          kv);
  checkPrefixedParams(options.frame.params, names);
  return names;
}

// Every parameter set of the run, resolved before the (long) truth runs so a typo fails fast.
struct RunPlan {
  ParamSet truthGiven;
  Params truthParams;
  std::vector<ParamSet> given;                    //!< per technique
  std::vector<std::vector<ParamSet>> sweepGiven;  //!< per technique, per --map-sizes entry (map_size techniques)
  std::vector<PlannedRun> planned;                //!< what the memory and time check counts
};

RunPlan planRuns(const CompareOptions& options, const Setup& setup, const std::vector<std::string>& names,
                 const std::vector<int>& mapSizes) {
  RunPlan plan;
  // The truth takes the scene file's reference parameters and --spp/--seed, never the --param of a
  // reference row.
  const TechniqueInfo& referenceInfo = findTechnique(kReference);
  FrameOptions truthFrame = options.frame;
  truthFrame.params.clear();
  plan.truthGiven = gatherParams(setup, referenceInfo, truthFrame, true);
  plan.truthParams = resolveParams(referenceInfo.name, referenceInfo.params, plan.truthGiven);
  // Each technique run, resolved once here, is also what the memory and time check counts.
  plan.sweepGiven.resize(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    const TechniqueInfo& info = findTechnique(names[i]);
    plan.given.push_back(gatherParams(setup, info, options.frame, true));
    plan.planned.push_back({&info, resolveParams(info.name, info.params, plan.given.back()), 1});
    if (!info.hasParam(kMapSize)) continue;
    for (int size : mapSizes) {
      ParamSet atSize = plan.given.back();
      atSize.set(kMapSize, int64_t{size}, "command line (--map-sizes)");
      plan.planned.push_back({&info, resolveParams(info.name, info.params, atSize), 1});
      plan.sweepGiven[i].push_back(std::move(atSize));
    }
  }
  return plan;
}

// Where the truth comes from: the cache entry when this exact setup was rendered before, else a
// render, stored when the cache can be written.
struct TruthSource {
  std::optional<ReferenceCache> cache;
  std::optional<CachedTruth> cached;
  std::string why = "--no-cache";  //!< why there is no cached truth
  bool store = false;
};

// The cache is looked up, and checked for writing, before any rendering: an unwritable cache is
// said now (the run goes on without storing the truth), and a cached truth costs no rays.
void lookUpTruth(const CompareOptions& options, const Setup& setup, const Params& truthParams, TruthSource& source) {
  if (!options.noCache)
    source.cache.emplace(options.cacheDir.empty() ? (fs::path(options.outDir) / "cache").string() : options.cacheDir,
                         setup, truthParams);
  source.cached = source.cache ? source.cache->load(source.why) : std::nullopt;
  if (source.cached && (source.cached->v.width() != setup.width || source.cached->v.height() != setup.height)) {
    source.why = "its image size differs";
    source.cached.reset();
  }
  if (source.cache && !source.cached) {
    const std::optional<std::string> unwritable = source.cache->whyUnwritable();
    if (unwritable) fmt::print(stderr, "penumbra: warning: {}; going on without caching the truth\n", *unwritable);
    source.store = !unwritable;
  }
}

// What every row's images and errors are made against: the frame, its error mask and the staged
// report folder.
struct CompareFrame {
  const CompareOptions& options;
  const Setup& setup;
  const Light& light;
  const GBuffer& gbuffer;
  const Image<uint8_t>& mask;
  const std::string& reportDir;
  std::string stem;  //!< file names' prefix

  std::string path(const std::string& name) const { return outputPath(setup, reportDir, name); }

  // A row's shaded image, V (EXR and PNG) and, against the truth, its signed error map.
  void writeImages(const std::string& base, const Image<float>& v, ReportRow& row, const Image<float>* truthV) const {
    writePng(path(base + ".png"), shade(setup.scene, light, gbuffer, v));
    writeExr(path(base + "_v.exr"), v);
    writePngGray(path(base + "_v.png"), v);
    row.images = {{"shaded", base + ".png"}, {"visibility", base + "_v.png"}, {"visibility_exr", base + "_v.exr"}};
    if (truthV) {
      writePng(path(base + "_err.png"), signedErrorMap(v, *truthV, mask, options.errorRange));
      row.images.emplace_back("error", base + "_err.png");
    }
  }
};

// The truth's row and V: from the cache when this exact setup was rendered before (lookUpTruth).
Image<float> truthRow(const CompareFrame& frame, const RunPlan& plan, TruthSource& source, ReportRow& truth) {
  const TechniqueInfo& referenceInfo = findTechnique(kReference);
  truth.technique = kReference;
  truth.label = rowLabel(referenceInfo, plan.truthParams);
  truth.params = describeParams(plan.truthParams);
  Image<float> vTruth;
  if (source.cached) {
    fmt::print("truth: reused {} ({}; rendered earlier in {:.1f} ms)\n", source.cache->path(), joinParams(truth.params),
               source.cached->timings.total());
    vTruth = std::move(source.cached->v);
    truth.timings = source.cached->timings;
    truth.stats = source.cached->stats;
    truth.cached = true;
  } else {
    fmt::print("truth: rendering reference {} ({})\n", joinParams(truth.params),
               source.cache ? fmt::format("cache {}: {}", source.cache->path(), source.why) : source.why);
    TechniqueRun run = runTechnique(frame.setup, frame.gbuffer, referenceInfo, plan.truthGiven);
    vTruth = std::move(run.v);
    truth.timings = run.timings;
    truth.stats = run.stats;
    if (source.cache && source.store) {
      try {
        source.cache->store(vTruth, truth.timings, truth.stats);
      } catch (const Error& e) {
        // The truth is rendered: losing the report for want of a cache would waste it.
        fmt::print(stderr, "penumbra: warning: {}; going on without caching the truth\n", e.what());
      }
    }
  }
  truth.error = compareVisibility(vTruth, vTruth, frame.mask);
  frame.writeImages(frame.stem + "truth", vTruth, truth, nullptr);
  return vTruth;
}

ScanProfile scanProfile(const CompareOptions& options, const Image<float>& vTruth, const Image<uint8_t>& mask) {
  ScanProfile profile;
  profile.row = options.profileRow ? *options.profileRow : mostPenumbraRow(vTruth, mask);
  profile.choice = options.profileRow ? "--profile-row" : "the row with the most penumbra pixels in the reference";
  profile.reference = rowOf(vTruth, profile.row);
  profile.mask.assign(mask.row(profile.row), mask.row(profile.row) + mask.width());
  return profile;
}

// One technique's row, its V in `v`; empty when the technique did not run (notRun says why).
std::optional<ReportRow> techniqueRow(const CompareFrame& frame, const TechniqueInfo& info, const Params& params,
                                      const ParamSet& given, const ReportRow& truth, const Image<float>& vTruth,
                                      const Params& truthParams, NotRunTechniques& notRun, Image<float>& v,
                                      std::unique_ptr<ShadowTechnique>* instance = nullptr) {
  ReportRow row;
  row.technique = info.name;
  row.label = rowLabel(info, params);
  row.params = describeParams(params);
  if (info.name == kReference && sameParams(params, truthParams)) {
    // The same parameters as the truth: the same deterministic image; rendering it again would only cost time.
    v = vTruth;
    row.timings = truth.timings;
    row.stats = truth.stats;
    row.cached = truth.cached;
    row.images = truth.images;
    row.images.emplace_back("error", frame.stem + info.name + "_err.png");
    writePng(frame.path(frame.stem + info.name + "_err.png"),
             signedErrorMap(v, vTruth, frame.mask, frame.options.errorRange));
    return row;
  }
  fmt::print("{}{}{}\n", row.shownName(), row.params.empty() ? "" : ": ", joinParams(row.params));
  std::optional<TechniqueRun> attempt;
  try {
    attempt = runTechnique(frame.setup, frame.gbuffer, info, given, 1, instance);
  } catch (const std::exception& e) {
    // A technique that cannot take this scene (its light's shape, or anything its prepare or
    // visibility refuses) costs its row, never the comparison: the others run and the report is
    // written with its reason. Only one the user named makes the exit status non-zero.
    notRun.add(info.name, e.what());
    return std::nullopt;
  }
  TechniqueRun& run = *attempt;
  v = std::move(run.v);
  row.timings = run.timings;
  row.stats = run.stats;
  frame.writeImages(frame.stem + info.name, v, row, &vTruth);
  return row;
}

// The row's points of the --map-sizes sweep: a run per size for a technique with a map_size (the
// row's own run where its map_size is that size), the row's own numbers at every size otherwise.
void sweepMapSizes(const CompareFrame& frame, const TechniqueInfo& info, const Params& params,
                   const std::vector<ParamSet>& sweepGiven, const std::vector<int>& mapSizes,
                   const Image<float>& vTruth, NotRunTechniques& notRun, ReportRow& row) {
  row.mapSizeVaries = info.hasParam(kMapSize);
  for (size_t s = 0; s < mapSizes.size(); ++s) {
    MapSizePoint point{mapSizes[s], *row.error, row.timings};
    if (row.mapSizeVaries && (params.isAuto(kMapSize) || params.getInt(kMapSize) != mapSizes[s])) {
      fmt::print("{}: map_size={}\n", row.shownName(), mapSizes[s]);
      try {
        const TechniqueRun run = runTechnique(frame.setup, frame.gbuffer, info, sweepGiven[s]);
        point.error = compareVisibility(run.v, vTruth, frame.mask);
        point.timings = run.timings;
      } catch (const std::exception& e) {
        // The row leaves the map-size sweep (its plot and table) and this size is listed as not run.
        notRun.add(fmt::format("{} (map_size={})", info.name, mapSizes[s]), e.what());
        row.mapSizeVaries = false;
        row.mapSizeSweep.clear();
        break;
      }
    }
    row.mapSizeSweep.push_back(point);
  }
}

// The page, its JSON and Markdown, and a copy of the scene into the staged folder.
void writeReportFiles(const Setup& setup, const std::string& reportDir, Report& report) {
  report.files = {{"every number of this page", "compare.json"},
                  {"Markdown tables", "compare.md"},
                  {"the scene, meshes inline", "scene.json"}};
  const auto path = [&](const std::string& name) { return outputPath(setup, reportDir, name); };
  writeTextFile(path("scene.json"), sceneToJson(setup.scene));
  writeTextFile(path("compare.json"), reportToJson(report));
  writeTextFile(path("compare.md"), reportToMarkdown(report));
  writeTextFile(path("index.html"), reportToHtml(report));
}

// A row's error over frames: the mean of each frame's (the maximum for the max error).
ErrorStats meanOverFrames(const std::vector<ErrorStats>& frames) {
  ErrorStats mean;
  const double n = static_cast<double>(frames.size());
  double leaks = 0.0, speckle = 0.0, mask = 0.0, penumbra = 0.0;
  for (const ErrorStats& e : frames) {
    mean.rmse8 += e.rmse8 / n;
    mean.penumbraRmse8 += e.penumbraRmse8 / n;
    mean.maxAbsError = std::max(mean.maxAbsError, e.maxAbsError);
    leaks += static_cast<double>(e.umbraLeaks) / n;
    speckle += static_cast<double>(e.speckle) / n;
    mask += static_cast<double>(e.maskPixels) / n;
    penumbra += static_cast<double>(e.penumbraPixels) / n;
  }
  mean.umbraLeaks = static_cast<size_t>(std::lround(leaks));
  mean.speckle = static_cast<size_t>(std::lround(speckle));
  mean.maskPixels = static_cast<size_t>(std::lround(mask));
  mean.penumbraPixels = static_cast<size_t>(std::lround(penumbra));
  return mean;
}

// compare over the frames of a motion: per frame the truth (cached per frame, as any still compare),
// a second truth of the next seed for the noise floor, and every technique; a row per technique with
// its error averaged over frames, its median pass times and its temporal error against the truth's
// sequence (include/penumbra/temporal_metrics.h). A technique that cannot take a frame leaves the
// sequence with its reason, as in a still compare.
int runCompareSequence(const CompareOptions& options, const Setup& setup, const Motion& motion,
                       const std::vector<std::string>& names, const std::string& baseline) {
  if (!options.mapSizes.empty())
    fail("--map-sizes is for a still scene; this one has a motion (--frames, --motion-path)");
  RunPlan plan = planRuns(options, setup, names, {});
  // The noise floor's truth: the same reference with the next seed.
  RunPlan floorPlan = plan;
  const TechniqueInfo& referenceInfo = findTechnique(kReference);
  const int64_t seed = plan.truthParams.getInt("seed");
  floorPlan.truthGiven.set("seed", int64_t{seed + 1}, "the noise floor's second truth (seed + 1)");
  floorPlan.truthParams = resolveParams(referenceInfo.name, referenceInfo.params, floorPlan.truthGiven);

  makeOutputDir(options.outDir);
  const OutputLock lock(options.outDir);
  StagedReport staged(options.outDir, setup);
  // Memory and time: every run once a frame, and the two truths (cached frames are not known yet).
  std::vector<PlannedRun> planned = plan.planned;
  for (PlannedRun& run : planned) run.repeat = motion.frames;
  planned.push_back({&referenceInfo, plan.truthParams, 2 * motion.frames});
  const int keptImages = (static_cast<int>(names.size()) + 2) * motion.frames;
  checkResources(setup, planned, keptImages, options.frame.force);

  fmt::print("{}\n{} frames: {}\n", describeSetup(setup), motion.frames, describeMotion(motion));
  std::vector<std::string> runHere = names;
  runHere.push_back(kReference);  // the truth, unless its cache has it
  const SharedBuildMs shared = buildSharedCaches(setup.scene, runHere);
  Report report = beginReport("compare", setup, baseline);
  report.settings = {{"frames", fmt::format("{}", motion.frames)},
                     {"ray_scene_ms", fmt::format("{:.2f}", shared.rayScene.value_or(0.0))},
                     {"mesh_edges_ms", fmt::format("{:.2f}", shared.meshEdges.value_or(0.0))},
                     {"timings",
                      "median over the frames of one technique instance (the first frame builds what "
                      "later ones reuse, into storage made before it: reserve, in none of its times); the scene's "
                      "Embree scene and its meshes' edge adjacency are built once "
                      "before any technique runs (ray_scene_ms, mesh_edges_ms) and shared by the techniques that "
                      "use them, in none of their times"}};
  addFrameSettings(report.settings, options.frame);
  report.errorMapRange = options.errorRange;
  report.command = reproduceCommand(options, setup, names, baseline);
  NotRunTechniques notRun(report, !options.techniques.empty(), options.baseline);

  std::vector<Image<float>> truths, floors;
  std::vector<Image<uint8_t>> masks;
  std::vector<std::optional<ReportRow>> rows(names.size());  // frame 0's row; empty once a technique fails
  std::vector<std::vector<Image<float>>> vs(names.size());
  std::vector<std::vector<PassTimings>> timings(names.size());
  std::vector<SequenceRow> sequences(names.size());
  std::vector<bool> running(names.size(), true);
  // One instance per technique for the whole sequence, as a renderer keeps its shadow technique from
  // frame to frame: what a prepare builds once for unchanged geometry is built at the first frame.
  std::vector<std::unique_ptr<ShadowTechnique>> instances(names.size());
  std::vector<Params> params;
  for (size_t i = 0; i < names.size(); ++i) {
    const TechniqueInfo& info = findTechnique(names[i]);
    params.push_back(resolveParams(info.name, info.params, plan.given[i]));
  }
  ReportRow truth0;
  SequenceRow truthSequence;  // the truth's images per frame, for the page's frame slider (its temporal error: 0)
  for (int k = 0; k < motion.frames; ++k) {
    Setup frameSetup = setup;
    frameSetup.scene = sceneAtFrame(setup.scene, motion, k);
    frameSetup.stem = fmt::format("{}_f{:03d}", setup.stem, k);
    fmt::print("\nframe {} of {}: {}\n", k + 1, motion.frames, describeLight(setupLight(frameSetup)));
    const GBuffer gbuffer = renderGBuffer(frameSetup.scene, setup.width, setup.height);
    const Image<uint8_t> mask = errorMask(gbuffer, setupLight(frameSetup));
    const CompareFrame frame{options, frameSetup,   setupLight(frameSetup), gbuffer,
                             mask,    staged.dir(), frameSetup.stem + "_"};
    TruthSource source, floorSource;
    lookUpTruth(options, frameSetup, plan.truthParams, source);
    lookUpTruth(options, frameSetup, floorPlan.truthParams, floorSource);
    ReportRow truth, floorRow;
    const Image<float> vTruth = truthRow(frame, plan, source, truth);
    CompareFrame floorFrame = frame;
    floorFrame.stem = frameSetup.stem + "_floor_";
    floors.push_back(truthRow(floorFrame, floorPlan, floorSource, floorRow));
    if (k == 0) truth0 = truth;
    truthSequence.frames.push_back(*truth.error);
    truthSequence.images.push_back(truth.images);
    for (size_t i = 0; i < names.size(); ++i) {
      if (!running[i]) continue;
      Image<float> v;
      std::optional<ReportRow> row = techniqueRow(frame, findTechnique(names[i]), params[i], plan.given[i], truth,
                                                  vTruth, plan.truthParams, notRun, v, &instances[i]);
      if (!row) {
        running[i] = false;
        continue;
      }
      sequences[i].frames.push_back(compareVisibility(v, vTruth, mask));
      sequences[i].images.push_back(row->images);
      timings[i].push_back(row->timings);
      vs[i].push_back(std::move(v));
      if (k == 0) rows[i] = std::move(row);
    }
    truths.push_back(vTruth);
    masks.push_back(mask);
  }

  for (size_t i = 0; i < names.size(); ++i) {
    if (!running[i]) continue;
    ReportRow row = std::move(*rows[i]);
    row.error = meanOverFrames(sequences[i].frames);
    row.timings = medianOverFrames(timings[i]);
    sequences[i].temporal = temporalError(vs[i], truths, masks);
    row.sequence = std::move(sequences[i]);
    report.rows.push_back(std::move(row));
  }
  report.sequence = SequenceInfo{motion.frames, describeMotion(motion), temporalError(floors, truths, masks),
                                 fmt::format("seeds {} and {}", seed, seed + 1)};
  fillBaselineRatios(report);
  truth0.sequence = std::move(truthSequence);
  report.truth = std::move(truth0);

  writeReportFiles(setup, staged.dir(), report);
  staged.commit();
  fmt::print("\n{}\nwrote {} ({}, {} and images beside it)\n", reportToText(report),
             (fs::path(staged.finalDir()) / "index.html").string(), "compare.json", "compare.md");
  return notRun.exitCode("report");
}

int runCompare(const CompareOptions& options) {
  ThreadLimit threads(options.frame.threads);
  const std::string baseline = options.baseline.empty() ? defaultBaseline() : options.baseline;
  const std::vector<std::string> names = comparedTechniques(options, baseline);

  const Setup setup = loadSetup(options.frame);
  const Light& light = setupLight(setup);
  if (options.profileRow && (*options.profileRow < 0 || *options.profileRow >= setup.height))
    fail("--profile-row {} is out of range: the image has {} rows (valid: 0 to {})", *options.profileRow, setup.height,
         setup.height - 1);
  if (const std::optional<Motion> motion = runMotion(options.motion, setup))
    return runCompareSequence(options, setup, *motion, names, baseline);
  std::vector<int> mapSizes = options.mapSizes;
  std::sort(mapSizes.begin(), mapSizes.end());
  mapSizes.erase(std::unique(mapSizes.begin(), mapSizes.end()), mapSizes.end());

  RunPlan plan = planRuns(options, setup, names, mapSizes);
  const int keptImages = static_cast<int>(plan.planned.size()) + 1;  // every run's V and the truth's

  makeOutputDir(options.outDir);
  const OutputLock lock(options.outDir);
  StagedReport staged(options.outDir, setup);
  TruthSource source;
  lookUpTruth(options, setup, plan.truthParams, source);

  // Memory and time, before the G-buffer: every planned run (the truth's unless cached) with the V
  // images the report keeps.
  if (!source.cached) plan.planned.push_back({&findTechnique(kReference), plan.truthParams, 1});
  checkResources(setup, plan.planned, keptImages, options.frame.force);

  fmt::print("{}\n", describeSetup(setup));
  Timer gbufferTimer;
  const GBuffer gbuffer = renderGBuffer(setup.scene, setup.width, setup.height);
  const double gbufferMs = gbufferTimer.elapsedMs();
  const Image<uint8_t> mask = errorMask(gbuffer, light);
  const CompareFrame frame{options, setup, light, gbuffer, mask, staged.dir(), setup.stem + "_"};

  std::vector<std::string> runHere = names;
  runHere.push_back(kReference);  // the truth, unless its cache has it
  const SharedBuildMs shared = buildSharedCaches(setup.scene, runHere);
  Report report = beginReport("compare", setup, baseline);
  report.settings = {{"gbuffer_ms", fmt::format("{:.2f}", gbufferMs)},
                     {"ray_scene_ms", fmt::format("{:.2f}", shared.rayScene.value_or(0.0))},
                     {"mesh_edges_ms", fmt::format("{:.2f}", shared.meshEdges.value_or(0.0))},
                     {"timings",
                      "one frame per technique, its first: it builds its maps and caches into storage made "
                      "for it before the frame (reserve, in none of its times; penumbra bench gives that "
                      "setup and steady frames apart); the scene's Embree scene and its "
                      "meshes' edge adjacency are built once before any technique runs (ray_scene_ms, "
                      "mesh_edges_ms) and shared by the techniques that use them, in none of their times"}};
  addFrameSettings(report.settings, options.frame);
  report.mapSizes = mapSizes;
  report.errorMapRange = options.errorRange;
  report.command = reproduceCommand(options, setup, names, baseline);

  ReportRow truth;
  const Image<float> vTruth = truthRow(frame, plan, source, truth);
  const ScanProfile profile = scanProfile(options, vTruth, mask);
  truth.profile = profile.reference;
  report.profile = profile;

  // Techniques the user named that did not run: the exit status says so once the report is written.
  NotRunTechniques notRun(report, !options.techniques.empty(), options.baseline);
  for (size_t i = 0; i < names.size(); ++i) {
    const TechniqueInfo& info = findTechnique(names[i]);
    const Params params = resolveParams(info.name, info.params, plan.given[i]);
    Image<float> v;
    std::optional<ReportRow> row =
        techniqueRow(frame, info, params, plan.given[i], truth, vTruth, plan.truthParams, notRun, v);
    if (!row) continue;
    row->error = compareVisibility(v, vTruth, mask);
    row->profile = rowOf(v, profile.row);
    if (!mapSizes.empty()) sweepMapSizes(frame, info, params, plan.sweepGiven[i], mapSizes, vTruth, notRun, *row);
    report.rows.push_back(std::move(*row));
  }
  fillBaselineRatios(report);
  report.truth = std::move(truth);

  writeReportFiles(setup, staged.dir(), report);
  staged.commit();
  fmt::print(
      "G-buffer {:.2f} ms; error mask: {} pixels; scan line: row {}\n\n{}\nwrote {} ({}, {} and images beside "
      "it)\n",
      gbufferMs, report.truth->error->maskPixels, profile.row, reportToText(report),
      (fs::path(staged.finalDir()) / "index.html").string(), "compare.json", "compare.md");
  return notRun.exitCode("report");
}

}  // namespace

Command addCompareCommand(CLI::App& parent) {
  auto options = std::make_shared<CompareOptions>();
  CLI::App* app = parent.add_subcommand(
      "compare",
      "compare techniques with the ray-traced reference: a report DIR/report/index.html with images, error maps, "
      "plots, compare.json/.md");
  app->add_option("--techniques,-t", options->techniques,
                  "comma-separated technique names (default: every registered technique); `reference` here is a row "
                  "with its own --param reference.*, measured against the truth")
      ->delimiter(',');
  app->add_option("--baseline", options->baseline,
                  "technique the time ratios are relative to (default: hard if registered, else raytraced-hard)");
  addFrameOptions(*app, options->frame,
                  "technique parameter technique.key=value, e.g. pcss.map_size=512, or *.key=value for every technique "
                  "that has the key, e.g. *.map_fit=stable (repeatable; overrides the scene file; a technique's own "
                  "key overrides *); the truth's samples are --spp, not reference.spp");
  app->add_option("--map-sizes", options->mapSizes,
                  "comma-separated shadow-map sizes (texels per side): every technique with a map_size parameter "
                  "also runs at each, for the error-against-map-size plot and table")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  app->add_option(
      "--profile-row", options->profileRow,
      "image row of the scan-line profile (default: the row with the most penumbra pixels in the reference)");
  app->add_option("--error-range", options->errorRange,
                  "signed error maps span V - V_ref in [-R, R] (V units; larger errors saturate)")
      ->check(CLI::Range(1e-6, 1.0))
      ->capture_default_str();
  app->add_option("--out,-o", options->outDir,
                  "output directory: the report goes to DIR/report, the cache to DIR/cache")
      ->capture_default_str();
  app->add_option("--cache-dir", options->cacheDir, "reference cache directory (default: DIR/cache)");
  app->add_flag("--no-cache", options->noCache, "render the truth even when it is cached, and do not store it");
  addMotionOptions(*app, options->motion);
  return {app, [options] { return runCompare(*options); }};
}

}  // namespace penumbra::cli
