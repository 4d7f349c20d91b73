# SPDX-License-Identifier: AGPL-3.0-or-later
"""The canonical Delaunay tetrahedralization of spec/delaunay.md, written
from that chapter alone (Python 3 standard library, exact integers).

    tetrahedralize(points) -> (tets, nbr)

points: distinct grid points in canonical order (the index of a point is
its position). tets: the canonical list of delaunay.md section 5, each
(t0, t1, t2, t3) with t0 < t1 its two smallest indices and
orient3d(t0, t1, t2, t3) > 0, sorted. nbr[i][k]: the tetrahedron number
across local face k of tets[i] (the face opposite t_k), or -1 on the hull.

Algorithm: incremental Bowyer-Watson with a symbolic vertex at infinity
(ghost tetrahedra on the hull faces), the perturbed in-sphere test of
section 3.2, and the hull rule of section 4.1: a hull face joins the
cavity when the new point sees it strictly from outside, or when the point
is coplanar with it and the real tetrahedron behind it joins the cavity.
"""
import random

INF = -1

# local face k (opposite vertex k), oriented outward: delaunay.md section 5
FACES = ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))


def orient3d(a, b, c, d):
    ux, uy, uz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    vx, vy, vz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    wx, wy, wz = d[0] - a[0], d[1] - a[1], d[2] - a[2]
    return ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx)


def insphere(a, b, c, d, e):
    """delaunay.md section 2: positive when e is strictly inside the sphere
    of the positively oriented (a, b, c, d)."""
    ax, ay, az = a
    rows = []
    for p in (b, c, d, e):
        x, y, z = p[0] - ax, p[1] - ay, p[2] - az
        rows.append((x, y, z, x * x + y * y + z * z))
    (ux, uy, uz, ul), (vx, vy, vz, vl), (wx, wy, wz, wl), (tx, ty, tz, tl) = rows
    # 2x2 minors of the first two rows (columns x, y, z, l)
    m01 = ux * vy - uy * vx
    m02 = ux * vz - uz * vx
    m03 = ux * vl - ul * vx
    m12 = uy * vz - uz * vy
    m13 = uy * vl - ul * vy
    m23 = uz * vl - ul * vz
    # 2x2 minors of the last two rows
    n01 = wx * ty - wy * tx
    n02 = wx * tz - wz * tx
    n03 = wx * tl - wl * tx
    n12 = wy * tz - wz * ty
    n13 = wy * tl - wl * ty
    n23 = wz * tl - wl * tz
    det = m01 * n23 - m02 * n13 + m03 * n12 + m12 * n03 - m13 * n02 + m23 * n01
    return -det


def insphere_eps(P, q):
    """delaunay.md section 3.2: the sign of the perturbed in-sphere test of
    the five indices q (points P[q[r]])."""
    pts = [P[i] for i in q]
    s = insphere(*pts)
    if s:
        return 1 if s > 0 else -1
    for r in sorted(range(5), key=lambda r: q[r]):
        rest = pts[:r] + pts[r + 1:]
        o = orient3d(*rest)
        if o:
            o = o if r % 2 == 0 else -o
            return 1 if o > 0 else -1
    return 0


def _ghost_norm(t):
    """An even permutation of t putting INF last (orientation kept)."""
    i = t.index(INF)
    if i == 3:
        return t
    t = list(t)
    t[i], t[3] = t[3], t[i]
    o = [j for j in range(3) if j != i] + [i]
    # swap two of the positions 0..2 to make the permutation even again
    a, b = (0, 1) if i != 0 and i != 1 else ((1, 2) if i == 0 else (0, 2))
    t[a], t[b] = t[b], t[a]
    return tuple(t)


