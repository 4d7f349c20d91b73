#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Tests of conformance/refdelaunay.py against the definition of
spec/delaunay.md section 3.4 evaluated by brute force: every 4-subset of
the points with orient3d != 0 whose perturbed circumsphere has every other
point strictly outside. Small random sets, lattices (cospherical and
coplanar everywhere), integer points on a sphere, sets whose first points
are collinear or coplanar, all-coplanar sets (empty output). Also checks
that the result does not depend on the insertion order (seed).

    python3 conformance/test_refdelaunay.py [--quick]
"""
import itertools
import os
import random
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import refdelaunay as rd  # noqa: E402


def brute(P):
    n = len(P)
    out = []
    for q in itertools.combinations(range(n), 4):
        a, b, c, d = q
        o = rd.orient3d(P[a], P[b], P[c], P[d])
        if o == 0:
            continue
        t = (a, b, c, d) if o > 0 else (a, b, d, c)
        if all(rd.insphere_eps(P, t + (e,)) < 0 for e in range(n) if e not in q):
            out.append(t)
    return sorted(out)


def check_volume(P, tets):
    """Total volume equals the hull volume (computed from the tets' hull
    faces would be circular; instead: every point of P is in some
    tetrahedron's closure, and no two tetrahedra overlap is implied by
    the brute-force equality)."""
    return True


def sphere_points(r2, lim):
    pts = []
    for x in range(-lim, lim + 1):
        for y in range(-lim, lim + 1):
            for z in range(-lim, lim + 1):
                if x * x + y * y + z * z == r2:
                    pts.append((x + lim, y + lim, z + lim))
    return sorted(pts)


def cases(rng, quick):
    yield "cube", sorted((x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1))
    yield "lattice3", sorted((x, y, z) for x in range(3) for y in range(3) for z in range(3))
    yield "lattice2x2x4", sorted((x, y, z) for x in range(2) for y in range(2) for z in range(4))
    yield "sphere25", sphere_points(25, 5)
    yield "sphere9", sphere_points(9, 3)
    yield "sphere3", sphere_points(3, 1)
    yield "octahedron", sorted([(1, 1, 0), (1, 1, 2), (0, 1, 1), (2, 1, 1), (1, 0, 1), (1, 2, 1)])
    yield "collinear-first", sorted([(0, 0, 0), (0, 0, 1), (0, 0, 2), (0, 0, 3), (0, 1, 0), (1, 0, 0), (1, 1, 1)])
    yield "coplanar-first", sorted([(0, 0, 0), (0, 0, 1), (0, 1, 0), (0, 1, 1), (0, 2, 2), (0, 2, 0), (3, 1, 1)])
    yield "all-coplanar", sorted([(0, 0, 0), (0, 0, 1), (0, 1, 0), (0, 1, 1), (0, 2, 2)])
    yield "all-collinear", [(0, 0, i) for i in range(6)]
    yield "three", [(0, 0, 0), (0, 0, 1), (1, 0, 0)]
    yield "four", [(0, 0, 0), (0, 0, 1), (0, 1, 0), (1, 0, 0)]
    yield "plane-plus-one", sorted([(x, y, 0) for x in range(4) for y in range(3)] + [(1, 1, 2)])
    yield "two-planes", sorted([(x, y, 0) for x in range(3) for y in range(3)] + [(x, y, 2) for x in range(3) for y in range(3)])
    yield "skew-lines", sorted([(i, 0, 0) for i in range(6)] + [(0, i, 3) for i in range(6)])
    n_random = 40 if quick else 200
    for trial in range(n_random):
        m = rng.choice([2, 3, 4, 5, 8, 1000])
        k = rng.randrange(4, 16 if m > 5 else 22)
        pts = sorted(set((rng.randrange(m), rng.randrange(m), rng.randrange(m)) for _ in range(k)))
        yield "random-%d-m%d" % (trial, m), pts
    for trial in range(10 if quick else 40):
        # a sheet: points on z = 0 plus a few above, the hull has big coplanar facets
        pts = set((rng.randrange(5), rng.randrange(5), 0) for _ in range(10))
        pts |= set((rng.randrange(5), rng.randrange(5), rng.randrange(1, 3)) for _ in range(3))
        yield "sheet-%d" % trial, sorted(pts)


def main():
    quick = "--quick" in sys.argv
    rng = random.Random(12345)
    bad = 0
    count = 0
    t0 = time.time()
    for name, P in cases(rng, quick):
        count += 1
        want = brute(P)
        for seed in (1, 2, 7):
            tets, nbr = rd.tetrahedralize(P, seed)
            if tets != want:
                bad += 1
                print("MISMATCH %s seed %d: %d tets, brute force %d" % (name, seed, len(tets), len(want)))
                print("  points", P)
                break
            if tets:
                rd.check(P, tets, nbr)
    # larger sets: no brute force, but the local check and order independence
    for name, P in (("lattice5", sorted((x, y, z) for x in range(5) for y in range(5) for z in range(5))),
                    ("lattice-6x6x3", sorted((x, y, z) for x in range(6) for y in range(6) for z in range(3))),
                    ("random-500", sorted(set((rng.randrange(64), rng.randrange(64), rng.randrange(64)) for _ in range(500))))):
        count += 1
        res = None
        for seed in (1, 2):
            tets, nbr = rd.tetrahedralize(P, seed)
            rd.check(P, tets, nbr)
            if res is not None and res != tets:
                bad += 1
                print("ORDER DEPENDENT %s" % name)
            res = tets
    print("%d point sets, %d mismatches, %.1f s" % (count, bad, time.time() - t0))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
