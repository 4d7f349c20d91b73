#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""A preview that arrives first (issue 53): levels of octree cells below the
independent-set levels (EncodeOptions::preview_ratio, `hmc enc --preview-ratio R`)
against the independent-set hierarchy alone, on the 13 shared models.

Configurations, each through `bench/fidelity MODEL --levels L --per-level ...`
(every decoded level against the input surface, a volume's boundary):
  1L        --levels 1 --preview-ratio 0           the 1-level stream, the size base
  IS4       --levels 4 --preview-ratio 0           4 levels of independent sets (the thesis')
  IS4+fit   --levels 4 --preview-ratio 0 --fit-coarse   the same, coarser levels fitted
  cells     --levels 1 --preview-ratio R           the default: octree-cell levels (fitted)
                                             down to R of the points
  IS2+cells --levels 2 --preview-ratio R           one independent-set level, then cells

Writes bench/results/preview.md and, with --pictures, renderings of the
decoded levels of two models (bench/results/preview/*.png, numpy and
matplotlib needed, through bench/hierarchy_report.py's drawing).

usage: bench/preview.py [--build build] [--data ../shared/data] [--ratio 0.04]
                        [--jobs 2] [--pictures] [--out bench/results/preview.md]
"""
import argparse, concurrent.futures, json, math, os, subprocess, sys, tempfile, time

ap = argparse.ArgumentParser()
ap.add_argument('--build', default='build')
ap.add_argument('--data', default='../shared/data')
ap.add_argument('--ratio', default='0.04')
ap.add_argument('--jobs', type=int, default=2)
ap.add_argument('--pictures', action='store_true')
ap.add_argument('--out', default='bench/results/preview.md')
args = ap.parse_args()
fidelity = os.path.join(args.build, 'bench', 'fidelity')
hmc = os.path.join(args.build, 'bin', 'hmc')

surf = sorted(os.listdir(os.path.join(args.data, 'surface')))
models = ['surface/' + f for f in surf] + ['volume/bunny_libigl.mesh', 'volume/hand_libigl.mesh',
                                          'volume/hand_tetgen.node', 'volume/skull_tetgen.node']
R = args.ratio
CONFIGS = {'1L': ['--levels', '1', '--preview-ratio', '0'], 'IS4': ['--levels', '4', '--preview-ratio', '0'],
           'IS4+fit': ['--levels', '4', '--preview-ratio', '0', '--fit-coarse'],
           'cells': ['--levels', '1', '--preview-ratio', R], 'IS2+cells': ['--levels', '2', '--preview-ratio', R]}


def run(m, cfg):
    cmd = [fidelity, os.path.join(args.data, m), '--per-level'] + CONFIGS[cfg]
    return json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)


t0 = time.time()
with concurrent.futures.ThreadPoolExecutor(args.jobs) as ex:
    res = {(m, c): ex.submit(run, m, c) for m in models for c in CONFIGS}
    res = {k: v.result() for k, v in res.items()}
elapsed = time.time() - t0


def name(m): return os.path.basename(m).split('.')[0]
def gmean(xs): return math.exp(sum(map(math.log, xs)) / len(xs))
def topo_in(r): return r['input_topology'] if 'input_topology' in r else r['input_boundary_topology']


def coarsest(r):
    return max(r['per_level'], key=lambda l: l['lod'])


L = ['# A preview that arrives first (issue 53)', '',
     f'Regenerate: `/usr/bin/python3 bench/preview.py --build build --ratio {R}{" --pictures" if args.pictures else ""}` '
     f'({elapsed:.0f} s, {args.jobs} at a time, {time.strftime("%Y-%m-%d", time.gmtime())}). q = 12, `shape` fidelity. '
     'Configurations: **1L** `--levels 1 --preview-ratio 0` (the size base); **IS4** `--levels 4 --preview-ratio 0`, four levels of '
     'independent sets (the thesis\' hierarchy, `hmc enc --levels 4`); **IS4+fit** the same with '
     '`--fit-coarse` (coarser levels corrected towards the input); **cells** `--levels 1 --preview-ratio ' + R + '`, the '
     'default: below the finest level, levels of one point per occupied octree cell (the point nearest the cell\'s '
     'centre) at the finest depth whose cells are at most half the level\'s points, until a level holds at most '
     f'{R} of the points, their reconstruction corrected towards the input surface clustered onto their points; '
     '**IS2+cells** `--levels 2 --preview-ratio ' + R + '`: one level of independent sets, then cells. '
     '*Coarsest*: the coarsest level\'s points and prefix bytes (the bytes a client reads to draw it) as shares of the '
     'whole; *whole / 1L*: the whole stream against the 1-level one; *H*: symmetric Hausdorff distance of a decoded '
     'level to the input surface (a volume\'s boundary), sampled at vertices, edge midpoints and centroids, % of the '
     'bounding-box diagonal.', '']

L += ['## Summary', '',
      '| model | points | IS4: levels, coarsest points / bytes | whole / 1L | cells: levels, coarsest points / bytes | whole / 1L | IS4+fit whole / 1L | IS2+cells whole / 1L |',
      '|---|---:|---|---:|---|---:|---:|---:|']
ratio = {c: [] for c in CONFIGS}
share = {c: ([], []) for c in CONFIGS}
for m in models:
    base = res[(m, '1L')]['bytes']
    row = [name(m), str(res[(m, '1L')]['per_level'][0]['points'])]
    for c in CONFIGS:
        r = res[(m, c)]
        ratio[c].append(r['bytes'] / base)
        co = coarsest(r)
        share[c][0].append(co['points_pct'])
        share[c][1].append(100.0 * co['stream_bytes'] / r['bytes'])
    for c in ('IS4', 'cells'):
        r = res[(m, c)]
        co = coarsest(r)
        row += [f"{len(r['per_level'])}, {co['points_pct']:.1f} % / {100.0 * co['stream_bytes'] / r['bytes']:.1f} %",
                f"{r['bytes'] / base:.3f}"]
    row += [f"{res[(m, 'IS4+fit')]['bytes'] / base:.3f}", f"{res[(m, 'IS2+cells')]['bytes'] / base:.3f}"]
    L.append('| ' + ' | '.join(row) + ' |')
L += ['', '| configuration | whole / 1L, geometric mean (min-max) | coarsest points %, median | coarsest bytes %, median |',
      '|---|---|---:|---:|']
for c in CONFIGS:
    if c == '1L':
        continue
    pts, byt = sorted(share[c][0]), sorted(share[c][1])
    L.append(f"| {c} | {gmean(ratio[c]):.3f} ({min(ratio[c]):.3f}-{max(ratio[c]):.3f}) | {pts[len(pts) // 2]:.1f} | "
             f"{byt[len(byt) // 2]:.1f} |")

L += ['', '## How the coarser levels look', '',
      'Worst Hausdorff distance (% of the diagonal) over the coarser levels that keep at least 10 % of the points '
      '(the issue\'s bar: at most 1 %), and over the levels below 10 %; levels whose triangles (a volume\'s boundary '
      'triangles) have the input\'s components and Euler characteristic, of the coarser levels.', '',
      '| model | input comp / χ | IS4 H ≥10 % | IS4+fit H ≥10 % | cells H ≥10 % / <10 % | IS4 topology kept | IS4+fit | cells |',
      '|---|---|---:|---:|---:|---:|---:|---:|']


def worst(r, lo, hi):
    hs = [l['hausdorff_pct_diag'] for l in r['per_level'] if l['lod'] > 0 and lo <= l['points_pct'] < hi]
    return f"{max(hs):.2f}" if hs else '-'


def kept(r, ti):
    c = [l for l in r['per_level'] if l['lod'] > 0]
    ok = sum(l['topology']['components'] == ti['components'] and l['topology']['euler'] == ti['euler'] for l in c)
    return f"{ok}/{len(c)}"


for m in models:
    ti = topo_in(res[(m, '1L')])
    L.append(f"| {name(m)} | {ti['components']} / {ti['euler']} | {worst(res[(m, 'IS4')], 10, 101)} | "
             f"{worst(res[(m, 'IS4+fit')], 10, 101)} | "
             f"{worst(res[(m, 'cells')], 10, 101)} / {worst(res[(m, 'cells')], 0, 10)} | "
             f"{kept(res[(m, 'IS4')], ti)} | {kept(res[(m, 'IS4+fit')], ti)} | {kept(res[(m, 'cells')], ti)} |")

L += ['', '## Per level', '',
      '| model | configuration | level | points (%) | prefix bytes (%) | side bytes | H % | comp | χ | border e. |',
      '|---|---|---:|---:|---:|---:|---:|---:|---:|---:|']
for m in models:
    for c in CONFIGS:
        r = res[(m, c)]
        for l in r['per_level']:
            t = l['topology']
            L.append(f"| {name(m)} | {c} | {l['lod']} | {l['points']} ({l['points_pct']:.1f}) | {l['stream_bytes']} "
                     f"({100.0 * l['stream_bytes'] / r['bytes']:.1f}) | {l['side_bytes']} | {l['hausdorff_pct_diag']:.2f} | "
                     f"{t['components']} | {t['euler']} | {t['border_edges']} |")

if args.pictures:
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import hierarchy_report as hr  # drawing helpers; its main() does not run on import
    import matplotlib.pyplot as plt
    outdir = os.path.join(os.path.dirname(args.out), 'preview')
    os.makedirs(outdir, exist_ok=True)
    L += ['', '## Pictures', '']
    # A closed surface with handles, an open scan, a volume (its boundary).
    for m, view in (('surface/fertility.off', (10, -80)), ('surface/stanford_bunny.obj', (15, -70)),
                    ('volume/hand_tetgen.node', (20, -60))):
        for c in ('IS4', 'cells'):
            with tempfile.TemporaryDirectory() as work:
                stream, folder = os.path.join(work, 'x.hmc'), os.path.join(work, 'levels')
                subprocess.run([hmc, 'enc', os.path.join(args.data, m), '-o', stream] + CONFIGS[c], check=True,
                               capture_output=True)
                ext = 'mesh' if m.startswith('volume/') else 'obj'
                subprocess.run([hmc, 'dec', stream, '--all-levels', folder, '--ext', ext], check=True,
                               capture_output=True)
                lods = sorted(int(f.split('-')[1].split('.')[0]) for f in os.listdir(folder))
                meshes = [(k,) + hr.read_level(os.path.join(folder, f'level-{k}.{ext}')) for k in lods]
                n0 = len(meshes[0][1])
                box = (hr.z_up(meshes[0][1]).min(0), hr.z_up(meshes[0][1]).max(0))
                fig = plt.figure(figsize=(4 * len(meshes), 4.3), dpi=100)
                for col, (k, V, F, T) in enumerate(meshes):
                    ax = fig.add_subplot(1, len(meshes), col + 1, projection='3d')
                    if len(T):  # a volume: its boundary triangles
                        F = hr.boundary_faces(T)[0]
                    hr.draw(ax, hr.z_up(V), F, view, box, hr.COLOURS['surface'])
                    ax.set_title(f"level {k}: {len(V):,} points ({100.0 * len(V) / n0:.1f} %)", fontsize=11, pad=-4)
                fig.subplots_adjust(left=0, right=1, bottom=0, top=0.93, wspace=0)
                import io
                buf = io.BytesIO()
                fig.savefig(buf, format='png', dpi=100)
                plt.close(fig)
                png = f"{name(m)}-{c.replace('+', '-')}.png"
                hr.save_png_small(buf, os.path.join(outdir, png))
                L.append(f"{name(m)}, {c}: ![{name(m)} {c}](preview/{png})")
                L.append('')

open(args.out, 'w').write('\n'.join(L) + '\n')
print('\n'.join(L[:len(models) + 30]))
