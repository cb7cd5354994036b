// runCommandLine (cli.h): parses one command line and runs its subcommand. Every bad input ends as one
// line "penumbra: error: <message>" on stderr and a non-zero exit code: 1 for penumbra::Error, CLI11's
// own code for a malformed command line; or, for a caller that handles errors itself (the Python
// module), as a penumbra::Error thrown with the same message.
#include <cstdio>
#include <exception>
#include <new>

#include <fmt/format.h>

#include "cli.h"
#include "penumbra/error.h"

namespace penumbra::cli {

int runCommandLine(int argc, const char* const* argv, bool rethrow) {
  CLI::App app{"penumbra: soft shadows from area lights, measured against a ray-traced reference", "penumbra"};
  app.set_version_flag("--version", PENUMBRA_VERSION);
  app.require_subcommand(1);
  const std::vector<Command> commands = {addRenderCommand(app), addCompareCommand(app),    addBenchCommand(app),
                                         addScenesCommand(app), addTechniquesCommand(app), addViewCommand(app)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    if (rethrow) throw Error(fmt::format("{} (see penumbra --help)", e.what()));
    fmt::print(stderr, "penumbra: error: {} (see penumbra --help)\n", e.what());
    return e.get_exit_code() != 0 ? e.get_exit_code() : 1;
  }
  const auto dispatch = [&] {
    for (const Command& command : commands)
      if (command.app->parsed()) return command.run();
    return 1;  // unreachable: require_subcommand(1)
  };
  if (rethrow) return dispatch();
  try {
    return dispatch();
  } catch (const Error& e) {
    fmt::print(stderr, "penumbra: error: {}\n", e.what());
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "penumbra: error: out of memory (try a smaller --width/--height or fewer samples)\n");
  } catch (const std::exception& e) {
    fmt::print(stderr, "penumbra: error: internal: {}\n", e.what());
  }
  return 1;
}

}  // namespace penumbra::cli
