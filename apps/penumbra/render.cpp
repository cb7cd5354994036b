// `penumbra render`: one technique on one scene. Writes the shaded image (sRGB PNG) and the
// visibility buffer (float EXR, channel "V") and prints the pass timings.
#include <fmt/format.h>

#include "cli.h"
#include "penumbra/error.h"
#include "penumbra/image_io.h"
#include "penumbra/raster.h"
#include "penumbra/report.h"
#include "penumbra/shade.h"

namespace penumbra::cli {

namespace {

struct RenderOptions {
  FrameOptions frame;
  std::string technique;
  std::string outDir = ".";
};

int runRender(const RenderOptions& options) {
  ThreadLimit threads(options.frame.threads);
  const TechniqueInfo& info = findTechnique(options.technique);
  const Setup setup = loadSetup(options.frame);
  const ParamSet given = gatherParams(setup, info, options.frame, false);
  const Params params = resolveParams(info.name, info.params, given);  // a bad value fails before any output or work
  // The shorthands only apply where they mean something; say so rather than drop them silently.
  if (options.frame.spp && !info.hasParam("spp"))
    fmt::print(stderr, "penumbra: note: technique '{}' has no parameter 'spp'; --spp has no effect\n", info.name);
  if (options.frame.seed && !info.hasParam("seed"))
    fmt::print(stderr, "penumbra: note: technique '{}' has no parameter 'seed'; --seed has no effect\n", info.name);

  // Every output path is checked before any work, so a refused path costs nothing.
  const std::string base = setup.stem + "_" + info.name;
  const std::string pngPath = outputPath(setup, options.outDir, base + ".png");
  const std::string exrPath = outputPath(setup, options.outDir, base + "_v.exr");

  checkResources(setup, {{&info, params, 1}}, 1, options.frame.force);
  // The folder is made (and its failure said) before the work, not after it.
  makeOutputDir(options.outDir);

  const Light& light = setupLight(setup);
  fmt::print("{}\n", describeSetup(setup));
  Timer gbufferTimer;
  const GBuffer gbuffer = renderGBuffer(setup.scene, setup.width, setup.height);
  const double gbufferMs = gbufferTimer.elapsedMs();
  const TechniqueRun run = runTechnique(setup, gbuffer, info, given);

  fmt::print("technique {}", info.name);
  for (const auto& [k, v] : describeParams(run.params)) fmt::print(" {}={}", k, v);
  fmt::print("\n{:<16} {:>10.2f} ms\n", "gbuffer", gbufferMs);
  for (const auto& [pass, ms] : run.timings.passes) fmt::print("{:<16} {:>10.2f} ms\n", pass, ms);
  fmt::print("{:<16} {:>10.2f} ms\n", "total", run.timings.total());
  for (const auto& [k, v] : run.stats) fmt::print("{:<16} {:>10.4g}\n", k, v);

  writePng(pngPath, shade(setup.scene, light, gbuffer, run.v));
  writeExr(exrPath, run.v);
  fmt::print("wrote {}\nwrote {}\n", pngPath, exrPath);
  return 0;
}

}  // namespace

Command addRenderCommand(CLI::App& parent) {
  auto options = std::make_shared<RenderOptions>();
  CLI::App* app = parent.add_subcommand("render", "render one technique: shaded PNG + visibility EXR + pass timings");
  app->add_option("--technique,-t", options->technique, "technique name (see `penumbra techniques`)")->required();
  addFrameOptions(*app, options->frame,
                  "technique parameter key=value (repeatable; overrides the scene file's \"techniques\" section)");
  app->add_option("--out,-o", options->outDir, "output directory (created if missing)")->capture_default_str();
  return {app, [options] { return runRender(*options); }};
}

}  // namespace penumbra::cli
