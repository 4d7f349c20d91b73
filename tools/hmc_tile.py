#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""hmc tile: encode a model as a tiled model (spec/tiles.md) with one job per tile.

`hmc tile IN -o TILED` runs this script. It cuts the model with
`hmc tile-split` (C++: it reads every mesh format), encodes each tile with
`hmc enc --lattice` as an independent job on Dask (a LocalCluster of
--workers processes, or the scheduler at --scheduler), or on a
concurrent.futures process pool when Dask is not installed (or with
--engine pool), retries a tile whose job failed or whose worker died, and
writes the index tiles.json. Everything is written into a temporary
directory beside TILED, renamed into place only when every tile is done:
a failed run leaves no TILED behind.

With --scheduler, the workers must see the same file system paths (TILED's
parent directory and the hmc program) as this process.
"""

import argparse
import json
import os
import resource
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import uuid
import zlib

INDEX_VERSION = "0.1"


def _die_with_parent():
    """In the child: get SIGKILL when the job's process dies (Linux), so a
    killed worker leaves no orphaned encoder writing into the output."""
    try:
        import ctypes
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, int(signal.SIGKILL))  # PR_SET_PDEATHSIG
    except Exception:
        pass


def crc32_of(path):
    crc = 0
    with open(path, "rb") as f:
        while True:
            block = f.read(1 << 20)
            if not block:
                return crc & 0xFFFFFFFF
            crc = zlib.crc32(block, crc)


def encode_tile(job):
    """One tile: `hmc enc` on its input, on the model's lattice. Returns the
    index entry's figures. Runs on a worker (Dask or pool)."""
    t0 = time.time()
    cmd = [job["hmc"], "enc", job["input"], "-o", None, "--bits", str(job["q"]),
           "--lattice", ",".join("%.17g" % v for v in job["origin"] + [job["step"]]),
           "--kind", job["kind"], "--levels", str(job["levels"]), "--threads", "1", "--json"] + job["enc_args"]
    # Test hooks (tests/tiles_test.py): fail one tile's job every time, or
    # kill one tile's worker process in the middle of its first attempt.
    if os.environ.get("HMC_TILE_TEST_FAIL") == str(job["index"]):
        cmd += ["--ratio", "2"]  # refused by hmc enc: the job fails
    kill = os.environ.get("HMC_TILE_TEST_KILL", "")
    kill_now = False
    if kill.split(":", 1)[0] == str(job["index"]):
        marker = kill.split(":", 1)[1]
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            os.close(fd)
            kill_now = True
        except FileExistsError:
            pass
    part = job["output"] + ".part-" + uuid.uuid4().hex
    cmd[4] = part
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, preexec_fn=_die_with_parent)
    if kill_now:
        time.sleep(0.3)
        os.kill(os.getpid(), signal.SIGKILL)  # the worker dies mid-job; its encoder with it
    out, err = proc.communicate()
    if proc.returncode != 0:
        try:
            os.remove(part)
        except OSError:
            pass
        raise RuntimeError("tile %d: hmc enc exited with %d: %s" % (job["index"], proc.returncode,
                                                                     err.decode(errors="replace").strip()))
    report = json.loads(out)
    os.replace(part, job["output"])
    levels = sorted(report["levels"], key=lambda l: l["level"])  # finest first
    return {
        "index": job["index"],
        "levels": len(levels),
        "stream_points": [l["points"] for l in levels],
        "level_bytes": [l["stream_bytes"] for l in levels],
        "bytes": os.path.getsize(job["output"]),
        "crc32": "%08x" % crc32_of(job["output"]),
        "seconds": time.time() - t0,
        "worker": "%s:%d" % (socket.gethostname(), os.getpid()),
        # Peak resident memory of this worker process and of the largest
        # encoder it has run so far (KiB, Linux).
        "worker_rss_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss,
        "encoder_rss_kib": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss,
    }


