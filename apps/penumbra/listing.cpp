// `penumbra scenes` and `penumbra techniques`: what can be rendered, listed from the one place
// that defines it (the embedded scenes, the technique registry with its parameter schemas).
#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "cli.h"
#include "penumbra/scene_io.h"

namespace penumbra::cli {

namespace {

int runScenes() {
  const std::vector<BuiltinScene> scenes = builtinScenes();
  size_t width = 0;
  for (const BuiltinScene& s : scenes) width = std::max(width, s.name.size());
  for (const BuiltinScene& s : scenes) fmt::print("{:<{}}  {}\n", s.name, width, s.description);
  return 0;
}

std::string describeSpec(const ParamSpec& spec) {
  std::string s(toString(spec.type));
  s += spec.autoDefault ? ", default auto" : fmt::format(", default {}", formatParamValue(spec.defaultValue));
  if (spec.min && spec.max)
    s += fmt::format(", range [{}, {}]", *spec.min, *spec.max);
  else if (spec.min)
    s += fmt::format(", >= {}", *spec.min);
  else if (spec.max)
    s += fmt::format(", <= {}", *spec.max);
  if (!spec.choices.empty()) s += fmt::format(", one of {}", fmt::join(spec.choices, "|"));
  if (!spec.unit.empty()) s += ", " + spec.unit;
  return s;
}

int runTechniques() {
  for (const TechniqueInfo& info : techniqueRegistry()) {
    fmt::print("{}  {}\n  source: {}\n  lights: {}\n", info.name, info.summary, info.source, info.lights);
    if (info.params.empty()) fmt::print("  parameters: none\n");
    for (const ParamSpec& spec : info.params)
      fmt::print("  --param {} ({}): {}\n", spec.name, describeSpec(spec), spec.help);
    fmt::print("\n");
  }
  fmt::print("Parameters marked \"auto\" are derived from the physical light; give a value to override.\n");
  return 0;
}

}  // namespace

Command addScenesCommand(CLI::App& parent) {
  CLI::App* app = parent.add_subcommand("scenes", "list the built-in scenes");
  return {app, [] { return runScenes(); }};
}

Command addTechniquesCommand(CLI::App& parent) {
  CLI::App* app = parent.add_subcommand("techniques", "list the techniques and their parameters");
  return {app, [] { return runTechniques(); }};
}

}  // namespace penumbra::cli
