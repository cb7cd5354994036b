// Internal interface of the `penumbra` command-line tool: the subcommands (one file each) and the
// pipeline steps they share (scene + light selection, parameter merging, running a technique,
// output paths that never overwrite the input scene file, a progress bar).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/params.h"
#include "penumbra/registry.h"
#include "penumbra/report.h"
#include "penumbra/scene.h"
#include "penumbra/technique.h"
#include "penumbra/timer.h"

#ifndef PENUMBRA_VERSION
#define PENUMBRA_VERSION "unknown"
#endif

namespace penumbra::cli {

// Parses and runs one command line as the `penumbra` program does (argv[0] is the program's name) and
// returns its exit code. With `rethrow`, bad input (a malformed command line included) propagates as
// penumbra::Error with the message the program would print, instead of being printed (run.cpp).
int runCommandLine(int argc, const char* const* argv, bool rethrow);

// A registered subcommand and what runs it once the command line is parsed. run() returns the exit code.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

Command addRenderCommand(CLI::App& parent);
Command addCompareCommand(CLI::App& parent);
Command addBenchCommand(CLI::App& parent);
Command addScenesCommand(CLI::App& parent);
Command addTechniquesCommand(CLI::App& parent);
Command addViewCommand(CLI::App& parent);

// Options render, compare and bench share. Unset optionals mean "the scene's value" or "the
// technique's default".
struct FrameOptions {
  std::string scene = "torus";
  std::optional<int> width, height;
  int lightIndex = 0;
  std::optional<int64_t> spp, seed;
  std::vector<std::string> params;   //!< "key=value" (render) or "technique.key=value" (compare, bench)
  int threads = 0;                   //!< 0: oneTBB's default (every core)
  std::string name;                  //!< stem of the output files; empty: the scene's name (made safe either way)
  bool force = false;                //!< --force: go on past the memory and time checks (checkResources)
  std::optional<double> maxMeshMiB;  //!< --max-mesh-size: the mesh file size limit, MiB (default: kDefaultMaxMeshBytes)
};
// Adds --scene, --width, --height, --light, --spp, --seed, --threads (and --param) to a subcommand.
void addFrameOptions(CLI::App& app, FrameOptions& options, const std::string& paramHelp);

// A sequence (include/penumbra/motion.h) from the command line of compare and bench: --motion-path
// replaces the scene file's motion, --frames either's frame count.
struct MotionOptions {
  std::string path;             //!< "x,y,z;x,y,z;...": key points; empty: the scene file's motion, if any
  std::string moves = "light";  //!< what `path` moves: "light" (the --light used) or "camera"
  std::optional<int> frames;
};
// Adds --motion-path, --motion-moves and --frames to a subcommand.
void addMotionOptions(CLI::App& app, MotionOptions& options);

// The loaded scene and everything derived from the frame options.
struct Setup {
  Scene scene;
  std::optional<std::string> sceneFile;  //!< the input file, when the scene came from one
  int width = 0, height = 0;
  int lightIndex = 0;
  std::string stem;  //!< output files are stem + "_" + ...: the scene's name or --name as a safe file name
};
// Loads the scene and checks the light index and image size. Throws Error with the fix.
Setup loadSetup(const FrameOptions& options);
const Light& setupLight(const Setup& setup);
// One line: the scene, where it came from, the image size and the light used (printed by every command).
std::string describeSetup(const Setup& setup);
// The settings every report records from the frame options: threads, and --spp / --seed when given.
void addFrameSettings(KeyValues& settings, const FrameOptions& options);

// The run's motion: `options` over the scene file's, validated against the scene and the light used
// (a motion of another light than --light is refused). None: a still scene. Throws Error naming the
// option or the scene file's field.
std::optional<Motion> runMotion(const MotionOptions& options, const Setup& setup);
// One line: what moves, along which key points.
std::string describeMotion(const Motion& motion);

// The planned runs of a command, checked before any heavy work (the G-buffer included): the memory
// of the G-buffer, of `keptImages` V images and of the largest technique's buffers (its
// ResourceEstimate) against the machine's memory (physical, or the cgroup's limit when lower), and
// the rays and light-map texels of all runs together against a time budget. Over either, an Error
// names the technique, its parameters and the estimate, and says --force goes on; with --force, a
// warning instead.
struct PlannedRun {
  const TechniqueInfo* info = nullptr;
  Params params;
  int repeat = 1;
};
void checkResources(const Setup& setup, const std::vector<PlannedRun>& runs, int keptImages, bool force);
// The memory this process may use: physical memory, or the cgroup's limit when lower, bytes.
double machineMemoryBytes();

// Scene-file parameters of the technique, then --spp / --seed where the technique has them, then
// the command line's key=value pairs (`prefixed`: "technique.key=value", others skipped).
ParamSet gatherParams(const Setup& setup, const TechniqueInfo& info, const FrameOptions& options, bool prefixed);
// Checks that every "technique.key=value" names a technique in `techniques` (else a typo would be
// silently ignored).
void checkPrefixedParams(const std::vector<std::string>& params, const std::vector<std::string>& techniques);

struct TechniqueRun {
  std::string name;
  Params params;
  Image<float> v;
  PassTimings timings;
  double setupMs = 0.0;       //!< reserve() of the instance this call built (0 for one given in `instance`)
  double firstFrameMs = 0.0;  //!< prepare + visibility of the first run
  std::vector<std::pair<std::string, double>> stats;
};
// Builds the technique from `given` and runs prepare + visibility `repeat` times (timings: median of
// each pass over the runs after the first when there are several, the first run alone otherwise;
// setupMs: the new instance's reserve() for the G-buffer's size; firstFrameMs: the first run's total;
// V and stats: the last run). With `instance`, the technique object is
// kept there and the next call with it reuses it instead of building another (a sequence's frames,
// where a frame's prepare may reuse what the previous one built, as a renderer's would); `given`
// must then be the same at every call. With `target`, V is written there instead of into run.v: the
// caller's image, kept from call to call as a renderer keeps its render target (a fresh image's pages
// are faulted in by the pass that first writes them, which is then timed for the caller's memory).
TechniqueRun runTechnique(const Setup& setup, const GBuffer& gbuffer, const TechniqueInfo& info, const ParamSet& given,
                          int repeat = 1, std::unique_ptr<ShadowTechnique>* instance = nullptr,
                          Image<float>* target = nullptr);

// Techniques that could not take the scene, for compare and bench: each keeps its row in the report
// with the reason (printed too), never ending the run; exitCode() is 1, after saying which, when the
// user named one of them (in --techniques, or as --baseline).
class NotRunTechniques {
 public:
  NotRunTechniques(Report& report, bool techniquesNamed, std::string namedBaseline)
      : report_(report), techniquesNamed_(techniquesNamed), namedBaseline_(std::move(namedBaseline)) {}
  void add(const std::string& name, const std::string& why);
  // 0, or 1 after an error line naming the named techniques that did not run; `where` says where
  // their reasons are ("report", "table").
  int exitCode(const char* where) const;

