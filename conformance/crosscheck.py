#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Cross-check of the two decoders on streams outside the conformance suite:
the reference decoder (`hmc dec --canonical`) and the second decoder
(conformance/refdec.py, with refdelaunay.py and refrecon.py) must write
the same canonical dump, header.json, level-K.points and
level-K.simplices, byte for byte.

    crosscheck.py --hmc build/bin/hmc [--data ../shared/data] [--work DIR]
                  [--seed S] [--models a,b] [--subsets patch,sample]
                  [--levels 1,3] [--fidelity rule,topology,shape,exact]
                  [--jobs N] [--keep]

For each model (surfaces: OBJ, OFF, binary PLY; volumes: MEDIT .mesh,
TetGen .node/.ele) it draws subsets of 1,000 to 3,000 points:

* patch: a region grown breadth-first from a random vertex over the
  mesh's edges, with the triangles or tetrahedra it holds entirely (an
  open surface with its border, a piece of a solid): the encoder sees a
  real mesh, so it writes border, toggle and drop lists;
* sample: a uniformly random subset of the vertices without connectivity,
  encoded as points with --kind surface or volume (the rule and whatever
  the encoder chooses without a mesh to match).

Each subset is encoded at every --levels with every --fidelity, then
decoded by both decoders, and the dumps compared. The inputs, streams and
dumps go to a temporary folder (--work, removed at the end unless --keep):
never into the repository. Prints one line per stream and a summary; exit
status 0 iff no dump differs and no decoder failed.

Python 3 standard library only.
"""
import argparse
import concurrent.futures
import filecmp
import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))

SURFACES = ["stanford_bunny.obj", "cat_lowres.obj", "bimba.obj", "fertility.off", "torus.obj", "horse.ply",
            "spot.obj", "skull.obj", "rocker_arm.obj"]
VOLUMES = ["hand_libigl.mesh", "bunny_libigl.mesh", "hand_tetgen.node", "skull_tetgen.node"]


# ---------------------------------------------------------------- readers

def read_obj(path):
    V, F = [], []
    with open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "v":
                V.append(tuple(float(x) for x in p[1:4]))
            elif p[0] == "f":
                idx = [int(x.split("/")[0]) for x in p[1:]]
                idx = [i - 1 if i > 0 else len(V) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    F.append((idx[0], idx[k], idx[k + 1]))
    return V, F


def read_off(path):
    with open(path) as f:
        toks = [t for line in f for t in line.split("#")[0].split()]
    assert toks[0] == "OFF"
    nv, nf = int(toks[1]), int(toks[2])
    pos = 4
    V = []
    for _ in range(nv):
        V.append(tuple(float(x) for x in toks[pos:pos + 3]))
        pos += 3
    F = []
    for _ in range(nf):
        k = int(toks[pos])
        idx = [int(x) for x in toks[pos + 1:pos + 1 + k]]
        pos += 1 + k
        for j in range(1, k - 1):
            F.append((idx[0], idx[j], idx[j + 1]))
    return V, F


def read_ply(path):
    """Binary little-endian PLY with float vertex properties and a uchar/int
    face list (what the shared horse is)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    assert "format binary_little_endian 1.0" in header
    nv = nf = 0
    props = []
    el = None
    for line in header:
        p = line.split()
        if p[:2] == ["element", "vertex"]:
            nv, el = int(p[2]), "v"
        elif p[:2] == ["element", "face"]:
            nf, el = int(p[2]), "f"
        elif p and p[0] == "property" and el == "v":
            assert p[1] == "float"
            props.append(p[2])
    stride = 4 * len(props)
    ix, iy, iz = props.index("x"), props.index("y"), props.index("z")
    V = []
    pos = end
    for _ in range(nv):
        vals = struct.unpack_from("<%df" % len(props), data, pos)
        V.append((vals[ix], vals[iy], vals[iz]))
        pos += stride
    F = []
    for _ in range(nf):
        k = data[pos]
        idx = struct.unpack_from("<%di" % k, data, pos + 1)
        pos += 1 + 4 * k
        for j in range(1, k - 1):
            F.append((idx[0], idx[j], idx[j + 1]))
    return V, F


