# SPDX-License-Identifier: AGPL-3.0-or-later
"""Reconstruction of spec/hmc.md section 11, written from the spec alone
(Python 3 standard library, exact integers): the second decoder's
connectivity, used by conformance/refdec.py.

    resolve_border(rc, points, coarser) -> (B, state)
    reconstruct(kind, points, rc, B) -> simplices

rc is the dict parse_rcon() of refdec.py returns; B the level's border set
(section 10, a set of indices); coarser the state returned for the
previous level (None at the coarsest). reconstruct() returns the level's
output of section 11.6: triangles (kind 1) oriented outward with their
smallest index first, sorted, or tetrahedra (kind 2) in canonical form and
order. It raises refdec's DecodeError("bad_layer") for the checks of
sections 10 and 11.5 that need the tetrahedralization.

Setting the environment variable HMC_RECON_STATS to a file name appends,
per level, one JSON line saying which steps of section 11 changed
anything (the coverage table of conformance/IMPLEMENTERS.md).
"""
import json
import os

import refdelaunay

# local face k of (v0, v1, v2, v3): the face opposite v_k, oriented outward
FACES = ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1))


class ReconError(Exception):
    def __init__(self, cls, msg):
        Exception.__init__(self, msg)
        self.cls = cls
        self.msg = msg


def d2(a, b):
    x, y, z = a[0] - b[0], a[1] - b[1], a[2] - b[2]
    return x * x + y * y + z * z


def tri_nd(p, q, r):
    """Section 11.4: N = d2(q, r) d2(r, p) d2(p, q), D = |(q - p) x (r - p)|^2."""
    ux, uy, uz = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    vx, vy, vz = r[0] - p[0], r[1] - p[1], r[2] - p[2]
    cx, cy, cz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    return d2(q, r) * d2(r, p) * d2(p, q), cx * cx + cy * cy + cz * cz


def r2_less(x, y):
    """R^2(x) < R^2(y) for x, y = (N, D); D = 0 is an infinite radius."""
    nx, dx = x
    ny, dy = y
    if dx == 0:
        return False
    if dy == 0:
        return True
    return nx * dy < ny * dx


def resolve_border(rc, points, coarser):
    """Section 10, border set: returns (B as a set of indices of this level,
    the state the next finer level needs)."""
    listed = set(rc["border_list"])
    if rc["inherit_border"]:
        prev = coarser if coarser is not None else set()
        index = {p: i for i, p in enumerate(points)}
        inherited = set(index[p] for p in prev)
        B = inherited ^ listed
    else:
        B = listed
    return B, set(points[i] for i in B)