 private:
  Report& report_;
  bool techniquesNamed_;
  std::string namedBaseline_;
  std::vector<std::string> named_;
};

// A report of `kind` ("compare", "bench") with the scene, light, image size, baseline and version
// of this setup filled in.
Report beginReport(const std::string& kind, const Setup& setup, const std::string& baseline);

// The truth of `penumbra compare` kept on disk between runs (reference_cache.cpp): keyed by a hash
// of the scene, light, image size, the reference's parameters and the version.
struct CachedTruth {
  Image<float> v;
  PassTimings timings;  //!< of the run that rendered it
  std::vector<std::pair<std::string, double>> stats;
};
class ReferenceCache {
 public:
  ReferenceCache(std::string dir, const Setup& setup, const Params& referenceParams);
  // The entry, or nullopt with `why` saying why not (missing, unreadable, another key).
  std::optional<CachedTruth> load(std::string& why) const;
  // Why the cache cannot be written (its folder cannot be created, or a file cannot be made in it),
  // found without writing an entry; nullopt when it can. Asked before the truth is rendered.
  std::optional<std::string> whyUnwritable() const;
  // Throws Error naming the directory when it cannot be written.
  void store(const Image<float>& v, const PassTimings& timings,
             const std::vector<std::pair<std::string, double>>& stats) const;
  const std::string& path() const { return exrPath_; }

 private:
  std::string dir_, key_, exrPath_, metaPath_;
};

// Creates the output directory (and parents). Throws Error naming it when that fails.
void makeOutputDir(const std::string& dir);
// dir/file, where `file` is one file name of penumbra's own making (never a path), refused when it
// names one of the scene's input files (the scene file, its meshes), compared by identity.
std::string outputPath(const Setup& setup, const std::string& dir, const std::string& file);
void refuseInputOverwrite(const Setup& setup, const std::string& path);
// Throws Error, before any work, when the folder `path` would be written into does not exist or
// cannot be written.
void checkWritableFolderOf(const std::string& path);

// Holds an exclusive lock on an output folder for the lifetime of the object (flock on
// DIR/.penumbra.lock), so two runs cannot mix their files in one folder: the second is refused at
// once with a message naming the folder.
class OutputLock {
 public:
  explicit OutputLock(const std::string& dir);
  ~OutputLock();
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

 private:
  int fd_ = -1;
};

// Builds what the techniques share from the scene's geometry (Scene::caches) before any technique is
// timed and returns the milliseconds each took: the Embree scene, used by the ray-traced techniques
// (TechniqueInfo::tracesRays), and the meshes' edge adjacency (sharedMeshEdges), used by the
// silhouette-finding ones (TechniqueInfo::usesMeshEdges). None of their times then includes them
// (whichever ran first would otherwise pay for all); reports show them apart, as the G-buffer's time.
// Each is built (and its time set) only when one of `techniques` uses it.
struct SharedBuildMs {
  std::optional<double> rayScene, meshEdges;
};
SharedBuildMs buildSharedCaches(const Scene& scene, const std::vector<std::string>& techniques);

// Every technique name if `names` is empty; otherwise the names, checked against the registry.
std::vector<std::string> techniqueList(const std::vector<std::string>& names);
// `hard` if registered, else `raytraced-hard`.
std::string defaultBaseline();

double median(std::vector<double> values);
// Each pass's median over frames (or runs), in the first one's pass order.
PassTimings medianOverFrames(const std::vector<PassTimings>& frames);

// A one-line progress bar on stderr, drawn only when stderr is a terminal and a pass has run for
// more than a second. callback() is thread-safe (a mutex taken with try_lock, so worker threads
// never wait on it) and throttled to ~10 redraws a second.
class ProgressBar {
 public:
  explicit ProgressBar(std::string label);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  ProgressCallback callback();
  void finish();

 private:
  void update(double fraction);
  std::string label_;
  bool enabled_;
  std::mutex mutex_;
  Timer timer_;
  double lastDrawMs_ = -1.0e9;
  bool drawn_ = false;
};

// RAII for --threads: limits oneTBB's parallelism for the lifetime of the object (0: no limit).
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace penumbra::cli
