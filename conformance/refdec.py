#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""refdec: a second, independent HMC decoder, written from spec/hmc.md alone.

It decodes the points of every level (every base and refinement coder) and parses
and validates all side information (HEAD, SQNT, BASE, REFN, RCON);
for kinds surface and volume it also rebuilds every level's triangles or
tetrahedra (section 11, in refrecon.py, on the canonical Delaunay of
refdelaunay.py, both written from spec/hmc.md and spec/delaunay.md alone):
it writes the "full" profile of the canonical dump (spec/conformance.md),
header.json, level-K.points and level-K.simplices.

    refdec.py IN.hmc OUTDIR

Exit status 0 on success (a truncated stream that still decodes prints a
warning), 3 on an invalid stream, with "refdec: IN: <error_class>: <message>"
on stderr, 1 on a bad command line, 4 if the output cannot be written.
Python 3 standard library only; slow but readable. Section numbers (§) refer
to spec/hmc.md.
"""
import heapq
import math
import os
import struct
import sys
import zlib

import refrecon  # §11 reconstruction (full profile), beside this file

SIGNATURE = bytes([0x89, 0x48, 0x4D, 0x43, 0x0D, 0x0A, 0x1A, 0x0A])
KIND_NAMES = {0: "points", 1: "surface", 2: "volume"}
MAX_LEN = 2**31 - 1
INDEX_BOUND = 2**32 - 1  # §10: every RCON index is below 2^32 - 1


class DecodeError(Exception):
    def __init__(self, cls, msg):
        super().__init__(msg)
        self.cls = cls
        self.msg = msg


# ---------------------------------------------------------------- §1 bytes


class ByteReader:
    """Fixed-width little-endian fields and varints over one payload; every
    overrun or malformed varint is an error of class `cls` (§1)."""

    def __init__(self, data, cls, what):
        self.data = data
        self.pos = 0
        self.cls = cls
        self.what = what

    def fail(self, msg):
        raise DecodeError(self.cls, "%s: %s" % (self.what, msg))

    def left(self):
        return len(self.data) - self.pos

    def take(self, n):
        if self.left() < n:
            self.fail("payload too short")
        b = self.data[self.pos:self.pos + n]
        self.pos += n
        return b

    def u8(self):
        return self.take(1)[0]

    def f64(self):
        return struct.unpack("<d", self.take(8))[0]

    def varint(self):
        value = 0
        for i in range(10):
            if self.left() < 1:
                self.fail("varint runs past the payload")
            b = self.data[self.pos]
            self.pos += 1
            if i == 9 and b > 1:
                self.fail("varint above 2^64 - 1")
            value |= (b & 0x7F) << (7 * i)
            if not b & 0x80:
                if b == 0 and i > 0:
                    self.fail("varint not in shortest form")
                return value
        self.fail("varint longer than 10 bytes")

    def end(self):
        if self.left():
            self.fail("%d byte(s) left over" % self.left())


# ---------------------------------------------------------------- bit streams (§1)


class BitReader:
    def __init__(self, data, start, cls, what):
        self.data = data
        self.pos = start * 8  # in bits
        self.cls = cls
        self.what = what

    def bit(self):
        p = self.pos
        if (p >> 3) >= len(self.data):
            raise DecodeError(self.cls, "%s: bit stream runs past the payload" % self.what)
        self.pos = p + 1
        return (self.data[p >> 3] >> (7 - (p & 7))) & 1

    def bits(self, n):
        v = 0
        for _ in range(n):
            v = (v << 1) | self.bit()
        return v

    def ue(self):
        z = 0
        while self.bit() == 0:
            z += 1
            if z > 31:
                raise DecodeError(self.cls, "%s: exp-Golomb code with more than 31 leading zeros" % self.what)
        return (1 << z) + self.bits(z) - 1

    def pad(self):
        """Skips the padding to the next byte boundary, which must be zero;
        returns the byte offset after it."""
        while self.pos & 7:
            if self.bit():
                raise DecodeError(self.cls, "%s: non-zero padding bits" % self.what)
        return self.pos >> 3

    def finish(self):
        end = self.pad()
        if end != len(self.data):
            raise DecodeError(self.cls, "%s: %d byte(s) after the bit stream" % (self.what, len(self.data) - end))


# ---------------------------------------------------------------- §7 Huffman


class Code:
    """A canonical prefix code (§7.2) or a one-symbol code."""

    def __init__(self, single=None, lengths=None):
        self.single = single
        if lengths is None:
            return
        # DEFLATE-style tables: per length, the first code and the symbols.
        self.count = [0] * 16
        for l in lengths:
            if l:
                self.count[l] += 1
        self.symbols = [s for l in range(1, 16) for s, ls in enumerate(lengths) if ls == l]
        self.first = [0] * 16
        self.index = [0] * 16
        code = 0
        idx = 0
        for l in range(1, 16):
            code <<= 1
            self.first[l] = code
            self.index[l] = idx
            code += self.count[l]
            idx += self.count[l]

    def decode(self, br, cls):
        if self.single is not None:
            return self.single
        code = 0
        for l in range(1, 16):
            code = (code << 1) | br.bit()  # overrun raises br's class (bad_layer)
            off = code - self.first[l]
            if 0 <= off < self.count[l]:
                return self.symbols[self.index[l] + off]
        raise DecodeError(cls, "no code matches (impossible for a complete code)")


class PairedCode:
    """§7.4: a paired table. Each pair (a, b) is read where its first symbol
    is needed; b stays pending until the table is next used."""

    def __init__(self, br, alphabet, form):
        self.pairs = read_code(br, 65, form)
        uses_escape = self.pairs.single == 64 if self.pairs.single is not None else 64 in self.pairs.symbols
        self.escape = read_code(br, alphabet, form) if uses_escape else None
        self.pending = None

    def decode(self, br, cls):
        if self.pending is not None:
            s, self.pending = self.pending, None
            return s
        v = self.pairs.decode(br, cls)
        if v < 64:
            a, b = v // 8, v % 8
        else:
            a = self.escape.decode(br, cls)
            b = self.escape.decode(br, cls)
        self.pending = b
        return a


def read_table(br, alphabet, form, flagged):
    """A table of a layer whose tables may be paired (`flagged`: §8.2,
    §8A.1): a flag, then a paired table (§7.4) or a code-length table;
    otherwise a code-length table (§7.1)."""
    if flagged and br.bits(1) == 1:
        return PairedCode(br, alphabet, form)
    return read_code(br, alphabet, form)


def read_delta_lengths(br, alphabet):
    """§7.1, delta form: tokens 00 same, 01 zero run, 100 +1, 101 -1,
    1100 +2, 1101 -2, 1110 end, 1111 s ue (far: -(ue + 3) if s else
    ue + 3); the first length is relative to 3."""
    lengths = [0] * alphabet
    s = 0
    prev = 3
    while s < alphabet:
        if br.bits(1) == 0:
            if br.bits(1) == 1:  # zero run
                run = br.ue() + 1
                if s + run > alphabet:
                    raise DecodeError("bad_huffman_table", "zero run past the alphabet (%d + %d > %d)" % (s, run, alphabet))
                s += run
                continue
            delta = 0
        elif br.bits(1) == 0:
            delta = -1 if br.bits(1) else 1
        elif br.bits(1) == 0:
            delta = -2 if br.bits(1) else 2
        elif br.bits(1) == 0:  # end: the rest are zero
            break
        else:
            down = br.bits(1)
            m = br.ue() + 3
            delta = -m if down else m
        length = prev + delta
        if not 1 <= length <= 15:
            raise DecodeError("bad_huffman_table", "length %d of symbol %d outside 1..15" % (length, s))
        lengths[s] = length
        prev = length
        s += 1
    return lengths


def read_code(br, alphabet, form=1):
    """§7.1: a code-length table for an alphabet of `alphabet` symbols, in
    the 4-bit form (form 0) or the delta form (form 1, HEAD flag bit 0). An
    overrun is an error of the bit stream's class; every other defect is
    bad_huffman_table."""
    if br.bits(1) == 1:
        w = max(1, (alphabet - 1).bit_length())
        sym = br.bits(w)
        if sym >= alphabet:
            raise DecodeError("bad_huffman_table", "single symbol %d >= alphabet size %d" % (sym, alphabet))
        return Code(single=sym)
    lengths = read_delta_lengths(br, alphabet) if form else [0] * alphabet
    s = alphabet if form else 0
    while s < alphabet:
        v = br.bits(4)
        if v:
            lengths[s] = v
            s += 1
        else:
            run = br.ue() + 1
            if s + run > alphabet:
                raise DecodeError("bad_huffman_table", "zero run past the alphabet (%d + %d > %d)" % (s, run, alphabet))
            s += run
    nonzero = sum(1 for l in lengths if l)
    if nonzero < 2:
        raise DecodeError("bad_huffman_table", "fewer than two non-zero code lengths")
    kraft = sum(1 << (15 - l) for l in lengths if l)
    if kraft != 1 << 15:
        raise DecodeError("bad_huffman_table",
                          "code %s (Kraft sum %d / 32768)" % ("over-subscribed" if kraft > 1 << 15 else "incomplete", kraft))
    return Code(lengths=lengths)


# ---------------------------------------------------------------- §8 base layer


def morton_children(node, d, q):
    """Children of node (X, Y, Z) at depth d: (c, child) for c = 0..7."""
    X, Y, Z = node
    return [(c, (2 * X + (c >> 2), 2 * Y + ((c >> 1) & 1), 2 * Z + (c & 1))) for c in range(8)]


def causal_points(nodes, occs, i, nb, neighbours, h):
    """§8.2: the points that rank node i of a depth (doubled coordinates;
    nb searches the depth's node centres, h is the node side): its
    neighbours' centres, those decoded before it (index below i, whose
    occupancies occs[j] are known) replaced by their occupied children's
    centres; 32 at most."""
    P = []
    X, Y, Z = nodes[i]
    for j in nb.nearest((2 * X * h + h, 2 * Y * h + h, 2 * Z * h + h), min(neighbours, len(nodes))):
        if j < i:
            Xj, Yj, Zj = nodes[j]
            P += [((2 * Xj + (c >> 2)) * h + h // 2, (2 * Yj + ((c >> 1) & 1)) * h + h // 2,
                   (2 * Zj + (c & 1)) * h + h // 2) for c in range(8) if occs[j] >> c & 1]
        else:
            P.append(nb.pts[j])
    return P[:32]


def decode_base(payload, q, n, form=1):
    if not payload:
        raise DecodeError("bad_layer", "BASE: empty payload")
    if payload[0] not in (0, 5):  # §8: coder 0, the octree; coder 5, the ranked octree
        raise DecodeError("bad_layer", "BASE: unknown coder %d" % payload[0])
    ranked_coder = payload[0] == 5
    br = BitReader(payload, 1, "bad_layer", "BASE")
    neighbours = br.bits(4) if ranked_coder else 0
    classes = br.bits(2) + 1 if ranked_coder else 1
    ranked, tables, gaps, quadric = [], [], [], []
    for _ in range(q):
        ranked.append(ranked_coder and br.bits(1) == 1)
        # §8.2: the depth's 5-bit weight (16 the far ranking) and quadric flag
        gaps.append(br.bits(5) if ranked[-1] else 0)
        if gaps[-1] > 16:
            raise DecodeError("bad_layer", "BASE: ranking weight %d above 16" % gaps[-1])
        quadric.append(br.bits(1) == 1 if ranked[-1] else False)
        tables.append([read_table(br, 255, form, True) for _ in range(classes)] if ranked[-1]
                      else [read_table(br, 256, form, ranked_coder)])
        # §8.2: every ranked node costs a bit, every pair of them when paired
        if ranked[-1] and any((t.pairs if isinstance(t, PairedCode) else t).single is not None for t in tables[-1]):
            raise DecodeError("bad_layer", "BASE: a one-symbol code at ranked depth %d" % (len(tables) - 1))
    nodes = [(0, 0, 0)]
    for d in range(q):
        nxt = []
        t = tables[d]
        if ranked[d]:  # §8.2: neighbours among the node centres of depth d
            h = 1 << (q - d)
            centres = [(X * h + h // 2, Y * h + h // 2, Z * h + h // 2) for (X, Y, Z) in nodes]
            nb = Neighbours(centres, q)
        occs = []
        for i, (X, Y, Z) in enumerate(nodes):
            if ranked[d]:
                P = causal_points(nodes, occs, i, nb, neighbours, h)
                pi, split = child_order((X, Y, Z), d, q, 0, None, None, 0, want_split=True, gap=gaps[d], gap_from=1,
                                        fit=len(P) if quadric[d] else 0, points=P)
                x = (0, 1, 2, 2, 3)[split]
                s = t[min(x, classes - 1)].decode(br, "bad_layer")
                rho = E[s]
                occ = sum(1 << pi[r] for r in range(8) if rho >> r & 1)
            else:
                occ = t[0].decode(br, "bad_layer")
                if occ == 0:
                    raise DecodeError("bad_layer", "BASE: zero occupancy at depth %d" % d)
            occs.append(occ)
            for c in range(8):
                if occ >> c & 1:
                    if len(nxt) >= n:
                        raise DecodeError("bad_layer", "BASE: more than %d nodes at depth %d" % (n, d + 1))
                    nxt.append((2 * X + (c >> 2), 2 * Y + ((c >> 1) & 1), 2 * Z + (c & 1)))
        nodes = nxt
    br.finish()
    if len(nodes) != n:
        raise DecodeError("bad_layer", "BASE: %d points, the header declares %d" % (len(nodes), n))
    return sorted(nodes)


# ---------------------------------------------------------------- §8A refinement layer

# E: 1..255 by number of one bits, then value.
E = sorted(range(1, 256), key=lambda v: (bin(v).count("1"), v))


def reduce_bits(values, b):
    l = max(abs(v) for v in values).bit_length()
    s = max(0, l - b)
    if s == 0:
        return list(values)
    return [(abs(v) >> s) * (1 if v >= 0 else -1) for v in values]


class Neighbours:
    """Exact k nearest points of C (doubled coordinates) to a query point,
    ties to the smaller canonical index, by a uniform grid searched in
    rings of cells."""

    def __init__(self, pts, q):
        self.pts = [(2 * x, 2 * y, 2 * z) for (x, y, z) in pts]
        n = len(pts)
        # The smallest cell (a power of two in grid units) with about three
        # points per occupied cell; the result does not depend on it.
        shift = q
        for s in range(0, q + 1):
            cells = {(x >> s, y >> s, z >> s) for (x, y, z) in pts}
            if n >= 3 * len(cells) or s == q:
                shift = s
                break
        self.side = 2 << shift  # in doubled units
        self.cells = {}
        for i, (x, y, z) in enumerate(pts):
            self.cells.setdefault((x >> shift, y >> shift, z >> shift), []).append(i)
        self.maxcell = (1 << q) >> shift

    def nearest(self, o, k):
        if k == 0:
            return []
        pts = self.pts
        if k >= len(pts):
            idx = range(len(pts))
            return sorted(idx, key=lambda i: (sq(pts[i], o), i))
        side = self.side
        cx, cy, cz = o[0] // side, o[1] // side, o[2] // side
        cand = []
        reach = max(cx, cy, cz, self.maxcell - cx, self.maxcell - cy, self.maxcell - cz) + 1
        r = 0
        while True:
            for key in ring(cx, cy, cz, r):
                lst = self.cells.get(key)
                if lst:
                    for i in lst:
                        p = pts[i]
                        dx = p[0] - o[0]
                        dy = p[1] - o[1]
                        dz = p[2] - o[2]
                        cand.append((dx * dx + dy * dy + dz * dz, i))
            if len(cand) >= k:
                best = heapq.nsmallest(k, cand)
                # Any point not yet seen is at least r * side away.
                if best[-1][0] < (r * side) ** 2 or r > reach:
                    return [i for _, i in best]
            elif r > reach:
                return [i for _, i in sorted(cand)]
            r += 1


def sq(p, o):
    return (p[0] - o[0]) ** 2 + (p[1] - o[1]) ** 2 + (p[2] - o[2]) ** 2


def ring(cx, cy, cz, r):
    if r == 0:
        yield (cx, cy, cz)
        return
    for dx in range(-r, r + 1):
        for dy in range(-r, r + 1):
            if abs(dx) == r or abs(dy) == r:
                for dz in range(-r, r + 1):
                    yield (cx + dx, cy + dy, cz + dz)
            else:
                yield (cx + dx, cy + dy, cz - r)
                yield (cx + dx, cy + dy, cz + r)


def quadric_keys(n, j, O, F, h, k):
    """§8A.1: the keys t'_c of the eight children from the quadric fitted
    to the fit points F (doubled coordinates), or None when the fit fails.
    Python floats are IEEE binary64; each operation below is rounded on its
    own, in the spec's order."""
    a, b = [x for x in range(3) if x != j]

    def cross(axis):  # e_axis x n
        c = [0, 0, 0]
        c[(axis + 1) % 3] = -n[(axis + 2) % 3]
        c[(axis + 2) % 3] = n[(axis + 1) % 3]
        return c

    T, B = cross(a), cross(b)

    def frame(D):
        return tuple(float(D[0] * V[0] + D[1] * V[1] + D[2] * V[2]) for V in (T, B, n))

    M = [[0.0] * 6 for _ in range(6)]
    R = [0.0] * 6
    for p in F:
        u, v, w = frame([p[0] - O[0], p[1] - O[1], p[2] - O[2]])
        beta = (1.0, u, v, u * u, u * v, v * v)
        for r in range(6):
            for s in range(r, 6):
                M[r][s] = M[r][s] + beta[r] * beta[s]
            R[r] = R[r] + beta[r] * w
    L = [[0.0] * 6 for _ in range(6)]
    D = [0.0] * 6
    for r in range(6):
        acc = M[r][r]
        for s in range(r):
            acc = acc - L[r][s] * L[r][s] * D[s]
        if not acc > M[r][r] * 2.0 ** -40:
            return None
        D[r] = acc
        for z in range(r + 1, 6):
            e = M[r][z]
            for s in range(r):
                e = e - L[z][s] * L[r][s] * D[s]
            L[z][r] = e / D[r]
    y = [0.0] * 6
    for r in range(6):
        y[r] = R[r]
        for s in range(r):
            y[r] = y[r] - L[r][s] * y[s]
    c = [0.0] * 6
    for r in range(5, -1, -1):
        c[r] = y[r] / D[r]
        for z in range(r + 1, 6):
            c[r] = c[r] - L[z][r] * c[z]
    keys = []
    for child in range(8):
        bits = (child >> 2, (child >> 1) & 1, child & 1)
        u, v, w = frame([(h if bit else -h) // 2 for bit in bits])
        f = c[0] + c[1] * u + c[2] * v + c[3] * (u * u) + c[4] * (u * v) + c[5] * (v * v)
        x = abs(w - f) * float(k)
        keys.append(int(x) if x < 2.0 ** 47 else 1 << 47)
    return keys


def child_order(node, d, q, m, coarse, nb, neighbours, want_split=False, gap=0, gap_from=0, fit=0, points=None):
    """§8A.1 ranking: returns pi, pi[r] = child at rank r (and, with
    want_split, how many children lie on the plane's smaller side, §8.2).
    gap: the gap weight G (§8A.1); 0 is the plain ranking. gap_from:
    the distances g skip the first gap_from neighbours (§8.2: the node itself).
    fit: the quadric's F (§8A.1), the points the quadric is fitted to.
    gap 16: the far ranking (§8A.1, and BASE coder 5's, §8.2), by g
    alone, farthest first.
    points: the neighbours themselves (§8.2), instead of a search in coarse;
    the first `fit` of them are the fit points."""
    X, Y, Z = node
    h = 1 << (q - d)
    O = (2 * X * h + h, 2 * Y * h + h, 2 * Z * h + h)
    if points is None:
        k = min(neighbours, len(coarse))
        f = min(fit, len(coarse))
        idx = nb.nearest(O, max(k, f))
        P = [nb.pts[i] for i in idx[:k]]
        fit_points = [nb.pts[i] for i in idx[:f]]
    else:
        P = list(points)
        k = len(P)
        f = fit
        fit_points = P[:f]
    S = [sum(p[a] for p in P) for a in range(3)]

    def mom(a, b):
        return k * sum(p[a] * p[b] for p in P) - S[a] * S[b]

    if k > 0:
        Mxx, Myy, Mzz, Mxy, Mxz, Myz = reduce_bits(
            [mom(0, 0), mom(1, 1), mom(2, 2), mom(0, 1), mom(0, 2), mom(1, 2)], 31)
    else:
        Mxx = Myy = Mzz = Mxy = Mxz = Myz = 0
    Axx = Myy * Mzz - Myz * Myz
    Ayy = Mxx * Mzz - Mxz * Mxz
    Azz = Mxx * Myy - Mxy * Mxy
    Axy = Mxz * Myz - Mxy * Mzz
    Axz = Mxy * Myz - Mxz * Myy
    Ayz = Mxy * Mxz - Mxx * Myz
    A = [[Axx, Axy, Axz], [Axy, Ayy, Ayz], [Axz, Ayz, Azz]]
    j = 0
    for a in (1, 2):
        if A[a][a] > A[j][j]:
            j = a
    n = reduce_bits([A[0][j], A[1][j], A[2][j]], 20)
    N = n[0] * n[0] + n[1] * n[1] + n[2] * n[2]
    quadric = None
    if f >= 6 and n[j] > 0:
        quadric = quadric_keys(n, j, O, fit_points, h, k)
    keys = []
    above = below = 0
    for c in range(8):
        bx, by, bz = c >> 2, (c >> 1) & 1, c & 1
        U = ((2 * X + bx) * h + h // 2, (2 * Y + by) * h + h // 2, (2 * Z + bz) * h + h // 2)
        V = (k * U[0] - S[0], k * U[1] - S[1], k * U[2] - S[2])
        dot = n[0] * V[0] + n[1] * V[1] + n[2] * V[2]
        above += dot > 0
        below += dot < 0
        e = V[0] * V[0] + V[1] * V[1] + V[2] * V[2]
        t = abs(dot) if quadric is None else quadric[c]  # §8A.1: the height above the quadric
        # §8A.1: kappa = 32 t^2 - G k^2 N g, g the squared distance from U to
        # the nearest neighbour (0 without neighbours)
        g = min((sum((U[a] - p[a]) ** 2 for a in range(3)) for p in P[gap_from:]), default=0)
        kappa = -g if gap == 16 else 32 * t * t - gap * k * k * N * g  # §8A.1: far ranking
        keys.append((1 - (m >> c & 1), kappa, t, e, c))
    keys.sort()
    pi = [key[4] for key in keys]
    return (pi, min(above, below)) if want_split else pi


def decode_refn(payload, q, coarse, n, form=1):
    """Returns the added points A (list). coarse: C in canonical order."""
    if not payload:
        raise DecodeError("bad_layer", "REFN: empty payload")
    if payload[0] not in (0, 7):  # §8A.1: the short header (0) and the full one (7)
        raise DecodeError("bad_layer", "REFN: unknown coder %d" % payload[0])
    full = payload[0] == 7
    planes = 1
    br = BitReader(payload, 1, "bad_layer", "REFN")
    neighbours = br.bits(4)
    classes = br.bits(2) + 1
    gaps = [0] * q
    fit = 0
    if full:  # the plane contexts, the quadric's fit points, then one 5-bit weight or one per depth
        planes = br.bits(1) + 1
        fit = br.bits(4)
        per_depth = br.bits(1) == 1
        gaps = [br.bits(5) for _ in range(q)] if per_depth else [br.bits(5)] * q
        if max(gaps) > 16:
            raise DecodeError("bad_layer", "REFN: ranking weight %d above 16" % max(gaps))
    table = [[[None] * planes for _ in range(classes)] for _ in range(q)]
    for d in range(q):
        for j in range(classes):
            for x in range(planes):
                if br.bits(1) == 1:
                    table[d][j][x] = read_table(br, 255, form, full)
                elif d > 0:
                    table[d][j][x] = table[d - 1][j][x]
    # Occupied nodes of C per depth.
    occ = [set() for _ in range(q + 1)]
    for (x, y, z) in coarse:
        for d in range(q + 1):
            s = q - d
            occ[d].add((x >> s, y >> s, z >> s))
    nb = Neighbours(coarse, q)
    points = []

    def visit(node, d):
        X, Y, Z = node
        kids = [(2 * X + (c >> 2), 2 * Y + ((c >> 1) & 1), 2 * Z + (c & 1)) for c in range(8)]
        m = 0
        for c in range(8):
            if kids[c] in occ[d + 1]:
                m |= 1 << c
        w = bin(m).count("1")
        pi, split = child_order(node, d, q, m, coarse, nb, neighbours, want_split=True, gap=gaps[d], fit=fit)
        x = 1 if planes == 2 and split >= 2 else 0
        T = table[d][min(w, classes - 1)][x]
        if T is None:
            raise DecodeError("bad_layer", "REFN: depth %d class %d plane context %d has no table" % (d, min(w, classes - 1), x))
        s = T.decode(br, "bad_layer")
        rho = E[s]
        occupied = [0] * 8
        for r in range(8):
            if rho >> r & 1:
                occupied[pi[r]] = 1
        if d == q - 1:
            for c in range(8):
                if occupied[c] and m >> c & 1:
                    raise DecodeError("bad_layer", "REFN: added point %s is a coarser level's point" % (kids[c],))
            for c in range(8):
                if occupied[c]:
                    if len(points) >= n:
                        raise DecodeError("bad_layer", "REFN: more than %d added points" % n)
                    points.append(kids[c])
        else:
            for c in range(8):
                if occupied[c]:
                    visit(kids[c], d + 1)

    visit((0, 0, 0), 0)
    br.finish()
    if len(points) != n:
        raise DecodeError("bad_layer", "REFN: %d added points, the header declares %d" % (len(points), n))
    return points


# ---------------------------------------------------------------- §10 RCON


def rice_list(br, what, inverted=None):
    """§10.2: one list, a count then, if not empty, a Rice parameter and the
    Rice-coded gaps between its ascending entries. inverted (a list of one
    flag, for the neighbour contexts of §11.5): the count field carries
    2 * count + inverted, and the flag is stored there."""
    count = br.ue()
    if inverted is not None:
        inverted[0] = count & 1
        count >>= 1
    if count > len(br.data) * 8 - br.pos:
        raise DecodeError("bad_layer", "RCON: %s count %d above the bits left" % (what, count))
    out = []
    if count == 0:
        return out
    k = br.bits(5)
    prev = -1
    for _ in range(count):
        q = 0
        while br.bit() == 1:
            q += 1
            if q << k >= INDEX_BOUND:
                raise DecodeError("bad_layer", "RCON: %s >= 2^32 - 1" % what)
        v = prev + 1 + (q << k) + br.bits(k)
        if v >= INDEX_BOUND:
            raise DecodeError("bad_layer", "RCON: %s %d >= 2^32 - 1" % (what, v))
        out.append(v)
        prev = v
    return out


def parse_rcon(payload, n, form=1):
    r = ByteReader(payload, "bad_layer", "RCON")
    flags = r.u8()  # bit 3 (inherit_border) changes only what the border list means
    compact = flags >> 2 & 1
    class_list = flags >> 4 & 1
    if class_list and not compact:
        r.fail("class_list (flag bit 4) without compact")
    candidate_contexts = flags >> 5 & 1  # §11.5: 40 toggle contexts instead of 8
    if candidate_contexts and not compact:
        r.fail("candidate_contexts (flag bit 5) without compact")
    vertex_contexts = flags >> 6 & 1  # §11.5: 80 toggle contexts
    if vertex_contexts and not candidate_contexts:
        r.fail("vertex_contexts (flag bit 6) without candidate_contexts")
    neighbour_contexts = flags >> 7 & 1  # §11.5: 240 toggle contexts, lists that may be inverted
    if neighbour_contexts and not vertex_contexts:
        r.fail("neighbour_contexts (flag bit 7) without vertex_contexts")
    k = r.u8()
    if not 1 <= k <= 64:
        r.fail("scale_rank %d out of range" % k)
    mask = r.u8()
    if mask & 0x80:
        r.fail("reserved filter_mask bit 7 set (filter_mask = %d)" % mask)
    thresholds = {}
    for i in range(6):
        if mask >> i & 1:
            t = r.varint()
            if not 1 <= t <= 65535:
                r.fail("threshold %d of filter %d out of range" % (t, i))
            if i == 3 and t != 1:
                r.fail("threshold %d of filter 3 (lone triangle) is not 1" % t)
            thresholds[i] = t
    seal = None  # §10, §11.3: filter_mask bit 6, the seal box x0, y0, z0, x1, y1, z1
    if mask >> 6 & 1:
        seal = [r.varint() for _ in range(6)]
        for ax in range(3):
            if not seal[ax] < seal[3 + ax] <= 1 << 21:
                r.fail("seal box axis %d [%d, %d) empty or beyond 2^21" % (ax, seal[ax], seal[3 + ax]))
    K = r.varint()
    if not 1 <= K <= 64:
        r.fail("class_count %d out of range" % K)
    mult = []
    for _ in range(K):
        m = r.varint()
        if not 1 <= m <= 65535:
            r.fail("multiplier %d out of range" % m)
        if mult and m <= mult[-1]:
            r.fail("multipliers not strictly increasing")
        mult.append(m)
    counts = [n] + [0] * (K - 1)
    classes = [0] * n  # §10.1: the class of each point (refrecon.py, §11.1)
    if K > 1:
        counts = [0] * K
        br = BitReader(payload, r.pos, "bad_layer", "RCON classes")
        if class_list:  # §10.1: the common class d, the other points listed as in §10.2
            d = br.bits(6)
            if d >= K:
                raise DecodeError("bad_layer", "RCON: common class %d of %d" % (d, K))
            listed = rice_list(br, "class list entry")
            if listed and listed[-1] >= n:
                raise DecodeError("bad_layer", "RCON: class list entry %d >= %d points" % (listed[-1], n))
            counts[d] = n - len(listed)
            classes = [d] * n
            code = read_code(br, K - 1, form) if K > 2 else None
            for v in listed:
                s = code.decode(br, "bad_layer") if code else 0
                counts[s if s < d else s + 1] += 1
                classes[v] = s if s < d else s + 1
        elif compact:  # §10.1: classes in groups of G points, digits base K
            G = br.bits(3) + 1
            A = K ** G
            if A > 4096:
                raise DecodeError("bad_layer", "RCON: %d classes in groups of %d make %d > 4096 symbols" % (K, G, A))
            code = read_code(br, A, form)
            for b in range((n + G - 1) // G):
                s = code.decode(br, "bad_layer")
                for i in range(G):
                    if b * G + i < n:
                        counts[s % K] += 1
                        classes[b * G + i] = s % K
                    elif s % K:
                        raise DecodeError("bad_layer", "RCON: a class group gives a class to a point beyond the last")
                    s //= K
        else:
            code = read_code(br, K, form)
            for v in range(n):
                classes[v] = code.decode(br, "bad_layer")
                counts[classes[v]] += 1
        r.pos = br.pad()

    def index_list(what, limit):
        count = r.varint()
        if limit is not None and count > limit:
            r.fail("%s count %d above %d" % (what, count, limit))
        if count > r.left():
            r.fail("%s count %d larger than the %d payload bytes left" % (what, count, r.left()))
        out = []
        prev = -1
        for _ in range(count):
            v = prev + 1 + r.varint()
            if limit is not None and v >= limit:
                r.fail("%s index %d >= %d" % (what, v, limit))
            if v >= INDEX_BOUND:
                r.fail("%s index %d >= 2^32 - 1" % (what, v))
            out.append(v)
            prev = v
        return out

    border = index_list("border", n)
    toggles = [0] * (240 if neighbour_contexts else 80 if vertex_contexts else 40 if candidate_contexts else 8)
    inverted = []
    toggle_list, toggle_ranks = [], []
    if not compact:
        toggle_list = index_list("toggle", None)  # checked against the tetrahedra only when reconstructing
        toggles = len(toggle_list)
        drops = index_list("drop", None)
        r.end()
    else:
        drops = index_list("drop", None)
        # §10.2: per context, a count and Rice-coded gaps of ranks; the ranks
        # are checked against the contexts only when reconstructing.
        br = BitReader(payload, r.pos, "bad_layer", "RCON toggles")
        for j in range(len(toggles)):
            flag = [0] if neighbour_contexts else None
            toggle_ranks.append(rice_list(br, "toggle rank of context %d" % j, flag))
            toggles[j] = len(toggle_ranks[-1])
            if flag and flag[0]:
                inverted.append(j)
        br.finish()
    return {"peel": flags & 1, "repair": flags >> 1 & 1, "compact": compact, "class_list": class_list,
            "candidate_contexts": candidate_contexts, "vertex_contexts": vertex_contexts,
            "neighbour_contexts": neighbour_contexts, "inverted": inverted, "scale_rank": k,
            "filters": thresholds, "seal": seal,
            "multipliers": mult, "class_members": counts, "border": len(border), "toggles": toggles,
            "drops": len(drops),
            # the lists themselves, for the reconstruction (refrecon.py)
            "inherit_border": flags >> 3 & 1, "classes": classes, "border_list": border,
            "toggle_list": toggle_list, "toggle_ranks": toggle_ranks, "drop_list": drops}


# ---------------------------------------------------------------- §2, §3, §12 container


def frame(data):
    """§2: splits the stream into chunks, checking every framing rule for
    the whole stream first. Returns (chunks, cut): chunks = [(type, payload,
    offset)], cut = True when the data ends before HEND's end."""
    if data[:8] != SIGNATURE[:len(data[:8])]:
        raise DecodeError("bad_magic", "not an HMC stream (bad signature)")
    if len(data) < 10:
        return [], True  # the version of a cut preamble is not examined (§2)
    if data[8] != 0:
        raise DecodeError("unsupported_version", "stream version %d.x, this decoder implements 0.x" % data[8])
    pos = 10
    chunks = []
    while True:
        if pos == len(data):
            return chunks, True
        if len(data) - pos < 8:
            return chunks, True
        ctype = data[pos:pos + 4]
        if not all(65 <= b <= 90 or 97 <= b <= 122 for b in ctype):
            raise DecodeError("bad_chunk", "chunk type %r at offset %d is not four letters" % (bytes(ctype), pos))
        length = struct.unpack("<I", data[pos + 4:pos + 8])[0]
        if length > MAX_LEN:
            raise DecodeError("bad_chunk", "chunk %s at offset %d: length %d > 2^31 - 1" % (ctype.decode(), pos, length))
        if len(data) - pos - 8 < length + 4:
            return chunks, True
        payload = data[pos + 8:pos + 8 + length]
        crc = struct.unpack("<I", data[pos + 8 + length:pos + 12 + length])[0]
        if zlib.crc32(ctype + payload) & 0xFFFFFFFF != crc:
            raise DecodeError("crc_mismatch", "chunk %s at offset %d: CRC mismatch" % (ctype.decode(), pos))
        chunks.append((ctype.decode("ascii"), payload, pos))
        pos += 12 + length
        if ctype == b"HEND":
            if pos != len(data):
                raise DecodeError("bad_chunk", "%d byte(s) after HEND" % (len(data) - pos))
            return chunks, False


def decode(data):
    chunks, cut = frame(data)
    st = {"kind": None, "q": None, "origin": None, "step": None, "declared": None}
    levels = []  # (K, points) complete levels, coarsest first
    current = None  # points of the last decoded layer
    pending_rcon = False  # a layer chunk waits for its RCON
    layers = 0
    seen = set()

    def need(cond, msg):
        if not cond:
            raise DecodeError("bad_chunk", msg)

    for i, (t, payload, off) in enumerate(chunks):
        if i == 0:
            need(t == "HEAD", "the first chunk is %s, not HEAD" % t)
        if t[0].islower():
            continue  # ancillary: info and unknown ones are skipped
        if pending_rcon:
            need(t == "RCON", "%s where the RCON of level %d is due" % (t, st["L"] - layers))
        if t == "HEAD":
            need("HEAD" not in seen, "second HEAD")
            r = ByteReader(payload, "bad_header", "HEAD")
            kind = r.u8()
            if kind not in KIND_NAMES:
                r.fail("kind %d" % kind)
            flags = r.u8()
            if flags & 0xFE:
                r.fail("reserved flag bits set (flags = %d)" % flags)
            L = r.varint()
            if not 1 <= L <= 64:
                r.fail("level_count %d" % L)
            pts = []
            for _ in range(L):
                v = r.varint()
                if (not pts and v < 1) or (pts and v <= pts[-1]):
                    r.fail("level_points not strictly increasing from 1")
                pts.append(v)
            r.end()
            st.update(kind=kind, declared=pts, L=L, tables=flags & 1)
        elif t == "SQNT":
            need("SQNT" not in seen, "second SQNT")
            need("BASE" not in seen, "SQNT after BASE")
            r = ByteReader(payload, "bad_header", "SQNT")
            if len(payload) != 33:
                r.fail("payload of %d bytes, not 33" % len(payload))
            q = r.u8()
            if not 1 <= q <= 21:
                r.fail("q = %d out of range" % q)
            origin = [r.f64() for _ in range(3)]
            step = r.f64()
            if not all(math.isfinite(v) for v in origin):
                r.fail("origin not finite")
            if not (math.isfinite(step) and step > 0):
                r.fail("step not finite and positive")
            if st["declared"][-1] > 1 << (3 * q):
                r.fail("%d points do not fit a grid of 2^%d points" % (st["declared"][-1], 3 * q))
            st.update(q=q, origin=origin, step=step)
        elif t == "BASE":
            need("SQNT" in seen, "BASE before SQNT")
            need("BASE" not in seen, "second BASE")
            current = decode_base(payload, st["q"], st["declared"][0], st["tables"])
            layers = 1
            pending_rcon = st["kind"] != 0
            if not pending_rcon:
                levels.append((st["L"] - 1, current))
        elif t == "REFN":
            need("BASE" in seen, "REFN before BASE")
            need(layers < st["L"], "more layer chunks than the %d declared levels" % st["L"])
            n = st["declared"][layers] - st["declared"][layers - 1]
            added = decode_refn(payload, st["q"], current, n, st["tables"])
            current = sorted(current + added)
            layers += 1
            pending_rcon = st["kind"] != 0
            if not pending_rcon:
                levels.append((st["L"] - layers, current))
        elif t == "RCON":
            need(st["kind"] != 0, "RCON in a stream of kind points")
            need(pending_rcon, "RCON without a layer chunk before it")
            rc = parse_rcon(payload, len(current), st["tables"])
            pending_rcon = False
            # §11: the level's triangles or tetrahedra (refrecon.py)
            B, st["border_state"] = refrecon.resolve_border(rc, current, st.get("border_state"))
            try:
                st.setdefault("simplices", {})[st["L"] - layers] = refrecon.reconstruct(st["kind"], current, rc, B)
            except refrecon.ReconError as e:
                raise DecodeError(e.cls, e.msg)
            levels.append((st["L"] - layers, current))
        elif t == "HEND":
            need(len(payload) == 0, "non-empty HEND")
            need(len(levels) == st["L"], "HEND after %d of %d levels" % (len(levels), st["L"]))
        else:
            raise DecodeError("bad_chunk", "unknown critical chunk %s" % t)
        seen.add(t)
    if not levels:
        raise DecodeError("truncated", "the stream ends before its first level is complete")
    warning = None
    if cut:
        warning = "the stream is cut: %d of %d levels decoded" % (len(levels), st["L"])
    return st, levels, warning


def g17(v):
    return "%.17g" % v


def header_json(st):
    pts = list(reversed(st["declared"]))
    return ("{\n"
            '  "kind": "%s",\n'
            '  "q": %d,\n'
            '  "origin": [%s, %s, %s],\n'
            '  "step": %s,\n'
            '  "levels": %d,\n'
            '  "level_points": [%s]\n'
            "}\n") % (KIND_NAMES[st["kind"]], st["q"], g17(st["origin"][0]), g17(st["origin"][1]),
                      g17(st["origin"][2]), g17(st["step"]), len(pts), ", ".join(str(v) for v in pts))


def main(argv):
    if len(argv) != 3:
        sys.stderr.write("usage: refdec.py IN.hmc OUTDIR\n")
        return 1
    src, out = argv[1], argv[2]
    try:
        with open(src, "rb") as f:
            data = f.read()
    except OSError as e:
        sys.stderr.write("refdec: %s: io_error: %s\n" % (src, e))
        return 2
    try:
        st, levels, warning = decode(data)
    except DecodeError as e:
        sys.stderr.write("refdec: %s: %s: %s\n" % (src, e.cls, e.msg))
        return 3
    if warning:
        sys.stderr.write("refdec: warning: %s: %s\n" % (src, warning))
    try:
        os.makedirs(out, exist_ok=True)
        with open(os.path.join(out, "header.json"), "w", newline="\n") as f:
            f.write(header_json(st))
        for K, pts in levels:
            with open(os.path.join(out, "level-%d.points" % K), "w", newline="\n") as f:
                f.write("".join("%d %d %d\n" % p for p in pts))
            if K in st.get("simplices", {}):  # conformance.md §2.3: indices sorted within and across lines
                with open(os.path.join(out, "level-%d.simplices" % K), "w", newline="\n") as f:
                    f.write("".join(" ".join(map(str, s)) + "\n" for s in sorted(tuple(sorted(s)) for s in st["simplices"][K])))
    except OSError as e:
        sys.stderr.write("refdec: %s: io_error: %s\n" % (out, e))
        return 4
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
