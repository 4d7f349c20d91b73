#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Tiled models (spec/tiles.md) through the command line, on generated tori.

usage: tiles_test.py HMC WORKDIR CASE   (CASE: points, closed, kill, atomic, region, pool, scheduler)

Each case is one CTest test (tests/CMakeLists.txt). The Dask cases need
Debian's python3-dask and python3-distributed in the python3 that runs this.
"""

import collections
import json
import os
import shutil
import subprocess
import sys


def run(cmd, env=None, check=True):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, text=True)
    if check and p.returncode != 0:
        raise AssertionError("%s failed (%d):\n%s\n%s" % (" ".join(cmd), p.returncode, p.stdout, p.stderr))
    return p


def dump(d, level=0):
    pts = [tuple(map(int, l.split())) for l in open(os.path.join(d, "level-%d.points" % level))]
    simp = [tuple(map(int, l.split())) for l in open(os.path.join(d, "level-%d.simplices" % level))]
    return pts, simp


def check(cond, what):
    if not cond:
        raise AssertionError(what)
    print("ok:", what)


class Case:
    def __init__(self, hmc, work):
        self.hmc, self.work = hmc, work
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)

    def path(self, *p):
        return os.path.join(self.work, *p)

    def torus(self, n=8000):
        out = self.path("torus.ply")
        if not os.path.exists(out):
            run([self.hmc, "gen", "torus", "--vertices", str(n), "-o", out])
        return out

    def tile(self, out, *extra, env=None, check_rc=True):
        return run([self.hmc, "tile", self.torus(), "-o", self.path(out), "--tile-points", "600", "--workers", "2",
                    "--json"] + list(extra), env=env, check=check_rc)

    def untiled(self, *extra):
        run([self.hmc, "enc", self.torus(), "-o", self.path("whole.hmc")] + list(extra))
        run([self.hmc, "dec", self.path("whole.hmc"), "--canonical", self.path("whole-dump")])
        return self.path("whole-dump")


def case_points(c):
    """Merged points == the untiled stream's, exactly; same header lattice; no duplicate simplex."""
    r = c.tile("model", "--levels", "2")
    summary = json.loads(r.stdout)
    check(summary["tiles"] >= 12, "the torus is cut into many tiles (%d)" % summary["tiles"])
    run([c.hmc, "dec", c.path("model"), "--canonical", c.path("merged")])
    whole = c.untiled("--levels", "2")
    pts, simp = dump(c.path("merged"))
    wpts, _ = dump(whole)
    check(pts == wpts, "merged level-0 points == untiled stream's (%d points)" % len(pts))
    h, wh = (json.load(open(os.path.join(d, "header.json"))) for d in (c.path("merged"), whole))
    check(all(h[k] == wh[k] for k in ("kind", "q", "origin", "step")), "same kind, q, origin and step as untiled")
    check(len(set(simp)) == len(simp), "no simplex twice in the merged model (%d triangles)" % len(simp))
    check(h["levels"] == 2 and os.path.exists(c.path("merged", "level-1.points")), "both levels in the merged dump")
    info = json.loads(run([c.hmc, "info", c.path("model"), "--json"]).stdout)
    check(info["points"] == len(wpts) and info["tiles"] and len(info["tiles"]) == summary["tiles"], "hmc info: the index")


def case_closed(c):
    """A closed torus across 16 tiles: every merged edge in exactly two triangles, the untiled surface's triangles."""
    c.tile("model")
    run([c.hmc, "dec", c.path("model"), "--canonical", c.path("merged")])
    pts, simp = dump(c.path("merged"))
    edges = collections.Counter()
    for t in simp:
        for i in range(3):
            for j in range(i + 1, 3):
                edges[(t[i], t[j])] += 1
    mult = collections.Counter(edges.values())
    check(set(mult) == {2}, "every edge of the merged surface in exactly two triangles (%s)" % dict(mult))
    check(len(pts) - len(edges) + len(simp) == 0, "Euler characteristic 0 (a torus)")
    wpts, wsimp = dump(c.untiled("--fidelity", "exact"))
    as_points = lambda p, s: {frozenset(p[i] for i in t) for t in s}
    check(as_points(pts, simp) == as_points(wpts, wsimp), "the merged triangles are the untiled stream's (%d)" % len(simp))
    # Tiles really cross: many triangles' corners have different owners.
    index = json.load(open(c.path("model", "tiles.json")))
    def owner(p):
        for k, t in enumerate(index["tiles"]):
            b = t["box"]
            if all(b[a] <= p[a] < b[3 + a] for a in range(3)):
                return k
    crossing = sum(1 for t in simp if len({owner(pts[i]) for i in t}) > 1)
    check(crossing > 100, "%d triangles span two or more tiles" % crossing)


def case_kill(c):
    """A worker killed in the middle of a tile's job: the tile is retried, the output is the same bytes."""
    c.tile("reference")
    marker = c.path("killed")
    env = dict(os.environ, HMC_TILE_TEST_KILL="3:" + marker)
    r = c.tile("model", env=env)
    check(os.path.exists(marker), "tile 3's first attempt killed its worker")
    names = sorted(os.listdir(c.path("reference")))
    check(names == sorted(os.listdir(c.path("model"))), "the same files (%d)" % len(names))
    for n in names:
        with open(c.path("reference", n), "rb") as a, open(c.path("model", n), "rb") as b:
            check(a.read() == b.read(), n + " identical")
    check(json.loads(r.stdout)["tiles"] == len(names) - 1, "every tile in the index")