def read_mesh(path):
    with open(path) as f:
        toks = f.read().split()
    V, T = [], []
    i = 0
    while i < len(toks):
        t = toks[i]
        if t == "Vertices":
            n = int(toks[i + 1])
            i += 2
            for _ in range(n):
                V.append(tuple(float(x) for x in toks[i:i + 3]))
                i += 4
        elif t == "Tetrahedra":
            n = int(toks[i + 1])
            i += 2
            for _ in range(n):
                T.append(tuple(int(x) - 1 for x in toks[i:i + 4]))
                i += 5
        elif t in ("Triangles", "Edges", "Quadrilaterals", "Hexahedra"):
            n = int(toks[i + 1])
            per = {"Triangles": 4, "Edges": 3, "Quadrilaterals": 5, "Hexahedra": 9}[t]
            i += 2 + n * per
        else:
            i += 1
    return V, T


def read_node(path):
    with open(path) as f:
        lines = [l.split("#")[0].split() for l in f]
    lines = [l for l in lines if l]
    n = int(lines[0][0])
    first = int(lines[1][0])
    V = [tuple(float(x) for x in l[1:4]) for l in lines[1:1 + n]]
    with open(path[:-5] + ".ele") as f:
        el = [l.split("#")[0].split() for l in f]
    el = [l for l in el if l]
    m = int(el[0][0])
    T = [tuple(int(x) - first for x in l[1:5]) for l in el[1:1 + m]]
    return V, T


def read_model(path):
    ext = path.rsplit(".", 1)[1]
    return {"obj": read_obj, "off": read_off, "ply": read_ply, "mesh": read_mesh, "node": read_node}[ext](path)


# ---------------------------------------------------------------- subsets

def patch(V, E, n, rng):
    """A breadth-first region of about n vertices from a random vertex, with
    the elements it holds entirely; vertices in no kept element dropped."""
    adj = [[] for _ in V]
    for e in E:
        for a in e:
            for b in e:
                if a != b:
                    adj[a].append(b)
    start = rng.randrange(len(V))
    while not adj[start]:
        start = rng.randrange(len(V))
    seen = {start}
    queue = [start]
    i = 0
    while i < len(queue) and len(seen) < n:
        v = queue[i]
        i += 1
        nb = adj[v][:]
        rng.shuffle(nb)
        for w in nb:
            if w not in seen and len(seen) < n:
                seen.add(w)
                queue.append(w)
    kept = [e for e in E if all(a in seen for a in e)]
    used = sorted(set(a for e in kept for a in e))
    new = {a: i for i, a in enumerate(used)}
    return [V[a] for a in used], [tuple(new[a] for a in e) for e in kept]


def write_input(path, V, E, volume):
    with open(path, "w") as f:
        if path.endswith(".xyz"):
            f.write("".join("%.17g %.17g %.17g\n" % v for v in V))
        elif volume:
            f.write("MeshVersionFormatted 1\nDimension 3\nVertices\n%d\n" % len(V))
            f.write("".join("%.17g %.17g %.17g 0\n" % v for v in V))
            f.write("Tetrahedra\n%d\n" % len(E))
            f.write("".join("%d %d %d %d 0\n" % tuple(a + 1 for a in e) for e in E))
            f.write("End\n")
        else:
            f.write("".join("v %.17g %.17g %.17g\n" % v for v in V))
            f.write("".join("f %d %d %d\n" % tuple(a + 1 for a in e) for e in E))


# ---------------------------------------------------------------- one stream

def same_dump(a, b):
    fa, fb = sorted(os.listdir(a)), sorted(os.listdir(b))
    if fa != fb:
        return "files differ: %s vs %s" % (fa, fb)
    for n in fa:
        if not filecmp.cmp(os.path.join(a, n), os.path.join(b, n), shallow=False):
            with open(os.path.join(a, n)) as f:
                la = f.read().splitlines()
            with open(os.path.join(b, n)) as f:
                lb = f.read().splitlines()
            for i, (x, y) in enumerate(zip(la, lb)):
                if x != y:
                    return "%s line %d: hmc %r, refdec %r" % (n, i + 1, x, y)
            return "%s: hmc %d lines, refdec %d" % (n, len(la), len(lb))
    return None


