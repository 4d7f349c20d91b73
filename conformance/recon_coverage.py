#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Which conformance vectors exercise which step of spec/hmc.md section 11
(and the tie rule of spec/delaunay.md): for each step, the second decoder
(refdec.py with refrecon.py) is run on the suite with that step broken
(left out, or changed in one detail the spec fixes), and the cases that
then fail are the ones that check the step. A step no vector notices is
not covered.

    python3 conformance/recon_coverage.py [--jobs N] [--only MUTATION,...] [--cases DIR]

Prints, per mutation, the number of failing cases and their names.
Python 3 standard library only. Slow: one full-profile run per mutation.
"""
import argparse
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

MUTATIONS = [
    ("D-tie", "delaunay.md 3.2: the perturbation ordered by descending index instead of ascending"),
    ("11.1-rank", "11.1: the largest element of E(v) instead of the k-th smallest"),
    ("11.1-classes", "11.1: every point in class 0 (multipliers[0] for all)"),
    ("11.2-strict", "11.2: 256 d2 < min(L_u, L_w) instead of <="),
    ("11.2a-f0", "11.2a: filter 0 (circle radius) ignored"),
    ("11.2a-f1", "11.2a: filter 1 (min/max edge ratio) ignored"),
    ("11.2a-f2", "11.2a: filter 2 (density) ignored"),
    ("11.2a-f3", "11.2a: filter 3 (lone triangle) ignored"),
    ("11.2a-f4", "11.2a: filter 4 (neighbour circle radius ratio) ignored"),
    ("11.2a-f5", "11.2a: filter 5 (neighbour min/max edge ratio) ignored"),
    ("11.2a-sequential", "11.2a: filters 3, 4, 5 each on the set the previous one left, not all on one set"),
    ("11.3-seeds", "11.3: only the seeds (hull faces not candidates) outside, no propagation"),
    ("11.4-off", "11.4: no peeling"),
    ("11.4-sequential", "11.4: a selected tetrahedron changes label at once, not at the end of the round"),
    ("11.4a-bubbles", "11.4a: no bubbles"),
    ("11.4a-search", "11.4a: no greedy search"),
    ("11.4a-W", "11.4a: W empty for kind surface too"),
    ("11.4a-bubble3", "11.4a: bubbles of at most 3 tetrahedra"),
    ("11.4a-bubble5", "11.4a: bubbles of at most 5 tetrahedra"),
    ("11.4a-hull", "11.4a: outside bubbles with a hull face go too"),
    ("11.4a-euler", "11.4a: the local Euler number not checked"),
    ("11.4a-rounds1", "11.4a: one round of the search only"),
    ("11.4a-empty", "11.4a: a volume point off the interface has (0 fans) - 1 = -1 defects"),
    ("11.4a-order", "11.4a: the points visited in descending index"),
    ("11.5-off", "11.5: no toggles"),
    ("11.5-n0", "11.5: neighbour contexts with n(t) = 0 always"),
    ("11.6-border", "11.6: the border set drops nothing"),
    ("11.6-drops", "11.6: the drop list drops nothing"),
]


def mutate(name):
    import refdelaunay
    import refrecon
    L = refrecon.Level
    if name == "D-tie":
        orig = refdelaunay.insphere_eps

        def eps(P, q):
            pts = [P[i] for i in q]
            s = refdelaunay.insphere(*pts)
            if s:
                return 1 if s > 0 else -1
            for r in sorted(range(5), key=lambda r: -q[r]):
                o = refdelaunay.orient3d(*(pts[:r] + pts[r + 1:]))
                if o:
                    o = o if r % 2 == 0 else -o
                    return 1 if o > 0 else -1
            return 0
        refdelaunay.insphere_eps = eps
        del orig
    elif name in ("11.1-rank", "11.1-classes"):
        orig = L.local_scale

        def ls(self):
            rc = dict(self.rc)
            if name == "11.1-rank":
                rc["scale_rank"] = 1 << 30
            else:
                rc["classes"] = [0] * len(self.P)
            self.rc, keep = rc, self.rc
            orig(self)
            self.rc = keep
        L.local_scale = ls
    elif name == "11.2-strict":
        def cand(self):
            P, Lim = self.P, self.L
            d2 = refrecon.d2
            c = [all(256 * d2(P[u], P[w]) < min(Lim[u], Lim[w]) for u, w in ((a, b), (b, cc), (cc, a)))
                 for (a, b, cc) in self.faces]
            if self.rc["filters"]:
                self.filters(c, self.rc["filters"])
            self.cand = c
        L.candidates = cand
    elif name.startswith("11.2a-f"):
        i = int(name[-1])
        orig = L.filters

        def filt(self, cand, f):
            f = dict(f)
            f.pop(i, None)
            orig(self, cand, f)
        L.filters = filt
    elif name == "11.2a-sequential":
        orig = L.filters

        def filt(self, cand, f):
            orig(self, cand, {i: f[i] for i in f if i < 3 or i == 3})
            for i in (4, 5):
                if i in f:
                    orig(self, cand, {i: f[i]})
        L.filters = filt
    elif name == "11.4a-bubble3":
        L.BUBBLE_MAX = 3
    elif name == "11.4a-bubble5":
        L.BUBBLE_MAX = 5
    elif name == "11.4a-hull":
        def bub(self):
            M = len(self.tets)
            nbr, inside = self.nbr, self.inside
            done = [False] * M
            flip = []
            for t in range(M):
                if done[t]:
                    continue
                comp = [t]
                done[t] = True
                i = 0
                while i < len(comp):
                    for u in nbr[comp[i]]:
                        if u >= 0 and not done[u] and inside[u] == inside[t]:
                            done[u] = True
                            comp.append(u)
                    i += 1
                if len(comp) <= self.BUBBLE_MAX:
                    flip.extend(comp)
            for t in flip:
                inside[t] = not inside[t]
        L.bubbles = bub
    elif name == "11.4a-euler":
        L.euler = lambda self, t: 0
    elif name == "11.4a-rounds1":
        L.REPAIR_ROUNDS = 1
    elif name == "11.4a-empty":
        orig = L.defects

        def defects(self, v):
            d = orig(self, v)
            if d == 0 and self.kind == 2 and not self.on_iface(v):
                return -1
            return d
        L.defects = defects
    elif name == "11.4a-order":
        orig = L.repair

        def rep_(self):
            P = self.P
            n = len(P)
            # visit v = N-1 ... 0: renumber the points of the loop only
            inc = self.inc
            self.bubbles()
            self.bubbles = lambda: None
            for rnd in range(self.REPAIR_ROUNDS):
                changed = False
                for v in reversed(range(n)):
                    if self.defects(v) == 0:
                        continue
                    for t in inc[v]:
                        vt = self.tets[t]
                        b = sum(self.defects(u) for u in vt)
                        e = self.euler(t)
                        self.inside[t] = not self.inside[t]
                        if sum(self.defects(u) for u in vt) < b and self.euler(t) == e:
                            changed = True
                            if self.defects(v) == 0:
                                break
                        else:
                            self.inside[t] = not self.inside[t]
                if not changed:
                    break
        L.repair = rep_
    elif name == "11.3-seeds":
        orig = L.flood

        def flood(self):
            nbr = self.nbr
            self.nbr = [[-1 if u >= 0 else u for u in row] for row in nbr]
            try:
                orig(self)
            finally:
                self.nbr = nbr
        L.flood = flood
    elif name == "11.4-off":
        L.peel = lambda self: None
    elif name == "11.4-sequential":
        def peel(self):
            P = self.P
            while True:
                any_ = False
                for t in range(len(self.tets)):
                    if not self.inside[t]:
                        continue
                    ex, inn = [], []
                    for k in range(4):
                        u = self.nbr[t][k]
                        a, b, c = self.faces[self.fid[t][k]]
                        (ex if u < 0 or not self.inside[u] else inn).append(refrecon.tri_nd(P[a], P[b], P[c]))
                    if len(ex) != 2:
                        continue
                    ri = inn[0] if refrecon.r2_less(inn[1], inn[0]) else inn[1]
                    re_ = ex[0] if refrecon.r2_less(ex[1], ex[0]) else ex[1]
                    if refrecon.r2_less(ri, re_):
                        self.inside[t] = False
                        any_ = True
                if not any_:
                    break
        L.peel = peel
    elif name == "11.4a-bubbles":
        L.bubbles = lambda self: None
    elif name == "11.4a-search":
        L.repair = lambda self: self.bubbles()
    elif name == "11.4a-W":
        orig = L.defects

        def defects(self, v):
            k = self.kind
            self.kind = 2
            try:
                return orig(self, v)
            finally:
                self.kind = k
        L.defects = defects
    elif name == "11.5-off":
        def tog(self):
            self.rc = dict(self.rc, toggle_list=[], toggle_ranks=[[] for _ in self.rc["toggle_ranks"]], inverted=[])
            orig(self)
        orig = L.toggles
        L.toggles = tog
    elif name == "11.5-n0":
        L.toggled_before = lambda self, t, toggled: 0
    elif name == "11.6-border":
        orig = L.output

        def out(self):
            self.B = set()
            return orig(self)
        L.output = out
    elif name == "11.6-drops":
        orig = L.output

        def out(self):
            self.rc = dict(self.rc, drop_list=[])
            return orig(self)
        L.output = out
    else:
        raise SystemExit("unknown mutation %s" % name)


def main():
    if len(sys.argv) >= 2 and sys.argv[1] == "--as-decoder":
        mutate(sys.argv[2])
        import refdec
        return refdec.main([sys.argv[0]] + sys.argv[3:])
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--only", default=None)
    ap.add_argument("--cases", default=os.path.join(HERE, "vectors"))
    a = ap.parse_args()
    names = [m for m, _ in MUTATIONS]
    if a.only:
        names = a.only.split(",")
    desc = dict(MUTATIONS)
    for m in names:
        dec = "'%s' '%s' --as-decoder %s {in} {outdir}" % (sys.executable, os.path.abspath(__file__), m)
        r = subprocess.run([sys.executable, os.path.join(HERE, "run.py"), "--decoder", dec, "--profile", "full",
                            "--jobs", str(a.jobs), "--cases", a.cases], stdout=subprocess.PIPE, universal_newlines=True)
        failed = sorted(re.findall(r"^FAIL ([^:]+):", r.stdout, re.M))
        print("%-16s %3d  %s" % (m, len(failed), desc.get(m, "")))
        print("                      %s" % (" ".join(failed) if failed else "(no vector notices)"), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
