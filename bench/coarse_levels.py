#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Coarse levels that look like the model (issue 53, Deliver 2): every level
of a 4-level stream of each shared model against the input surface (a
volume's boundary), encoded with the default options and with
`--fit-coarse` (EncodeOptions::fit_coarse_levels), through
`bench/fidelity MODEL --levels 4 --per-level [--fit-coarse]`.

Writes bench/results/coarse_levels.md.

usage: bench/coarse_levels.py [--fidelity build/bench/fidelity] [--data ../shared/data]
                              [--out bench/results/coarse_levels.md] [--jobs 2]
"""
import argparse, concurrent.futures, json, math, os, subprocess, time

ap = argparse.ArgumentParser()
ap.add_argument('--fidelity', default='build/bench/fidelity')
ap.add_argument('--data', default='../shared/data')
ap.add_argument('--out', default='bench/results/coarse_levels.md')
ap.add_argument('--jobs', type=int, default=2)
args = ap.parse_args()

surf = sorted(os.listdir(os.path.join(args.data, 'surface')))
models = ['surface/' + f for f in surf] + ['volume/bunny_libigl.mesh', 'volume/hand_libigl.mesh',
                                          'volume/hand_tetgen.node', 'volume/skull_tetgen.node']

def run(m, fit):
    cmd = [args.fidelity, os.path.join(args.data, m), '--levels', '4', '--per-level'] + (['--fit-coarse'] if fit else [])
    return json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)

t0 = time.time()
with concurrent.futures.ThreadPoolExecutor(args.jobs) as ex:
    res = {(m, fit): ex.submit(run, m, fit) for m in models for fit in (False, True)}
    res = {k: v.result() for k, v in res.items()}

def name(m): return os.path.basename(m).split('.')[0]
def topo(r): return r['input_topology'] if 'input_topology' in r else r['input_boundary_topology']

L = ['# Coarse levels that look like the model (issue 53)', '',
     f'Regenerate: `/usr/bin/python3 bench/coarse_levels.py --fidelity build/bench/fidelity` ({time.time() - t0:.0f} s, '
     f'{args.jobs} at a time; {time.strftime("%Y-%m-%d", time.gmtime())}). Each model encoded at 4 levels, q = 12, '
     'default options (`shape` fidelity), then again with `--fit-coarse`; every decoded level compared with the '
     'input surface (a volume\'s boundary) on the grid: symmetric Hausdorff distance sampled at vertices, edge '
     'midpoints and centroids, as % of the bounding-box diagonal; components and Euler characteristic of the '
     'level\'s triangles (a volume\'s boundary triangles); *side*: the level\'s `RCON` bytes with framing.', '',
     '## Summary', '',
     '| model | input comp / χ | bytes default | bytes fit | ratio | worst coarse-level Hausdorff % default | fit | coarse levels with the input\'s comp and χ, default | fit |',
     '|---|---|---:|---:|---:|---:|---:|---|---|']
ratios = []
for m in models:
    d, f = res[(m, False)], res[(m, True)]
    ti = topo(d)
    def worst(r): return max(l['hausdorff_pct_diag'] for l in r['per_level'] if l['lod'] > 0)
    def same(r):
        c = [l for l in r['per_level'] if l['lod'] > 0]
        return f"{sum(l['topology']['components'] == ti['components'] and l['topology']['euler'] == ti['euler'] for l in c)}/{len(c)}"
    ratios.append(f['bytes'] / d['bytes'])
    L.append(f"| {name(m)} | {ti['components']} / {ti['euler']} | {d['bytes']} | {f['bytes']} | {f['bytes'] / d['bytes']:.3f} | "
             f"{worst(d):.2f} | {worst(f):.2f} | {same(d)} | {same(f)} |")
gm = math.exp(sum(map(math.log, ratios)) / len(ratios))
L += ['', f'Geometric mean of the byte ratios: **{gm:.3f}** (min {min(ratios):.3f}, max {max(ratios):.3f}).', '',
      '## Per level', '',
      '| model | mode | level | points (%) | prefix bytes | side bytes | Hausdorff % (out→in / in→out) | comp | χ | border e. | non-manifold e. |',
      '|---|---|---:|---:|---:|---:|---|---:|---:|---:|---:|']
for m in models:
    for fit in (False, True):
        for l in res[(m, fit)]['per_level']:
            t = l['topology']
            L.append(f"| {name(m)} | {'fit' if fit else 'default'} | {l['lod']} | {l['points']} ({l['points_pct']:.1f}) | "
                     f"{l['stream_bytes']} | {l['side_bytes']} | {l['hausdorff_pct_diag']:.3f} ({l['hausdorff_out_to_in_pct']:.3f} / "
                     f"{l['hausdorff_in_to_out_pct']:.3f}) | {t['components']} | {t['euler']} | {t['border_edges']} | {t['nonmanifold_edges']} |")
open(args.out, 'w').write('\n'.join(L) + '\n')
print('\n'.join(L[:len(models) + 12]))
