#!/usr/bin/env python3
"""Writes the obstacle meshes the shipped scenes use (scenes/meshes/*.obj). Run once; the
files are committed. icosphere.obj: a unit sphere, an icosahedron subdivided 3 times (1,280
triangles). box.obj: a unit cube centred on the origin, each face a 4x4 grid (192 triangles).
disc_30cm.obj: the Cusick drape test's specimen, a 30 cm disc in z = 0 of 25 concentric rings
(ring k holds 6k vertices, 6 mm apart: 1,951 vertices, 3,750 triangles), the mesh a user brings;
disc_30cm_12mm.obj and disc_30cm_3mm.obj the same disc of 12 rings 12.5 mm apart (469 vertices) and 50
rings 3 mm apart (7,651 vertices), for bench/textile_runs.sh; disc_30cm_grid_12mm.obj,
disc_30cm_grid.obj and disc_30cm_grid_3mm.obj the disc cut from a square grid 12.5, 6.25 and
3.125 mm apart (441, 1,793 and 7,213 vertices; grid_disc), for bench/textile_runs.sh;
disc_30cm_cells_12mm.obj, disc_30cm_cells.obj and disc_30cm_cells_3mm.obj the disc of whole half
cells of those grids (489, 1,877 and 7,377 vertices; cell_disc), for bench/textile_runs.sh, and
disc_30cm_cells_12mm_turned30.obj and disc_30cm_cells_turned30.obj the first two turned by 30
degrees about their axis (a cloth's warp is its x axis: their edges no longer follow it; the
membrane's locking in docs/materials.md).
cusick_support.obj: an 18 cm disc support, a closed cylinder of radius 0.09 m and height 0.3 m
standing on z = 0 (64 segments around); cusick_clamp.obj: the top 18 cm disc that clamps the
specimen onto it, a closed cylinder of radius 0.09 m and height 0.02 m on z = 0, which the scene
lifts to two thicknesses above the support. table.obj: a table, a top 1.2 x 0.8 x 0.04 m at 0.75 m and
four legs 0.05 x 0.05 m under it, each a separate closed box of 4x4 quads a face (the table-like
mesh obstacle of issue 19's tablecloth)."""
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

def disc(radius, rings):
    vertices, faces = [(0.0, 0.0, 0.0)], []
    first = [0]  # index of each ring's first vertex
    for k in range(1, rings + 1):
        first.append(len(vertices))
        r = radius * k / rings
        for i in range(6 * k):
            a = 2 * math.pi * i / (6 * k)
            vertices.append((r * math.cos(a), r * math.sin(a), 0.0))
    def at(k, i):  # vertex i (mod 6k) of ring k
        return 0 if k == 0 else first[k] + i % (6 * k)
    for j in range(6):  # the centre's fan
        faces.append((0, at(1, j), at(1, j + 1)))
    for k in range(2, rings + 1):
        # Ring k-1 (6(k-1) vertices) to ring k (6k): walk both rings by angle, counter-clockwise.
        i = j = 0
        n_in, n_out = 6 * (k - 1), 6 * k
        while i < n_in or j < n_out:
            # advance on the ring whose next vertex comes first in angle
            if j < n_out and (i >= n_in or (j + 1) / n_out <= (i + 1) / n_in):
                faces.append((at(k - 1, i), at(k, j), at(k, j + 1)))
                j += 1
            else:
                faces.append((at(k - 1, i), at(k, j), at(k - 1, i + 1)))
                i += 1
    return vertices, faces

