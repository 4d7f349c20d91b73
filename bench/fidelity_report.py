#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Reconstruction fidelity report (issue 3): every shared model at q = 12,
decoded at its finest level, compared with the input's own connectivity, at
each encoder fidelity setting. Writes bench/results/fidelity.md.

usage: bench/fidelity_report.py [--fidelity-bin build/bench/fidelity] [--data ../shared/data]"""
import argparse
import json
import os
import subprocess
import sys
import time


def surface_verdict(r):
    """Issue 3's bars for a closed surface; returns the list of misses."""
    i, o = r["input_topology"], r["output_topology"]
    miss = []
    if r["reproduced_pct_of_ceiling"] < 97:
        miss.append(f"reproduces {r['reproduced_pct_of_ceiling']:.2f}% of the ceiling (bar 97%)")
    if o["nonmanifold_edges"]:
        miss.append(f"{o['nonmanifold_edges']} non-manifold edges")
    if o["border_edges"]:
        miss.append(f"{o['border_edges']} border edges")
    if (o["components"], o["euler"]) != (i["components"], i["euler"]):
        miss.append(f"components/Euler {o['components']}/{o['euler']}, input {i['components']}/{i['euler']}")
    if r["hausdorff_pct_diag"] > 0.5:
        miss.append(f"Hausdorff {r['hausdorff_pct_diag']:.3f}% (bar 0.5%)")
    return miss


def volume_verdict(r):
    """Issue 3's bars for a volume; returns the list of misses."""
    miss = []
    if r["reproduced_pct_of_ceiling"] < 97:
        miss.append(f"reproduces {r['reproduced_pct_of_ceiling']:.2f}% of the ceiling (bar 97%)")
    if r["boundary_vertices_missing"]:
        miss.append(f"{r['boundary_vertices_missing']} boundary vertices off the boundary")
    if r["boundary_hausdorff_pct_diag"] > 0.5:
        miss.append(f"boundary Hausdorff {r['boundary_hausdorff_pct_diag']:.3f}% (bar 0.5%)")
    if abs(r["volume_ratio"] - 1) > 0.01:
        miss.append(f"volume ratio {r['volume_ratio']:.4f} (bar within 1%)")
    return miss


