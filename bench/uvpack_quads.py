#!/usr/bin/env python3
"""Writes an OBJ of N separate quads of random size and aspect, each its own UV chart, with every
chart's UVs starting at the origin (so they all overlap before packing): the many-charts input of
docs/benchmarks.md ("uvpack pack with many charts").
Usage: bench/uvpack_quads.py N OUT.obj [SEED]"""
import random
import sys

n, out = int(sys.argv[1]), sys.argv[2]
random.seed(int(sys.argv[3]) if len(sys.argv) > 3 else 3)
with open(out, "w") as f:
    v = 1
    for q in range(n):
        w = random.uniform(0.05, 0.4)
        h = w * random.uniform(0.3, 1.0)
        corners = [(0, 0), (w, 0), (w, h), (0, h)]
        for x, y in corners:
            f.write(f"v {x} {y} {q}.0\n")  # each quad in its own plane z = q
        for x, y in corners:
            f.write(f"vt {x} {y}\n")
        f.write(f"f {v}/{v} {v+1}/{v+1} {v+2}/{v+2}\nf {v}/{v} {v+2}/{v+2} {v+3}/{v+3}\n")
        v += 4