def grid_disc(radius, spacing):
    """A disc cut from a square grid (spacing apart, on the axes) as a fabric is cut from its
    warp and weft: the grid's vertices inside the circle, each cell's two triangles where all
    three corners are kept (diagonals mirrored between quadrants, so the disc is symmetric about
    both axes), then the rim's vertices (those on an edge of one triangle) moved out along their
    radius onto the circle. Inside the rim every triangle is a right triangle of the grid, whose
    edge springs hold the fabric's tension and shear exactly (docs/materials.md)."""
    n = int(math.ceil(radius / spacing)) + 1
    index, vertices = {}, []
    for j in range(-n, n + 1):
        for i in range(-n, n + 1):
            if math.hypot(i, j) * spacing <= radius * (1 + 1e-9):
                index[i, j] = len(vertices)
                vertices.append([i * spacing, j * spacing, 0.0])
    faces = []
    for j in range(-n, n):
        for i in range(-n, n):
            a, b, c, d = (i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)
            cell = [(a, b, c), (a, c, d)] if (i >= 0) == (j >= 0) else [(a, b, d), (b, c, d)]
            faces += [tuple(index[v] for v in t) for t in cell if all(v in index for v in t)]
    uses = {}
    for t in faces:
        for k in range(3):
            edge = tuple(sorted((t[k], t[(k + 1) % 3])))
            uses[edge] = uses.get(edge, 0) + 1
    for v in {v for edge, count in uses.items() if count == 1 for v in edge}:
        x, y, _ = vertices[v]
        r = math.hypot(x, y)
        vertices[v][:2] = [x * radius / r, y * radius / r]
    for a, b, c in faces:  # none folded over or flattened by the move
        (ax, ay, _), (bx, by, _), (cx, cy, _) = vertices[a], vertices[b], vertices[c]
        assert (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) > 0.1 * spacing * spacing
    return [tuple(v) for v in vertices], faces

def cell_disc(radius, spacing):
    """A disc of whole half cells of a square grid (spacing apart, on the axes): the grid's
    vertices within a cut radius, each cell's two triangles where all three corners are kept,
    no vertex moved. Each cell's diagonal runs along the circles about the centre (from
    (i + 1, j) to (i, j + 1) where the cell's centre has x y > 0, the other way elsewhere), so
    the rim is a chain of the grid's edges and diagonals, within about half a cell of the
    circle. The cut radius is the one (of 401 between radius - spacing and radius + spacing)
    whose disc's area is nearest pi radius^2. Every triangle, the rim's too, is a right
    triangle of the grid with its legs along the warp and weft, whose edge springs hold the
    fabric's tension and shear exactly (docs/materials.md)."""
    n = int(math.ceil(radius / spacing)) + 2
    def cut_at(cut):
        index, vertices = {}, []
        for j in range(-n, n + 1):
            for i in range(-n, n + 1):
                if math.hypot(i, j) * spacing <= cut:
                    index[i, j] = len(vertices)
                    vertices.append((i * spacing, j * spacing, 0.0))
        faces = []
        for j in range(-n, n):
            for i in range(-n, n):
                a, b, c, d = (i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)
                cell = [(a, b, d), (b, c, d)] if (2 * i + 1 > 0) == (2 * j + 1 > 0) else [(a, b, c), (a, c, d)]
                faces += [tuple(index[v] for v in t) for t in cell if all(v in index for v in t)]
        used = sorted({v for t in faces for v in t})  # no vertex left without a triangle
        renumber = {v: k for k, v in enumerate(used)}
        return [vertices[v] for v in used], [tuple(renumber[v] for v in t) for t in faces]
    def area(mesh):
        v, faces = mesh
        return sum(0.5 * ((v[b][0] - v[a][0]) * (v[c][1] - v[a][1]) - (v[b][1] - v[a][1]) * (v[c][0] - v[a][0]))
                   for a, b, c in faces)
    goal = math.pi * radius * radius
    vertices, faces = min((cut_at(radius + spacing * (k / 200 - 1)) for k in range(401)),
                          key=lambda mesh: abs(area(mesh) - goal))
    uses = {}
    for t in faces:
        for k in range(3):
            edge = tuple(sorted((t[k], t[(k + 1) % 3])))
            uses[edge] = uses.get(edge, 0) + 1
    rim = {}
    for edge, count in uses.items():
        assert count <= 2
        for v in edge if count == 1 else ():
            rim[v] = rim.get(v, 0) + 1
    assert all(count == 2 for count in rim.values()), "a rim vertex where two parts of the disc meet"
    return vertices, faces

