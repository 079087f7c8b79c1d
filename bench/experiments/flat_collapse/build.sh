#!/bin/sh
# An experiment, not part of meso's build: meshreduce's `fast` loop on flat arrays
# (meshoptimizer-style passes) with meso's guarantees, against meshopt_simplify and
# reduce_mesh(fast). Needs `scripts/build release` and libmeshoptimizer-dev, valgrind-dev.
# Results and conclusions: docs/benchmarks.md, "meshreduce: the collapse loop on flat arrays".
set -e
cd "$(dirname "$0")"
M=$(cd ../../.. && pwd)
R=$M/build/release
CXX="g++ -O2 -g -DNDEBUG -std=c++17 -D_USE_MATH_DEFINES -I$M/meshreduce/include -I$M/core/include -I$M/formats/include -I$M/examples/include -I$M/meshreduce/src -I$M/bench -isystem /usr/include/eigen3"
$CXX -c fastcore.cpp -o /tmp/flat_collapse_fastcore.o
$CXX -c bench.cpp -o /tmp/flat_collapse_bench.o
g++ -o /tmp/flat_collapse_bench /tmp/flat_collapse_bench.o /tmp/flat_collapse_fastcore.o $R/bench/libmeshreduce_cgal_peer.a \
  $R/meshreduce/libmeso_meshreduce.a $R/formats/libmeso_formats.a $R/examples/libmeso_examples.a \
  -lgmpxx -lmpfr -lgmp $R/meshreduce/libmeso_meshreduce_distance.a -lembree3 -lassimp -lz -ldraco -lminizip -lrt -ldl $R/core/libmeso_core.a \
  -ltbb -lOpenMeshTools -lOpenMeshCore -lmeshoptimizer
echo "built /tmp/flat_collapse_bench: run it with --repeat 5 --methods meshopt,meso,proto,protoE,protoV,protoEV,protoB"
