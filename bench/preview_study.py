#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Preview study (issue 53): what the coarsest level of today's 4-level
stream holds, against a preview made of the base layer's first octree
depths (the occupied cells at depth d, the deepest with at most 5 % of the
points as cells), priced by coding those cells alone as a q = d point set
with `hmc enc` (an upper bound of the base octree's first d depths, which
the stream codes anyway). Prints a Markdown table.

usage: bench/preview_study.py [--hmc build/bin/hmc] [--data ../shared/data] [--work DIR]
"""
import argparse, json, os, subprocess, tempfile
ap = argparse.ArgumentParser()
ap.add_argument('--hmc', default='build/bin/hmc')
ap.add_argument('--data', default='../shared/data')
ap.add_argument('--work', default=None)
args = ap.parse_args()
H = args.hmc; D = args.data
work = args.work or tempfile.mkdtemp(prefix='hmc-preview-')
models=[('surface/'+f) for f in sorted(os.listdir(D+'/surface'))]+['volume/bunny_libigl.mesh','volume/hand_libigl.mesh','volume/hand_tetgen.node','volume/skull_tetgen.node']
def run(*a): return subprocess.run([H,*a],capture_output=True,text=True,check=True).stdout
print('| model | points | 1-level bytes | 4-level coarsest points | 4-level coarsest prefix bytes | depth d | depth-d cells (share) | cells coded alone, bytes (share of 1-level) |')
print('|---|---:|---:|---:|---:|---:|---:|---:|---:|')
for m in models:
    name=os.path.basename(m).split('.')[0]; w=os.path.join(work,name)
    os.makedirs(w,exist_ok=True)
    run('enc',D+'/'+m,'-o',w+'/l1.hmc','--levels','1','--threads','1')
    run('enc',D+'/'+m,'-o',w+'/l4.hmc','--levels','4','--threads','1')
    b1=os.path.getsize(w+'/l1.hmc')
    info=json.loads(run('info',w+'/l4.hmc','--json')); L=info['levels']; tot4=info['bytes']
    run('dec',w+'/l1.hmc','--canonical',w+'/c','--points-only')
    pts=[tuple(map(int,l.split())) for l in open(w+'/c/level-0.points')]
    n=len(pts); q=json.load(open(w+'/c/header.json'))['q']
    best=None
    for d in range(1,q):
        cells=set((x>>(q-d),y>>(q-d),z>>(q-d)) for x,y,z in pts)
        if len(cells)>0.05*n: nxt=len(cells); break
        best=(d,cells)
    d,cells=best
    with open(w+'/cells.xyz','w') as f:
        for c in sorted(cells): f.write('%d %d %d\n'%c)
    run('enc',w+'/cells.xyz','-o',w+'/cells.hmc','--bits',str(d),'--kind','points','--no-info','--threads','1')
    cb=os.path.getsize(w+'/cells.hmc')
    print(f"| {name} | {n} | {b1} | {L[0]['points']} ({L[0]['points']/L[-1]['points']:.1%}) | {L[0]['stream_bytes']} ({L[0]['stream_bytes']/tot4:.1%}) | {d} | {len(cells)} ({len(cells)/n:.1%}) | {cb} ({cb/b1:.1%}) | {nxt} ({nxt/n:.1%}) |",flush=True)
