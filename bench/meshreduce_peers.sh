#!/usr/bin/env bash
# Reproduces the meshreduce figures of docs/benchmarks.md: meso's reducer against
# meshoptimizer, CGAL (Garland–Heckbert plane policies), Blender's Decimate (Collapse) and
# MeshLab's Quadric Edge Collapse Decimation on the bundled brick wall and a smooth torus
# (262,144 triangles each), at 10 %, 1 % and 0.1 % of the faces, in one run with one error
# measure; then meso's --error target on the brick wall.
#   bench/meshreduce_peers.sh [BUILD_DIR]      (default build/release)
# Peers that are missing are skipped with a message (apt-get install -y libmeshoptimizer-dev
# blender meshlab xvfb; meshoptimizer needs a reconfigure). Environment: RATIOS (default
# 0.1,0.01,0.001), REPEAT (default 1), NO_BUILD=1 (use the binaries in BUILD_DIR as they are),
# PRESETS (meso's --quality presets, default fast,balanced,best), PEER_ARGS (more options of
# meshreduce_peers, e.g. "--no-cgal --no-blender --no-meshlab" to rerun meso and meshoptimizer
# only), NO_ERROR_RUNS=1 (skip the --error runs at the end).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
build=${1:-build/release}
for p in blender meshlabserver xvfb-run; do
  command -v "$p" >/dev/null || echo "meshreduce_peers: $p not found; its peer is skipped" >&2
done
[ -f /usr/include/meshoptimizer.h ] || echo "meshreduce_peers: libmeshoptimizer-dev not installed; its peer is skipped" >&2
[ -n "${NO_BUILD:-}" ] || cmake --build "$build" -j1 --target meshreduce_peers meso meso-example
# shellcheck disable=SC2086  # PEER_ARGS is a list of options
"$build/bench/meshreduce_peers" --ratios "${RATIOS:-0.1,0.01,0.001}" --repeat "${REPEAT:-1}" --presets "${PRESETS:-fast,balanced,best}" ${PEER_ARGS:-}
[ -z "${NO_ERROR_RUNS:-}" ] || exit 0
high=$(mktemp -d)/bricks_high.obj
"$build/examples/meso-example" -o "$high"
for e in 0.5% 0.1%; do
  "$build/apps/meso" meshreduce "$high" -o "${high%/*}/bricks_error.obj" --error "$e" --json --quiet |
    python3 -c "import json,sys; d=json.load(sys.stdin); e=d['error']; print(f\"--error $e: {d['output']['faces']} faces, {d['seconds']:.2f} s, Hausdorff {e['hausdorff_percent']:.4f} % of the diagonal, RMS {e['rms_percent']:.5f} %\")"
done
rm -rf "${high%/*}"
