#!/usr/bin/env bash
# meso uvpack pack against xatlas (npm xatlasjs: jpcy/xatlas compiled to WebAssembly, its
# pack-only path AddUvMesh + PackCharts, driven by bench/uvpack_peers/xatlas_pack.mjs).
#
# Installs the Node project bench/uvpack_peers (npm ci) and builds nothing else: it needs
# build/ci/apps/meso and build/ci/examples/meso-example
# (cmake --build build/ci --target meso meso-example). Packs each input with both packers at
# sizes 512 and 1024 and paddings 2 and 4, checks every result with
# `meso uvpack check --size N --padding P`, and prints Markdown tables.
#
# Inputs: bricks_base (meso's example reduced to 4000 faces: one chart), torus_40 and torus_200 (a torus
# tiled into about 40 or 200 charts of varied shapes and sizes whose UVs overlap before packing) and
# bricks_split (bricks_base cut into 150 irregular charts). See bench/uvpack_peers/gen_charts.mjs.
#
# xatlas variants (P = the padding asked for):
#   "P, bilinear, random, axis"    PackOptions padding P, bilinear on, random placement,
#                                  rotateChartsToAxis on: xatlas's defaults - the main comparison
#                                  (meso also turns charts to their minimum-area orientation)
#   "P, bilinear, random"          the same with rotateChartsToAxis off: 90-degree turns only
#   "P, bilinear, brute force"     the same with bruteForce (xatlas's best-placement mode)
#   "P/2, no bilinear, random, axis" padding ceil(P/2), bilinear off: what meso's checker asks for,
#                                  since xatlas dilates every chart by its padding (so two charts
#                                  end up about 2 P apart) while meso's P is the gap between charts
#   "P/2, no bilinear, random"     the same with rotateChartsToAxis off
#   "P/2, no bilinear, brute force"
# xatlas packs at a given scale, so xatlas_pack.mjs searches the largest scale at which all
# charts fit one atlas (1 % steps down from the area bound, then refined to 0.1 %; see there).
# XATLAS_BRUTE=0 skips the brute-force variants (slow at 1024).
#
# Environment: MESO, MESO_EXAMPLE (binaries), OUT (work directory, default /tmp/uvpack_peers),
# SIZES, PADDINGS, QUALITIES (lists; meso's --quality presets), XATLAS_BRUTE, CLAMP (1: also
# meso balanced --clamp, charts allowed to touch the atlas border as xatlas's are; 0: not).
# meso's default (--wrap) keeps ceil(P/2) texels to the border so that the atlas can be sampled
# with repeat addressing; xatlas keeps none, so its atlases are right for clamp-to-edge only.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
MESO=${MESO:-$ROOT/build/ci/apps/meso}
MESO_EXAMPLE=${MESO_EXAMPLE:-$ROOT/build/ci/examples/meso-example}
OUT=${OUT:-/tmp/uvpack_peers}
SIZES=${SIZES:-"512 1024"}
PADDINGS=${PADDINGS:-"2 4"}
XATLAS_BRUTE=${XATLAS_BRUTE:-1}
QUALITIES=${QUALITIES:-"fast balanced best"}
CLAMP=${CLAMP:-1}
PEERS=$ROOT/bench/uvpack_peers

for b in "$MESO" "$MESO_EXAMPLE"; do
  [[ -x $b ]] || { echo "uvpack_peers.sh: $b is missing: cmake --build build/ci --target meso meso-example" >&2; exit 2; }
done
command -v node >/dev/null || { echo "uvpack_peers.sh: node is required" >&2; exit 2; }

(cd "$PEERS" && npm ci --no-audit --no-fund --loglevel=error) >&2

mkdir -p "$OUT"
RUNS=$OUT/runs.jsonl
: >"$RUNS"

# Inputs.
"$MESO_EXAMPLE" -o "$OUT/bricks_high.obj" >&2
"$MESO" --quiet meshreduce "$OUT/bricks_high.obj" -o "$OUT/bricks_base.obj" --faces 4000
node "$PEERS/gen_charts.mjs" torus -o "$OUT/torus_40.obj" --charts 40 --seed 1 >&2
node "$PEERS/gen_charts.mjs" torus -o "$OUT/torus_200.obj" --charts 200 --seed 1 >&2
node "$PEERS/gen_charts.mjs" split "$OUT/bricks_base.obj" -o "$OUT/bricks_split.obj" --charts 150 --seed 1 >&2
INPUTS=${INPUTS:-"bricks_base torus_40 torus_200 bricks_split"}

now_ms() { echo $(( $(date +%s%N) / 1000000 )); }

# Charts per input, as meso's checker counts them.
declare -A CHARTS
for input in $INPUTS; do
  CHARTS[$input]=$("$MESO" --json --quiet uvpack check "$OUT/$input.obj" --size 64 |
    node -e 'let s="";process.stdin.on("data",d=>s+=d).on("end",()=>console.log(JSON.parse(s).charts))')