class Level:
    BUBBLE_MAX = 4     # section 11.4a: bubbles of at most 4 tetrahedra
    REPAIR_ROUNDS = 6  # section 11.4a: rounds 0 ... 5

    def __init__(self, kind, P, rc, B):
        self.kind = kind
        self.P = P
        self.rc = rc
        self.B = B
        self.stats = {}

    # ------------------------------------------------------------ topology
    def build(self):
        P = self.P
        tets, nbr = refdelaunay.tetrahedralize(P)
        self.tets, self.nbr = tets, nbr
        M = len(tets)
        # face ids: fid[t][k]; faces[f] = (vertex triple of the lower tet's
        # local face, tet, k)
        fid = [[-1] * 4 for _ in range(M)]
        faces = []
        for t in range(M):
            v = tets[t]
            for k in range(4):
                if fid[t][k] >= 0:
                    continue
                f = len(faces)
                a, b, c = FACES[k]
                faces.append((v[a], v[b], v[c]))
                fid[t][k] = f
                u = nbr[t][k]
                if u >= 0:
                    kk = nbr[u].index(t)
                    fid[u][kk] = f
        self.fid, self.faces = fid, faces
        self.hull = [False] * len(faces)
        for t in range(M):
            for k in range(4):
                if nbr[t][k] < 0:
                    self.hull[fid[t][k]] = True
        inc = [[] for _ in P]
        for t in range(M):
            for x in tets[t]:
                inc[x].append(t)
        self.inc = inc

    # ------------------------------------------------------------ 11.1
    def local_scale(self):
        P = self.P
        E = [[] for _ in P]
        seen = set()
        for v in self.tets:
            for i in range(4):
                for j in range(i + 1, 4):
                    a, b = v[i], v[j]
                    if a > b:
                        a, b = b, a
                    if (a, b) in seen:
                        continue
                    seen.add((a, b))
                    e = d2(P[a], P[b])
                    E[a].append(e)
                    E[b].append(e)
        k = self.rc["scale_rank"]
        s = []
        for lst in E:
            if not lst:
                s.append(0)
                continue
            lst.sort()
            s.append(lst[k - 1] if len(lst) >= k else lst[-1])
        self.s = s
        cls = self.rc["classes"]
        mult = self.rc["multipliers"]
        self.L = [s[v] * mult[cls[v]] for v in range(len(P))]

    # ------------------------------------------------------------ 11.2, 11.2a
    def candidates(self):
        P, L = self.P, self.L
        cand = []
        for (a, b, c) in self.faces:
            ok = True
            for u, w in ((a, b), (b, c), (c, a)):
                if 256 * d2(P[u], P[w]) > min(L[u], L[w]):
                    ok = False
                    break
            cand.append(ok)
        self.stats["candidates"] = sum(cand)
        filt = self.rc["filters"]
        if filt:
            self.filters(cand, filt)
        self.cand = cand

    def filters(self, cand, filt):
        P, s = self.P, self.s
        info = {}
        for f, ok in enumerate(cand):
            if not ok:
                continue
            a, b, c = self.faces[f]
            N, D = tri_nd(P[a], P[b], P[c])
            e = (d2(P[b], P[c]), d2(P[c], P[a]), d2(P[a], P[b]))
            info[f] = (N, D, min(e), max(e), min(s[a], s[b], s[c]))
        removed = {}
        for f in list(info):
            N, D, emin, emax, sf = info[f]
            keep = True
            if 0 in filt and not 256 * N <= 4 * filt[0] * sf * D:
                keep = False
                removed[0] = removed.get(0, 0) + 1
            if 1 in filt and not 256 * emin >= filt[1] * emax:
                keep = False
                removed[1] = removed.get(1, 0) + 1
            if 2 in filt and not 256 * D <= filt[2] * sf * sf:
                keep = False
                removed[2] = removed.get(2, 0) + 1
            if not keep:
                cand[f] = False
                del info[f]
        if any(i in filt for i in (3, 4, 5)):
            by_edge = {}
            for f in info:
                a, b, c = self.faces[f]
                for u, w in ((a, b), (b, c), (c, a)):
                    key = (u, w) if u < w else (w, u)
                    by_edge.setdefault(key, []).append(f)
            drop = []
            for f in info:
                a, b, c = self.faces[f]
                nbrs = []
                for u, w in ((a, b), (b, c), (c, a)):
                    key = (u, w) if u < w else (w, u)
                    nbrs.extend(g for g in by_edge[key] if g != f)
                N, D, emin, emax, sf = info[f]
                keep = True
                if 3 in filt and not nbrs:
                    keep = False
                    removed[3] = removed.get(3, 0) + 1
                if 4 in filt and nbrs:
                    g = nbrs[0]
                    for h in nbrs[1:]:
                        if r2_less(info[g][:2], info[h][:2]):
                            g = h
                    Ng, Dg = info[g][:2]
                    if not (Dg == 0 or 256 * N * Dg <= filt[4] * Ng * D):
                        keep = False
                        removed[4] = removed.get(4, 0) + 1
                if 5 in filt and nbrs:
                    h = nbrs[0]
                    for g in nbrs[1:]:
                        # e_min/e_max of g larger than h's
                        if info[g][2] * info[h][3] > info[h][2] * info[g][3]:
                            h = g
                    if not 256 * emin * info[h][3] >= filt[5] * info[h][2] * emax:
                        keep = False
                        removed[5] = removed.get(5, 0) + 1
                if not keep:
                    drop.append(f)
            for f in drop:
                cand[f] = False
        self.stats["filter_removed"] = removed

    # ------------------------------------------------------------ 11.3
    def flood(self):
        M = len(self.tets)
        fid, nbr, cand, hull = self.fid, self.nbr, self.cand, self.hull
        inside = [True] * M
        stack = []
        seal = self.rc.get("seal")

        def sealed(f):  # §11.3: with a seal, no vertex of face f in the box
            return seal is not None and not any(
                all(seal[ax] <= self.P[v][ax] < seal[3 + ax] for ax in range(3)) for v in self.faces[f])
        for t in range(M):
            for k in range(4):
                f = fid[t][k]
                if hull[f] and not cand[f] and not sealed(f):
                    inside[t] = False
                    stack.append(t)
                    break
        while stack:
            t = stack.pop()
            for k in range(4):
                u = nbr[t][k]
                if u >= 0 and inside[u] and not cand[fid[t][k]] and not sealed(fid[t][k]):
                    inside[u] = False
                    stack.append(u)
        self.inside = inside
        self.stats["flood_outside"] = M - sum(inside)

    # ------------------------------------------------------------ 11.4
    def peel(self):
        P, M = self.P, len(self.tets)
        fid, nbr, inside = self.fid, self.nbr, self.inside
        R = {}

        def r2(f):
            x = R.get(f)
            if x is None:
                a, b, c = self.faces[f]
                x = R[f] = tri_nd(P[a], P[b], P[c])
            return x

        def selected(t):
            exposed, inner = [], []
            for k in range(4):
                u = nbr[t][k]
                (exposed if u < 0 or not inside[u] else inner).append(fid[t][k])
            if len(exposed) != 2:
                return False
            ri = r2(inner[0]) if r2_less(r2(inner[1]), r2(inner[0])) else r2(inner[1])
            re = r2(exposed[0]) if r2_less(r2(exposed[1]), r2(exposed[0])) else r2(exposed[1])
            return r2_less(ri, re)

        todo = range(M)
        rounds = 0
        peeled = 0
        while True:
            sel = [t for t in todo if inside[t] and selected(t)]
            if not sel:
                break
            rounds += 1
            peeled += len(sel)
            for t in sel:
                inside[t] = False
            nxt = set()
            for t in sel:
                for u in nbr[t]:
                    if u >= 0 and inside[u]:
                        nxt.add(u)
            todo = sorted(nxt)
        self.stats["peeled"] = peeled
        self.stats["peel_rounds"] = rounds

    # ------------------------------------------------------------ 11.4a
    def bubbles(self):
        M = len(self.tets)
        nbr, inside, fid, hull = self.nbr, self.inside, self.fid, self.hull
        done = [False] * M
        flip = []
        for t in range(M):
            if done[t]:
                continue
            lab = inside[t]
            comp = [t]
            done[t] = True
            i = 0
            while i < len(comp):
                x = comp[i]
                i += 1
                for u in nbr[x]:
                    if u >= 0 and not done[u] and inside[u] == lab:
                        done[u] = True
                        comp.append(u)
            if len(comp) > self.BUBBLE_MAX:
                continue
            if not lab and any(nbr[x][k] < 0 for x in comp for k in range(4)):
                continue
            flip.extend(comp)
        for t in flip:
            inside[t] = not inside[t]
        self.stats["bubbles_flipped"] = len(flip)

    def is_iface(self, t, k):
        u = self.nbr[t][k]
        if u < 0:
            return self.inside[t]
        return self.inside[t] != self.inside[u]

    def on_iface(self, v):
        tets = self.tets
        for t in self.inc[v]:
            j = tets[t].index(v)
            for k in range(4):
                if k != j and self.is_iface(t, k):
                    return True
        return False

    def edge_on_iface(self, a, b):
        tets = self.tets
        for t in self.inc[a]:
            v = tets[t]
            if b not in v:
                continue
            ia, ib = v.index(a), v.index(b)
            for k in range(4):
                if k != ia and k != ib and self.is_iface(t, k):
                    return True
        return False

    def defects(self, v):
        tets, fid = self.tets, self.fid
        seen = set()
        link = []
        for t in self.inc[v]:
            vt = tets[t]
            j = vt.index(v)
            for k in range(4):
                if k == j:
                    continue
                f = fid[t][k]
                if f in seen or not self.is_iface(t, k):
                    continue
                seen.add(f)
                w, x = [vt[m] for m in range(4) if m != j and m != k]
                link.append((w, x))
        if not link:
            return 1 if self.kind == 1 else 0
        deg = {}
        parent = {}

        def find(a):
            while parent[a] != a:
                parent[a] = parent[parent[a]]
                a = parent[a]
            return a

        for w, x in link:
            deg[w] = deg.get(w, 0) + 1
            deg[x] = deg.get(x, 0) + 1
            parent.setdefault(w, w)
            parent.setdefault(x, x)
        comps = len(parent)
        for w, x in link:
            rw, rx = find(w), find(x)
            if rw != rx:
                parent[rw] = rx
                comps -= 1
        return sum(1 for d in deg.values() if d == 1 or d > 2) + comps - 1

    def euler(self, t):
        v = self.tets[t]
        nv = sum(1 for x in v if self.on_iface(x))
        ne = 0
        for i in range(4):
            for j in range(i + 1, 4):
                if self.edge_on_iface(v[i], v[j]):
                    ne += 1
        nf = sum(1 for k in range(4) if self.is_iface(t, k))
        return nv - ne + nf

    def repair(self):
        self.bubbles()
        inside, tets = self.inside, self.tets
        flips = 0
        rounds = 0
        for rnd in range(self.REPAIR_ROUNDS):
            changed = False
            for v in range(len(self.P)):
                if self.defects(v) == 0:
                    continue
                for t in self.inc[v]:
                    vt = tets[t]
                    b = sum(self.defects(u) for u in vt)
                    e = self.euler(t)
                    inside[t] = not inside[t]
                    if sum(self.defects(u) for u in vt) < b and self.euler(t) == e:
                        changed = True
                        flips += 1
                        if self.defects(v) == 0:
                            break
                    else:
                        inside[t] = not inside[t]
            rounds += 1
            if not changed:
                break
        self.stats["repair_flips"] = flips
        self.stats["repair_rounds"] = rounds

    # ------------------------------------------------------------ 11.5
    def toggles(self):
        rc, M = self.rc, len(self.tets)
        inside = self.inside
        if not rc["compact"]:
            tog = rc["toggle_list"]
            for t in tog:
                if t >= M:
                    raise ReconError("bad_layer", "RCON: toggle index %d >= %d tetrahedra" % (t, M))
            for t in tog:
                inside[t] = not inside[t]
            self.stats["toggled"] = len(tog)
            return
        lists = rc["toggle_ranks"]
        J = len(lists)
        nbr, fid, cand = self.nbr, self.fid, self.cand
        ctx = []
        on = None
        if rc["vertex_contexts"]:
            on = [self.on_iface(v) for v in range(len(self.P))]
        for t in range(M):
            f = 0
            c = 0
            for k in range(4):
                if self.is_iface(t, k):
                    f += 1
                if cand[fid[t][k]]:
                    c += 1
            x = 4 * (1 if inside[t] else 0) + min(f, 3)
            if rc["candidate_contexts"]:
                x += 8 * c
            if rc["vertex_contexts"]:
                if all(on[v] for v in self.tets[t]):
                    x += 40
            ctx.append(x)
        count = [0] * J
        toggled = [False] * M
        listed = [set(l) for l in lists]
        if rc["neighbour_contexts"]:
            inverted = set(rc["inverted"])
            for t in range(M):
                j = 3 * ctx[t] + min(self.toggled_before(t, toggled), 2)
                r = count[j]
                count[j] += 1
                toggled[t] = (r in listed[j]) != (j in inverted)
        else:
            for t in range(M):
                j = ctx[t]
                r = count[j]
                count[j] += 1
                toggled[t] = r in listed[j]
        for j in range(J):
            if lists[j] and lists[j][-1] >= count[j]:
                raise ReconError("bad_layer", "RCON: toggle rank %d of context %d, which has %d tetrahedra"
                                 % (lists[j][-1], j, count[j]))
        n = 0
        for t in range(M):
            if toggled[t]:
                inside[t] = not inside[t]
                n += 1
        self.stats["toggled"] = n
        self.stats["toggle_contexts"] = sorted(j for j in range(J) if lists[j] or j in rc.get("inverted", ()))

    def toggled_before(self, t, toggled):
        """Section 11.5, n(t): the faces of t shared with a toggled u < t."""
        return sum(1 for u in self.nbr[t] if 0 <= u < t and toggled[u])

    # ------------------------------------------------------------ 11.6
    def output(self):
        M = len(self.tets)
        inside, nbr, tets = self.inside, self.nbr, self.tets
        if self.kind == 2:
            return [t for i, t in enumerate(tets) if inside[i]]
        drops = set(self.rc["drop_list"])
        B = self.B
        out = []
        nb = nd = 0
        for i in range(M):
            if not inside[i]:
                continue
            v = tets[i]
            for k in range(4):
                u = nbr[i][k]
                if u >= 0 and inside[u]:
                    continue
                a, b, c = FACES[k]
                tri = (v[a], v[b], v[c])
                if B and tri[0] in B and tri[1] in B and tri[2] in B:
                    nb += 1
                    continue
                if 4 * i + k in drops:
                    nd += 1
                    continue
                m = tri.index(min(tri))
                out.append(tri[m:] + tri[:m])
        out.sort()
        self.stats["border_dropped"] = nb
        self.stats["drops_dropped"] = nd
        return out

    def run(self):
        rc = self.rc
        self.build()
        M = len(self.tets)
        self.stats["points"] = len(self.P)
        self.stats["tets"] = M
        if M == 0:
            # no tetrahedra: every toggle index, toggle rank and drop index
            # is out of range (sections 10, 11.5)
            if not rc["compact"] and rc["toggle_list"]:
                raise ReconError("bad_layer", "RCON: toggle index %d >= 0 tetrahedra" % rc["toggle_list"][0])
            if rc["compact"]:
                for j, l in enumerate(rc["toggle_ranks"]):
                    if l:
                        raise ReconError("bad_layer", "RCON: toggle rank %d of context %d, which has 0 tetrahedra" % (l[0], j))
            if rc["drop_list"]:
                raise ReconError("bad_layer", "RCON: drop index %d >= 0" % rc["drop_list"][0])
            return []
        self.local_scale()
        self.candidates()
        self.flood()
        if rc["peel"]:
            self.peel()
        if rc["repair"]:
            self.repair()
        self.toggles()
        for d in rc["drop_list"]:
            if d >= 4 * M:
                raise ReconError("bad_layer", "RCON: drop index %d >= 4 x %d tetrahedra" % (d, M))
        return self.output()


def reconstruct(kind, points, rc, B):
    lv = Level(kind, points, rc, B)
    out = lv.run()
    path = os.environ.get("HMC_RECON_STATS")
    if path:
        st = dict(lv.stats)
        st.update(kind=kind, peel=rc["peel"], repair=rc["repair"], compact=rc["compact"],
                  filters=sorted(rc["filters"]), classes=len(rc["multipliers"]), border=len(B),
                  inherit_border=rc["inherit_border"], drops=len(rc["drop_list"]),
                  contexts=len(rc["toggle_ranks"]) if rc["compact"] else 0, simplices=len(out))
        with open(path, "a") as f:
            f.write(json.dumps(st, sort_keys=True) + "\n")
    return out