class _DT:
    def __init__(self, P):
        self.P = P
        self.V = []      # tetrahedra (4-tuples of indices, INF last for ghosts), None when deleted
        self.N = []      # neighbours: 4 slots
        self.free = []

    def new(self, v):
        if self.free:
            i = self.free.pop()
            self.V[i] = v
            self.N[i] = [-1, -1, -1, -1]
        else:
            i = len(self.V)
            self.V.append(v)
            self.N.append([-1, -1, -1, -1])
        return i

    def conflict(self, t, p, cache):
        r = cache.get(t)
        if r is not None:
            return r
        v = self.V[t]
        P = self.P
        if v[3] != INF:
            r = insphere_eps(P, (v[0], v[1], v[2], v[3], p)) > 0
        else:
            # ghost on the hull face (v0, v2, v1) seen from the real side, i.e.
            # the hull face oriented outward is (v0, v1, v2)
            o = orient3d(P[v[0]], P[v[1]], P[v[2]], P[p])
            if o > 0:
                r = True
            elif o < 0:
                r = False
            else:
                r = self.conflict(self.N[t][3], p, cache)
        cache[t] = r
        return r

    def locate(self, start, p, rng):
        P = self.P
        pp = P[p]
        t = start
        prev = -1
        steps = 0
        while True:
            v = self.V[t]
            if v[3] == INF:
                return t
            order = [0, 1, 2, 3]
            rng.shuffle(order)
            moved = False
            for k in order:
                nb = self.N[t][k]
                if nb == prev:
                    continue
                f = FACES[k]
                if orient3d(P[v[f[0]]], P[v[f[1]]], P[v[f[2]]], pp) > 0:
                    prev, t = t, nb
                    moved = True
                    break
            if not moved:
                # check the face we came through too
                if prev != -1:
                    k = self.N[t].index(prev)
                    f = FACES[k]
                    if orient3d(P[v[f[0]]], P[v[f[1]]], P[v[f[2]]], pp) > 0:
                        prev, t = t, prev
                        continue
                return t
            steps += 1
            if steps > 100000:
                raise RuntimeError("walk does not end")

    def insert(self, p, start, rng):
        t0 = self.locate(start, p, rng)
        cache = {}
        if not self.conflict(t0, p, cache):
            raise RuntimeError("located tetrahedron not in conflict")
        cavity = {t0}
        stack = [t0]
        boundary = []  # (tet in cavity, local face k, outside neighbour)
        while stack:
            t = stack.pop()
            for k in range(4):
                nb = self.N[t][k]
                if nb in cavity:
                    continue
                if self.conflict(nb, p, cache):
                    cavity.add(nb)
                    stack.append(nb)
        for t in cavity:
            for k in range(4):
                nb = self.N[t][k]
                if nb not in cavity:
                    boundary.append((t, k, nb))
        P = self.P
        edges = {}
        made = []
        for t, k, nb in boundary:
            v = self.V[t]
            f = FACES[k]
            a, b, c = v[f[0]], v[f[1]], v[f[2]]
            # face (a, b, c) is outward from t; p is on t's side
            nt = (a, c, b, p)
            if INF in nt:
                nt = _ghost_norm(nt)
            else:
                if orient3d(P[a], P[c], P[b], P[p]) <= 0:
                    raise RuntimeError("cavity not star-shaped")
            i = self.new(nt)
            made.append(i)
            # the face of the new tetrahedron opposite p is (a, c, b): find its slot
            j = nt.index(p)
            self.N[i][j] = nb
            kk = self.N[nb].index(t)
            self.N[nb][kk] = i
        for t in cavity:
            self.V[t] = None
            self.free.append(t)
        for i in made:
            v = self.V[i]
            j = v.index(p)
            for k in range(4):
                if k == j:
                    continue
                key = tuple(sorted(v[m] for m in range(4) if m != k and m != j))
                other = edges.pop(key, None)
                if other is None:
                    edges[key] = (i, k)
                else:
                    oi, ok = other
                    self.N[i][k] = oi
                    self.N[oi][ok] = i
        if edges:
            raise RuntimeError("cavity boundary not closed")
        return made[0]


