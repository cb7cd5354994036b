// The steps render, compare and bench share: loading the scene and choosing its light, merging
// technique parameters (scene file < --spp/--seed < --param), running a technique with timings,
// output paths that never overwrite the input scene file, --threads, and the progress bar.
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <tbb/global_control.h>

#include "cli.h"
#include "core/output_file.h"
#include "penumbra/error.h"
#include "penumbra/scene_io.h"
#include "rt/ray_scene.h"
#include "techniques/mesh_edges.h"

namespace penumbra::cli {

namespace fs = std::filesystem;

// Large enough for any figure, small enough that a typo (an extra zero) fails fast instead of
// allocating gigabytes of G-buffer.
constexpr int kMaxImageSize = 16384;

void addFrameOptions(CLI::App& app, FrameOptions& options, const std::string& paramHelp) {
  app.add_option("--scene", options.scene, "built-in scene name (see `penumbra scenes`) or path to a JSON scene file")
      ->capture_default_str();
  app.add_option("--width", options.width, "image width in pixels (default: the scene's)")
      ->check(CLI::Range(1, kMaxImageSize));
  app.add_option("--height", options.height, "image height in pixels (default: the scene's)")
      ->check(CLI::Range(1, kMaxImageSize));
  app.add_option("--light", options.lightIndex, "index of the scene's light to use")->capture_default_str();
  app.add_option("--spp", options.spp,
                 "samples per pixel: render's technique's, if it has an `spp` parameter; in compare and bench the "
                 "reference's (the few-ray techniques take --param NAME.spp)")
      ->check(CLI::PositiveNumber);
  app.add_option("--seed", options.seed, "random seed, for techniques that have a `seed` parameter")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--param,-p", options.params, paramHelp);
  app.add_option("--threads", options.threads, "worker threads (0: every core)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_flag("--force", options.force,
               "go on past the up-front checks: a run estimated to need more memory than the machine has, or more "
               "than 1e10 rays or light-map texels (about a quarter of an hour on 2 cores)");
  app.add_option("--max-mesh-size", options.maxMeshMiB,
                 fmt::format("largest mesh file imported, MiB (default {}); a larger file is refused before it is read",
                             kDefaultMaxMeshBytes >> 20))
      ->check(CLI::PositiveNumber);
  app.add_option("--name", options.name,
                 "stem of the output file names (default: the scene's name); either is made a safe file name "
                 "(letters, digits, '-', '_', '.'; others become '_')");
}

Setup loadSetup(const FrameOptions& options) {
  Setup setup;
  SceneLoadOptions load;
  if (options.maxMeshMiB) load.maxMeshBytes = static_cast<uint64_t>(*options.maxMeshMiB * 1024.0 * 1024.0);
  setup.scene = loadScene(options.scene, load);
  // The command's meshes stay as loaded (a sequence moves lights and the camera only): declared, so
  // that no frame hashes them again to prove it (Scene::geometryRevision).
  setup.scene.declareGeometry();
  if (setup.scene.source.rfind("built-in:", 0) != 0) setup.sceneFile = setup.scene.source;
  const Scene& scene = setup.scene;
  // Check the scene file's "techniques" section whole, including techniques not run now: a typo in
  // a name or value there would otherwise be ignored until the day that technique runs.
  for (const auto& [name, given] : scene.techniqueParams) {
    const TechniqueInfo* info = nullptr;
    for (const TechniqueInfo& candidate : techniqueRegistry())
      if (candidate.name == name) info = &candidate;
    if (!info) {
      std::vector<std::string> known;
      for (const TechniqueInfo& candidate : techniqueRegistry()) known.push_back(candidate.name);
      fail("{}: techniques.{}: unknown technique '{}' (known: {})", scene.source, name, name, fmt::join(known, ", "));
    }
    resolveParams(info->name, info->params, given);
  }
  if (scene.lights.empty()) fail("scene '{}' ({}) has no light; add one to \"lights\"", scene.name, scene.source);
  const int count = static_cast<int>(scene.lights.size());
  if (options.lightIndex < 0 || options.lightIndex >= count)
    fail("--light {} is out of range: scene '{}' has {} light{} (valid: {})", options.lightIndex, scene.name, count,
         count == 1 ? "" : "s", count == 1 ? std::string("0") : fmt::format("0 to {}", count - 1));
  setup.lightIndex = options.lightIndex;
  // A scene's name comes from a file anyone may have written: never a path, a NUL or a URL's '#'.
  setup.stem = fileNameSlug(options.name.empty() ? scene.name : options.name);
  setup.width = options.width.value_or(scene.image.width);
  setup.height = options.height.value_or(scene.image.height);
  if (setup.width < 1 || setup.height < 1 || setup.width > kMaxImageSize || setup.height > kMaxImageSize)
    fail("{}: image size {}x{} must be in 1..{} on each side", scene.source, setup.width, setup.height, kMaxImageSize);
  return setup;
}

void addMotionOptions(CLI::App& app, MotionOptions& options) {
  app.add_option("--motion-path", options.path,
                 "a sequence: key points 'x,y,z;x,y,z;...' (at least 2) that the light (its centre; a directional "
                 "light: its direction) or the camera moves along, at constant speed; replaces the scene file's "
                 "motion");
  app.add_option("--motion-moves", options.moves, "what --motion-path moves: light (the --light used) or camera")
      ->check(CLI::IsMember({"light", "camera"}))
      ->capture_default_str();
  app.add_option("--frames", options.frames, "frames of the sequence (default: the scene file's motion's, else 12)")
      ->check(CLI::Range(2, kMaxMotionFrames));
}

// The run's motion: --motion-path (moving the compared light or the camera) over the scene file's
// motion; --frames over either's frame count. None: a still scene.
std::optional<Motion> runMotion(const MotionOptions& options, const Setup& setup) {
  std::optional<Motion> motion = setup.scene.motion;
  if (!options.path.empty()) {
    motion.emplace();
    if (options.moves == "camera")
      motion->target = MotionTarget::Camera;
    else if (options.moves == "light")
      motion->target = MotionTarget::Light;
    else
      fail("--motion-moves '{}': expected light or camera", options.moves);
    motion->lightIndex = setup.lightIndex;
    size_t start = 0;
    for (int key = 0; start <= options.path.size(); ++key) {
      const size_t end = std::min(options.path.find(';', start), options.path.size());
      const std::string text = options.path.substr(start, end - start);
      Vec3 p;
      char extra = 0;
      if (std::sscanf(text.c_str(), "%f,%f,%f %c", &p.x, &p.y, &p.z, &extra) != 3)
        fail("--motion-path: key {} '{}' is not three numbers x,y,z (keys are separated by ';')", key, text);
      motion->path.push_back(p);
      start = end + 1;
    }
  } else if (options.moves != "light") {
    fail("--motion-moves is for --motion-path, which is not given");
  }
  if (!motion) {
    if (options.frames) fail("--frames {}: the scene has no motion; give one with --motion-path", *options.frames);
    return std::nullopt;
  }
  if (options.frames) motion->frames = *options.frames;
  motion->validate(setup.scene, options.path.empty() ? setup.scene.source + ": motion" : "--motion-path");
  if (motion->target == MotionTarget::Light && motion->lightIndex != setup.lightIndex)
    fail("{}: the motion moves light {}, but light {} is used: pass --light {}", setup.scene.source, motion->lightIndex,
         setup.lightIndex, motion->lightIndex);
  return motion;
}

std::string describeMotion(const Motion& motion) {
  std::string path;
  for (const Vec3& p : motion.path)
    path += fmt::format("{}({:g}, {:g}, {:g})", path.empty() ? "" : " -> ", p.x, p.y, p.z);
  return motion.target == MotionTarget::Light ? fmt::format("light {} along {}", motion.lightIndex, path)
                                              : fmt::format("the camera along {}", path);
}

// Each pass's median over frames, in the first frame's pass order.
PassTimings medianOverFrames(const std::vector<PassTimings>& frames) {
  PassTimings out;
  for (const auto& [pass, ms] : frames.front().passes) {
    std::vector<double> values;
    for (const PassTimings& t : frames) values.push_back(t.get(pass));
    out.add(pass, median(values));
  }
  return out;
}

std::string describeSetup(const Setup& setup) {
  return fmt::format("scene {} ({}), {}x{}, light {}: {}", setup.scene.name, setup.scene.source, setup.width,
                     setup.height, setup.lightIndex, describeLight(setupLight(setup)));
}

void addFrameSettings(KeyValues& settings, const FrameOptions& options) {
  settings.emplace_back("threads", options.threads > 0 ? fmt::format("{}", options.threads) : "all");
  if (options.spp) settings.emplace_back("spp", fmt::format("{}", *options.spp));
  if (options.seed) settings.emplace_back("seed", fmt::format("{}", *options.seed));
}

const Light& setupLight(const Setup& setup) { return setup.scene.lights[static_cast<size_t>(setup.lightIndex)]; }

SharedBuildMs buildSharedCaches(const Scene& scene, const std::vector<std::string>& techniques) {
  const auto anyUses = [&](bool TechniqueInfo::*what) {
    return std::any_of(techniques.begin(), techniques.end(),
                       [&](const std::string& name) { return findTechnique(name).*what; });
  };
  SharedBuildMs ms;
  if (anyUses(&TechniqueInfo::tracesRays)) {
    Timer timer;
    RaySceneCache cache;
    cache.get(scene);  // kept in scene.caches after this holder goes
    ms.rayScene = timer.elapsedMs();
  }
  if (anyUses(&TechniqueInfo::usesMeshEdges)) {
    Timer timer;
    for (size_t i = 0; i < scene.objects.size(); ++i) sharedMeshEdges(scene, i);  // kept in scene.caches
    ms.meshEdges = timer.elapsedMs();
  }
  return ms;
}

void checkPrefixedParams(const std::vector<std::string>& params, const std::vector<std::string>& techniques) {
  for (const std::string& kv : params) {
    const size_t eq = kv.find('=');
    const size_t dot = kv.find('.');
    if (eq == std::string::npos || dot == std::string::npos || dot == 0 || dot > eq || dot + 1 == eq)
      fail("command line: parameter '{}' must be written technique.key=value here (for example reference.spp=64)", kv);
    const std::string technique = kv.substr(0, dot);
    if (technique == "*") {  // every technique run here that has the key; at least one must
      const std::string key = kv.substr(dot + 1, eq - dot - 1);
      if (std::none_of(techniques.begin(), techniques.end(),
                       [&](const std::string& t) { return findTechnique(t).hasParam(key); }))
        fail("command line: parameter '{}': none of the techniques run here has a parameter '{}'", kv, key);
      continue;
    }
    findTechnique(technique);  // an unknown name: the registry's message lists the known ones
    if (std::find(techniques.begin(), techniques.end(), technique) == techniques.end())
      fail("command line: parameter '{}' is for technique '{}', which is not among the techniques run here", kv,
           technique);
  }
}

ParamSet gatherParams(const Setup& setup, const TechniqueInfo& info, const FrameOptions& options, bool prefixed) {
  ParamSet given;
  auto it = setup.scene.techniqueParams.find(info.name);
  if (it != setup.scene.techniqueParams.end()) given = it->second;
  // Where several techniques run, --spp is the Monte Carlo reference's: raytraced-soft and hybrid also
  // have an `spp`, of a few rays (1 to 16), which the reference's thousand must not set.
  if (options.spp && info.hasParam("spp") && (!prefixed || info.name == "reference"))
    given.set("spp", *options.spp, "command line (--spp)");
  if (options.seed && info.hasParam("seed")) given.set("seed", *options.seed, "command line (--seed)");
  if (!prefixed) {
    for (const std::string& kv : options.params) given.setFromKeyValue(kv, "command line (--param)");
    return given;
  }
  // `*.key=value` first, so that a technique's own `name.key=value` overrides it.
  for (const bool wildcard : {true, false})
    for (const std::string& kv : options.params) {
      const size_t dot = kv.find('.');
      const std::string technique = kv.substr(0, dot), keyValue = kv.substr(dot + 1);
      if (wildcard && technique == "*" && info.hasParam(keyValue.substr(0, keyValue.find('='))))
        given.setFromKeyValue(keyValue, "command line (--param *)");
      else if (!wildcard && technique == info.name)
        given.setFromKeyValue(keyValue, "command line (--param)");
    }
  return given;
}

// Beyond this many shadow rays or light-map texels a run is long enough to ask for --force: 1e10 rays
// take about 15 minutes on 2 cores (the reference traced 1.1e7 rays a second on torus, 2 busy cores).
constexpr double kRayBudget = 1.0e10;
constexpr double kTexelBudget = 1.0e10;
// G-buffer bytes per pixel: position, shading and face normals (3 x 12), object and triangle ids, depth.
constexpr double kGBufferBytesPerPixel = 48.0;

double machineMemoryBytes() {
  double bytes = static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
  // A container's limit (cgroup v2) is what the kernel enforces with the OOM killer.
  if (std::FILE* f = std::fopen("/sys/fs/cgroup/memory.max", "r")) {
    char text[64] = {};
    if (std::fgets(text, sizeof text, f)) {
      char* end = nullptr;
      const double limit = std::strtod(text, &end);
      if (end != text && limit > 0.0) bytes = std::min(bytes, limit);
    }
    std::fclose(f);
  }
  return bytes;
}

namespace {
std::string formatBytes(double bytes) {
  if (bytes >= 1024.0 * 1024.0 * 1024.0) return fmt::format("{:.1f} GiB", bytes / (1024.0 * 1024.0 * 1024.0));
  return fmt::format("{:.0f} MiB", bytes / (1024.0 * 1024.0));
}
}  // namespace

void checkResources(const Setup& setup, const std::vector<PlannedRun>& runs, int keptImages, bool force) {
  const double pixels = static_cast<double>(setup.width) * static_cast<double>(setup.height);
  const double frameBytes = pixels * (kGBufferBytesPerPixel + 4.0 * keptImages);
  const double memory = machineMemoryBytes();
  double rays = 0.0, texels = 0.0;
  std::string heaviest;  // the run that traces or renders the most, for the message
  double heaviestWork = 0.0;
  std::vector<std::string> problems;
  for (const PlannedRun& run : runs) {
    const ResourceEstimate e = run.info->estimate(run.params, setup.width, setup.height);
    const double bytes = frameBytes + e.bytes;
    if (bytes > memory)
      problems.push_back(
          fmt::format("{} needs about {} of memory ({}{} x {} pixels), more than the {} this machine has",
                      run.info->name, formatBytes(bytes), e.drivers.empty() ? "" : e.drivers + ", ", setup.width,
                      setup.height, formatBytes(memory)));
    const double work = std::max(e.rays / kRayBudget, e.texels / kTexelBudget) * run.repeat;
    rays += e.rays * run.repeat;
    texels += e.texels * run.repeat;
    if (work > heaviestWork) {
      heaviestWork = work;
      heaviest = fmt::format("{} ({})", run.info->name, e.drivers);
    }
  }
  // Over the time budget: the run's total, naming the heaviest run and what sets it.
  const auto overBudget = [&](const char* verb, double amount, const char* noun, double budget) {
    problems.push_back(
        fmt::format("the run would {} about {:.2g} {}, over the time budget of {:.0e} (about a quarter of "
                    "an hour on 2 cores); the most by {}",
                    verb, amount, noun, budget, heaviest));
  };
  if (rays > kRayBudget) overBudget("trace", rays, "shadow rays", kRayBudget);
  if (texels > kTexelBudget) overBudget("render", texels, "light-map texels", kTexelBudget);
  if (problems.empty()) return;
  const std::string text = fmt::format("{}", fmt::join(problems, "; "));
  if (!force) fail("{}; lower those parameters (or --width/--height), or pass --force to run it anyway", text);
  fmt::print(stderr, "penumbra: warning: {}; going on (--force)\n", text);
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

TechniqueRun runTechnique(const Setup& setup, const GBuffer& gbuffer, const TechniqueInfo& info, const ParamSet& given,
                          int repeat, std::unique_ptr<ShadowTechnique>* instance, Image<float>* target) {
  TechniqueRun run;
  Image<float>& v = target ? *target : run.v;
  run.name = info.name;
  run.params = resolveParams(info.name, info.params, given);
  std::unique_ptr<ShadowTechnique> fresh;
  if (!instance || !*instance) {
    fresh = info.create(run.params);
    // Its frames' storage made before the first frame, as an engine makes its render targets when its
    // window is sized (ShadowTechnique::reserve): the first frame then measures a frame, and the making
    // of the memory is reported apart (setupMs).
    const Timer timer;
    fresh->reserve(gbuffer.width(), gbuffer.height());
    run.setupMs = timer.elapsedMs();
  }
  ShadowTechnique* technique = fresh ? fresh.get() : instance->get();
  ProgressBar bar(info.name);
  technique->setProgressCallback(bar.callback());
  std::vector<std::string> order;
  std::map<std::string, std::vector<double>> passMs;
  const int runs = std::max(1, repeat);
  for (int r = 0; r < runs; ++r) {
    technique->prepare(setup.scene, setupLight(setup));
    technique->visibility(gbuffer, v);
    if (r == 0) run.firstFrameMs = technique->timings().total();
    // The first run builds what the later ones reuse and faults in what reserve did not make: with more than one
    // run, the medians are over the steady runs after it.
    if (r == 0 && runs > 1) continue;
    for (const auto& [pass, ms] : technique->timings().passes) {
      if (!passMs.count(pass)) order.push_back(pass);
      passMs[pass].push_back(ms);
    }
  }
  bar.finish();
  if (v.width() != gbuffer.width() || v.height() != gbuffer.height())
    fail("internal: technique '{}' wrote a {}x{} visibility image for a {}x{} G-buffer", info.name, v.width(),
         v.height(), gbuffer.width(), gbuffer.height());
  for (const std::string& pass : order) run.timings.add(pass, median(passMs[pass]));
  run.stats = technique->stats();
  if (instance && fresh) *instance = std::move(fresh);
  return run;
}

Report beginReport(const std::string& kind, const Setup& setup, const std::string& baseline) {
  Report report;
  report.kind = kind;
  report.version = PENUMBRA_VERSION;
  report.scene = setup.scene.name;
  report.sceneSource = setup.scene.source;
  report.lightIndex = setup.lightIndex;
  report.light = describeLight(setupLight(setup));
  report.width = setup.width;
  report.height = setup.height;
  report.baseline = baseline;
  return report;
}

void makeOutputDir(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    fail("cannot create output directory '{}': {}", dir, ec ? ec.message() : "a file of that name exists");
}

void refuseInputOverwrite(const Setup& setup, const std::string& path) {
  // By identity (device and inode), which no other spelling of the path escapes; a file that does
  // not exist yet is no input.
  const std::optional<FileIdentity> target = fileIdentity(path);
  if (!target) return;
  for (const std::string& input : setup.scene.inputFiles)
    if (fileIdentity(input) == target)
      fail("refusing to write '{}': it is {} '{}'; choose another output path", path,
           input == setup.scene.inputFiles.front() && setup.sceneFile ? "the input scene file" : "an input file,",
           input);
}

void checkWritableFolderOf(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) fail("cannot write '{}': the folder '{}' does not exist", path, parent.string());
  if (::access(parent.c_str(), W_OK) != 0)
    fail("cannot write '{}': the folder '{}' is not writable ({})", path, parent.string(), std::strerror(errno));
}

std::string outputPath(const Setup& setup, const std::string& dir, const std::string& file) {
  if (file.empty() || file.find('/') != std::string::npos || file == "." || file == ".." ||
      file.find('\0') != std::string::npos)
    fail("internal: output file name '{}' is not one file name", file);
  const std::string path = (fs::path(dir) / file).string();
  refuseInputOverwrite(setup, path);
  return path;
}

void NotRunTechniques::add(const std::string& name, const std::string& why) {
  fmt::print("{}: not run here: {}\n", name, why);
  report_.skipped.emplace_back(name, why);
  if (techniquesNamed_ || (!namedBaseline_.empty() && name == namedBaseline_)) named_.push_back(name);
}

int NotRunTechniques::exitCode(const char* where) const {
  if (named_.empty()) return 0;
  std::fflush(stdout);  // the table first, then the error, also when both go to one pipe
  fmt::print(stderr, "penumbra: error: {} did not run on this scene (the reasons are in the {}): {}\n",
             named_.size() == 1 ? "a technique asked for" : "techniques asked for", where, fmt::join(named_, ", "));
  return 1;
}

OutputLock::OutputLock(const std::string& dir) {
  const std::string path = (fs::path(dir) / ".penumbra.lock").string();
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd_ < 0) fail("cannot lock the output folder '{}': {} ({})", dir, std::strerror(errno), path);
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd_);
    fd_ = -1;
    fail(
        "the output folder '{}' is in use by another penumbra run (it holds {}); wait for it to finish or choose "
        "another --out",
        dir, path);
  }
}