def cylinder(radius, height, segments, cap_rings):
    vertices, faces = [], []
    def ring(z, r):
        start = len(vertices)
        for i in range(segments):
            a = 2 * math.pi * i / segments
            vertices.append((r * math.cos(a), r * math.sin(a), z))
        return start
    bottom, top = ring(0.0, radius), ring(height, radius)
    for i in range(segments):
        j = (i + 1) % segments
        faces += [(bottom + i, bottom + j, top + j), (bottom + i, top + j, top + i)]  # outward
    for z, up in ((height, True), (0.0, False)):
        outer = top if up else bottom
        for k in range(cap_rings - 1, 0, -1):
            inner = ring(z, radius * k / cap_rings)
            for i in range(segments):
                j = (i + 1) % segments
                quad = [(outer + i, outer + j, inner + j), (outer + i, inner + j, inner + i)]
                faces += quad if up else [(a, c, b) for a, b, c in quad]
            outer = inner
        centre = len(vertices)
        vertices.append((0.0, 0.0, z))
        for i in range(segments):
            j = (i + 1) % segments
            faces.append((outer + i, outer + j, centre) if up else (outer + j, outer + i, centre))
    return vertices, faces

def boxes(parts, n):
    """Closed boxes, each (centre, size), in one mesh."""
    unit_v, unit_f = box(n)
    vertices, faces = [], []
    for centre, size in parts:
        first = len(vertices)
        vertices += [tuple(c + s * x for c, s, x in zip(centre, size, p)) for p in unit_v]
        faces += [(a + first, b + first, c + first) for a, b, c in unit_f]
    return vertices, faces

def table():
    top = ((0.0, 0.0, 0.73), (1.2, 0.8, 0.04))
    legs = [((x * 0.55, y * 0.35, 0.355), (0.05, 0.05, 0.71)) for x in (-1, 1) for y in (-1, 1)]
    return boxes([top] + legs, 4)

if __name__ == "__main__":  # bench/user_scenes/make_meshes.py imports write
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "meshes")
    os.makedirs(here, exist_ok=True)
    write(os.path.join(here, "icosphere.obj"), *icosphere(3), "unit icosphere, 3 subdivisions (tools/make_meshes.py)")
    write(os.path.join(here, "box.obj"), *box(4), "unit cube, 4x4 quads a face (tools/make_meshes.py)")
    write(os.path.join(here, "disc_30cm.obj"), *disc(0.15, 25), "30 cm disc, 25 rings 6 mm apart (tools/make_meshes.py)")
    write(os.path.join(here, "disc_30cm_12mm.obj"), *disc(0.15, 12), "30 cm disc, 12 rings 12.5 mm apart (tools/make_meshes.py)")
    write(os.path.join(here, "disc_30cm_3mm.obj"), *disc(0.15, 50), "30 cm disc, 50 rings 3 mm apart (tools/make_meshes.py)")
    for name, spacing in (("disc_30cm_grid_12mm.obj", 0.0125), ("disc_30cm_grid.obj", 0.00625),
                          ("disc_30cm_grid_3mm.obj", 0.003125)):
        write(os.path.join(here, name), *grid_disc(0.15, spacing),
              "30 cm disc cut from a square grid %g mm apart (tools/make_meshes.py)" % (spacing * 1000))
    for name, spacing in (("disc_30cm_cells_12mm.obj", 0.0125), ("disc_30cm_cells.obj", 0.00625),
                          ("disc_30cm_cells_3mm.obj", 0.003125)):
        write(os.path.join(here, name), *cell_disc(0.15, spacing),
              "30 cm disc of a square grid's half cells %g mm apart (tools/make_meshes.py)" % (spacing * 1000))
    for name, spacing in (("disc_30cm_cells_12mm_turned30.obj", 0.0125), ("disc_30cm_cells_turned30.obj", 0.00625)):
        vertices, faces = cell_disc(0.15, spacing)
        c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
        write(os.path.join(here, name), [(c * x - s * y, s * x + c * y, z) for x, y, z in vertices], faces,
              "30 cm disc of a square grid's half cells %g mm apart turned 30 degrees (tools/make_meshes.py)" % (spacing * 1000))
    write(os.path.join(here, "cusick_support.obj"), *cylinder(0.09, 0.3, 64, 4),
          "18 cm support: cylinder r 0.09 m, h 0.3 m on z = 0 (tools/make_meshes.py)")
    write(os.path.join(here, "cusick_clamp.obj"), *cylinder(0.09, 0.02, 64, 4),
          "18 cm clamp disc: cylinder r 0.09 m, h 0.02 m on z = 0 (tools/make_meshes.py)")
    write(os.path.join(here, "table.obj"), *table(),
          "table: top 1.2 x 0.8 x 0.04 m at 0.75 m, four 0.05 m legs, separate boxes (tools/make_meshes.py)")