done

# record INPUT SIZE PADDING PACKER VARIANT WALL_MS FAILED PREFIX: one line of runs.jsonl
# (PREFIX.pack.json, .check.json, .compare.json: the reports of the packer, the checker and
# compare.mjs).
record() {
  printf '{"input":"%s","charts":%s,"size":%s,"padding":%s,"packer":"%s","variant":"%s","wall_ms":%s,"failed":%s,"pack_json":"%s","check_json":"%s","compare_json":"%s"}\n' \
    "$1" "${CHARTS[$1]}" "$2" "$3" "$4" "$5" "$6" "$7" "$8.pack.json" "$8.check.json" "$8.compare.json" >>"$RUNS"
}

# verify INPUT SIZE PADDING PREFIX: meso's checker on the packed PREFIX.obj, and what the
# packing did to each chart (mirrored or not, scale relative to the packer's common scale).
verify() {
  "$MESO" --quiet uvpack check "$4.obj" --size "$2" --padding "$3" --report "$4.check.json"
  local scale
  scale=$(node -e 'console.log(JSON.parse(require("fs").readFileSync(process.argv[1], "utf8")).scale)' "$4.pack.json")
  node "$PEERS/compare.mjs" "$OUT/$1.obj" "$4.obj" "$2" "$scale" >"$4.compare.json"
}

for input in $INPUTS; do
  for size in $SIZES; do
    for pad in $PADDINGS; do
      tag=$input.$size.$pad
      echo "== $input size $size padding $pad" >&2
      # meso, at each quality preset
      for quality in $QUALITIES; do
        prefix=$OUT/$tag.meso-$quality
        t0=$(now_ms)
        if "$MESO" --json --quiet uvpack pack "$OUT/$input.obj" -o "$prefix.obj" --size "$size" --padding "$pad" --quality "$quality" >"$prefix.pack.json"; then
          t1=$(now_ms)
          verify "$input" "$size" "$pad" "$prefix"
          record "$input" "$size" "$pad" meso "$quality" $((t1 - t0)) false "$prefix"
        else
          record "$input" "$size" "$pad" meso "$quality" 0 true "$prefix"
        fi
      done
      # meso balanced with --clamp (no border margin): xatlas packs up to the atlas border,
      # which is right for clamp-to-edge sampling only, so this is the like-for-like row
      if [[ $CLAMP == 1 ]]; then
        prefix=$OUT/$tag.meso-clamp
        t0=$(now_ms)
        if "$MESO" --json --quiet uvpack pack "$OUT/$input.obj" -o "$prefix.obj" --size "$size" --padding "$pad" --clamp >"$prefix.pack.json"; then
          t1=$(now_ms)
          verify "$input" "$size" "$pad" "$prefix"
          record "$input" "$size" "$pad" meso "balanced --clamp" $((t1 - t0)) false "$prefix"
        else
          record "$input" "$size" "$pad" meso "balanced --clamp" 0 true "$prefix"
        fi
      fi
      # xatlas variants
      half=$(( (pad + 1) / 2 ))
      variants=("P, bilinear, random, axis|--padding $pad --bilinear 1 --axis" "P, bilinear, random|--padding $pad --bilinear 1")
      [[ $XATLAS_BRUTE == 1 ]] && variants+=("P, bilinear, brute force|--padding $pad --bilinear 1 --brute-force")
      variants+=("P/2, no bilinear, random, axis|--padding $half --bilinear 0 --axis" "P/2, no bilinear, random|--padding $half --bilinear 0")
      [[ $XATLAS_BRUTE == 1 ]] && variants+=("P/2, no bilinear, brute force|--padding $half --bilinear 0 --brute-force")
      i=0
      for v in "${variants[@]}"; do
        name=${v%%|*}
        read -r -a opts <<<"${v#*|}"
        prefix=$OUT/$tag.xatlas$i
        t0=$(now_ms)
        if node "$PEERS/xatlas_pack.mjs" "$OUT/$input.obj" -o "$prefix.obj" --size "$size" "${opts[@]}" --json "$prefix.pack.json"; then
          t1=$(now_ms)
          verify "$input" "$size" "$pad" "$prefix"
          record "$input" "$size" "$pad" xatlas "$name" $((t1 - t0)) false "$prefix"
        else
          record "$input" "$size" "$pad" xatlas "$name" 0 true "$prefix"
        fi
        i=$((i + 1))
      done
    done
  done
done

echo
echo "Times are wall-clock times of the whole packer process (read the OBJ, search the scale, pack,"
echo "write the OBJ; meso also runs its checker on its result), with the number of packings each"
echo "scale search made; for xatlas also the time of one packing (PackCharts at the final scale)."
echo "Utilization: the charts' UV triangle area / the atlas area (true coverage), by meso uvpack check"
echo "on each result; texel coverage (texels touched / all texels) beside it; both packers are checked"
echo "at the same size and padding."
echo
node "$PEERS/table.mjs" "$RUNS"
