// The `penumbra` command-line tool: render, compare, bench, scenes, techniques (docs/architecture.md,
// "Command-line tool"). Every bad input ends here as one line "penumbra: error: <message>" on stderr and a
// non-zero exit code: 1 for penumbra::Error, CLI11's own code for a malformed command line.
#include <cstdio>
#include <exception>
#include <new>

#include <fmt/format.h>

#include "cli.h"
#include "penumbra/error.h"

int main(int argc, char** argv) {
  using namespace penumbra::cli;
  CLI::App app{"penumbra: soft shadows from area lights, measured against a ray-traced reference", "penumbra"};
  app.set_version_flag("--version", PENUMBRA_VERSION);
  app.require_subcommand(1);
  const std::vector<Command> commands = {addRenderCommand(app), addCompareCommand(app), addBenchCommand(app),
                                         addScenesCommand(app), addTechniquesCommand(app)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    fmt::print(stderr, "penumbra: error: {} (see penumbra --help)\n", e.what());
    return e.get_exit_code() != 0 ? e.get_exit_code() : 1;
  }
  try {
    for (const Command& command : commands)
      if (command.app->parsed()) return command.run();
    return 1;  // unreachable: require_subcommand(1)
  } catch (const penumbra::Error& e) {
    fmt::print(stderr, "penumbra: error: {}\n", e.what());
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "penumbra: error: out of memory (try a smaller --width/--height or fewer samples)\n");
  } catch (const std::exception& e) {
    fmt::print(stderr, "penumbra: error: internal: {}\n", e.what());
  }
  return 1;
}