def run_stream(job):
    hmc, inp, kind, levels, fid, outdir, timeout = job
    os.makedirs(outdir)
    s = os.path.join(outdir, "s.hmc")
    t0 = time.time()
    r = subprocess.run([hmc, "enc", inp, "-o", s, "--levels", str(levels), "--fidelity", fid, "--kind", kind,
                        "--threads", "1"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    if r.returncode != 0:
        return "ENCFAIL", r.stderr.decode(errors="replace").strip().splitlines()[-1:], 0, 0
    r = subprocess.run([hmc, "dec", s, "--canonical", os.path.join(outdir, "a"), "--threads", "1"],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    if r.returncode != 0:
        return "HMCFAIL", r.stderr.decode(errors="replace").strip().splitlines()[-1:], 0, 0
    t1 = time.time()
    try:
        r = subprocess.run([sys.executable, os.path.join(HERE, "refdec.py"), s, os.path.join(outdir, "b")],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "REFTIMEOUT", ["no answer within %g s" % timeout], t1 - t0, timeout
    t2 = time.time()
    if r.returncode != 0:
        return "REFFAIL", r.stderr.decode(errors="replace").strip().splitlines()[-1:], t1 - t0, t2 - t1
    d = same_dump(os.path.join(outdir, "a"), os.path.join(outdir, "b"))
    if d:
        return "MISMATCH", [d], t1 - t0, t2 - t1
    return "SAME", [], t1 - t0, t2 - t1


def main():
    ap = argparse.ArgumentParser(description="cross-check hmc dec --canonical against refdec.py")
    ap.add_argument("--hmc", required=True)
    ap.add_argument("--data", default=os.path.join(HERE, "..", "..", "shared", "data"))
    ap.add_argument("--work", default=None)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--models", default=None, help="comma-separated file names (default: all)")
    ap.add_argument("--subsets", default="patch,sample")
    ap.add_argument("--levels", default="1,3")
    ap.add_argument("--fidelity", default="rule,topology,shape,exact")
    ap.add_argument("--min-points", type=int, default=1000)
    ap.add_argument("--max-points", type=int, default=3000)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=1800)
    ap.add_argument("--keep", action="store_true")
    a = ap.parse_args()
    rng = random.Random(a.seed)
    models = [("surface", m) for m in SURFACES] + [("volume", m) for m in VOLUMES]
    if a.models:
        want = a.models.split(",")
        models = [m for m in models if m[1] in want]
    work = a.work or tempfile.mkdtemp(prefix="hmc-crosscheck-")
    os.makedirs(work, exist_ok=True)
    jobs = []
    for kind, name in models:
        path = os.path.join(a.data, kind, name)
        V, E = read_model(path)
        for sub in a.subsets.split(","):
            n = min(rng.randint(a.min_points, a.max_points), len(V))
            base = os.path.join(work, "%s-%s" % (name.rsplit(".", 1)[0], sub))
            if sub == "patch":
                SV, SE = patch(V, E, n, rng)
                inp = base + (".mesh" if kind == "volume" else ".obj")
            else:
                SV = [V[i] for i in sorted(rng.sample(range(len(V)), n))]
                SE = []
                inp = base + ".xyz"
            write_input(inp, SV, SE, kind == "volume")
            for lv in a.levels.split(","):
                for fid in a.fidelity.split(","):
                    label = "%s %s n=%d levels=%s fidelity=%s" % (name, sub, len(SV), lv, fid)
                    jobs.append((label, (a.hmc, inp, kind, int(lv), fid, "%s-l%s-%s" % (base, lv, fid), a.timeout)))
    counts = {}
    t0 = time.time()
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        futs = [pool.submit(run_stream, j) for _, j in jobs]
        for (label, _), fut in zip(jobs, futs):
            verdict, why, th, tr = fut.result()
            counts[verdict] = counts.get(verdict, 0) + 1
            print("%-10s %s (hmc %.1f s, refdec %.1f s) %s" % (verdict, label, th, tr, " ".join(why)), flush=True)
    if not a.keep:
        shutil.rmtree(work, ignore_errors=True)
    else:
        print("kept %s" % work)
    print("%d streams: %s; %.0f s" % (len(jobs), ", ".join("%d %s" % (v, k) for k, v in sorted(counts.items())),
                                      time.time() - t0))
    return 0 if set(counts) <= {"SAME"} else 1


if __name__ == "__main__":
    sys.exit(main())
