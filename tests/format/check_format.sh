#!/usr/bin/env bash
# The format check, as ctest runs it (entry `format`):
#   tests/format/check_format.sh [REPO_ROOT]     (default: two folders up from this script)
# Every tracked C++ file (*.cpp, *.h) is as clang-format (Debian's, installed by scripts/install-deps)
# leaves it under the repository's .clang-format. On failure, the files that differ are named; run
#   git ls-files '*.cpp' '*.h' | xargs clang-format -i
# to format them.
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd -P)"
root="$(cd "${1:-$here/../..}" && pwd -P)" || { echo "check_format: no such folder: ${1:-}" >&2; exit 2; }
cd "$root" || exit 2
if ! command -v clang-format >/dev/null 2>&1; then
  echo "check_format: clang-format is not installed (scripts/install-deps installs it)" >&2
  exit 1
fi
# One clang-format process for every file; --Werror makes each difference an error naming file and line.
if ! output="$(git ls-files '*.cpp' '*.h' | grep -v '^tests/browser/node_modules/' |
               xargs clang-format --dry-run --Werror 2>&1)"; then
  echo "$output" | grep -E '^[^ ].*: error:' | head -20 >&2
  echo "check_format: not formatted; run: git ls-files '*.cpp' '*.h' | xargs clang-format -i" >&2
  exit 1
fi
echo "check_format: every C++ file follows .clang-format"
