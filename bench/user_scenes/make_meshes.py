#!/usr/bin/env python3
"""Writes the meshes of the scenes in this folder, scenes of the kind users bring rather than
the shipped ones (bench/user_scenes/README.md). Run once; the files are committed.
hips.obj: a closed body of revolution about z, radius 0.15 m widening to 0.25 m at the hips
(z = 0.85 m), 1.3 m tall (40 segments around, 40 rows). skirt.obj: an open cone of cloth,
radius 0.21 m at z = 1.15 m to 0.40 m at z = 0.55 m (72 around, 30 rows, alternate rows
offset half a segment). paddle.obj: a closed box 0.8 x 0.05 x 0.3 m centred on the origin.
irregular_cloth.obj: a 1 m square of cloth in z = 0, 48 x 48 cells whose inner vertices are
moved by up to 0.42 of a cell (a fixed pseudo-random sequence), each cell's diagonal drawn
either way at random unless that would turn a triangle over: an irregular triangulation of the
kind a remesher or a garment tool writes (edges from 4.6 to 51 mm). needle.obj: a closed cone
standing on z = 0, radius 0.01 m at its base and its tip at z = 0.3 m (16 segments around).
extra/blade.obj: a closed box 0.002 x 0.8 x 0.3 m centred on the origin."""
import math, os, random, sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.dont_write_bytecode = True  # no __pycache__ left in tools/
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools"))
import make_meshes  # tools/make_meshes.py: the shipped meshes' writer


def write(name, vertices, faces, comment):
    make_meshes.write(os.path.join(HERE, name), vertices, faces, comment)


def hips():
    around, rows, bottom, top = 40, 40, 0.0, 1.3
    radius = lambda z: 0.15 + 0.1 * math.exp(-(((z - 0.85) / 0.12) ** 2))
    v, f = [], []
    for j in range(rows + 1):
        z = bottom + (top - bottom) * j / rows
        for i in range(around):
            a = 2 * math.pi * i / around
            v.append((radius(z) * math.cos(a), radius(z) * math.sin(a), z))
    for j in range(rows):
        for i in range(around):
            a, b = j * around + i, j * around + (i + 1) % around
            f += [(a, b, b + around), (a, b + around, a + around)]  # outward, counter-clockwise seen from outside
    low, high = len(v), len(v) + 1
    v += [(0, 0, bottom), (0, 0, top)]
    for i in range(around):
        f += [(low, (i + 1) % around, i), (high, rows * around + i, rows * around + (i + 1) % around)]
    return v, f


def skirt():
    around, rows, r_top, r_bottom, z_top, z_bottom = 72, 30, 0.21, 0.40, 1.15, 0.55
    v, f = [], []
    for j in range(rows + 1):
        s = j / rows
        r, z = r_top + (r_bottom - r_top) * s, z_top + (z_bottom - z_top) * s
        for i in range(around):
            a = 2 * math.pi * (i + 0.5 * (j % 2)) / around
            v.append((r * math.cos(a), r * math.sin(a), z))
    for j in range(rows):
        for i in range(around):
            a, b = j * around + i, j * around + (i + 1) % around
            c, d = a + around, b + around
            f += [(a, b, c), (b, d, c)] if j % 2 == 0 else [(a, b, d), (a, d, c)]
    return v, f


def paddle(sx, sy, sz):
    v = [(x * sx / 2, y * sy / 2, z * sz / 2) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    corner = lambda x, y, z: 4 * x + 2 * y + z
    quads = [((0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)), ((1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)),
             ((0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)), ((0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)),
             ((0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)), ((0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1))]
    f = []
    for q in quads:
        a, b, c, d = (corner(*p) for p in q)
        f += [(a, b, c), (a, c, d)]
    return v, f


def irregular_cloth(cells=48, size=1.0, jitter=0.42, seed=7):
    rng = random.Random(seed)
    cell = size / cells
    v = []
    for j in range(cells + 1):
        for i in range(cells + 1):
            x, y = -size / 2 + i * cell, -size / 2 + j * cell
            if 0 < i < cells:
                x += rng.uniform(-jitter, jitter) * cell
            if 0 < j < cells:
                y += rng.uniform(-jitter, jitter) * cell
            v.append((x, y, 0.0))
    area = lambda p, q, r: (v[q][0] - v[p][0]) * (v[r][1] - v[p][1]) - (v[q][1] - v[p][1]) * (v[r][0] - v[p][0])
    f = []
    for j in range(cells):
        for i in range(cells):
            a = j * (cells + 1) + i
            b, c = a + 1, a + cells + 1
            d = c + 1
            one, two = [(a, b, d), (a, d, c)], [(a, b, c), (b, d, c)]
            pick = one if rng.random() < 0.5 else two
            if min(area(*t) for t in pick) <= 0:
                pick = two if pick is one else one
            f += pick
    return v, f


def needle(around=16, radius=0.01, height=0.3):
    v = [(0, 0, height), (0, 0, 0)]
    v += [(radius * math.cos(2 * math.pi * i / around), radius * math.sin(2 * math.pi * i / around), 0) for i in range(around)]
    f = []
    for i in range(around):
        a, b = 2 + i, 2 + (i + 1) % around
        f += [(0, a, b), (1, b, a)]  # outward, counter-clockwise seen from outside
    return v, f


if __name__ == "__main__":
    write("hips.obj", *hips(), "a body of revolution widening at the hips (bench/user_scenes/make_meshes.py)")
    write("skirt.obj", *skirt(), "an open cone of cloth, a skirt (bench/user_scenes/make_meshes.py)")
    write("paddle.obj", *paddle(0.8, 0.05, 0.3), "a closed box 0.8 x 0.05 x 0.3 m (bench/user_scenes/make_meshes.py)")
    write("irregular_cloth.obj", *irregular_cloth(), "an irregular triangulation of a 1 m square (bench/user_scenes/make_meshes.py)")
    write("needle.obj", *needle(), "a closed cone 0.3 m tall, 0.01 m in radius at its base (bench/user_scenes/make_meshes.py)")
    write(os.path.join("extra", "blade.obj"), *paddle(0.002, 0.8, 0.3), "a closed box 0.002 x 0.8 x 0.3 m (bench/user_scenes/make_meshes.py)")
