#!/usr/bin/env python3
"""Writes a high-poly "rock" for the previewer's curved-base measurements (docs/benchmarks.md,
"preview: per-pixel rays through each triangle's own UV mapping"): a UV sphere of radius 1000
centred at (1e5, -3e4, 2e3) (far from the origin, as scanned assets are), 512 x 256 segments
(261,120 triangles, no UVs), displaced radially by 24 plane waves of random direction and
frequency (seeded: the same file every run) to about +-7 % of the radius. Reduced to a few
thousand faces its displacement is near the size of its triangles: the extreme case for
per-pixel displacement on a curved base.

usage: make_rock.py OUT.obj
"""
import math
import random
import sys


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__.strip().splitlines()[-1])
    rng = random.Random(3)
    nu, nv, radius = 512, 256, 1000.0
    centre = (1.0e5, -3.0e4, 2.0e3)
    waves = [(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(20, 90), rng.uniform(0, 6.28)) for _ in range(24)]

    def displaced(x, y, z):
        s = 0.0
        for a, b, c, f, phase in waves:
            s += math.sin(f * (a * x + b * y + c * z) / math.sqrt(a * a + b * b + c * c) + phase) / f
        r = radius * (1 + 0.4 * s)
        return (x * r + centre[0], y * r + centre[1], z * r + centre[2])

    verts = []
    for j in range(1, nv):
        theta = math.pi * j / nv
        for i in range(nu):
            phi = 2 * math.pi * i / nu
            verts.append(displaced(math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)))
    north, south = len(verts), len(verts) + 1
    verts += [displaced(0, 0, 1), displaced(0, 0, -1)]

    def vid(j, i):
        return (j - 1) * nu + i % nu

    faces = []  # counter-clockwise seen from outside
    for j in range(1, nv - 1):
        for i in range(nu):
            a, b, c, d = vid(j, i), vid(j, i + 1), vid(j + 1, i + 1), vid(j + 1, i)
            faces += [(a, d, c), (a, c, b)]
    for i in range(nu):
        faces += [(north, vid(1, i), vid(1, i + 1)), (south, vid(nv - 1, i + 1), vid(nv - 1, i))]
    with open(sys.argv[1], "w") as out:
        out.writelines("v %.6f %.6f %.6f\n" % v for v in verts)
        out.writelines("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1) for t in faces)


if __name__ == "__main__":
    main()
