#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""WebAssembly against native decoding (issue 51): each shared model encoded
at 4 levels with the native `hmc enc`, then decoded (all levels, connectivity
rebuilt, one thread) by the native decoder (`hmc dec --json --threads 1`,
its in-process decode_seconds) and by web/dist's module in Node
(bench/wasm_time.mjs, in-process, module load excluded), alternating, RUNS
times each; medians and their ratio, the per-level counts checked equal;
then the .wasm and JS sizes, gzip-compressed. Writes bench/results/wasm.md.

    scripts/web.sh && python3 bench/wasm.py [--hmc build/bin/hmc] [--models bunny,horse] [--runs 3]
"""
import argparse
import gzip
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def compression_module():
    spec = importlib.util.spec_from_file_location("compression", os.path.join(ROOT, "bench", "compression.py"))
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--hmc", default=os.path.join(ROOT, "build", "bin", "hmc"))
    ap.add_argument("--data", default=os.path.join(ROOT, "..", "shared", "data"))
    ap.add_argument("--models", help="comma-separated substrings: only these models")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "wasm.md"))
    a = ap.parse_args()
    for f in ("hmc.wasm", "hmc.mjs"):
        if not os.path.exists(os.path.join(ROOT, "web", "dist", f)):
            sys.exit(f"bench/wasm.py: web/dist/{f} is missing: run scripts/web.sh first")
    models = compression_module().find_models(a.data, a.models)
    if not models:
        sys.exit("bench/wasm.py: no models found")
    tmp = tempfile.mkdtemp(prefix="hmc-wasm-")
    rows = []
    for name, path in models:
        h = os.path.join(tmp, name + ".hmc")
        subprocess.run([a.hmc, "enc", path, "-o", h, "--levels", "4"], check=True, capture_output=True)
        native, wasm, cold, counts_n, counts_w = [], [], [], None, None
        for _ in range(a.runs):  # alternating, so that the machine's drift hits both
            j = json.loads(subprocess.run([a.hmc, "dec", h, "--json", "--threads", "1"], check=True,
                                          capture_output=True, text=True).stdout)
            native.append(j["decode_seconds"])
            counts_n = [[l["level"], l["points"], l["triangles"], l["tetrahedra"]] for l in j["levels"]]
            # Two decodes per process: the first runs while V8 still tiers the
            # module up (what a page's first decode pays), the second warm.
            w = json.loads(subprocess.run(["node", os.path.join(ROOT, "bench", "wasm_time.mjs"), "2", h],
                                          check=True, capture_output=True, text=True).stdout)
            cold.append(w["seconds"][0])
            wasm.append(w["seconds"][1])
            counts_w = w["counts"]
        same = sorted(map(tuple, counts_n)) == sorted(map(tuple, counts_w))
        points = max(c[1] for c in counts_n)
        rows.append((name, points, os.path.getsize(h), statistics.median(native), statistics.median(wasm), same,
                     statistics.median(cold)))
        print(f"{name}: {points} points, native {rows[-1][3]:.3f} s, wasm {rows[-1][4]:.3f} s "
              f"(first decode {rows[-1][6]:.3f} s), ratio {rows[-1][4] / rows[-1][3]:.2f}, "
              f"counts {'equal' if same else 'DIFFER'}", flush=True)
    sizes = {f: (os.path.getsize(os.path.join(ROOT, "web", "dist", f)),
                 len(gzip.compress(open(os.path.join(ROOT, "web", "dist", f), "rb").read(), 9)))
             for f in ("hmc.wasm", "hmc.mjs")}
    idx = os.path.join(ROOT, "web", "src", "index.mjs")
    sizes["src/index.mjs"] = (os.path.getsize(idx), len(gzip.compress(open(idx, "rb").read(), 9)))
    ratios = [r[4] / r[3] for r in rows]
    gm = statistics.geometric_mean(ratios)
    gm_cold = statistics.geometric_mean([r[6] / r[3] for r in rows])
    head = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    node = subprocess.run(["node", "--version"], capture_output=True, text=True).stdout.strip()
    with open(a.out, "w") as o:
        o.write("# WebAssembly against native decoding (issue 51)\n\n")
        o.write(f"Regenerate: `scripts/web.sh && python3 bench/wasm.py --runs {a.runs}` (tree {head}, Node {node}). "
                "Each model encoded at 4 levels by the native `hmc enc`; decoded with every level's connectivity "
                "rebuilt, one thread, in-process times (native: `hmc dec --json --threads 1`'s decode_seconds; "
                "WebAssembly: `decode()` of web/src/index.mjs in Node, module load excluded, the second decode of the process; the first, while V8 still "
                "optimizes the module, in its own column), medians of "
                f"{a.runs} alternating runs. Bar: WebAssembly at most 2 times native.\n\n")
        o.write("| model | points | stream bytes | native s | WebAssembly s | ratio | first decode s | ratio | levels' counts |\n")
        o.write("|---|---:|---:|---:|---:|---:|---:|---:|---|\n")
        for name, points, size, n, w, same, c in rows:
            o.write(f"| {name} | {points} | {size} | {n:.3f} | {w:.3f} | {w / n:.2f} | {c:.3f} | {c / n:.2f} | "
                    f"{'equal' if same else 'DIFFER'} |\n")
        o.write(f"\nGeometric mean of the ratios: **{gm:.2f}** over {len(rows)} models "
                f"({sum(r <= 2 for r in ratios)}/{len(rows)} at most 2); first decodes {gm_cold:.2f}.\n\n")
        o.write("| file | bytes | gzip -9 |\n|---|---:|---:|\n")
        for f, (raw, gz) in sizes.items():
            o.write(f"| {f} | {raw} | {gz} |\n")
        total = sum(gz for _, gz in sizes.values())
        o.write(f"\nTotal gzip-compressed: {total} bytes (aim: under 400 KB).\n")
    print(f"geometric mean ratio {gm:.2f}; wrote {a.out}")


if __name__ == "__main__":
    main()
