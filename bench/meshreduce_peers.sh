#!/usr/bin/env bash
# Reproduces the meshreduce figures of docs/benchmarks.md: meso's reducer against
# meshoptimizer on the bundled brick wall and a smooth torus (262,144 triangles each), at
# 10 % and 1 % of the faces, then meso's --error target on the brick wall.
#   bench/meshreduce_peers.sh [BUILD_DIR]      (default build/release)
set -euo pipefail
build=${1:-build/release}
if [ ! -f /usr/include/meshoptimizer.h ]; then
  echo "meshreduce_peers needs libmeshoptimizer-dev (apt-get install -y libmeshoptimizer-dev)" >&2
  exit 1
fi
cmake --build "$build" -j2 --target meshreduce_peers meso meso-example
"$build/bench/meshreduce_peers" --ratios 0.1,0.01
high=$(mktemp -d)/bricks_high.obj
"$build/examples/meso-example" -o "$high"
for e in 0.5% 0.1%; do
  "$build/apps/meso" meshreduce "$high" -o "${high%/*}/bricks_error.obj" --error "$e" --json --quiet |
    python3 -c "import json,sys; d=json.load(sys.stdin); e=d['error']; print(f\"--error $e: {d['output']['faces']} faces, {d['seconds']:.2f} s, Hausdorff {e['hausdorff_percent']:.4f} % of the diagonal, RMS {e['rms_percent']:.5f} %\")"
done
