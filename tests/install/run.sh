#!/usr/bin/env bash
# The installed package from a consumer's side: installs the build into a fresh prefix, builds the
# examples that use find_package(penumbra) against it, runs them, and checks what they print; then
# configures a parent project that adds penumbra as a subdirectory.
#   tests/install/run.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build=$1 source=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
# The package (lib/ or a multiarch lib/<triplet>/). Nothing of the source tree may leak into it: its
# headers come from the prefix alone.
config=$(find "$work/prefix" -name penumbraConfig.cmake -print -quit)
[ -n "$config" ] || { echo "install: no penumbraConfig.cmake in the prefix" >&2; exit 1; }
package=$(dirname "$config")
if grep -rq "$source" "$package"; then
  echo "install: the package names the source tree:" >&2
  grep -rl "$source" "$package" >&2
  exit 1
fi
for example in minimal engine; do
  cmake -S "$source/examples/$example" -B "$work/$example" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
  cmake --build "$work/$example" -j 2 >/dev/null
done
out=$("$work/minimal/minimal" torus)
echo "$out"
grep -Eq '^torus: pcss RMSE8 [0-9]+\.[0-9]+, penumbra RMSE8 [0-9]+\.[0-9]+ \(reference at 64 spp\)$' <<<"$out"
out=$("$work/engine/engine")
echo "$out"
grep -Eq '^engine buffers 320x240: pcss RMSE8 [0-9]+\.[0-9]+ against the reference at 64 spp$' <<<"$out"
# The engine's G-buffer and penumbra's own of the same triangles give the same V but for a few edge pixels.
differ=$(sed -nE "s/^penumbra's own G-buffer: ([0-9.]+)% of pixels differ.*/\1/p" <<<"$out")
awk -v d="$differ" 'BEGIN { exit !(d != "" && d < 1.0) }' || { echo "install: engine V differs on $differ% of pixels" >&2; exit 1; }
# A bad scene name is an error message and a non-zero exit, not a crash.
if "$work/minimal/minimal" no-such-scene 2>"$work/error.txt"; then
  echo "install: minimal accepted an unknown scene" >&2
  exit 1
fi
grep -q "no-such-scene" "$work/error.txt"
# As a subproject: configured only (tests/install/subproject/CMakeLists.txt checks what it must not touch).
cmake -S "$source/tests/install/subproject" -B "$work/subproject" -DPENUMBRA_SOURCE="$source" >"$work/subproject.txt" 2>&1 ||
  { cat "$work/subproject.txt" >&2; exit 1; }
grep -q "penumbra as a subproject: ok" "$work/subproject.txt"
echo "install: ok"
