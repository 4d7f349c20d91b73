#!/usr/bin/python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Folded into bench/compression.py (issue 6), which measures everything this
script did -- bits per point of every shared model at q = 12 beside the
anchors, and encoding/decoding 1 million generated points with HMC and Draco
(its section 5) -- and more. This name is kept so old command lines still
work: the arguments are passed on unchanged (--hmc, --data, --out, --repeat
and --big mean what they meant here; see bench/compression.py --help)."""
import os
import sys

here = os.path.dirname(os.path.abspath(__file__))
print("bench_points.py: folded into bench/compression.py; running that", file=sys.stderr)
os.execv(sys.executable, [sys.executable, os.path.join(here, "compression.py")] + sys.argv[1:])
