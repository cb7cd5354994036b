// The `penumbra` command-line tool: render, compare, bench, scenes, techniques (docs/architecture.md,
// "Command-line tool"). The commands themselves are a library (penumbra_commands) that the Python
// module runs too; this is only the program's entry.
#include "cli.h"

int main(int argc, char** argv) { return penumbra::cli::runCommandLine(argc, argv, false); }
