#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""What contexts could gain in the octree base layer (issue 6; an estimate, not a test).

Reads one level's grid points (the canonical dump format: one "x y z" line
per point, e.g. `hmc dec X.hmc --points-only --canonical DIR` writes
DIR/level-0.points) and the grid's bits q, and prints, in bits per point, the
empirical entropy of the octree's occupancy symbols (spec section 8.1):

  * one distribution per depth (what the coder's per-depth Huffman tables
    approach);
  * one per depth and count of occupied face neighbours of the node (0..6);
  * one per depth and pattern of occupied face neighbours (64 patterns).

Table costs are not counted, so the figures are lower bounds for codes
with those contexts. Neighbours are nodes of the same depth, which a
breadth-first decoder knows before it reads the depth's symbols.

usage: bench/octree_context_entropy.py LEVEL.points Q
"""
import collections
import math
import sys


def entropy(counter):
    n = sum(counter.values())
    return -sum(c * math.log2(c / n) for c in counter.values())


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__.strip().splitlines()[-1])
    with open(sys.argv[1]) as f:
        pts = [tuple(map(int, line.split())) for line in f if line.strip()]
    q = int(sys.argv[2])
    plain = by_count = by_pattern = 0.0
    steps = ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1))
    for d in range(q):
        shift = q - d - 1
        occ = collections.defaultdict(int)
        for x, y, z in pts:
            parent = (x >> (shift + 1), y >> (shift + 1), z >> (shift + 1))
            occ[parent] |= 1 << (4 * ((x >> shift) & 1) + 2 * ((y >> shift) & 1) + ((z >> shift) & 1))
        count_ctx = collections.defaultdict(collections.Counter)
        pattern_ctx = collections.defaultdict(collections.Counter)
        for (a, b, c), o in occ.items():
            pattern = sum(1 << i for i, (dx, dy, dz) in enumerate(steps) if (a + dx, b + dy, c + dz) in occ)
            count_ctx[bin(pattern).count("1")][o] += 1
            pattern_ctx[pattern][o] += 1
        plain += entropy(collections.Counter(occ.values()))
        by_count += sum(entropy(c) for c in count_ctx.values())
        by_pattern += sum(entropy(c) for c in pattern_ctx.values())
    n = len(pts)
    print(f"{n} points, q = {q}: one table per depth {plain / n:.2f} bpp; by neighbour count "
          f"{by_count / n:.2f}; by neighbour pattern {by_pattern / n:.2f} (entropies, table costs not counted)")


if __name__ == "__main__":
    main()
