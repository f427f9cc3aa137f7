#!/usr/bin/env python3
"""Writes the obstacle meshes the shipped scenes use (scenes/meshes/*.obj). Run once; the
files are committed. icosphere.obj: a unit sphere, an icosahedron subdivided 3 times (1,280
triangles). box.obj: a unit cube centred on the origin, each face a 4x4 grid (192 triangles)."""
import math, os

def write(path, vertices, faces, comment):
    with open(path, "w") as f:
        f.write(f"# {comment}\n")
        for v in vertices:
            f.write("v %.9f %.9f %.9f\n" % v)
        for a, b, c in faces:
            f.write(f"f {a + 1} {b + 1} {c + 1}\n")

def icosphere(levels):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    for _ in range(levels):
        cache, nf = {}, []
        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                p = [(v[a][k] + v[b][k]) / 2 for k in range(3)]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                cache[key] = len(v) - 1
            return cache[key]
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return v, f

def box(n):
    vertices, faces, index = [], [], {}
    def vid(p):
        key = tuple(round(x, 9) for x in p)
        if key not in index:
            index[key] = len(vertices)
            vertices.append(key)
        return index[key]
    for axis in range(3):
        for side in (-0.5, 0.5):
            u, w = [a for a in range(3) if a != axis]
            for i in range(n):
                for j in range(n):
                    quad = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0.0, 0.0, 0.0]
                        p[axis], p[u], p[w] = side, -0.5 + (i + di) / n, -0.5 + (j + dj) / n
                        quad.append(vid(p))
                    a, b, c, d = quad
                    # Outward orientation: flip on the negative side.
                    if (side > 0) == (axis != 1):
                        faces += [(a, b, c), (a, c, d)]
                    else:
                        faces += [(a, c, b), (a, d, c)]
    return vertices, faces

here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "meshes")
os.makedirs(here, exist_ok=True)
write(os.path.join(here, "icosphere.obj"), *icosphere(3), "unit icosphere, 3 subdivisions (tools/make_meshes.py)")
write(os.path.join(here, "box.obj"), *box(4), "unit cube, 4x4 quads a face (tools/make_meshes.py)")