def tetrahedralize(P, seed=1):
    n = len(P)
    if n < 4:
        return [], []
    # an initial tetrahedron: p0, then the first points that are not equal,
    # collinear, coplanar
    i0 = 0
    i1 = 1
    i2 = None
    a, b = P[i0], P[i1]
    u = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
    for i in range(2, n):
        w = (P[i][0] - a[0], P[i][1] - a[1], P[i][2] - a[2])
        cr = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
        if cr != (0, 0, 0):
            i2 = i
            break
    if i2 is None:
        return [], []
    i3 = None
    for i in range(i2 + 1, n):
        if orient3d(P[i0], P[i1], P[i2], P[i]) != 0:
            i3 = i
            break
    if i3 is None:
        return [], []
    dt = _DT(P)
    if orient3d(P[i0], P[i1], P[i2], P[i3]) < 0:
        i1, i2 = i2, i1
    t = dt.new((i0, i1, i2, i3))
    ghosts = []
    for k in range(4):
        f = FACES[k]
        v = (i0, i1, i2, i3)
        a, b, c = v[f[0]], v[f[1]], v[f[2]]  # outward
        g = dt.new((a, b, c, INF))  # INF on the positive side of (a, b, c)
        dt.N[t][k] = g
        dt.N[g][3] = t
        ghosts.append(g)
    # ghost-ghost adjacency by shared edges
    edges = {}
    for g in ghosts:
        v = dt.V[g]
        for k in range(3):
            key = tuple(sorted(v[m] for m in range(3) if m != k))
            other = edges.pop(key, None)
            if other is None:
                edges[key] = (g, k)
            else:
                dt.N[g][k] = other[0]
                dt.N[other[0]][other[1]] = g
    rng = random.Random(seed)
    rest = [i for i in range(n) if i not in (i0, i1, i2, i3)]
    rng.shuffle(rest)
    last = t
    for p in rest:
        last = dt.insert(p, last, rng)
        if dt.V[last][3] == INF:
            # start walks from a real tetrahedron
            nb = dt.N[last][3]
            last = nb if dt.V[nb] is not None and dt.V[nb][3] != INF else last
    return canonical(dt)


def canonical(dt):
    P = dt.P
    real = [i for i, v in enumerate(dt.V) if v is not None and v[3] != INF]
    forms = {}
    for i in real:
        v = sorted(dt.V[i])
        t0, t1, t2, t3 = v
        if orient3d(P[t0], P[t1], P[t2], P[t3]) < 0:
            t2, t3 = t3, t2
        forms[i] = (t0, t1, t2, t3)
    order = sorted(real, key=lambda i: forms[i])
    num = {old: k for k, old in enumerate(order)}
    tets = [forms[i] for i in order]
    nbr = []
    for i in order:
        v = dt.V[i]
        row = [-1] * 4
        ct = forms[i]
        for k in range(4):
            nb = dt.N[i][k]
            opp = v[k]
            kk = ct.index(opp)
            row[kk] = num.get(nb, -1)
        nbr.append(row)
    return tets, nbr


def check(P, tets, nbr):
    """delaunay.md section 6 (partly): orientation, adjacency, local Delaunay."""
    for i, t in enumerate(tets):
        assert orient3d(*(P[j] for j in t)) > 0
        for k in range(4):
            j = nbr[i][k]
            if j < 0:
                continue
            u = tets[j]
            e = [x for x in u if x not in t]
            assert len(e) == 1
            assert nbr[j][u.index(e[0])] == i
            assert insphere_eps(P, (t[0], t[1], t[2], t[3], e[0])) < 0, (t, e)
    used = set(x for t in tets for x in t)
    assert len(used) == len(P) or not tets


if __name__ == "__main__":
    import sys
    cube = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    tets, nbr = tetrahedralize(cube)
    print(tets)
    assert tets == [(0, 1, 5, 7), (0, 1, 7, 3), (0, 2, 3, 7), (0, 2, 7, 6), (0, 4, 6, 7), (0, 4, 7, 5)]
    check(cube, tets, nbr)
    rng = random.Random(5)
    for trial in range(30):
        m = rng.choice([3, 4, 5])
        pts = sorted(set((rng.randrange(m), rng.randrange(m), rng.randrange(m)) for _ in range(rng.randrange(5, 60))))
        res = None
        for seed in range(3):
            tets, nbr = tetrahedralize(pts, seed)
            check(pts, tets, nbr)
            if res is not None:
                assert res == tets
            res = tets
    print("ok")
