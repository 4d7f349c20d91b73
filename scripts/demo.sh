#!/bin/sh
# SPDX-License-Identifier: AGPL-3.0-or-later
# Quick start: set up, then encode a generated 36,450-vertex torus (the size
# of the thesis' table 4.1) with the default levels (the finest level, then
# octree-cell preview levels down to about 4 % of the points), decode it,
# and print the per-level table.
set -eu
. "$(dirname "$0")/setup.sh"

HMC="$HMC_BUILD/bin/hmc"
OUT="$HMC_BUILD/demo"
mkdir -p "$OUT"
"$HMC" gen torus --vertices 36450 -o "$OUT/torus.ply"
echo
"$HMC" enc "$OUT/torus.ply" -o "$OUT/torus.hmc" --bits 12
echo
"$HMC" dec "$OUT/torus.hmc" -o "$OUT/torus-decoded.ply"
echo
"$HMC" info "$OUT/torus.hmc"
echo
echo "demo: files in $OUT"