def run_dask(jobs, args, progress):
    from dask.distributed import Client, LocalCluster, as_completed
    import logging
    cluster = None
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR)
        client = Client(cluster)
    try:
        token = uuid.uuid4().hex[:8]
        futures = [client.submit(encode_tile, j, key="hmc-tile-%05d-%s" % (j["index"], token), pure=False,
                                 retries=args.retries) for j in jobs]
        results = []
        for f in as_completed(futures):
            r = f.result()  # a job that failed retries+1 times, or killed too many workers, raises here
            results.append(r)
            progress(r)
        return results
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def run_pool(jobs, args, progress):
    import concurrent.futures as cf
    from concurrent.futures.process import BrokenProcessPool
    pending = {j["index"]: j for j in jobs}
    attempts = {j["index"]: 0 for j in jobs}
    results = []
    while pending:
        with cf.ProcessPoolExecutor(max_workers=args.workers) as pool:
            futures = {pool.submit(encode_tile, j): i for i, j in pending.items()}
            for f in cf.as_completed(futures):
                i = futures[f]
                try:
                    r = f.result()
                except BrokenProcessPool:
                    continue  # a worker died: every unfinished job is retried in a fresh pool
                except Exception:
                    attempts[i] += 1
                    if attempts[i] > args.retries:
                        raise
                    continue
                results.append(r)
                del pending[i]
                progress(r)
        for i in pending:  # jobs lost with a broken pool count as attempts too
            attempts[i] += 1
            if attempts[i] > args.retries + 3:
                raise RuntimeError("tile %d: its worker died %d times" % (i, attempts[i]))
    return results


def write_index(path, plan, tiles, levels):
    lines = ['{',
             '  "format": "hmc-tiles",',
             '  "version": "%s",' % INDEX_VERSION,
             '  "kind": "%s",' % plan["kind"],
             '  "q": %d,' % plan["q"],
             '  "origin": [%s],' % ", ".join("%.17g" % v for v in plan["origin"]),
             '  "step": %.17g,' % plan["step"],
             '  "margin": %d,' % plan["margin"],
             '  "levels": %d,' % levels,
             '  "points": %d,' % plan["points"],
             '  "tiles": [']
    for k, t in enumerate(tiles):
        entry = json.dumps({key: t[key] for key in ("file", "box", "bounds", "points", "levels", "stream_points",
                                                    "level_bytes", "bytes", "crc32")})
        lines.append("    " + entry + ("," if k + 1 < len(tiles) else ""))
    lines += ["  ]", "}", ""]
    with open(path, "w") as f:
        f.write("\n".join(lines))
        f.flush()
        os.fsync(f.fileno())