def case_atomic(c):
    """A tile job that always fails: no output, no temporary left behind; an earlier model is kept."""
    env = dict(os.environ, HMC_TILE_TEST_FAIL="2")
    r = c.tile("model", "--retries", "1", env=env, check_rc=False)
    check(r.returncode != 0, "hmc tile fails (exit %d)" % r.returncode)
    check("tile 2" in r.stderr, "the error names the tile")
    left = [n for n in os.listdir(c.work) if n.startswith("model")]
    check(left == [], "nothing named model* left in the directory (%s)" % left)
    c.tile("model")
    before = open(c.path("model", "tiles.json")).read()
    r = c.tile("model", "--retries", "0", env=env, check_rc=False)
    check(r.returncode != 0, "a second failing run fails too")
    check(open(c.path("model", "tiles.json")).read() == before, "the earlier model is untouched")
    check(sorted(n for n in os.listdir(c.work) if n.startswith("model")) == ["model"], "and no temporary is left")


def case_region(c):
    """A region query reads only the tiles it needs, and at a coarser level only their prefixes."""
    c.tile("model", "--levels", "3")
    index = json.load(open(c.path("model", "tiles.json")))
    total = sum(t["bytes"] for t in index["tiles"])
    full = json.loads(run([c.hmc, "dec", c.path("model"), "-o", c.path("all.ply"), "--json"]).stdout)
    check(full["tiles_read"] == len(index["tiles"]) and full["bytes_read"] == total, "decoding everything reads every byte")
    # The torus spans about [-1.35, 1.35] x [-1.35, 1.35] x [-0.35, 0.35]: one corner.
    r = run([c.hmc, "dec", c.path("model"), "--region", "0.8,0.8,-1,2,2,1", "-o", c.path("corner.ply"), "--json"])
    q = json.loads(r.stdout)
    check(0 < q["tiles_read"] < len(index["tiles"]) / 2, "the corner needs %d of %d tiles" % (q["tiles_read"], len(index["tiles"])))
    check(q["bytes_read"] < total / 2, "and %d of %d bytes" % (q["bytes_read"], total))
    check("tiles" in r.stderr and "bytes read" in r.stderr, "stderr reports tiles and bytes read")
    r = run([c.hmc, "dec", c.path("model"), "--region", "0.8,0.8,-1,2,2,1", "--level", "2", "--canonical",
             c.path("coarse"), "--json"])
    k = json.loads(r.stdout)
    prefix = sum(t["level_bytes"][2] for t in index["tiles"])  # upper bound: every tile's level-2 prefix
    check(k["tiles_read"] == q["tiles_read"] and k["bytes_read"] < q["bytes_read"],
          "level 2 reads only prefixes (%d < %d bytes)" % (k["bytes_read"], q["bytes_read"]))
    check(k["bytes_read"] <= prefix, "no more than the level-2 prefixes")
    pts, _ = dump(c.path("coarse"), 2)
    fpts, _ = dump(c.untiled(), 0)
    check(set(pts) <= set(fpts) and len(pts) < len(fpts) / 4, "level 2 of the corner: %d model points" % len(pts))


def case_pool(c):
    """The process pool (no Dask) writes the same model, byte for byte."""
    c.tile("dask", "--engine", "dask")
    c.tile("pool", "--engine", "pool")
    names = sorted(os.listdir(c.path("dask")))
    same = all(open(c.path("dask", n), "rb").read() == open(c.path("pool", n), "rb").read() for n in names)
    check(names == sorted(os.listdir(c.path("pool"))) and same, "Dask and the pool write identical files (%d)" % len(names))


def case_scheduler(c):
    """--scheduler ADDRESS: a running scheduler's own workers encode every tile, and the model is the local cluster's."""
    import socket
    import time
    py = os.environ.get("HMC_PYTHON", sys.executable)
    with socket.socket() as s:  # a free port
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = "tcp://127.0.0.1:%d" % port
    log = open(c.path("dask.log"), "w")
    procs = [subprocess.Popen([py, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", str(port),
                               "--no-dashboard", "--no-show"], stdout=log, stderr=log)]
    try:
        # Without a nanny each worker is the process started here, so its
        # pid is the one the tiles report.
        for k in range(2):
            procs.append(subprocess.Popen([py, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                                           "--no-nanny", "--no-dashboard", "--name", "hmc-test-%d" % k],
                                          stdout=log, stderr=log))
        from dask.distributed import Client
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
        r = c.tile("remote", "--scheduler", address)
        summary = json.loads(r.stdout)
        pids = {int(w.rsplit(":", 1)[1]) for w in summary["workers"]}
        ours = {p.pid for p in procs[1:]}
        check(pids <= ours and summary["tiles"] >= 12,
              "all %d tiles ran on the scheduler's two workers (pids %s of %s)" % (summary["tiles"], sorted(pids), sorted(ours)))
        check(sum(w["tiles"] for w in summary["workers"].values()) == summary["tiles"], "each tile once")
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
        log.close()
    c.tile("local")
    names = sorted(os.listdir(c.path("local")))
    same = all(open(c.path("local", n), "rb").read() == open(c.path("remote", n), "rb").read() for n in names)
    check(names == sorted(os.listdir(c.path("remote"))) and same,
          "the scheduler's model and the local cluster's are identical files (%d)" % len(names))


if __name__ == "__main__":
    hmc, work, name = sys.argv[1:4]
    globals()["case_" + name](Case(os.path.abspath(hmc), os.path.abspath(work)))
