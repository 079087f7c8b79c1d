#!/usr/bin/env bash
# Reproduces the preview-method curves of docs/benchmarks.md: every per-pixel method of
# `meso preview` over its iteration budgets on three height maps (rocks: uniform heights,
# bricks: top heavy, mountains: bottom heavy), at five view angles (30° to the grazing 85° and 89°), against the reference
# renderer; a CSV, one SVG per map and view, and the issue's two goals (DIG-DM against POM
# at equal error; safe methods missing no first intersection).
#   bench/preview_curves.sh [BUILD_DIR] [preview_curves options...]   (default build/release)
#   bench/preview_curves.sh build/release --quick                     (a smoke run of seconds)
# Options after the build folder go to the program (--help lists them); results go under
# --out (default out/bench/preview). Headless OpenGL through EGL: Mesa's llvmpipe works.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
shift || true
if [ ! -f "$build/CMakeCache.txt" ]; then
  echo "$build is not configured: scripts/build release (or cmake --preset release) first" >&2
  exit 1
fi
cmake --build "$build" -j2 --target preview_curves
out=out/bench/preview
args=("$@")
for ((i = 0; i < ${#args[@]}; ++i)); do
  if [ "${args[i]}" = "--out" ] && [ $((i + 1)) -lt ${#args[@]} ]; then out=${args[i + 1]}; fi
done
"$build/bench/preview_curves" "$@"
echo
echo "results: $out/curves.csv, $out/summary.md, $out/*.svg (maps and streams under $out/maps/)"