def goals_section(rows):
    """The bars of issue 3, checked row by row for the default and exact modes."""
    L = ["## Against the goals", ""]
    L.append("Closed surfaces: at least 97% of the ceiling, no border or non-manifold edge, the input's "
             "components and Euler characteristic, Hausdorff at most 0.5% of the diagonal. Volumes: at least "
             "97% of the ceiling, every boundary vertex on the decoded boundary, boundary Hausdorff at most "
             "0.5%, volume within 1%. Open surfaces (border edges in the input) are listed apart: their "
             "bars are not stated.")
    L.append("")
    L.append("| model | kind | `shape` (default) | `exact` |")
    L.append("|---|---|---|---|")
    by = {}
    for r in rows:
        by.setdefault(r["name"], {})[r["fidelity"]] = r
    met = {"shape": 0, "exact": 0}
    counted = 0
    for name, modes in by.items():
        any_row = next(iter(modes.values()))
        if any_row["kind"] == "surface" and any_row["input_topology"]["border_edges"]:
            kind = "open surface"
            verdict = surface_verdict
        else:
            kind = any_row["kind"]
            verdict = surface_verdict if kind == "surface" else volume_verdict
        cells = []
        for mode in ("shape", "exact"):
            if mode not in modes:
                cells.append("–")
                continue
            miss = verdict(modes[mode])
            if kind != "open surface" and not miss:
                met[mode] += 1
            cells.append("met" if not miss else "; ".join(miss))
        counted += kind != "open surface"
        L.append(f"| {name} | {kind} | {cells[0]} | {cells[1]} |")
    L.append("")
    L.append(f"All bars met: `shape` on {met['shape']} of {counted} closed surfaces and volumes, `exact` on "
             f"{met['exact']} of {counted}.")
    L.append("")
    L.append("Why it falls short (observations as of the run above; the figures are in the tables):")
    L.append("")
    L.append("- *Share below 97% with `shape`* (fertility, spot, torus): `shape` leaves mismatched tetrahedra "
             "thinner than 0.1% of the diagonal to the rule, i.e. the other diagonal of a nearly planar quad. "
             "The surface has the same shape (see the Hausdorff column) but other triangles; `exact` corrects "
             "them at the side-information cost shown. On the torus every quad is cocircular in the input, so "
             "both diagonals are Delaunay and the rule picks the other one about half the time.")
    L.append("- *`topology`* is not held to these bars: it gives up input triangles (flat flips, the other "
             "diagonal of a nearly planar quad) for less side information, at the same components and Euler "
             "characteristic as `shape` on the closed surfaces. Where the flat flips `shape` leaves would "
             "change the topology (horse, skull, rocker_arm), `shape` corrects every mismatch and so is "
             "nearly `exact`; `topology` corrects only the groups of flat flips whose correction changes the "
             "Euler characteristic.")
    L.append("- *Topology with `exact`* (horse, skull): where input triangles are missing from the Delaunay "
             "(the ceiling), the input's inside/outside labels (winding number) pinch or leave non-manifold "
             "edges; `exact` reproduces them, `shape` mends them by flipping short tetrahedra around the "
             "defects, aiming at the input's components and Euler characteristic.")
    L.append("- *skull with `shape`*: a quarter of its triangles are not Delaunay; the mended surface is "
             "manifold but one handle short of the input's genus.")
    L.append("- *stanford_bunny* (open): the border list and hole drops reproduce the input's holes only in "
             "part; there is no topology target for open surfaces yet. `shape` mends the edges with more than "
             "two faces by the repair's search alone (every flip keeps the Euler characteristic), `exact` "
             "keeps them. Open *sheets* (not among these models): the winding number is about 1/2 in size on "
             "both sides of a sheet, so its magnitude leaves most labels open (99% of a height field's "
             "tetrahedra, 0.4% of this bunny's); the encoder then also plans the surface read as a sheet "
             "(signed winding number above 1/10) and keeps the reading that sends less side information. A "
             "generated 1,600-point height field at q = 12 with `shape`: 78% -> 95% of its ceiling, 900 -> 166 "
             "border edges (input 156), 98 -> 28 non-manifold edges, side information 13.5 -> 7.9 bits per "
             "point; still 10 components where the input has one, and 2.8% of the diagonal Hausdorff. A "
             "reconstruction that sends a sheet's faces rather than a solid's boundary would need a new "
             "`RCON` form.")
    L.append("- *bunny_libigl*: 337 of its 5,433 points on the boundary, so its boundary tetrahedra are large "
             "and thin. Until 2026-11-25 the encoder turned the boundary faces outward by the tetrahedra's "
             "orientation on the grid, where rounding flattens or inverts thin ones: 22 of 670 faces faced "
             "inward, the winding numbers were 0.62 instead of 1 at 5% of the diagonal inside, and the boundary "
             "came back 4–7% of the diagonal away with a handle (Euler 0 or -1). Turned by the input's own "
             "coordinates, `exact` gives back the solid (boundary Hausdorff 0.008%); `shape` stays 0.77% away, "
             "where it leaves thin mismatched tetrahedra to the rule.")
    L.append("")
    return L


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(here)
    ap = argparse.ArgumentParser()
    ap.add_argument("--fidelity-bin", default=os.path.join(root, "build", "bench", "fidelity"))
    ap.add_argument("--data", default=os.path.join(root, "..", "shared", "data"))
    ap.add_argument("--out", default=None, help="default bench/results/fidelity.md")
    ap.add_argument("--modes", default="rule,topology,shape,exact")
    ap.add_argument("--models", default="", help="comma-separated substrings of model names")
    ap.add_argument("--replot", action="store_true", help="rewrite the report from its .jsonl without running")
    a = ap.parse_args()
    models = []
    for sub in ("surface", "volume"):
        d = os.path.join(a.data, sub)
        for f in sorted(os.listdir(d)):
            if os.path.splitext(f)[1] in (".obj", ".ply", ".off", ".mesh", ".node"):
                if not a.models or any(w in f for w in a.models.split(",")):
                    models.append(os.path.join(d, f))
    a.out = a.out or os.path.join(here, "results", "fidelity.md")
    rows = []
    if a.replot:
        with open(os.path.splitext(a.out)[0] + ".jsonl") as f:
            rows = [json.loads(line) for line in f if line.strip()]
        models = []
    for m in models:
        for mode in a.modes.split(","):
            out = subprocess.run([a.fidelity_bin, m, "--fidelity", mode], capture_output=True, text=True)
            if out.returncode != 0:
                sys.exit(f"fidelity failed on {m}: {out.stderr}")
            r = json.loads(out.stdout)
            r["name"] = os.path.splitext(os.path.basename(m))[0]
            rows.append(r)
            print(r["name"], mode, file=sys.stderr)

    L = []
    L.append("# Reconstruction fidelity")
    L.append("")
    L.append(f"Produced by `bench/fidelity_report.py` on {time.strftime('%Y-%m-%d')} (q = 12, finest level). "
             "Each model is quantized, its Delaunay tetrahedralization labelled by the decoder's rule with the "
             "side information the encoder chose, and the result compared with the input's own triangles "
             "(surfaces) or tetrahedra (volumes). *Ceiling*: share of input simplices that are simplices of the "
             "Delaunay tetrahedralization of the quantized points; no reconstruction from vertices can keep "
             "the others. *Reproduced*: share of the ceiling present in the output. *Side*: the `RCON` chunk "
             "(alpha classes, border list, label toggles) in bits per point. Fidelity settings: `rule` sends "
             "only the rule's parameters; `shape` (the default) also corrects every label that changes the "
             "shape, the manifoldness or the vertex set, and every mismatch where the flat ones it leaves "
             "would change the topology; `topology` corrects what `shape` does but leaves flat flips to the "
             "rule wherever they keep the topology (correcting only the groups of them that change the Euler "
             "characteristic); `exact` corrects every label.")
    L.append("")
    L.append("## Surfaces")
    L.append("")
    L.append("| model | mode | points | ceiling % | reproduced % | extra triangles | Hausdorff % diag | border e. in/out | non-manifold e. | components in/out | Euler in/out | side bits/pt |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if r["kind"] != "surface":
            continue
        i, o = r["input_topology"], r["output_topology"]
        L.append(f"| {r['name']} | {r['fidelity']} | {r['points']:,} | {r['ceiling_pct']:.2f} | {r['reproduced_pct_of_ceiling']:.2f} | "
                 f"{r['extra']:,} | {r['hausdorff_pct_diag']:.3f} | {i['border_edges']}/{o['border_edges']} | "
                 f"{o['nonmanifold_edges']} | {i['components']}/{o['components']} | {i['euler']}/{o['euler']} | {r['rcon_bits_per_point']:.2f} |")
    L.append("")
    L.append("## Volumes")
    L.append("")
    L.append("| model | mode | points | ceiling % | reproduced % | extra tets | volume ratio | boundary vertices missing | boundary Hausdorff % diag | boundary non-manifold e. | Euler in/out | side bits/pt |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        if r["kind"] != "volume":
            continue
        i, o = r["input_boundary_topology"], r["output_boundary_topology"]
        L.append(f"| {r['name']} | {r['fidelity']} | {r['points']:,} | {r['ceiling_pct']:.2f} | {r['reproduced_pct_of_ceiling']:.2f} | "
                 f"{r['extra']:,} | {r['volume_ratio']:.4f} | {r['boundary_vertices_missing']} of {r['boundary_vertices']:,} | "
                 f"{r['boundary_hausdorff_pct_diag']:.3f} | {o['nonmanifold_edges']} | {i['euler']}/{o['euler']} | {r['rcon_bits_per_point']:.2f} |")
    L.append("")
    L += goals_section(rows)
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    with open(a.out, "w") as f:
        f.write("\n".join(L) + "\n")
    with open(os.path.splitext(a.out)[0] + ".jsonl", "w") as f:
        for r in rows:
            f.write(json.dumps(r) + "\n")
    print("\n".join(L))


if __name__ == "__main__":
    main()
