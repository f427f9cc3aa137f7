#!/usr/bin/env python3
"""Exact analysis of one query of a CCD query file (the public CSV format): the Bernstein
coefficients of the coplanarity cubic d(t) in rational arithmetic, its roots on [0, 1]
isolated by exact subdivision and bisection, and the exact distance between the features at
each root and at t = 0 and t = 1. Used to settle, by hand, what a method reported on a query
(docs/benchmarks.md). Python's fractions only; slow (seconds a query) but exact.

    tools/exact_query.py FILE INDEX      (FILE under a folder named vertex-face or edge-edge)
"""
import sys
from fractions import Fraction as F

def read(path, index):
    rows = open(path).read().split('\n')[8*index:8*index+8]
    pts = []
    for r in rows:
        c = [int(x) for x in r.split(',')]
        pts.append([F(c[0], c[1]), F(c[2], c[3]), F(c[4], c[5])])
    return pts[:4], pts[4:]

sub = lambda a, b: [x - y for x, y in zip(a, b)]
add = lambda a, b: [x + y for x, y in zip(a, b)]
mul = lambda s, a: [s * x for x in a]
dot = lambda a, b: sum(x * y for x, y in zip(a, b))
cross = lambda a, b: [a[1]*b[2]-a[2]*b[1], a[2]*b[0]-a[0]*b[2], a[0]*b[1]-a[1]*b[0]]

def at(s, e, t): return [add(mul(1 - t, p), mul(t, q)) for p, q in zip(s, e)]

def d(s, e, t, vf):
    x = at(s, e, t)
    if vf: x = [x[1], x[2], x[3], x[0]]   # face0, face1, face2, vertex
    return dot(cross(sub(x[1], x[0]), sub(x[2], x[0])), sub(x[3], x[0]))

def bernstein(s, e, vf):
    # d is cubic: Bernstein coefficients from values at 0, 1/3, 2/3, 1
    v = [d(s, e, F(k, 3), vf) for k in range(4)]
    # power to Bernstein via solving: b0=v0, b3=v3, v(1/3)=(8b0+12b1+6b2+b3)/27, v(2/3)=(b0+6b1+12b2+8b3)/27
    b0, b3 = v[0], v[3]
    r1 = 27 * v[1] - 8 * b0 - b3   # 12 b1 + 6 b2
    r2 = 27 * v[2] - b0 - 8 * b3   # 6 b1 + 12 b2
    b1 = (2 * r1 - r2) / 18
    b2 = (2 * r2 - r1) / 18
    return [b0, b1, b2, b3]

def variations(b):
    signs = [1 if x > 0 else -1 for x in b if x != 0]
    return sum(1 for i in range(1, len(signs)) if signs[i] != signs[i-1])

def split(b):
    b01, b12, b23 = (b[0]+b[1])/2, (b[1]+b[2])/2, (b[2]+b[3])/2
    b012, b123 = (b01+b12)/2, (b12+b23)/2
    m = (b012+b123)/2
    return [b[0], b01, b012, m], [m, b123, b23, b[3]]

def roots(b, lo=F(0), hi=F(1), depth=0, out=None):
    out = [] if out is None else out
    v = variations(b)
    if depth == 0 and b[0] == 0: out.append((lo, lo))
    if depth == 0 and b[3] == 0: out.append((hi, hi))
    if v == 0: return out
    if v == 1 or depth > 60:
        out.append((lo, hi)); return out
    l, r = split(b); mid = (lo + hi) / 2
    roots(l, lo, mid, depth + 1, out)
    if r[0] == 0: out.append((mid, mid))  # a root exactly at the split
    roots(r, mid, hi, depth + 1, out)
    return out

def seg_seg_sq(p0, p1, q0, q1):
    # exact squared distance between segments (clamped closest points, Ericson 5.1.9)
    d1, d2, r = sub(p1, p0), sub(q1, q0), sub(p0, q0)
    a, e, f = dot(d1, d1), dot(d2, d2), dot(d2, r)
    c, b = dot(d1, r), dot(d1, d2)
    best = None
    # brute force over the candidate parameter pairs: interior critical point and the 4 edges
    cands = []
    den = a * e - b * b
    if den != 0:
        s = (b * f - c * e) / den; t = (a * f - b * c) / den
        cands.append((s, t))
    for s in (F(0), F(1)):
        t = (b * s + f) / e if e else F(0); cands.append((s, min(max(t, F(0)), F(1))))
    for t in (F(0), F(1)):
        s = (b * t - c) / a if a else F(0); cands.append((min(max(s, F(0)), F(1)), t))
    for s, t in cands:
        if not (0 <= s <= 1 and 0 <= t <= 1): continue
        w = sub(add(p0, mul(s, d1)), add(q0, mul(t, d2)))
        val = dot(w, w)
        best = val if best is None or val < best else best
    return best

def point_tri_sq(p, a, b, c):
    # exact: the minimum of the interior projection (if inside) and the three edge distances
    n = cross(sub(b, a), sub(c, a))
    best = min(seg_seg_sq(p, p, a, b), seg_seg_sq(p, p, b, c), seg_seg_sq(p, p, c, a))
    nn = dot(n, n)
    if nn:
        dist = dot(sub(p, a), n)
        q = sub(p, mul(dist / nn, n))
        # barycentric sign test
        ok = all(dot(cross(sub(y, x), sub(q, x)), n) >= 0 for x, y in ((a, b), (b, c), (c, a)))
        if ok: best = min(best, dist * dist / nn)
    return best

def dist_sq(s, e, t, vf):
    x = at(s, e, t)
    return point_tri_sq(x[0], x[1], x[2], x[3]) if vf else seg_seg_sq(x[0], x[1], x[2], x[3])

if len(sys.argv) != 3:
    sys.exit('usage: exact_query.py FILE INDEX')
path, index = sys.argv[1], int(sys.argv[2])
import os
kinds = [part for part in os.path.abspath(path).split(os.sep)[:-1] if part in ('vertex-face', 'edge-edge')]
if not kinds:
    sys.exit(path + ': no parent folder is named vertex-face or edge-edge')
vf = kinds[-1] == 'vertex-face'
s, e = read(path, index)
b = bernstein(s, e, vf)
print('bernstein', [float(x) for x in b])
for lo, hi in roots(b):
    # refine a V=1 interval by exact bisection to width 2^-50
    f = lambda t: d(s, e, t, vf)
    while hi - lo > F(1, 2**50) and f(lo) * f(hi) < 0:
        mid = (lo + hi) / 2
        if f(lo) * f(mid) <= 0: hi = mid
        else: lo = mid
    print('root in [%.17g, %.17g]: distance at ends %.3e %.3e' % (float(lo), float(hi), float(dist_sq(s, e, lo, vf)) ** 0.5, float(dist_sq(s, e, hi, vf)) ** 0.5))
print('distance at t=0 %.3e, at t=1 %.3e' % (float(dist_sq(s, e, F(0), vf)) ** 0.5, float(dist_sq(s, e, F(1), vf)) ** 0.5))
