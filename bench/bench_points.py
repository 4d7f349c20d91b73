#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Point-coding benchmark (not a test): bits per point of HMC on every
shared model at q = 12, beside the anchors of the brief, plus encode/decode
time and peak memory on 1 million generated points, with Draco's point-cloud
coder timed on the same points.

usage: bench/bench_points.py [--hmc build/bin/hmc] [--data ../shared/data]
                             [--out bench/results/points.md] [--repeat 3]
Prints a Markdown report and writes it to --out."""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

# Anchors (bits per point at q = 12, whole file) from issue 6 / the brief.
ANCHORS = {
    "stanford_bunny": (22.31, 19.47, 15.10, 12.09),
    "horse": (21.88, 16.87, 12.78, 11.17),
    "bimba": (22.95, 20.20, 17.47, 13.24),
    "cat_lowres": (24.49, 21.07, 18.78, 12.75),
    "skull": (21.83, 18.39, 16.80, 18.89),
    "rocker_arm": (24.15, 20.20, 18.95, 21.28),
    "fertility": (25.31, 22.98, 21.82, 23.19),
    "spot": (25.92, 24.21, 22.77, 19.90),
    "torus": (26.27, 22.03, 21.02, 11.47),
    "hand_tetgen": (22.62, 18.97, 17.90, None),
    "skull_tetgen": (23.23, 22.16, 21.01, None),
    "hand_libigl": (24.62, 21.26, 20.61, None),
    "bunny_libigl": (25.03, 24.33, 23.81, None),
}


def run(cmd):
    """Run a command; return (seconds, peak RSS in MiB, stdout)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out = p.stdout.read()
    err = p.stderr.read()
    _, status, ru = os.wait4(p.pid, 0)
    dt = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        sys.exit(f"bench: {' '.join(cmd)} failed ({p.returncode}): {err.decode(errors='replace')}")
    return dt, ru.ru_maxrss / 1024.0, out.decode()


def timed(cmd, repeat):
    """Median seconds and max peak memory over `repeat` runs; last stdout."""
    times, mems, out = [], [], ""
    for _ in range(repeat):
        dt, mem, out = run(cmd)
        times.append(dt)
        mems.append(mem)
    return statistics.median(times), max(mems), out


def models(data):
    found = []
    for sub in ("surface", "volume"):
        d = os.path.join(data, sub)
        if not os.path.isdir(d):
            continue
        for f in sorted(os.listdir(d)):
            stem, ext = os.path.splitext(f)
            if ext in (".obj", ".ply", ".off", ".mesh", ".node"):
                found.append((stem, os.path.join(d, f)))
    return found


def fmt(x):
    return "–" if x is None else f"{x:.2f}"


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(here)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hmc", default=os.path.join(root, "build", "bin", "hmc"))
    ap.add_argument("--data", default=os.path.join(root, "..", "shared", "data"))
    ap.add_argument("--out", default=os.path.join(here, "results", "points.md"))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--big", type=int, default=1000000, help="points in the generated speed test")
    a = ap.parse_args()

    tmp = tempfile.mkdtemp(prefix="hmc-bench-")
    lines = []
    say = lambda s="": (print(s), lines.append(s))
    say("# HMC point-coding benchmark")
    say()
    say(f"Command: `bench/bench_points.py --repeat {a.repeat}`, {time.strftime('%Y-%m-%d')}, "
        f"`hmc {run([a.hmc, 'version'])[2].split()[-1]}`, {os.cpu_count()} CPUs. "
        "Bits per point of the whole file at q = 12 over the de-duplicated quantized points; "
        "anchors from the brief (Draco and G-PCC measured with the public tools).")
    say()
    say("| model | points | HMC bpp | uniform bound | Draco PC | G-PCC | Draco mesh | HMC / G-PCC | enc ms | dec ms |")
    say("|---|---|---|---|---|---|---|---|---|---|")
    ratios = []
    for name, path in models(a.data):
        hmc_file = os.path.join(tmp, name + ".hmc")
        t_enc, _, out = timed([a.hmc, "enc", path, "-o", hmc_file, "--bits", "12", "--json"], a.repeat)
        rep = json.loads(out)
        t_dec, _, _ = timed([a.hmc, "dec", hmc_file], a.repeat)
        bpp = rep["bits_per_point"]
        anc = ANCHORS.get(name, (None, None, None, None))
        ratio = bpp / anc[2] if anc[2] else None
        if ratio:
            ratios.append(ratio)
        say(f"| {name} | {rep['distinct_points']:,} | {bpp:.2f} | {fmt(anc[0])} | {fmt(anc[1])} | {fmt(anc[2])} | "
            f"{fmt(anc[3])} | {fmt(ratio)} | {t_enc * 1000:.0f} | {t_dec * 1000:.0f} |")
    if ratios:
        say()
        say(f"Geometric mean of HMC / G-PCC: {statistics.geometric_mean(ratios):.3f} "
            "(below 1 means smaller than G-PCC). Encode/decode times are whole `hmc` runs "
            "(file reading and writing included), median of the repeats.")

    # Speed on 1M generated points.
    big_ply = os.path.join(tmp, "ball.obj")  # OBJ: both coders read it
    run([a.hmc, "gen", "ball", "--vertices", str(a.big), "--seed", "1", "-o", big_ply])
    big_hmc = os.path.join(tmp, "ball.hmc")
    t_enc, m_enc, out = timed([a.hmc, "enc", big_ply, "-o", big_hmc, "--bits", "12", "--json"], a.repeat)
    rep = json.loads(out)
    t_dec, m_dec, _ = timed([a.hmc, "dec", big_hmc, "-o", os.path.join(tmp, "ball-hmc.ply")], a.repeat)
    say()
    say(f"## {a.big:,} random points in a ball, q = 12")
    say()
    say("| coder | bits/point | encode s | encode peak MiB | decode s | decode peak MiB |")
    say("|---|---|---|---|---|---|")
    say(f"| HMC (points only) | {rep['bits_per_point']:.2f} | {t_enc:.3f} | {m_enc:.0f} | {t_dec:.3f} | {m_dec:.0f} |")
    if shutil.which("draco_encoder") and shutil.which("draco_decoder"):
        drc = os.path.join(tmp, "ball.drc")
        t_denc, m_denc, _ = timed(["draco_encoder", "-point_cloud", "-i", big_ply, "-o", drc, "-qp", "12", "-cl", "10"],
                                  a.repeat)
        t_ddec, m_ddec, _ = timed(["draco_decoder", "-i", drc, "-o", os.path.join(tmp, "ball-drc.ply")], a.repeat)
        bits = os.path.getsize(drc) * 8 / rep["distinct_points"]
        say(f"| Draco point cloud -qp 12 -cl 10 | {bits:.2f} | {t_denc:.3f} | {m_denc:.0f} | {t_ddec:.3f} | {m_ddec:.0f} |")
    say()
    say(f"Times are whole runs including reading the input ({os.path.getsize(big_ply) / 2**20:.0f} MiB OBJ) "
        "and, for decoding, writing a PLY; median of the repeats, peak = max RSS.")
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    with open(a.out, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