OutputLock::~OutputLock() {
  if (fd_ >= 0) ::close(fd_);  // closing releases the lock
}

std::vector<std::string> techniqueList(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  if (names.empty()) {
    for (const TechniqueInfo& info : techniqueRegistry()) out.push_back(info.name);
    return out;
  }
  for (const std::string& name : names) {
    findTechnique(name);  // throws, listing the known names
    if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  }
  return out;
}

std::string defaultBaseline() {
  for (const TechniqueInfo& info : techniqueRegistry())
    if (info.name == "hard") return "hard";
  return "raytraced-hard";
}

ProgressBar::ProgressBar(std::string label) : label_(std::move(label)), enabled_(isatty(STDERR_FILENO) != 0) {}

ProgressBar::~ProgressBar() { finish(); }

ProgressCallback ProgressBar::callback() {
  if (!enabled_) return {};
  return [this](double fraction) { update(fraction); };
}

void ProgressBar::update(double fraction) {
  // Worker threads must never queue behind the drawing thread: skip this report if it is busy.
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;
  const double ms = timer_.elapsedMs();
  if (ms < 1000.0 || ms - lastDrawMs_ < 100.0) return;
  lastDrawMs_ = ms;
  drawn_ = true;
  const double f = std::clamp(fraction, 0.0, 1.0);
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(f * kWidth);
  fmt::print(stderr, "\r{} [{}{}] {:3.0f}% {:.1f} s", label_, std::string(static_cast<size_t>(filled), '#'),
             std::string(static_cast<size_t>(kWidth - filled), ' '), 100.0 * f, ms / 1000.0);
  std::fflush(stderr);
}

void ProgressBar::finish() {
  std::lock_guard lock(mutex_);
  if (drawn_) {
    fmt::print(stderr, "\r\033[K");
    std::fflush(stderr);
    drawn_ = false;
  }
}

struct ThreadLimit::Impl {
  explicit Impl(size_t threads) : control(tbb::global_control::max_allowed_parallelism, threads) {}
  tbb::global_control control;
};

ThreadLimit::ThreadLimit(int threads) {
  if (threads > 0) impl_ = std::make_unique<Impl>(static_cast<size_t>(threads));
}

ThreadLimit::~ThreadLimit() = default;

}  // namespace penumbra::cli
