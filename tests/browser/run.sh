#!/usr/bin/env bash
# The browser tests, as ctest runs them: `penumbra compare`'s HTML report (report_test.mjs, the default)
# and the page of `penumbra view` (view_test.mjs):
#   tests/browser/run.sh PENUMBRA_BINARY OUT_DIR [SCRIPT]
# Needs Debian's Chromium and Node.js (scripts/install-deps installs both). playwright-core, pinned
# by package-lock.json, is installed here with `npm ci` the first time (the only step that needs the
# npm registry; later runs are offline). It drives /usr/bin/chromium; no browser is downloaded.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
chromium="${PENUMBRA_CHROMIUM:-/usr/bin/chromium}"

if [ ! -x "$chromium" ]; then
  echo "browser test: Chromium not found at $chromium. Install it with: sudo apt-get install -y chromium" \
       "(or run scripts/install-deps), or point PENUMBRA_CHROMIUM at a Chromium binary." >&2
  exit 1
fi
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  echo "browser test: Node.js and npm are needed. Install them with: sudo apt-get install -y nodejs npm" \
       "(or run scripts/install-deps)." >&2
  exit 1
fi
wanted="$(node -p "require('$here/package-lock.json').packages['node_modules/playwright-core'].version")"
# Under a lock: ctest runs the browser tests side by side, and two npm ci in one folder would collide.
exec 9>"$here/node_modules.lock"
flock 9
installed="$(node -p "try { require('$here/node_modules/playwright-core/package.json').version } catch { '' }")"
if [ "$installed" != "$wanted" ]; then
  echo "browser test: installing playwright-core $wanted (npm ci in $here)"
  if ! (cd "$here" && npm ci --no-audit --no-fund --loglevel=error); then
    echo "browser test: npm ci failed; it needs the npm registry once (run it by hand: cd $here && npm ci)." >&2
    exit 1
  fi
fi
flock -u 9
script="${3:-report_test.mjs}"
exec node "$here/$script" "$1" "$2"