def main(argv):
    p = argparse.ArgumentParser(prog="hmc tile", description="Encode IN as a tiled model TILED (spec/tiles.md).")
    p.add_argument("input", metavar="IN")
    p.add_argument("-o", "--output", required=True, metavar="TILED", help="the tiled model's directory")
    p.add_argument("--tile-points", type=int, default=200000, help="at most N points owned per tile (default 200000)")
    p.add_argument("--levels", type=int, default=1, help="levels of detail per tile (default 1)")
    p.add_argument("--bits", type=int, default=12, help="q of the model's one lattice (default 12)")
    p.add_argument("--kind", default="auto", choices=["auto", "points", "surface", "volume"])
    p.add_argument("--margin", type=int, default=None, help="margin in lattice units (default: 4 mean edge lengths)")
    p.add_argument("--fidelity", default="exact", choices=["rule", "topology", "shape", "exact"],
                   help="per tile (default exact: tiles then agree at their borders, where shape leaves "
                        "flat flips to each tile's own rule)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS", help="a Dask scheduler (default: a LocalCluster)")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster or pool workers (default 2)")
    p.add_argument("--retries", type=int, default=2, help="retries of a failed tile job (default 2)")
    p.add_argument("--engine", default="auto", choices=["auto", "dask", "pool"],
                   help="dask, a process pool, or auto: Dask when installed (default)")
    p.add_argument("--json", action="store_true", help="print a summary as JSON on stdout")
    p.add_argument("--hmc", default="hmc", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.workers < 1 or args.tile_points < 16 or not 1 <= args.levels <= 64 or args.retries < 0:
        p.error("--workers >= 1, --tile-points >= 16, --levels 1..64, --retries >= 0")

    engine = args.engine
    if engine == "auto":
        try:
            import dask.distributed  # noqa: F401
            engine = "dask"
        except ImportError:
            engine = "pool"
            if args.scheduler:
                p.error("--scheduler needs Dask (python3-distributed), which this python3 lacks")

    # SIGTERM (a killed job, a cancelled batch run) unwinds like an error:
    # the temporary directory is removed and no output appears.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    out = os.path.abspath(args.output)
    if os.path.exists(out) and not os.path.isfile(os.path.join(out, "tiles.json")):
        print("hmc tile: %s exists and is not a tiled model; not replacing it" % args.output, file=sys.stderr)
        return 4
    parent = os.path.dirname(out)
    try:
        tmp = tempfile.mkdtemp(prefix=os.path.basename(out) + ".tmp-", dir=parent)
    except OSError as e:
        print("hmc tile: cannot create a directory in %s: %s" % (parent, e), file=sys.stderr)
        return 4
    t_start = time.time()
    try:
        work = os.path.join(tmp, "work")
        split = [args.hmc, "tile-split", args.input, "-o", work, "--tile-points", str(args.tile_points),
                 "--bits", str(args.bits), "--kind", args.kind]
        if args.margin is not None:
            split += ["--margin", str(args.margin)]
        rc = subprocess.call(split)
        if rc != 0:
            return rc
        t_split = time.time()
        with open(os.path.join(work, "plan.json")) as f:
            plan = json.load(f)
        jobs = [{"index": i, "hmc": args.hmc, "input": os.path.join(work, t["input"]),
                 "output": os.path.join(tmp, t["file"]), "q": plan["q"], "origin": plan["origin"],
                 "step": plan["step"], "kind": plan["kind"], "levels": args.levels,
                 "enc_args": ["--fidelity", args.fidelity,
                              "--seal-box", ",".join(str(b) for b in t["box"]),
                              "--tolerance-diagonal", "%.17g" % plan["diagonal"]]} for i, t in enumerate(plan["tiles"])]
        done = [0]

        def progress(r):
            done[0] += 1
            t = plan["tiles"][r["index"]]
            print("hmc tile: %d/%d %s: %d points (%d with margin), %d bytes, %.1f s on %s" %
                  (done[0], len(jobs), t["file"], t["points"], t["input_points"], r["bytes"], r["seconds"],
                   r["worker"]), file=sys.stderr, flush=True)

        print("hmc tile: encoding %d tiles on %s (%s)" %
              (len(jobs), engine, args.scheduler or "%d local workers" % args.workers), file=sys.stderr, flush=True)
        results = (run_dask if engine == "dask" else run_pool)(jobs, args, progress)
        t_enc = time.time()
        by_index = {r["index"]: r for r in results}
        tiles = []
        for i, t in enumerate(plan["tiles"]):
            r = by_index[i]
            tiles.append(dict(t, **{k: r[k] for k in ("levels", "stream_points", "level_bytes", "bytes", "crc32")}))
        levels = min(t["levels"] for t in tiles)
        shutil.rmtree(work)
        for name in os.listdir(tmp):  # parts left by killed attempts
            if ".part-" in name:
                os.remove(os.path.join(tmp, name))
        write_index(os.path.join(tmp, "tiles.json"), plan, tiles, levels)
        if os.path.exists(out):  # replacing an earlier tiled model
            old = tempfile.mkdtemp(prefix=os.path.basename(out) + ".old-", dir=parent)
            os.rename(out, os.path.join(old, "model"))
            os.rename(tmp, out)
            shutil.rmtree(old)
        else:
            os.rename(tmp, out)
        tmp = None
        total = sum(t["bytes"] for t in tiles) + os.path.getsize(os.path.join(out, "tiles.json"))
        workers = {}
        for r in results:
            w = workers.setdefault(r["worker"], {"tiles": 0, "worker_rss_kib": 0, "encoder_rss_kib": 0})
            w["tiles"] += 1
            w["worker_rss_kib"] = max(w["worker_rss_kib"], r["worker_rss_kib"])
            w["encoder_rss_kib"] = max(w["encoder_rss_kib"], r["encoder_rss_kib"])
        summary = {"output": args.output, "engine": engine, "tiles": len(tiles), "points": plan["points"],
                   "margin": plan["margin"], "levels": levels,
                   "stream_points": sum(t["stream_points"][0] for t in tiles),
                   "bytes": total, "bits_per_point": 8.0 * total / plan["points"],
                   "split_seconds": t_split - t_start, "encode_seconds": t_enc - t_split,
                   "wall_seconds": time.time() - t_start, "workers": workers}
        print("hmc tile: %s: %d tiles, %d points, %d bytes (%.3f bits per point), %.1f s" %
              (args.output, len(tiles), plan["points"], total, summary["bits_per_point"], summary["wall_seconds"]),
              file=sys.stderr)
        if args.json:
            print(json.dumps(summary, indent=2))
        return 0
    except Exception as e:  # noqa: BLE001 - any failure: report it, leave nothing behind
        print("hmc tile: failed: %s" % e, file=sys.stderr)
        return 70 if not isinstance(e, (OSError,)) else 4
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
