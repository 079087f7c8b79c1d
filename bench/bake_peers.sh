#!/usr/bin/env bash
# meso bake against Blender's Cycles "selected to active" normal-map bake (issue 5, "Speed,
# measured"): the same asset, resolution and samples, in the same run.
#
#   bench/bake_peers.sh [BUILD_DIR]          (default build/release)
#
# Installs Blender (Debian package `blender`, a bench-only dependency) when it is missing,
# builds meso, meso-example, bake_time and bake_compare in BUILD_DIR, then:
#  - asset: meso-example's brick wall as a 1,048,576-triangle high mesh (1024 x 512 quads)
#    and its smooth base surface as a 5,120-triangle base mesh (64 x 40 quads, UVs = the
#    wall's), both OBJ with meso's angle-weighted vertex normals;
#  - per size (SIZES, default "2048 4096"): `meso bake` (tangent-space normal map +
#    displacement + coverage, 1 sample, --threads 2), its wall time; bench/bake_time, the
#    bake() call alone on the same files (median of REPEATS); Blender 3.x Cycles bake of a
#    tangent-space normal map, 1 sample, 2 threads, margin 0, cage extrusion = --front and
#    max ray distance = --front + --back (the same reach), timed around bpy.ops.object.bake
#    alone (bench/bake_blender.py); bench/bake_compare, the angle between the two normal
#    maps over texels both wrote (meso: hit; Blender: changed from its (0,0,0,0) background).
#  - a Markdown table on stdout.
#
# Environment: OUT (work folder, default /tmp/bake_peers), SIZES, FRONT, BACK (object units,
# default 0.05: the bricks stand at most 0.03 off the base), REPEATS (default 3), THREADS
# (default 2), BLENDER (the binary, default blender), NO_BUILD=1 (use the binaries in
# BUILD_DIR as they are).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
BUILD=${1:-build/release}
OUT=${OUT:-/tmp/bake_peers}
SIZES=${SIZES:-"2048 4096"}
FRONT=${FRONT:-0.05}
BACK=${BACK:-0.05}
REPEATS=${REPEATS:-3}
THREADS=${THREADS:-2}
BLENDER=${BLENDER:-blender}

# Blender, installed the way scripts/setup-deps installs packages: only when missing, as root
# or through sudo.
if ! command -v "$BLENDER" >/dev/null; then
  echo "bake_peers: installing the Debian package blender (bench only)" >&2
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "bake_peers: need root or sudo to install blender" >&2; exit 1; }
    sudo="sudo"
  fi
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends blender >/dev/null
  echo "bake_peers: done" >&2
fi

if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  echo "bake_peers: $BUILD is not configured (scripts/build release, or cmake -S . -B $BUILD)" >&2
  exit 2
fi
[ "${NO_BUILD:-0}" = 1 ] || cmake --build "$BUILD" -j2 --target meso meso-example bake_time bake_compare >&2
MESO=$BUILD/apps/meso
EXAMPLE=$BUILD/examples/meso-example

mkdir -p "$OUT"
now() { date +%s.%N; }

# The asset.
"$EXAMPLE" --columns 1024 --rows 512 -o "$OUT/high.obj"
"$EXAMPLE" --base --columns 64 --rows 40 -o "$OUT/base.obj"

blender_version=$("$BLENDER" --version 2>/dev/null | head -1)
RESULTS=$OUT/results.jsonl
: >"$RESULTS"
for size in $SIZES; do
  echo "== $size x $size" >&2
  maps=$OUT/meso_$size
  t0=$(now)
  "$MESO" --threads "$THREADS" --quiet bake --low "$OUT/base.obj" --high "$OUT/high.obj" --size "$size" \
    --front "$FRONT" --back "$BACK" --maps displacement,normal_ts,coverage -o "$maps"
  t1=$(now)
  meso_cli=$(echo "$t1 - $t0" | bc -l)
  meso_call=$("$BUILD/bench/bake_time" "$OUT/base.obj" "$OUT/high.obj" "$size" "$FRONT" "$BACK" "$REPEATS")
  max_ray=$(echo "$FRONT + $BACK" | bc -l)
  "$BLENDER" -b --factory-startup --python bench/bake_blender.py -- \
    --low "$OUT/base.obj" --high "$OUT/high.obj" --size "$size" --extrusion "$FRONT" --max-ray "$max_ray" \
    --threads "$THREADS" --samples 1 --out "$OUT/blender_$size.rgba32f" --report "$OUT/blender_$size.json" >"$OUT/blender_$size.log" 2>&1 ||
    { tail -20 "$OUT/blender_$size.log" >&2; echo "bake_peers: blender failed (log: $OUT/blender_$size.log)" >&2; exit 1; }
  compare=$("$BUILD/bench/bake_compare" --meso "$maps/normal_ts.png" --coverage "$maps/coverage.png" \
    --blender "$OUT/blender_$size.rgba32f" --diff "$OUT/diff_$size.png")
  printf '{"size": %s, "meso_cli_seconds": %s, "meso": %s, "blender": %s, "compare": %s}\n' \
    "$size" "$meso_cli" "$meso_call" "$(cat "$OUT/blender_$size.json")" "$compare" | tr -d '\n' >>"$RESULTS"
  echo >>"$RESULTS"
  rm -f "$OUT/blender_$size.rgba32f"
done

python3 - "$RESULTS" "$blender_version" <<'EOF'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
print(f"meso bake() call (median) vs {sys.argv[2]} bpy.ops.object.bake call, 1 sample, 2 threads; "
      f"high {rows[0]['meso']['high_faces']:,} triangles, base {rows[0]['meso']['low_faces']:,} triangles")
print()
print("| size | meso s (bake call) | meso s (CLI, whole run) | meso rays/s | blender s (bake call) | blender ÷ meso | texels compared | mean angle ° | p99 angle ° | max angle ° |")
print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for r in rows:
    m, b, c = r["meso"], r["blender"], r["compare"]
    print(f"| {r['size']}² | {m['median_seconds']:.2f} | {r['meso_cli_seconds']:.2f} | {m['rays_per_second'] / 1e6:.1f} M | "
          f"{b['bake_seconds']:.2f} | {b['bake_seconds'] / m['median_seconds']:.1f} | {c['compared']:,} | "
          f"{c['mean_deg']:.4f} | {c['p99_deg']:.4f} | {c['max_deg']:.3f} |")
EOF
