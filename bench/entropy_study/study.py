#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""What would an adaptive binary arithmetic coder gain on HMC's layers?

A study for issue 50, not a test. It decodes the reference encoder's own
streams with a traced `hmc` (symbol_trace.patch, applied to a scratch
worktree of the given commit) that prints every octree node's ranked
occupancy with what the decoder knows there, then prices those same
decisions with adaptive binary models of several kinds:

  counts   ideal adaptive counts (KT-like, halved past 1,024): a bound that
           no practical shift-based estimator reaches;
  shift    the state of a practical coder: a 15-bit probability moved by
           p += (target - p) >> min(1 + n, 5) after the n-th update;
  dual     two such states (shifts up to 4 and 7), averaged.

The binarization codes the ranked occupancy's bits in rank order (the last
one skipped when no earlier bit is set), contexts from depth, the base
coder's plane context x, the rank r, the set bits so far, and for
refinement layers the coarse bit at rank r, the coarse children w and the
plane split. Variants add the node's own rank in its parent and the
parent's child count. A last experiment prices the base layer with
G-PCC-like neighbour-occupancy contexts (no nearest-node search).

    bench/entropy_study/study.py --hmc build/bin/hmc [--models bunny,horse]
"""
import argparse, json, math, os, subprocess, sys, tempfile
from collections import defaultdict

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
DATA = os.path.join(os.path.dirname(ROOT), "shared", "data")
MODELS = {"stanford_bunny": "surface/stanford_bunny.obj", "horse": "surface/horse.ply",
          "spot": "surface/spot.obj", "skull": "surface/skull.obj",
          "hand_libigl": "volume/hand_libigl.mesh", "skull_tetgen": "volume/skull_tetgen.node"}


def traced_hmc(commit, work):
    tree = os.path.join(work, "tree")
    subprocess.run(["git", "-C", ROOT, "worktree", "add", "--detach", tree, commit], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    subprocess.run(["git", "-C", tree, "apply", os.path.join(HERE, "symbol_trace.patch")], check=True)
    build = os.path.join(work, "build")
    subprocess.run(["cmake", "-S", tree, "-B", build, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                    "-DHMC_BUILD_BENCH=OFF"], check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["ninja", "-C", build, "hmc_cli"], check=True, stdout=subprocess.DEVNULL)
    return tree, os.path.join(build, "bin", "hmc")


def layer_bytes(hmc, stream):
    info = json.loads(subprocess.run([hmc, "info", stream, "--json"], check=True, capture_output=True).stdout)
    out = defaultdict(int)
    for c in info["chunks"]:
        out[c["type"]] += c["length"]
    return out


def trace(hmc, stream, path):
    env = dict(os.environ, HMC_SYMBOL_TRACE=path)
    subprocess.run([hmc, "dec", stream, "-o", path + ".xyz", "--points-only"], check=True, env=env,
                   stdout=subprocess.DEVNULL)
    rows = {"B": [], "R": []}
    with open(path) as f:
        for line in f:
            t = line.split()
            rows[t[0]].append(list(map(int, t[1:])))
    return rows


def events(rows, kind, ctx):
    """(context, bit) pairs of the ranked occupancies, bits in rank order."""
    out = []
    for row in rows:
        rho = row[3] if kind == "B" else row[4]
        ones = 0
        for r in range(8):
            if r == 7 and ones == 0:
                break  # a non-empty occupancy: the last bit is implied
            b = (rho >> r) & 1
            out.append((ctx(row, r, ones), b))
            ones += b
    return out


def cost_counts(ev):
    c = defaultdict(lambda: [0.4, 0.4])
    bits = 0.0
    for k, b in ev:
        n = c[k]
        bits -= math.log2(n[b] / (n[0] + n[1]))
        n[b] += 1
        if n[0] + n[1] > 1024:
            n[0] /= 2
            n[1] /= 2
    return bits


def cost_shift(ev, limits=(5,)):
    state = defaultdict(lambda: [16384] * len(limits) + [0])
    bits = 0.0
    for k, b in ev:
        s = state[k]
        p1 = sum(s[:-1]) / (32768 * len(limits))
        bits -= math.log2(p1 if b else 1 - p1)
        for j, lim in enumerate(limits):
            sh = min(1 + s[-1], lim)
            s[j] = s[j] + ((32768 - s[j]) >> sh) if b else s[j] - (s[j] >> sh)
            s[j] = min(max(s[j], 1), 32767)
        s[-1] += 1
    return bits


def rank_class(r):
    return min(r, 3) if r < 8 else 8


BASE_CTX = {"d,x,r,ones": lambda t, r, o: (t[0], t[1], t[2], r, min(o, 3)),
            "+own rank": lambda t, r, o: (t[0], t[1], t[2], r, min(o, 3), rank_class(t[4])),
            "+parent children": lambda t, r, o: (t[0], t[1], t[2], r, min(o, 3), min(t[5], 3))}
REFN_CTX = {"d,r,ones,m_r,w": lambda t, r, o: (t[0], r, min(o, 3), (t[1] >> r) & 1, min(t[2], 2)),
            "+split": lambda t, r, o: (t[0], r, min(o, 3), (t[1] >> r) & 1, min(t[2], 2), min(t[3], 2)),
            "+own rank": lambda t, r, o: (t[0], r, min(o, 3), (t[1] >> r) & 1, min(t[2], 2), rank_class(t[6]))}


def neighbour_contexts(points, q=12):
    """Base-layer bits with G-PCC-like contexts: per child, the occupied
    parent-level neighbours that touch it (face pattern, edge and corner
    counts) and its already-coded face neighbours at its own depth."""
    levels = [set((x >> (q - d), y >> (q - d), z >> (q - d)) for x, y, z in points) for d in range(q + 1)]

    def morton(n, d):
        k = 0
        for i in range(d - 1, -1, -1):
            k = (k << 3) | (((n[0] >> i) & 1) << 2) | (((n[1] >> i) & 1) << 1) | ((n[2] >> i) & 1)
        return k
    ev = []
    for d in range(q):
        cur = sorted(levels[d], key=lambda n: morton(n, d))
        idx = {n: i for i, n in enumerate(cur)}
        up, down = levels[d], levels[d + 1]
        for i, (X, Y, Z) in enumerate(cur):
            ones = 0
            for c in range(8):
                bx, by, bz = (c >> 2) & 1, (c >> 1) & 1, c & 1
                cx, cy, cz = 2 * X + bx, 2 * Y + by, 2 * Z + bz
                if c == 7 and ones == 0:
                    break
                sx, sy, sz = (1 if bx else -1), (1 if by else -1), (1 if bz else -1)
                face = ((X + sx, Y, Z) in up, (X, Y + sy, Z) in up, (X, Y, Z + sz) in up)
                edge = sum(((X + sx, Y + sy, Z) in up, (X + sx, Y, Z + sz) in up, (X, Y + sy, Z + sz) in up))
                corner = (X + sx, Y + sy, Z + sz) in up
                known = 0
                for a in ((cx - 1, cy, cz), (cx, cy - 1, cz), (cx, cy, cz - 1),
                          (cx + 1, cy, cz), (cx, cy + 1, cz), (cx, cy, cz + 1)):
                    parent = (a[0] >> 1, a[1] >> 1, a[2] >> 1)
                    if parent == (X, Y, Z):
                        coded = (((a[0] & 1) << 2) | ((a[1] & 1) << 1) | (a[2] & 1)) < c
                    else:
                        coded = parent in idx and idx[parent] < i
                    known += coded and a in down
                b = 1 if (cx, cy, cz) in down else 0
                ev.append(((d, c, min(ones, 3), face, edge, corner, min(known, 3)), b))
                ones += b
    return ev


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hmc", required=True, help="the hmc that encodes (any build of the commit studied)")
    ap.add_argument("--commit", default="HEAD")
    ap.add_argument("--models", default=",".join(MODELS))
    ap.add_argument("--neighbour-models", default="stanford_bunny,spot",
                    help="models for the (slow, pure Python) neighbour-occupancy experiment")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        tree, traced = traced_hmc(args.commit, work)
        try:
            print("| model | levels | Huffman BASE+REFN bytes | counts (bound) | shift | dual | best context variant |")
            print("|---|---:|---:|---:|---:|---:|---|")
            for name in args.models.split(","):
                src = os.path.join(DATA, MODELS[name])
                for levels in (1, 4):
                    stream = os.path.join(work, f"{name}-{levels}.hmc")
                    subprocess.run([args.hmc, "enc", src, "-o", stream, "--levels", str(levels), "--no-info"],
                                   check=True, stdout=subprocess.DEVNULL)
                    sizes = layer_bytes(args.hmc, stream)
                    huff = sizes["BASE"] + sizes["REFN"]
                    rows = trace(traced, stream, os.path.join(work, f"{name}-{levels}.trace"))
                    base0 = events(rows["B"], "B", BASE_CTX["d,x,r,ones"])
                    refn0 = events(rows["R"], "R", REFN_CTX["d,r,ones,m_r,w"])
                    ev = base0 + refn0
                    variants = []
                    for bn, bf in BASE_CTX.items():
                        for rn, rf in REFN_CTX.items():
                            if bn != "d,x,r,ones" and rn != "d,r,ones,m_r,w":
                                continue
                            e = events(rows["B"], "B", bf) + events(rows["R"], "R", rf)
                            variants.append((cost_counts(e) / 8, f"{bn} / {rn}"))
                    best = min(variants, key=lambda v: v[0])  # the first of equals: the plainest
                    c, s, d = cost_counts(ev) / 8, cost_shift(ev) / 8, cost_shift(ev, (4, 7)) / 8
                    print(f"| {name} | {levels} | {huff} | {c:.0f} ({c / huff:.3f}) | {s:.0f} ({s / huff:.3f}) | "
                          f"{d:.0f} ({d / huff:.3f}) | {best[1]}: {best[0]:.0f} ({best[0] / huff:.3f}) |", flush=True)
            print()
            print("| model | 1-level BASE bytes (Huffman, ranked) | neighbour-occupancy contexts, counts | ratio |")
            print("|---|---:|---:|---:|")
            for name in args.neighbour_models.split(","):
                if not name:
                    continue
                src = os.path.join(DATA, MODELS[name])
                dump = os.path.join(work, name + "-can")
                stream = os.path.join(work, name + "-1.hmc")
                subprocess.run([args.hmc, "enc", src, "-o", stream, "--levels", "1", "--no-info", "--canonical", dump],
                               check=True, stdout=subprocess.DEVNULL)
                with open(os.path.join(dump, "level-0.points")) as f:
                    pts = [tuple(map(int, line.split())) for line in f]
                base = layer_bytes(args.hmc, stream)["BASE"]
                nb = cost_counts(neighbour_contexts(pts)) / 8
                print(f"| {name} | {base} | {nb:.0f} | {nb / base:.3f} |", flush=True)
        finally:
            subprocess.run(["git", "-C", ROOT, "worktree", "remove", "--force", tree], check=False)


if __name__ == "__main__":
    sys.exit(main())
