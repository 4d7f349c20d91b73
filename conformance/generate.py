#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""Rebuilds the HMC conformance vectors deterministically.

    generate.py --hmc PATH/TO/hmc [--out DIR]     rebuild every case into DIR
                                                  (default: vectors/ beside this file)
    generate.py --hmc PATH/TO/hmc --check [--cases DIR]
                                                  re-encode every case from the input
                                                  and options recorded in its folder and
                                                  fail if the bytes differ from stream.hmc
                                                  while spec/hmc.md's version is unchanged

Every input is made here: by `hmc gen` or by the small writers below (XYZ,
OFF, MEDIT .mesh). Positive cases are encoded by `hmc enc` with recorded
options, then optionally edited at the chunk level (spliced ancillary
chunks, truncation); their expected canonical dump is written by
`hmc dec --canonical`. A few positive cases are built here bit by bit
(refinement layers with neighbour counts and context classes the encoder
never picks, hand-written RCON chunks). Negative cases are valid streams
with exactly one defect, each edit recomputing the CRCs it touches (except
the CRC cases).

Python 3 standard library only.
"""
import argparse
import heapq
import itertools
import json
import math
import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
import refdec  # noqa: E402  (ranking of §8A.1 for the hand-built layers, Huffman reader for descriptions)

SIG = bytes([0x89, 0x48, 0x4D, 0x43, 0x0D, 0x0A, 0x1A, 0x0A])
VERSION = b"\x00\x1b"  # version_major, version_minor of the hand-built streams
SPEC = os.path.join(HERE, "..", "spec", "hmc.md")


# ---------------------------------------------------------------- bytes, chunks


def varint(v):
    out = bytearray()
    while True:
        b = v & 0x7F
        v >>= 7
        if v:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def svarint(v):
    return varint((v << 1) ^ (v >> 63) if v >= 0 else ((v << 1) ^ -1) & (2**64 - 1))


def crc(t, payload):
    return zlib.crc32(t.encode("ascii") + payload) & 0xFFFFFFFF


def chunk_bytes(t, payload, stored_crc=None):
    c = crc(t, payload) if stored_crc is None else stored_crc
    return t.encode("ascii") + struct.pack("<I", len(payload)) + payload + struct.pack("<I", c)


def split(data):
    """A valid stream -> (preamble, [[type, payload], ...])."""
    assert data[:8] == SIG, "not an HMC stream"
    pos, out = 10, []
    while pos < len(data):
        t = data[pos:pos + 4].decode("ascii")
        n = struct.unpack("<I", data[pos + 4:pos + 8])[0]
        out.append([t, data[pos + 8:pos + 8 + n]])
        pos += 12 + n
    assert pos == len(data)
    return data[:10], out


def join(pre, chunks):
    return pre + b"".join(chunk_bytes(t, p) for t, p in chunks)


def offsets(data):
    """Byte offset of every chunk of a valid stream, and the end."""
    pos, out = 10, []
    while pos < len(data):
        out.append(pos)
        pos += 12 + struct.unpack("<I", data[pos + 4:pos + 8])[0]
    return out + [pos]


def apply_edits(data, edits):
    """Applies recorded edit operations (case.json "edit") to a stream."""
    for e in edits:
        op = e["op"]
        if op in ("insert_chunk", "remove_chunk", "replace_payload", "move_chunk", "copy_chunk", "set_type"):
            pre, ch = split(data)
            if op == "insert_chunk":
                ch.insert(e["at"], [e["type"], bytes.fromhex(e["payload"])])
            elif op == "remove_chunk":
                del ch[e["at"]]
            elif op == "replace_payload":
                ch[e["at"]][1] = bytes.fromhex(e["payload"])
            elif op == "move_chunk":
                c = ch.pop(e["from"])
                ch.insert(e["to"], c)
            elif op == "copy_chunk":
                ch.insert(e["to"], list(ch[e["from"]]))
            elif op == "set_type":
                ch[e["at"]][0] = e["type"]
            data = join(pre, ch)
        elif op == "truncate":
            data = data[:e["length"]]
        elif op == "truncate_in_chunk":  # cut `keep` bytes into chunk `at`
            data = data[:offsets(data)[e["at"]] + e["keep"]]
        elif op == "append":
            data = data + bytes.fromhex(e["hex"])
        elif op == "patch":  # overwrite bytes, CRCs untouched
            b = bytearray(data)
            off = e["offset"] if "offset" in e else offsets(data)[e["chunk"]] + e["chunk_offset"]
            new = bytes.fromhex(e["hex"])
            b[off:off + len(new)] = new
            data = bytes(b)
        elif op == "xor":  # flip bits of one byte, CRCs untouched
            b = bytearray(data)
            off = offsets(data)[e["chunk"]] + e["chunk_offset"]
            b[off] ^= e["mask"]
            data = bytes(b)
        else:
            raise ValueError("unknown edit " + op)
    return data


# ---------------------------------------------------------------- bit writer, Huffman codes


class BitWriter:
    def __init__(self):
        self.bits = []

    def put(self, v, n):
        for i in range(n - 1, -1, -1):
            self.bits.append((v >> i) & 1)

    def ue(self, v):
        x = v + 1
        z = x.bit_length() - 1
        self.put(0, z)
        self.put(x, z + 1)

    def bytes(self, pad_bit=0):
        b = list(self.bits)
        while len(b) % 8:
            b.append(pad_bit)
        return bytes(int("".join(map(str, b[i:i + 8])), 2) for i in range(0, len(b), 8))


def huffman_lengths(counts):
    """Code lengths (<= 15) for symbol counts {symbol: count}, >= 2 symbols."""
    heap = [(c, s, [s]) for s, c in sorted(counts.items())]
    heapq.heapify(heap)
    depth = {s: 0 for s in counts}
    while len(heap) > 1:
        c1, k1, g1 = heapq.heappop(heap)
        c2, k2, g2 = heapq.heappop(heap)
        for s in g1 + g2:
            depth[s] += 1
        heapq.heappush(heap, (c1 + c2, min(k1, k2), g1 + g2))
    assert max(depth.values()) <= 15
    return depth


def canonical_codes(lengths):
    """{symbol: length} -> {symbol: (code, length)} as in §7.2."""
    order = sorted((l, s) for s, l in lengths.items() if l)
    codes, code, prev = {}, 0, order[0][0]
    for l, s in order:
        code <<= l - prev
        prev = l
        codes[s] = (code, l)
        code += 1
    return codes


# The code-length table form of the hand-built streams being written: 0 the
# 4-bit form, 1 the delta form (HEAD flag bit 0); see delta_tables().
TABLE_FORM = [0]


class delta_tables:
    """Within `with delta_tables():`, tables are written in the delta form."""

    def __enter__(self):
        TABLE_FORM.append(1)

    def __exit__(self, *exc):
        TABLE_FORM.pop()


def write_delta_lengths(bw, alphabet, lengths):
    """§7.1 delta form: 00 same, 01 zero run, 100 +1, 101 -1, 1100 +2,
    1101 -2, 1110 end, 1111 s ue (far); the first length relative to 3."""
    prev = 3
    s = 0
    while s < alphabet:
        l = lengths.get(s, 0)
        if l:
            d = l - prev
            prev = l
            s += 1
            if d == 0:
                bw.put(0b00, 2)
            elif d in (1, -1):
                bw.put(0b100 if d > 0 else 0b101, 3)
            elif d in (2, -2):
                bw.put(0b1100 if d > 0 else 0b1101, 4)
            else:
                bw.put(0b1111, 4)
                bw.put(1 if d < 0 else 0, 1)
                bw.ue(abs(d) - 3)
            continue
        run = 0
        while s + run < alphabet and not lengths.get(s + run, 0):
            run += 1
        if s + run == alphabet and run > 1:
            bw.put(0b1110, 4)  # end: cheaper than a run of 2 or more
            return
        bw.put(0b01, 2)
        bw.ue(run - 1)
        s += run


def write_table(bw, alphabet, lengths=None, single=None):
    """§7.1. lengths: {symbol: length}; or single: the one symbol."""
    if single is not None:
        bw.put(1, 1)
        bw.put(single, max(1, (alphabet - 1).bit_length()))
        return
    bw.put(0, 1)
    if TABLE_FORM[-1]:
        write_delta_lengths(bw, alphabet, lengths)
        return
    s = 0
    while s < alphabet:
        l = lengths.get(s, 0)
        if l:
            bw.put(l, 4)
            s += 1
        else:
            run = 0
            while s + run < alphabet and not lengths.get(s + run, 0):
                run += 1
            bw.put(0, 4)
            bw.ue(run - 1)
            s += run


class Coder:
    """A code for a list of symbols, written with write_table."""

    def __init__(self, symbols, alphabet):
        counts = {}
        for s in symbols:
            counts[s] = counts.get(s, 0) + 1
        self.alphabet = alphabet
        if len(counts) == 1:
            self.single = next(iter(counts))
            self.codes = None
        else:
            self.single = None
            self.lengths = huffman_lengths(counts)
            self.codes = canonical_codes(self.lengths)

    def table(self, bw):
        if self.single is not None:
            write_table(bw, self.alphabet, single=self.single)
        else:
            write_table(bw, self.alphabet, lengths=self.lengths)

    def put(self, bw, s):
        if self.codes is not None:
            c, l = self.codes[s]
            bw.put(c, l)


class PairedCoder:
    """§7.4: a paired table for the symbols `sequence`, in their order of
    use; an odd sequence's last pair takes 0 as its second symbol."""

    def __init__(self, sequence, alphabet, tail=0, phantoms=False):
        self.sequence = list(sequence)
        self.alphabet = alphabet
        self.pairs = []
        for i in range(0, len(self.sequence), 2):
            a = self.sequence[i]
            b = self.sequence[i + 1] if i + 1 < len(self.sequence) else tail
            self.pairs.append((a, b))
        self.pair_syms = [a * 8 + b if a < 8 and b < 8 else 64 for a, b in self.pairs]
        escaped = [v for (a, b), p in zip(self.pairs, self.pair_syms) if p == 64 for v in (a, b)]
        # phantoms: pairs (0, 0) and (0, 1) counted once more, so that the pair
        # code has two symbols at least (§8.2, ranked depths)
        self.pair_coder = Coder(self.pair_syms + ([0, 1] if phantoms else []), 65)
        self.escape = Coder(escaped, alphabet) if escaped else None
        self.next = 0

    def table(self, bw):
        self.pair_coder.table(bw)
        if self.escape is not None:
            self.escape.table(bw)

    def put(self, bw, s):
        i = self.next
        assert self.sequence[i] == s
        self.next += 1
        if i % 2:
            return  # the second symbol of a pair: already sent
        self.pair_coder.put(bw, self.pair_syms[i // 2])
        if self.pair_syms[i // 2] == 64:
            a, b = self.pairs[i // 2]
            self.escape.put(bw, a)
            self.escape.put(bw, b)


# ---------------------------------------------------------------- hand-built layers and chunks


def morton(p, q):
    k = 0
    for b in range(q - 1, -1, -1):
        k = (k << 3) | (((p[0] >> b) & 1) << 2) | (((p[1] >> b) & 1) << 1) | ((p[2] >> b) & 1)
    return k


def octree_levels(points, q):
    """§8.1: for each depth, the nodes in Morton order and {node: occupancy}."""
    pts = sorted(set(points), key=lambda p: morton(p, q))
    nodes = [(0, 0, 0)]
    for d in range(q):
        s = q - d - 1
        occ_by_node = {}
        for p in pts:
            key = (p[0] >> (s + 1), p[1] >> (s + 1), p[2] >> (s + 1))
            c = (((p[0] >> s) & 1) << 2) | (((p[1] >> s) & 1) << 1) | ((p[2] >> s) & 1)
            occ_by_node[key] = occ_by_node.get(key, 0) | (1 << c)
        yield d, nodes, occ_by_node
        nodes = [(2 * X + (c >> 2), 2 * Y + ((c >> 1) & 1), 2 * Z + (c & 1))
                 for (X, Y, Z) in nodes for c in range(8) if occ_by_node[(X, Y, Z)] >> c & 1]


def base_payload(points, q):
    """§8.1 octree coder for a set of grid points."""
    syms = [[occ[n] for n in nodes] for _, nodes, occ in octree_levels(points, q)]
    bw = BitWriter()
    coders = [Coder(s, 256) for s in syms]
    for c in coders:
        c.table(bw)
    for c, ss in zip(coders, syms):
        for s in ss:
            c.put(bw, s)
    return b"\x00" + bw.bytes()


def base_ranked_payload(points, q, neighbours, ranked, classes=1, gaps=None, quadric=None, paired=None):
    """§8.2 ranked octree coder (coder 5), written from the decoder's ranking
    (refdec.child_order over each node's causal points); ranked[d] says
    whether depth d is ranked; `classes` contexts per ranked depth; gaps[d]
    the weight of ranked depth d (0 when None; 16 the far ranking);
    quadric[d] its quadric flag (all 0 when None); paired(d, j) whether table
    j of depth d is paired (§7.4; none when None)."""
    gaps = gaps or [0] * q
    quadric = quadric or [False] * q
    paired = paired or (lambda d, j: False)
    syms = []
    for d, nodes, occ_by_node in octree_levels(points, q):
        if not ranked[d]:
            syms.append([occ_by_node[n] for n in nodes])
            continue
        h = 1 << (q - d)
        centres = [(X * h + h // 2, Y * h + h // 2, Z * h + h // 2) for (X, Y, Z) in nodes]
        nb = refdec.Neighbours(centres, q)
        occs = [occ_by_node[n] for n in nodes]
        row = []
        for i, node in enumerate(nodes):
            P = refdec.causal_points(nodes, occs, i, nb, neighbours, h)
            pi, split = refdec.child_order(node, d, q, 0, None, None, 0, want_split=True, gap=gaps[d], gap_from=1,
                                           fit=len(P) if quadric[d] else 0, points=P)
            occ = occ_by_node[node]
            ctx = min((0, 1, 2, 2, 3)[split], classes - 1)
            row.append((ctx, refdec.E.index(sum(1 << r for r in range(8) if occ >> pi[r] & 1))))
        syms.append(row)
    bw = BitWriter()
    bw.put(neighbours, 4)
    bw.put(classes - 1, 2)
    coders = []
    for d in range(q):
        bw.put(1 if ranked[d] else 0, 1)
        if ranked[d]:
            bw.put(gaps[d], 5)
            bw.put(1 if quadric[d] else 0, 1)
        if ranked[d]:
            # One table per context, of two symbols at least (§8.2): a context
            # with fewer gets phantom symbols 0 and 1 (in a paired table, pairs).
            row = []
            for j in range(classes):
                seq = [v for c, v in syms[d] if c == j]
                row.append(PairedCoder(seq, 255, phantoms=True) if paired(d, j) and seq
                           else Coder(seq + [0, 1], 255))
            coders.append(row)
        else:
            coders.append([PairedCoder(syms[d], 256) if paired(d, 0) else Coder(syms[d], 256)])
        for c in coders[-1]:
            bw.put(1 if isinstance(c, PairedCoder) else 0, 1)
            c.table(bw)
    for d in range(q):
        for v in syms[d]:
            if ranked[d]:
                coders[d][v[0]].put(bw, v[1])
            else:
                coders[d][0].put(bw, v)
    return b"\x05" + bw.bytes()


def base_ranked_stream(kind, q, pts, neighbours, ranked, classes=1, gaps=None, quadric=None, paired=None):
    pts = sorted(set(pts))
    return stream_q1(base_ranked_payload(pts, q, neighbours, ranked, classes, gaps, quadric, paired),
                     counts=(len(pts),),
                     kind=kind, q=q,
                     rcon=None if kind == 0 else rcon_payload(len(pts), compact=True))


def refn_payload(coarse, added, q, neighbours, classes, share=True, force_tables=False, planes=1, gap=None, fit=None,
                 paired=None, merge=False, tail=0, wide=False):
    """§8A.1 conditional octree coder, written from the decoder's ranking
    (refdec.child_order): coder 0 (the short header) when planes = 1 and
    gap, fit and paired are None and not `wide`, else coder 7 (the full
    header) with planes 1 or 2 (the plane context), gap one weight (16: the
    far ranking) or a list of q, fit the quadric's F (0 when None), and
    paired(d, j) saying whether the table sent at depth d for slot j =
    (class, plane context) is paired (§7.4). merge: each slot sends one
    table, at its first depth with symbols, which the deeper depths share.
    tail: the unused second symbol of an odd paired sequence's last pair.
    coarse: C in canonical order; added: A."""
    full = wide or planes == 2 or gap is not None or fit is not None or paired is not None
    if full and paired is None:
        paired = lambda d, j: False
    coarse = sorted(coarse)
    occ = [set() for _ in range(q + 1)]
    for (x, y, z) in coarse:
        for d in range(q + 1):
            occ[d].add((x >> (q - d), y >> (q - d), z >> (q - d)))
    aocc = [set() for _ in range(q + 1)]
    for (x, y, z) in added:
        for d in range(q + 1):
            aocc[d].add((x >> (q - d), y >> (q - d), z >> (q - d)))
    nb = refdec.Neighbours(coarse, q)
    seq = []  # (d, (class, plane context), symbol)
    slots = [(j, x) for j in range(classes) for x in range(planes)]

    def visit(node, d):
        X, Y, Z = node
        kids = [(2 * X + (c >> 2), 2 * Y + ((c >> 1) & 1), 2 * Z + (c & 1)) for c in range(8)]
        m = sum(1 << c for c in range(8) if kids[c] in occ[d + 1])
        j = min(bin(m).count("1"), classes - 1)
        g = gap[d] if isinstance(gap, list) else gap or 0
        pi, split = refdec.child_order(node, d, q, m, coarse, nb, neighbours, want_split=True, gap=g, fit=fit or 0)
        x = 1 if planes == 2 and split >= 2 else 0
        rho = sum(1 << r for r in range(8) if kids[pi[r]] in aocc[d + 1])
        seq.append((d, (j, x), refdec.E.index(rho)))
        if d < q - 1:
            for c in range(8):
                if kids[c] in aocc[d + 1]:
                    visit(kids[c], d + 1)

    visit((0, 0, 0), 0)
    bw = BitWriter()
    bw.put(neighbours, 4)
    bw.put(classes - 1, 2)
    if full:
        bw.put(planes - 1, 1)
        bw.put(fit or 0, 4)
        bw.put(1 if isinstance(gap, list) else 0, 1)
        for g in (gap if isinstance(gap, list) else [gap or 0]):
            bw.put(g, 5)
    coder = {}
    for j in slots:
        prev = None
        for d in range(q):
            syms = [s for (dd, jj, s) in seq if dd == d and jj == j]
            if merge and syms and prev is not None:
                coder[(d, j)] = None  # the slot's one table serves this depth too
            elif syms or force_tables or (prev is None and not share):
                # a table of its own (flag 1); unused slots get a two-symbol code
                c = Coder(syms if syms else [0, 1], 255)
                coder[(d, j)] = c
                prev = c
            elif share and prev is not None and d > 0:
                coder[(d, j)] = None  # marks "inherit" (flag 0)
            else:
                coder[(d, j)] = False  # flag 0 at depth 0: none
    def tables_in_use():
        """The table each slot decodes with: its own, or the one above."""
        current = {}
        for j in slots:
            for d in range(q):
                if coder[(d, j)]:
                    current[(d, j)] = coder[(d, j)]
                elif d > 0 and (d - 1, j) in current:
                    current[(d, j)] = current[(d - 1, j)]
        return current

    current = tables_in_use()
    if merge or paired is not None:
        # Codes from every symbol a table codes (merge), paired where asked.
        uses = {}
        for (d, j, s) in seq:
            uses.setdefault(id(current[(d, j)]), []).append(s)
        for d in range(q):
            for j in slots:
                c = coder[(d, j)]
                if c:
                    sequence = uses.get(id(c), [])
                    if paired is not None and paired(d, j) and sequence:
                        coder[(d, j)] = PairedCoder(sequence, 255, tail)
                    elif merge and sequence:
                        coder[(d, j)] = Coder(sequence, 255)
        current = tables_in_use()
    for d in range(q):
        for j in slots:
            c = coder[(d, j)]
            if c:
                bw.put(1, 1)
                if paired is not None:
                    bw.put(1 if isinstance(c, PairedCoder) else 0, 1)
                c.table(bw)
            else:
                bw.put(0, 1)
    for (d, j, s) in seq:
        current[(d, j)].put(bw, s)
    return bytes([7 if full else 0]) + bw.bytes()


def zigzag(v):
    return 2 * v if v >= 0 else -2 * v - 1


def vq_payload(points, codebook_size, step, pad_bit=0):
    """A layer of REFN coder 1, the anchored vector quantizer of versions
    0.4-0.26 (removed in 0.27), as those versions' section 8A.2 coded it:
    for the negative vector that checks it is refused. points: [(anchor,
    index, (r0, r1, r2))] in stream order (anchors non-decreasing); the
    residuals are ignored when step is 0."""
    gaps, prev = [], 0
    for a, _, _ in points:
        gaps.append(a - prev)
        prev = a
    gap_coder = Coder([min(g, 63) for g in gaps], 64)
    index_coder = Coder([i for _, i, _ in points], codebook_size)
    res = [[zigzag(r[a]) for _, _, r in points] for a in range(3)]
    res_coders = [Coder([min(z, 63) for z in res[a]], 64) for a in range(3)] if step else []
    bw = BitWriter()
    bw.ue(step)
    gap_coder.table(bw)
    index_coder.table(bw)
    for c in res_coders:
        c.table(bw)

    def escaped(coder, v):
        coder.put(bw, min(v, 63))
        if v >= 63:
            bw.ue(v - 63)

    for j, (a, i, r) in enumerate(points):
        escaped(gap_coder, gaps[j])
        index_coder.put(bw, i)
        for ax in range(len(res_coders)):
            escaped(res_coders[ax], res[ax][j])
    return b"\x01" + bw.bytes(pad_bit)


def head_payload(kind, counts, flags=0):
    return bytes([kind, flags]) + varint(len(counts)) + b"".join(varint(c) for c in counts)


def sqnt_payload(q, origin=(0.0, 0.0, 0.0), step=1.0):
    return bytes([q]) + struct.pack("<dddd", origin[0], origin[1], origin[2], step)


def vqtb_payload(entries, dimension=3):
    """A VQTB chunk of versions 0.1-0.26 (removed in 0.27)."""
    return bytes([dimension]) + varint(len(entries)) + b"".join(svarint(v) for e in entries for v in e)


def rice_bits(bw, ranks, k=None, inverted=None):
    """§10.2: one context's count, Rice parameter and gap codes; inverted
    (neighbour contexts, 0 or 1): the count field is 2 * count + inverted."""
    bw.ue(len(ranks) if inverted is None else 2 * len(ranks) + int(inverted))
    if not ranks:
        return
    gaps = [v - p - 1 for p, v in zip([-1] + list(ranks[:-1]), ranks)]
    if k is None:
        k = min(range(32), key=lambda r: sum((g >> r) + 1 + r for g in gaps))
    bw.put(k, 5)
    for g in gaps:
        bw.put((1 << (g >> k)) - 1, g >> k)  # q one bits
        bw.put(0, 1)
        bw.put(g & ((1 << k) - 1), k)


def rcon_payload(n, flags=1, scale_rank=6, multipliers=(1024,), classes=None, border=(), toggles=(),
                 drops=(), class_code_bits=None, filters=None, mask=None, compact=False, group=1, toggle_bits=None,
                 common=None, candidate_contexts=False, vertex_contexts=False, neighbour_contexts=False,
                 inverted=(), seal=None):
    """§10. classes: the class of each of the n points (needed when K > 1);
    filters: {filter number: threshold}. compact: flag bit 2, classes in
    groups of `group` points (10.1) and `toggles` as {context: ranks} (10.2),
    or the toggle bit stream as given in `toggle_bits`. common: flag bit 4,
    the classes as a list of the points outside class `common` (10.1).
    candidate_contexts: flag bit 5, 40 toggle contexts (11.5);
    vertex_contexts: flag bit 6, 80 (with candidate_contexts);
    neighbour_contexts: flag bit 7, 240 (with vertex_contexts), the lists
    of the contexts in `inverted` naming the tetrahedra not toggled.
    seal: filter_mask bit 6, the seal box (x0, y0, z0, x1, y1, z1) after
    the thresholds (11.3)."""
    filters = filters or {}
    if mask is None:
        mask = sum(1 << i for i in filters) | (0x40 if seal is not None else 0)
    if compact:
        flags |= 4
    if common is not None:
        flags |= 16
    if candidate_contexts:
        flags |= 32
    if vertex_contexts:
        flags |= 64
    if neighbour_contexts:
        flags |= 128
    out = bytes([flags, scale_rank, mask]) + b"".join(varint(filters[i]) for i in sorted(filters))
    out += b"".join(varint(b) for b in seal or ())
    out += varint(len(multipliers)) + b"".join(varint(m) for m in multipliers)
    if len(multipliers) > 1:
        if class_code_bits is not None:
            out += class_code_bits
        elif common is not None:
            K = len(multipliers)
            listed = [v for v, c in enumerate(classes) if c != common]
            bw = BitWriter()
            bw.put(common, 6)
            rice_bits(bw, listed)
            if K > 2:
                symbols = [c - (c > common) for c in classes if c != common]
                c = Coder(symbols or [0], K - 1)
                c.table(bw)
                for sym in symbols:
                    c.put(bw, sym)
            out += bw.bytes()
        elif compact:
            K = len(multipliers)
            padded = list(classes) + [0] * (-len(classes) % group)
            symbols = [sum(padded[b + i] * K ** i for i in range(group)) for b in range(0, len(padded), group)]
            bw = BitWriter()
            bw.put(group - 1, 3)
            c = Coder(symbols, K ** group)
            c.table(bw)
            for s in symbols:
                c.put(bw, s)
            out += bw.bytes()
        else:
            bw = BitWriter()
            c = Coder(classes, len(multipliers))
            c.table(bw)
            for s in classes:
                c.put(bw, s)
            out += bw.bytes()

    def gaps(lst):
        b = varint(len(lst))
        prev = -1
        for v in lst:
            b += varint(v - prev - 1)
            prev = v
        return b

    if not compact:
        return out + gaps(border) + gaps(toggles) + gaps(drops)
    if toggle_bits is None:
        bw = BitWriter()
        toggles = toggles or {}
        for j in range(240 if neighbour_contexts else 80 if vertex_contexts else 40 if candidate_contexts else 8):
            rice_bits(bw, sorted(toggles.get(j, ())), inverted=(j in inverted) if neighbour_contexts else None)
        toggle_bits = bw.bytes()
    return out + gaps(border) + gaps(drops) + toggle_bits


def describe_rcon(payload, n):
    """Fields of an RCON for case.json (toggles: one count, or one per
    context in the compact form)."""
    d = refdec.parse_rcon(payload, n)
    for k in ("inherit_border", "classes", "border_list", "toggle_list", "toggle_ranks", "drop_list"):
        d.pop(k)  # the lists refdec.py keeps for its reconstruction
    if d["seal"] is None:
        d.pop("seal")  # RCON without a seal box (the form of every stream before 0.26)
    d["filters"] = {str(i): t for i, t in sorted(d["filters"].items())}
    return d


def describe_refn(payload):
    if payload[0] == 1:
        br = refdec.BitReader(payload, 1, "bad_layer", "REFN")
        return {"coder": 1, "residual_step": br.ue()}
    b = payload[1]
    return {"coder": payload[0], "neighbours": b >> 4, "classes": ((b >> 2) & 3) + 1}


def describe(data):
    """A summary of a valid (possibly cut) stream's chunks for case.json."""
    out = []
    pos = 10
    kind = None
    counts = []
    layer = 0
    while pos + 12 <= len(data):
        t = data[pos:pos + 4].decode("ascii", "replace")
        n = struct.unpack("<I", data[pos + 4:pos + 8])[0]
        if pos + 12 + n > len(data):
            break
        p = data[pos + 8:pos + 8 + n]
        d = {"type": t, "length": n}
        try:
            if t == "HEAD":
                r = refdec.ByteReader(p, "x", "x")
                kind = r.u8()
                r.u8()
                counts = [r.varint() for _ in range(r.varint())]
            elif t == "SQNT":
                d["q"] = p[0]
            elif t in ("BASE", "REFN"):
                if t == "REFN" and len(p) > 1:
                    d.update(describe_refn(p))
                if t == "BASE" and p:
                    d["coder"] = p[0]
                    if p[0] == 1 and len(p) > 1:
                        d["neighbours"] = p[1] >> 4
                layer += 1
            elif t == "RCON":
                d.update(describe_rcon(p, counts[layer - 1]))
        except Exception:  # a negative case's defect: no description
            pass
        out.append(d)
        pos += 12 + n
    return out


# ---------------------------------------------------------------- inputs


def write_xyz(path, pts):
    with open(path, "w", newline="\n") as f:
        for p in pts:
            f.write("%r %r %r\n" % tuple(float(c) for c in p))


def write_off(path, pts, tris):
    with open(path, "w", newline="\n") as f:
        f.write("OFF\n%d %d 0\n" % (len(pts), len(tris)))
        for p in pts:
            f.write("%r %r %r\n" % tuple(float(c) for c in p))
        for t in tris:
            f.write("3 %d %d %d\n" % tuple(t))


def write_mesh(path, pts, tets):
    with open(path, "w", newline="\n") as f:
        f.write("MeshVersionFormatted 1\nDimension 3\nVertices\n%d\n" % len(pts))
        for p in pts:
            f.write("%r %r %r 0\n" % tuple(float(c) for c in p))
        f.write("Tetrahedra\n%d\n" % len(tets))
        for t in tets:
            f.write("%d %d %d %d 0\n" % tuple(i + 1 for i in t))
        f.write("End\n")


def kuhn_cube(n, jitter=0.0, seed=0):
    """An n^3 lattice cut into 6 tetrahedra per cube (a volume mesh)."""
    rnd = random.Random(seed)
    pts = [(x + round(jitter * rnd.uniform(-1, 1), 3), y + round(jitter * rnd.uniform(-1, 1), 3), z + round(jitter * rnd.uniform(-1, 1), 3))
           for x in range(n) for y in range(n) for z in range(n)]
    idx = {(x, y, z): (x * n + y) * n + z for x in range(n) for y in range(n) for z in range(n)}
    tets = []
    for x, y, z in itertools.product(range(n - 1), repeat=3):
        for perm in itertools.permutations(range(3)):
            v = [x, y, z]
            path = [tuple(v)]
            for a in perm:
                v[a] += 1
                path.append(tuple(v))
            tets.append([idx[p] for p in path])
    return pts, tets


def height_field(n, seed=0):
    """An open surface: z = f(x, y) on an n x n grid, two triangles a cell."""
    rnd = random.Random(seed)
    pts = [(round(x + 0.3 * rnd.uniform(-1, 1), 3), round(y + 0.3 * rnd.uniform(-1, 1), 3),
            round(2.0 * math.sin(x * 0.7) * math.cos(y * 0.5) + 0.1 * rnd.uniform(-1, 1), 3))
           for x in range(n) for y in range(n)]
    tris = []
    for x in range(n - 1):
        for y in range(n - 1):
            a, b, c, d = x * n + y, (x + 1) * n + y, (x + 1) * n + y + 1, x * n + y + 1
            tris += [(a, b, c), (a, c, d)]
    return pts, tris


def cylinder(rings, per_ring, radius=1.0, height=3.0):
    """An open tube (two border loops)."""
    pts = [(round(radius * math.cos(2 * math.pi * j / per_ring), 4), round(radius * math.sin(2 * math.pi * j / per_ring), 4),
            round(height * i / (rings - 1), 4)) for i in range(rings) for j in range(per_ring)]
    tris = []
    for i in range(rings - 1):
        for j in range(per_ring):
            a, b = i * per_ring + j, i * per_ring + (j + 1) % per_ring
            c, d = a + per_ring, b + per_ring
            tris += [(a, b, d), (a, d, c)]
    return pts, tris


def torus_arc(rings, per_ring, R=1.0, r=0.3):
    """Half a torus, u in [0, pi]: a bent tube open at both ends, whose
    end loops lie in the plane y = 0 (a tile's piece of a closed surface)."""
    pts = []
    for i in range(rings):
        u = math.pi * i / (rings - 1)
        for j in range(per_ring):
            v = 2 * math.pi * j / per_ring
            w = R + r * math.cos(v)
            pts.append((round(w * math.cos(u), 4), round(w * math.sin(u), 4), round(r * math.sin(v), 4)))
    tris = []
    for i in range(rings - 1):
        for j in range(per_ring):
            a, b = i * per_ring + j, i * per_ring + (j + 1) % per_ring
            tris += [(a, b + per_ring, b), (a, a + per_ring, b + per_ring)]
    return pts, tris


CUBE_PTS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_TRIS = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (1, 2, 6), (1, 6, 5),
             (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]


def make_input(spec, folder, hmc):
    """Writes a case's input into folder; returns its file name."""
    kind = spec[0]
    if kind == "gen":
        _, sample, n, seed = spec
        name = "input.ply"
        run([hmc, "gen", sample, "--vertices", str(n), "--seed", str(seed), "-o", os.path.join(folder, name)])
        return name
    if kind == "xyz":
        name = "input.xyz"
        write_xyz(os.path.join(folder, name), spec[1])
        return name
    if kind == "off":
        name = "input.off"
        write_off(os.path.join(folder, name), spec[1], spec[2])
        return name
    if kind == "mesh":
        name = "input.mesh"
        write_mesh(os.path.join(folder, name), spec[1], spec[2])
        return name
    raise ValueError(kind)


def run(cmd, check=True):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    if check and r.returncode != 0:
        raise RuntimeError("%s failed (%d): %s" % (" ".join(cmd), r.returncode, r.stderr))
    return r


# ---------------------------------------------------------------- the cases

rnd = random.Random(20261122)
LINE = [(i * 0.5, 0.0, 0.0) for i in range(7)]
PLANE = [(x * 1.0, y * 1.0, 0.0) for x in range(6) for y in range(5)]
DUPS = [(0.10, 0.20, 0.30), (0.10, 0.20, 0.30), (0.11, 0.20, 0.30), (0.9, 0.1, 0.5), (0.91, 0.1, 0.5),
        (0.5, 0.9, 0.2), (0.5, 0.9, 0.2), (0.2, 0.4, 0.9), (0.7, 0.7, 0.7), (0.0, 0.0, 0.0), (1.0, 1.0, 1.0)]
OCTA = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
TETRA4 = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
COPLANAR4 = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]
HF = height_field(12, seed=3)
TUBE = cylinder(6, 16)
ARC = torus_arc(20, 12)
VOL4 = kuhn_cube(4)
VOL5J = kuhn_cube(5, jitter=0.15, seed=7)
VOL6J = kuhn_cube(6, jitter=0.2, seed=5)

S = {  # spec sections, by topic
    "container": ["2", "3"], "head": ["4"], "sqnt": ["5"], "huff": ["7"], "base": ["8"],
    "refn": ["8A"], "end": ["9"], "rcon": ["10"], "recon": ["11", "D"], "out": ["12"], "err": ["13"],
}


def sec(*topics):
    out = []
    for t in topics:
        for s in S[t]:
            if s not in out:
                out.append(s)
    return out


P = "points"
F = "full"

# Positive cases encoded by hmc: name -> (input, args, edits-builder or None, covers, profile)
# The profile is "points" for kind points (nothing to reconstruct) and "full" otherwise;
# a "full" case still runs in the points profile, without comparing its .simplices.
ENCODED = [
    # kinds, q, levels
    ("points-ball-q12-l1", ("gen", "ball", 200, 1), ["--bits", "12"], None,
     "kind points, q = 12, one level (BASE only), info chunk", sec("container", "head", "sqnt", "huff", "base", "end")),
    ("points-ball-q12-l4", ("gen", "ball", 250, 2), ["--levels", "4"], None,
     "kind points, four levels: BASE then three REFN, no RCON", sec("head", "base", "refn")),
    ("points-shells-q12-l3-noinfo", ("gen", "shells", 200, 1), ["--levels", "3", "--no-info"], None,
     "kind points, three levels, no ancillary chunk at all", sec("container", "refn")),
    ("points-lattice-q12-l3", ("gen", "lattice", 216, 1), ["--levels", "3"], None,
     "lattice (equal distances everywhere: neighbour ties broken by canonical index)", sec("refn")),
    ("points-ball-q1", ("gen", "ball", 100, 3), ["--bits", "1"], None,
     "q = 1: 100 points merged onto the 8-point grid", sec("sqnt", "base")),
    ("points-ball-q21-l3", ("gen", "ball", 200, 4), ["--bits", "21", "--levels", "3"], None,
     "q = 21, the largest grid, three levels", sec("sqnt", "base", "refn")),
    ("points-ball-q5-l6", ("gen", "ball", 300, 5), ["--bits", "5", "--levels", "6", "--ratio", "0.4"], None,
     "q = 5, dense grid, six levels", sec("base", "refn")),
    ("surface-torus-q12-l1", ("gen", "torus", 200, 1), [], None,
     "kind surface, one level with RCON", sec("rcon", "recon")),
    ("surface-torus-q12-l4", ("gen", "torus", 300, 1), ["--levels", "4"], None,
     "kind surface, four levels, one RCON per level", sec("refn", "rcon", "recon")),
    ("surface-sphere-q1", ("gen", "sphere", 60, 1), ["--bits", "1"], None,
     "kind surface at q = 1: the 8 cube corners, all cospherical", sec("sqnt", "recon")),
    ("surface-sphere-q21-l3", ("gen", "sphere", 200, 1), ["--bits", "21", "--levels", "3"], None,
     "kind surface at q = 21 (extent above 2^16: exact Delaunay beyond TetGen's safe range)", sec("sqnt", "refn", "recon")),
    ("surface-torus-q8-l8", ("gen", "torus", 300, 1), ["--bits", "8", "--levels", "8", "--ratio", "0.15"], None,
     "many levels (--levels 8, ratio 0.15) at q = 8", sec("head", "refn", "rcon")),
    ("volume-ball-q12-l1", ("gen", "ball", 150, 6), ["--kind", "volume"], None,
     "kind volume, one level", sec("rcon", "recon")),
    ("volume-ball-q12-l4", ("gen", "ball", 200, 7), ["--kind", "volume", "--levels", "4"], None,
     "kind volume, four levels", sec("refn", "rcon", "recon")),
    ("volume-lattice-q12-l3", ("gen", "lattice", 125, 1), ["--kind", "volume", "--levels", "3"], None,
     "kind volume on a lattice: nearly every tetrahedron decided by the perturbation rule", sec("recon")),
    ("volume-mesh-q3", ("mesh", VOL4[0], VOL4[1]), ["--bits", "3", "--levels", "2"], None,
     "a tetrahedral input mesh (MEDIT) on a 4^3 lattice at q = 3", sec("recon")),
    ("volume-mesh-jitter-q10-l3", ("mesh", VOL5J[0], VOL5J[1]), ["--bits", "10", "--levels", "3"], None,
     "a jittered 5^3 tetrahedral mesh, three levels", sec("refn", "recon")),
    ("volume-ball-q21-l2", ("gen", "ball", 150, 8), ["--kind", "volume", "--bits", "21", "--levels", "2"], None,
     "kind volume at q = 21", sec("sqnt", "recon")),
    ("volume-ball-q1", ("gen", "ball", 40, 9), ["--kind", "volume", "--bits", "1"], None,
     "kind volume at q = 1 (the unit cube's six tetrahedra)", sec("recon")),
    # octree-cell preview levels (hmc enc's default without --levels, here with its ratio named)
    ("surface-torus-q12-preview", ("gen", "torus", 400, 3), ["--preview-ratio", "0.04"], None,
     "kind surface, the default preview: octree-cell levels below the finest, each with RCON", sec("refn", "rcon", "recon")),
    ("volume-ball-q12-preview", ("gen", "ball", 400, 10), ["--kind", "volume", "--preview-ratio", "0.04"], None,
     "kind volume, octree-cell preview levels", sec("refn", "rcon", "recon")),
    ("points-ball-q12-preview", ("gen", "ball", 400, 11), ["--kind", "points", "--levels", "2", "--preview-ratio", "0.05"],
     None, "kind points, one independent-set level then octree-cell levels", sec("base", "refn")),
    # options
    ("surface-boundary-constant", ("gen", "torus", 250, 2), ["--levels", "4", "--boundary", "constant"], None,
     "boundary decimation mode constant", sec("refn", "rcon")),
    ("surface-boundary-linear", ("gen", "torus", 250, 2), ["--levels", "4", "--boundary", "linear"], None,
     "boundary decimation mode linear", sec("refn", "rcon")),
    ("surface-boundary-adaptive", ("gen", "torus", 250, 2), ["--levels", "4", "--boundary", "adaptive"], None,
     "boundary decimation mode adaptive", sec("refn", "rcon")),
    ("volume-optimizer-forward", ("mesh", VOL6J[0], VOL6J[1]), ["--bits", "10", "--levels", "3", "--ratio", "0.5", "--optimizer", "forward"], None,
     "inner optimiser forward", sec("refn", "rcon")),
    ("volume-optimizer-backward", ("mesh", VOL6J[0], VOL6J[1]), ["--bits", "10", "--levels", "3", "--ratio", "0.5", "--optimizer", "backward"], None,
     "inner optimiser backward", sec("refn", "rcon")),
    ("volume-optimizer-greedy", ("mesh", VOL6J[0], VOL6J[1]), ["--bits", "10", "--levels", "3", "--ratio", "0.5", "--optimizer", "greedy"], None,
     "inner optimiser greedy", sec("refn", "rcon")),
    ("volume-optimizer-best", ("mesh", VOL6J[0], VOL6J[1]), ["--bits", "10", "--levels", "3", "--ratio", "0.5", "--optimizer", "best"], None,
     "inner optimiser best", sec("refn", "rcon")),
    ("surface-fidelity-rule", ("gen", "torus", 250, 1), ["--levels", "3", "--fidelity", "rule"], None,
     "fidelity rule: RCON without corrections", sec("rcon", "recon")),
    ("surface-fidelity-shape", ("gen", "torus", 250, 1), ["--levels", "3", "--fidelity", "shape"], None,
     "fidelity shape", sec("rcon", "recon")),
    ("surface-fidelity-exact", ("gen", "torus", 250, 1), ["--levels", "3", "--fidelity", "exact"], None,
     "fidelity exact: toggle lists", sec("rcon", "recon")),
    ("surface-open-heightfield-exact", ("off", HF[0], HF[1]), ["--levels", "2", "--fidelity", "exact"], None,
     "open surface (one border loop), fidelity exact: border, toggle and drop lists", sec("rcon", "recon")),
    ("surface-open-tube-shape", ("off", TUBE[0], TUBE[1]), ["--bits", "10", "--fidelity", "shape"], None,
     "open tube (two border loops), fidelity shape", sec("rcon", "recon")),
    ("surface-arc-seal-exact", ("off", ARC[0], ARC[1]),
     ["--bits", "10", "--levels", "2", "--fidelity", "exact", "--seal-box", "0,1,0,1024,1024,1024"], None,
     "half a torus (a tile's piece) with a seal box that leaves out its end loops (y = 0): the flood "
     "crosses no face between them; decoded without the seal, its toggle ranks are out of range", sec("rcon", "recon")),
    ("volume-fidelity-exact", ("mesh", VOL5J[0], VOL5J[1]), ["--bits", "10", "--levels", "2", "--fidelity", "exact"], None,
     "kind volume, fidelity exact", sec("rcon", "recon")),
    ("volume-fidelity-rule", ("gen", "ball", 150, 11), ["--kind", "volume", "--levels", "2", "--fidelity", "rule"], None,
     "kind volume, fidelity rule", sec("rcon", "recon")),
    ("surface-ratio-05-l5", ("gen", "torus", 300, 3), ["--levels", "5", "--ratio", "0.5"], None,
     "ratio 0.5 per level, five levels", sec("refn", "rcon")),
    # degenerate geometry
    ("points-one", ("xyz", [(0.25, -1.5, 3.0)]), ["--kind", "points"], None,
     "a single point (extent 0: step 1.0)", sec("sqnt", "base")),
    ("surface-one-point", ("xyz", [(1.0, 2.0, 3.0)]), ["--kind", "surface"], None,
     "kind surface with one point: RCON present, nothing to rebuild", sec("rcon", "recon")),
    ("volume-two-points", ("xyz", [(0.0, 0.0, 0.0), (1.0, 2.0, 3.0)]), ["--kind", "volume", "--bits", "4"], None,
     "kind volume with two points: empty tetrahedralization", sec("recon")),
    ("surface-three-points", ("xyz", [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.5)]), ["--kind", "surface", "--bits", "6"], None,
     "kind surface with three points", sec("recon")),
    ("surface-four-coplanar", ("xyz", COPLANAR4), ["--kind", "surface", "--bits", "3"], None,
     "four coplanar (and cocircular) points: empty tetrahedralization", sec("recon")),
    ("volume-four-points", ("xyz", TETRA4), ["--kind", "volume", "--bits", "3"], None,
     "four points in general position: one tetrahedron", sec("recon")),
    ("surface-collinear", ("xyz", LINE), ["--kind", "surface", "--bits", "6", "--levels", "2"], None,
     "collinear points", sec("recon", "refn")),
    ("volume-coplanar", ("xyz", PLANE), ["--kind", "volume", "--bits", "5", "--levels", "2"], None,
     "30 coplanar points (a planar lattice)", sec("recon", "refn")),
    ("points-duplicates", ("xyz", DUPS), ["--kind", "points", "--bits", "3"], None,
     "duplicates before and after quantization (merged by the encoder)", sec("sqnt", "base")),
    ("surface-cube-q2", ("off", CUBE_PTS, CUBE_TRIS), ["--bits", "2"], None,
     "the cube's 8 cospherical corners as a closed surface", sec("recon")),
    ("surface-octahedron", ("off", OCTA, [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]),
     ["--bits", "4"], None, "octahedron: six cospherical points", sec("recon")),
]


def first_index(ch, t, nth=0):
    return [i for i, (tt, _) in enumerate(ch) if tt == t][nth]


def ancillary_edit(data):
    pre, ch = split(data)
    base = first_index(ch, "BASE")
    return [
        {"op": "insert_chunk", "at": len(ch) - 1, "type": "zzEn", "payload": b"before HEND".hex()},
        {"op": "insert_chunk", "at": base + 1, "type": "xtRa", "payload": bytes(range(40)).hex()},
        {"op": "insert_chunk", "at": base, "type": "empt", "payload": ""},
        {"op": "insert_chunk", "at": 1, "type": "aAaA", "payload": b"\xff\x00\xfe".hex()},
    ]


def info_garbage_edit(data):
    pre, ch = split(data)
    return [{"op": "replace_payload", "at": first_index(ch, "info"), "payload": b"\xff\xfe=\x00no newline or key\x80".hex()},
            {"op": "insert_chunk", "at": first_index(ch, "info") + 1, "type": "info", "payload": b"a=b\n".hex()}]


def cut_after_layer(layers):
    """Cut after the `layers`-th level's chunks (its RCON included)."""
    def f(data):
        pre, ch = split(data)
        idx = [i for i, (t, _) in enumerate(ch) if t in ("BASE", "REFN")][layers - 1]
        if idx + 1 < len(ch) and ch[idx + 1][0] == "RCON":
            idx += 1
        return [{"op": "truncate", "length": offsets(data)[idx + 1]}]
    return f


def cut_inside(t, nth, keep):
    def f(data):
        pre, ch = split(data)
        return [{"op": "truncate_in_chunk", "at": first_index(ch, t, nth), "keep": keep}]
    return f


EDITED = [
    ("ancillary-unknown", ("gen", "torus", 200, 1), ["--levels", "2"], ancillary_edit,
     "unknown ancillary chunks (empty, binary) after HEAD, between a layer and its RCON and before HEND", sec("container")),
    ("info-malformed", ("gen", "ball", 100, 13), [], info_garbage_edit,
     "info chunks with malformed content, and two of them: never an error", sec("end")),
    ("truncated-points-after-level2", ("gen", "ball", 250, 2), ["--levels", "4"], cut_after_layer(2),
     "cut at a chunk boundary after the second level: decodes levels 3 and 2", sec("out")),
    ("truncated-surface-inside-refn", ("gen", "torus", 300, 1), ["--levels", "4"], cut_inside("REFN", 1, 30),
     "cut inside the third layer: decodes levels 3 and 2", sec("out")),
    ("truncated-surface-inside-rcon", ("gen", "torus", 300, 1), ["--levels", "4"], cut_inside("RCON", 1, 13),
     "cut inside the RCON of level 2: level 2 is incomplete, decodes level 3 only", sec("out", "rcon")),
    ("truncated-volume-before-rcon", ("gen", "ball", 200, 7), ["--kind", "volume", "--levels", "4"], cut_inside("RCON", 2, 0),
     "cut between a REFN and its RCON: decodes levels 3 and 2", sec("out", "rcon")),
    ("truncated-no-hend", ("gen", "ball", 150, 4), ["--levels", "3"], cut_inside("HEND", 0, 0),
     "every level complete but HEND missing: all levels, with a warning", sec("out")),
    ("truncated-inside-hend", ("gen", "torus", 150, 1), ["--levels", "2"], cut_inside("HEND", 0, 7),
     "the stream ends inside HEND's chunk header: all levels, with a warning", sec("out")),
    ("truncated-inside-header", ("gen", "ball", 250, 2), ["--levels", "4"], cut_inside("REFN", 0, 5),
     "the stream ends inside a chunk header after the first level", sec("out")),
]

# A case that names no levels is one level: without --levels, hmc enc adds
# preview levels whose number is the encoder's choice (cases that test them
# name --preview-ratio), and a vector's stream should not move with it.
def one_level_unless_named(args):
    return args if "--levels" in args or "--preview-ratio" in args else args + ["--levels", "1"]


ENCODED = [(n, i, one_level_unless_named(a), e, c, x) for n, i, a, e, c, x in ENCODED]
EDITED = [(n, i, one_level_unless_named(a), e, c, x) for n, i, a, e, c, x in EDITED]


# ---------------------------------------------------------------- hand-built positive cases


def lattice_pts(n, step, off=(0, 0, 0)):
    return [(off[0] + x * step, off[1] + y * step, off[2] + z * step) for x in range(n) for y in range(n) for z in range(n)]


def rand_pts(n, q, seed):
    r = random.Random(seed)
    s = set()
    while len(s) < n:
        s.add((r.randrange(1 << q), r.randrange(1 << q), r.randrange(1 << q)))
    return sorted(s)


def sphere_pts(n, q, seed):
    r = random.Random(seed)
    c = (1 << q) / 2.0
    s = set()
    while len(s) < n:
        v = [r.gauss(0, 1) for _ in range(3)]
        l = math.sqrt(sum(x * x for x in v))
        s.add(tuple(int(c + (c - 1) * x / l) for x in v))
    return sorted(s)


def hand_stream(kind, q, levels, refn_opts, rcons=None, origin=(0.0, 0.0, 0.0), step=1.0, info=None):
    """levels: point lists, coarsest first, each containing the previous.
    HEAD flag bit 0 follows the table form being written (delta_tables)."""
    counts = [len(l) for l in levels]
    ch = [["HEAD", head_payload(kind, counts, TABLE_FORM[-1])], ["SQNT", sqnt_payload(q, origin, step)]]
    if info:
        ch.append(["info", info])
    ch.append(["BASE", base_payload(levels[0], q)])
    if rcons:
        ch.append(["RCON", rcons[0]])
    for i in range(1, len(levels)):
        added = sorted(set(levels[i]) - set(levels[i - 1]))
        nb, cl, share = refn_opts[i - 1][:3]
        planes = refn_opts[i - 1][3] if len(refn_opts[i - 1]) > 3 else 1
        gap = refn_opts[i - 1][4] if len(refn_opts[i - 1]) > 4 else None
        fit = refn_opts[i - 1][5] if len(refn_opts[i - 1]) > 5 else None
        paired, merge, tail, wide = (tuple(refn_opts[i - 1][6:10]) +
                                     (None, False, 0, False)[len(refn_opts[i - 1][6:10]):])
        ch.append(["REFN", refn_payload(sorted(levels[i - 1]), added, q, nb, cl, share, planes=planes, gap=gap,
                                        fit=fit, paired=paired, merge=merge, tail=tail, wide=wide)])
        if rcons:
            ch.append(["RCON", rcons[i]])
    ch.append(["HEND", b""])
    return join(SIG + VERSION, ch)


def nested(pts, sizes, seed):
    r = random.Random(seed)
    order = list(pts)
    r.shuffle(order)
    return [sorted(order[:k]) for k in sizes]


def hb_refn_neighbours():
    pts = sphere_pts(300, 10, 1)
    lv = nested(pts, [40, 100, 200, 300], 2)
    return hand_stream(0, 10, lv, [(0, 1, True), (2, 2, True), (15, 4, True)])


def hb_refn_classes():
    pts = rand_pts(400, 7, 3)
    lv = nested(pts, [60, 250, 400], 4)
    return hand_stream(0, 7, lv, [(3, 4, False), (1, 3, True)])


def hb_refn_lattice_ties():
    pts = lattice_pts(6, 3, (2, 2, 2))
    lv = nested(pts, [27, 120, 216], 5)
    return hand_stream(0, 5, lv, [(15, 2, True), (8, 1, True)])


def hb_rcon_surface():
    q = 6
    pts = sphere_pts(120, q, 6)
    lv = nested(pts, [50, 120], 7)
    n0, n1 = len(lv[0]), len(lv[1])
    r = random.Random(8)
    rc0 = rcon_payload(n0, flags=0, scale_rank=3, multipliers=(300, 700, 2000), filters={0: 900, 2: 40000, 3: 1},
                       classes=[r.choice((0, 1, 1, 2)) for _ in range(n0)], border=(0, 5, 6, 40), toggles=(1, 2, 30),
                       drops=(0, 7, 9))
    rc1 = rcon_payload(n1, flags=3, scale_rank=64, multipliers=(256, 65535), classes=[i % 2 for i in range(n1)],
                       filters={0: 1200, 1: 20, 2: 65535, 3: 1, 4: 700, 5: 90},
                       border=tuple(range(0, n1, 3)), toggles=(), drops=(3, 4))
    return hand_stream(1, q, lv, [(4, 1, True)], rcons=[rc0, rc1], origin=(-1.5, 2.25, 1e-300), step=0.1)


def hb_rcon_volume():
    q = 5
    pts = rand_pts(150, q, 9)
    lv = nested(pts, [70, 150], 10)
    n0, n1 = len(lv[0]), len(lv[1])
    rc0 = rcon_payload(n0, flags=3, scale_rank=1, multipliers=(400,), toggles=(0, 3, 10, 11, 12), filters={1: 30, 4: 500})
    rc1 = rcon_payload(n1, flags=0, scale_rank=10, multipliers=tuple(range(100, 100 + 64 * 50, 50)), filters={5: 100},
                       classes=[(i * 7) % 64 for i in range(n1)], border=(n1 - 1,), toggles=(5,), drops=(1, 2))
    return hand_stream(2, q, lv, [(1, 2, True)], rcons=[rc0, rc1], origin=(1e6, -1e6, 0.0), step=1.0 / 3.0)


def hb_rcon_compact_surface():
    q = 6
    pts = sphere_pts(150, q, 31)
    lv = nested(pts, [60, 150], 32)
    n0, n1 = len(lv[0]), len(lv[1])
    r = random.Random(33)
    rc0 = rcon_payload(n0, flags=1, multipliers=(400, 900, 3000), compact=True, group=3,
                       classes=[0 if r.random() < 0.7 else r.choice((1, 2)) for _ in range(n0)],
                       toggles={0: (0, 9), 2: (1, 2, 3, 13), 6: (4, 5), 7: (0,)}, border=(2, 3, 8), drops=(1, 30))
    rc1 = rcon_payload(n1, flags=1, multipliers=(1024, 2048), compact=True, group=8,
                       classes=[1 if i % 11 == 0 else 0 for i in range(n1)],
                       toggles={1: (6,), 4: (0, 100, 253), 6: (0, 1, 2, 3, 4, 5, 6, 7, 8)})
    return hand_stream(1, q, lv, [(4, 1, True)], rcons=[rc0, rc1])


def hb_rcon_class_list():
    # Flag bit 4: classes as the points outside a common class. K = 3 with
    # common class 1 (listed points of classes 0 and 2, so the symbols map
    # around it); K = 2 with common class 1 and nobody listed; K = 64 with
    # common class 40 and a few points of classes on both sides of it.
    q = 6
    pts = sphere_pts(200, q, 41)
    lv = nested(pts, [50, 110, 200], 42)
    n0, n1, n2 = len(lv[0]), len(lv[1]), len(lv[2])
    r = random.Random(43)
    rc0 = rcon_payload(n0, flags=1, multipliers=(400, 900, 3000), compact=True, common=1,
                       classes=[1 if r.random() < 0.8 else r.choice((0, 2)) for _ in range(n0)], toggles={2: (1, 4)})
    rc1 = rcon_payload(n1, flags=1, multipliers=(500, 1500), compact=True, common=1, classes=[1] * n1)
    rc2 = rcon_payload(n2, flags=1, multipliers=tuple(range(100, 100 + 64 * 60, 60)), compact=True, common=40,
                       classes=[40 if i % 17 else (i * 7) % 64 for i in range(n2)], toggles={6: (0, 2)})
    return hand_stream(1, q, lv, [(4, 1, True), (4, 2, True)], rcons=[rc0, rc1, rc2])


def hb_rcon_contexts(vertices):
    # Flag bit 5 (40 toggle contexts) or bits 5 and 6 (80). Each listed
    # context holds 4 tetrahedra at least on its level: with 40 contexts, 0,
    # 8, 9, 16, 17, 33, 34 and 36-39 on both, 21 on the first, 18 on the
    # second; with 80, 44, 52, 60, 61 and 74-78 on the first, 36, 37, 40,
    # 48, 49, 56-58, 72-74 and 76-79 on the second, whose classes then
    # travel as a list.
    q = 6
    pts = sphere_pts(180, q, 46) if vertices else sphere_pts(160, q, 44)
    lv = nested(pts, [70, 180], 47) if vertices else nested(pts, [60, 160], 45)
    n0, n1 = len(lv[0]), len(lv[1])
    flags = dict(flags=1, compact=True, candidate_contexts=True, vertex_contexts=vertices)
    if vertices:
        rc0 = rcon_payload(n0, multipliers=(900,), toggles={44: (0,), 60: (1, 3), 78: (2,)}, **flags)
        rc1 = rcon_payload(n1, multipliers=(700, 1800), common=0, classes=[1 if i % 9 == 0 else 0 for i in range(n1)],
                           toggles={37: (0,), 48: (3,), 57: (1, 2), 79: (0,)}, **flags)
    else:
        rc0 = rcon_payload(n0, multipliers=(900,), toggles={9: (0,), 16: (0, 2), 21: (3,), 36: (1,)}, **flags)
        rc1 = rcon_payload(n1, multipliers=(700, 1800), group=2, classes=[i % 3 // 2 for i in range(n1)],
                           toggles={0: (0,), 8: (1,), 18: (2,), 39: (0, 3)}, **flags)
    return hand_stream(1, q, lv, [(4, 1, True)], rcons=[rc0, rc1])


def hb_rcon_candidate_contexts():
    return hb_rcon_contexts(vertices=False)


def hb_rcon_vertex_contexts():
    return hb_rcon_contexts(vertices=True)


def hb_rcon_neighbour_contexts(bad=False):
    # Flag bits 5, 6 and 7 (240 toggle contexts, lists that may be
    # inverted) on the sphere of hb_rcon_contexts(vertices=True). The first
    # level inverts context 3 * 76 (every one of its tetrahedra toggled but
    # ranks 0 and 2), so that later tetrahedra meet toggled neighbours; the
    # listed ranks of the split contexts 3c + 1 and 3c + 2 are ones the walk
    # reaches. The second level inverts an empty list (context 3 * 36 wholly
    # toggled) beside plain lists. bad: the inverted list also names rank
    # 5000, beyond its context.
    q = 6
    pts = sphere_pts(180, q, 46)
    lv = nested(pts, [70, 180], 47)
    n0, n1 = len(lv[0]), len(lv[1])
    flags = dict(flags=1, compact=True, candidate_contexts=True, vertex_contexts=True, neighbour_contexts=True)
    rc0 = rcon_payload(n0, multipliers=(900,), toggles={3 * 44: (0,), 3 * 76: (0, 2, 5000) if bad else (0, 2), 3 * 76 + 1: (0,), 3 * 60: (1,)},
                       inverted=(3 * 76,), **flags)
    rc1 = rcon_payload(n1, multipliers=(700, 1800), common=0, classes=[1 if i % 9 == 0 else 0 for i in range(n1)],
                       toggles={3 * 48: (1,), 3 * 57: (0, 2)}, inverted=(3 * 36,), **flags)
    return hand_stream(1, q, lv, [(4, 1, True)], rcons=[rc0, rc1])


def hb_rcon_filters():
    # Filters 3 (lone triangle) and 1 (min/max edge ratio), each alone on a
    # level where it changes the output (in the other cases they remove
    # faces that no later step looks at). The coarsest level (scale rank 3,
    # multiplier 256: few candidates) loses 7 lone candidate faces, all of
    # them faces of outside tetrahedra without interface faces, which then
    # count one candidate face less: with candidate contexts their ranks in
    # context 0 (200 tetrahedra) are toggled, so a decoder that kept the
    # lone faces would toggle others. The finer level's filter 1 at T = 20
    # removes the thin hull faces, so the flood enters there (348 instead of
    # 404 triangles).
    q = 6
    pts = sphere_pts(160, q, 51)
    lv = nested(pts, [70, 160], 52)
    n0, n1 = len(lv[0]), len(lv[1])
    rc0 = rcon_payload(n0, flags=1, scale_rank=3, multipliers=(256,), filters={3: 1}, compact=True, candidate_contexts=True,
                       toggles={0: (58, 62, 85, 90, 99, 118, 130, 144, 177)})
    rc1 = rcon_payload(n1, flags=1, scale_rank=6, multipliers=(900,), filters={1: 20})
    return hand_stream(1, q, lv, [(4, 1, True)], rcons=[rc0, rc1])


def hb_rcon_compact_volume():
    q = 5
    pts = rand_pts(120, q, 34)
    lv = nested(pts, [50, 120], 35)
    n0, n1 = len(lv[0]), len(lv[1])
    rc0 = rcon_payload(n0, flags=3, scale_rank=4, multipliers=(600,), compact=True, toggles={4: (0,), 5: (2, 3, 8), 7: (0, 4)})
    rc1 = rcon_payload(n1, flags=0, scale_rank=8, multipliers=tuple(range(100, 100 + 64 * 40, 40)), compact=True,
                       group=2, classes=[(i * 5) % 64 for i in range(n1)], toggles={1: (7, 89), 4: (0, 397), 7: (1,)})
    return hand_stream(2, q, lv, [(1, 2, True)], rcons=[rc0, rc1])


def hb_rcon_border_inherit():
    # Flag bit 3 over three levels of a sphere whose border set is a polar
    # cap (so the border rule opens a hole): the coarsest level inherits the
    # empty set; the middle level lists its set in full; the finest lists
    # changes to it (two inherited points removed, three cap points added).
    q = 6
    pts = sphere_pts(150, q, 51)
    lv = nested(pts, [40, 80, 150], 52)
    n0, n1, n2 = len(lv[0]), len(lv[1]), len(lv[2])
    cap = lambda level, z: tuple(i for i, p in enumerate(level) if p[2] >= z)
    b1 = cap(lv[1], 50)
    inherited = sorted(lv[2].index(lv[1][i]) for i in b1)
    removed = inherited[1:3]
    added = [i for i in cap(lv[2], 50) if i not in inherited][:3]
    rc0 = rcon_payload(n0, flags=1 | 8, multipliers=(1500,), border=cap(lv[0], 50))
    rc1 = rcon_payload(n1, flags=1, multipliers=(1500,), border=b1)
    rc2 = rcon_payload(n2, flags=1 | 8, multipliers=(1500,), border=tuple(sorted(removed + added)))
    return hand_stream(1, q, lv, [(4, 1, True), (4, 2, True)], rcons=[rc0, rc1, rc2])


def hb_delta_tables():
    # Every table in the delta form (HEAD flag bit 0): BASE coder 0, REFN
    # tables over 1 to 4 classes, RCON class tables (grouped and not).
    q = 7
    pts = sphere_pts(300, q, 61)
    lv = nested(pts, [60, 140, 300], 62)
    n0, n1, n2 = len(lv[0]), len(lv[1]), len(lv[2])
    r = random.Random(63)
    with delta_tables():
        rc0 = rcon_payload(n0, flags=1, multipliers=(700, 1500, 4000), classes=[r.choice((0, 1, 1, 2)) for _ in range(n0)])
        rc1 = rcon_payload(n1, flags=1, multipliers=(900, 2000), compact=True, group=4,
                           classes=[1 if i % 5 == 0 else 0 for i in range(n1)], toggles={1: (2,), 4: (0, 3)})
        rc2 = rcon_payload(n2, flags=3, multipliers=(1200,), compact=True, toggles={0: (1, 5)})
        return hand_stream(1, q, lv, [(4, 4, True), (1, 3, False)], rcons=[rc0, rc1, rc2])


def hb_refn_planes():
    # REFN coder 7 with plane contexts: neighbours 4 with 4 and 2 classes, shared
    # and unshared tables, then neighbours 0 (no plane: every node in plane
    # context 0) in the delta table form.
    pts = sphere_pts(400, 9, 71)
    lv = nested(pts, [60, 150, 280, 400], 72)
    a = hand_stream(0, 9, lv, [(4, 4, True, 2), (4, 2, False, 2), (0, 1, True, 2)])
    with delta_tables():
        b = hand_stream(0, 9, lv[:2], [(4, 3, True, 2)])
    return a, b


def hb_refn_gap():
    # REFN coder 7, gap ranking: neighbours 4, G = 6 with plane contexts and
    # 4 classes; G = 15 without plane contexts, 2 classes, unshared tables;
    # neighbours 1 with G = 9 (no plane: the order of 8A.1); neighbours 15,
    # G = 1. Added points are the points of the next level, spread by taking
    # them in random order, as the other hand-built cases do.
    pts = sphere_pts(500, 10, 81)
    lv = nested(pts, [80, 200, 300, 420, 500], 82)
    return hand_stream(0, 10, lv, [(4, 4, True, 2, 6), (4, 2, False, 1, 15), (1, 3, True, 2, 9), (15, 1, True, 1, 1)])


def hb_refn_depth_gaps():
    # REFN coder 7, a gap weight per depth: neighbours 4, weights 0 to 15
    # over the depths with plane contexts and 3 classes; then the same weight
    # at every depth (written as one weight) without plane
    # contexts; then neighbours 1 (no plane: the weights change nothing).
    pts = sphere_pts(450, 10, 91)
    lv = nested(pts, [90, 250, 380, 450], 92)
    return hand_stream(0, 10, lv, [(4, 3, True, 2, [0, 15, 1, 7, 3, 12, 2, 9, 4, 1]), (4, 2, True, 1, [5] * 10),
                                   (1, 1, True, 2, [8, 0, 8, 0, 8, 0, 8, 0, 8, 0])])


def hb_refn_quadric():
    # REFN coder 7, quadric ranking. On a sphere: F = 10 with G = 6, plane
    # contexts, 3 classes; F = 15 with a weight per depth, 2 classes,
    # unshared tables; F = 5 (below 6: no quadric, the plane's ranking);
    # neighbours 1 with F = 8 (no plane normal, so no quadric). On a lattice,
    # whose points lie on few planes and conics (fits that fail, equal keys):
    # F = 10 and F = 6 with neighbours 4.
    pts = sphere_pts(500, 10, 101)
    lv = nested(pts, [70, 180, 300, 420, 500], 102)
    a = hand_stream(0, 10, lv, [(4, 3, True, 2, 6, 10), (4, 2, False, 1, [0, 1, 2, 3, 4, 6, 8, 12, 15, 5], 15),
                                (4, 2, True, 2, 3, 5), (1, 1, True, 1, 9, 8)])
    grid = lattice_pts(6, 3, (2, 1, 3)) + rand_pts(40, 6, 103)
    lv = nested(sorted(set(grid)), [60, 150, 256], 104)
    b = hand_stream(0, 6, lv, [(4, 2, True, 2, 2, 10), (4, 1, True, 1, [0, 4, 8, 1, 0, 2], 6)])
    return a, b


def hb_refn_paired():
    # REFN coder 7, paired tables. On a sphere: every table paired, one
    # table per slot shared by all its depths (pending symbols carried from
    # one depth to the next), escapes where nodes hold several points, the
    # quadric with plane contexts; then tables paired at alternate depths and
    # classes, a weight per depth, no quadric (F = 0). At q = 3 with
    # neighbours 0: many escapes. An odd sequence whose unused last symbol is
    # 5 instead of the encoder's 0 (decoders ignore it). A layer whose every
    # pair is the same: the pair code's one-symbol form (no bits per pair).
    pts = sphere_pts(500, 10, 111)
    lv = nested(pts, [70, 200, 500], 112)
    all_tables = lambda d, j: True
    a = hand_stream(0, 10, lv, [(4, 2, True, 2, 6, 10, all_tables, True),
                                (4, 3, True, 1, [0, 1, 2, 3, 4, 6, 8, 12, 15, 5], 0,
                                 lambda d, j: (d + j[0]) % 2 == 0)])
    lv = nested(rand_pts(120, 3, 113), [20, 60, 120], 114)
    b = hand_stream(0, 3, lv, [(0, 1, True, 1, None, None, all_tables, True, 5), (2, 2, False, 1, 3, None, all_tables)])
    c = hand_stream(0, 2, [[(0, 0, 0)], [(0, 0, 0), (3, 3, 3)]], [(1, 1, True, 1, None, None, all_tables)])
    return a, b, c


def hb_refn_far():
    # REFN coder 7, far ranking. Random points filling a
    # cube (a volume's interior), q = 8: neighbours 8, far ranking at some
    # depths and gap weights 0-15 at others, plane contexts, 3 classes,
    # tables paired at alternate depths; then one weight, 16, for every
    # depth with the quadric through 10 neighbours (its heights break the
    # ties), 2 classes; then neighbours 0 with weight 16 (no neighbour: g is
    # 0 and the order is the child number's). On a lattice plus random points
    # at q = 5: neighbours 4 and weight 16, where many children are equally
    # far from their nearest neighbour (ties by t, e and child number).
    lv = nested(rand_pts(600, 8, 121), [90, 250, 450, 600], 122)
    a = hand_stream(0, 8, lv, [(8, 3, True, 2, [0, 16, 3, 16, 16, 15, 16, 0], 0, lambda d, j: (d + j[0]) % 2 == 0,
                                False, 0, True),
                               (4, 2, True, 1, 16, 10, None, False, 0, True),
                               (0, 1, True, 1, 16, None, None, False, 0, True)])
    lat = lattice_pts(6, 5, (1, 2, 3))
    pts = sorted(set(lat) | set(rand_pts(120, 5, 123)))
    b = hand_stream(0, 5, nested(pts, [60, len(pts)], 124), [(4, 2, False, 1, 16, None, None, False, 0, True)])
    return a, b


def hb_base_gaps():
    # BASE coder 5, gap weights: an evenly spread sphere (a lattice's points
    # near a sphere), neighbours 10, weights 0 to 15 over the depths, plain
    # and ranked depths mixed, 3 contexts; and neighbours 1 (no plane: the
    # weights change nothing).
    pts = [p for p in lattice_pts(16, 1, (0, 0, 0)) if abs(sum((c - 7.5) ** 2 for c in p) - 36) < 7]
    a = base_ranked_stream(0, 4, pts, 10, [False, True, True, True], classes=3, gaps=[0, 15, 3, 8])
    b = base_ranked_stream(1, 8, sphere_pts(300, 8, 95), 1, [True] * 8, classes=2, gaps=[9, 0, 4, 15, 1, 2, 6, 11])
    return a, b


def hb_base_causal():
    # BASE coder 5, causal points: points on a sphere at q = 8, neighbours
    # 10, quadric and plane depths mixed with weights, a plain depth, 3
    # contexts; a lattice with random points (ties, fits that fail: points on
    # few planes) with neighbours 15 (up to 32 points, lists cut short);
    # neighbours 3 and 1 (fewer than 6 points: no quadric even where flagged).
    a = base_ranked_stream(0, 8, sphere_pts(500, 8, 17), 10, [False] + [True] * 7, classes=3,
                           gaps=[0, 0, 4, 15, 1, 6, 0, 3], quadric=[False, True, False, True, True, False, True, True])
    b = base_ranked_stream(0, 6, lattice_pts(5, 4, (3, 2, 5)) + rand_pts(30, 6, 44), 15, [True] * 6, classes=4,
                           gaps=[2, 8, 0, 11, 3, 1], quadric=[True] * 6)
    c = base_ranked_stream(1, 5, sphere_pts(120, 5, 23), 3, [True] * 5, classes=2, gaps=[0, 2, 4, 6, 8],
                           quadric=[True, False, True, False, True])
    d = base_ranked_stream(0, 4, rand_pts(40, 4, 45), 1, [False, True, True, True], classes=1, gaps=[0, 5, 0, 9],
                           quadric=[False, True, True, True])
    e = base_ranked_stream(0, 3, rand_pts(20, 3, 46), 0, [True] * 3, classes=2, gaps=[3, 0, 7],
                           quadric=[True, True, False])
    return a, b, c, d, e


def hb_base_paired():
    # BASE coder 5, paired tables: a sphere at q = 8, neighbours 10, every
    # table paired (the plain depth 0 too; escapes where nodes have several
    # children; pair codes with phantom pairs where a context has few
    # nodes), quadric and plane depths, 3 contexts; lattice and random
    # points with neighbours 15, tables paired at alternate depths and
    # contexts, kind surface.
    a = base_ranked_stream(0, 8, sphere_pts(500, 8, 121), 10, [False] + [True] * 7, classes=3,
                           gaps=[0, 3, 0, 6, 1, 0, 2, 4], quadric=[False, True, True, False, True, True, False, True],
                           paired=lambda d, j: True)
    b = base_ranked_stream(1, 6, lattice_pts(5, 4, (1, 2, 3)) + rand_pts(40, 6, 122), 15, [True] * 6, classes=2,
                           gaps=[1, 0, 5, 2, 0, 3], quadric=[True, False, True, True, False, True],
                           paired=lambda d, j: (d + j) % 2 == 0)
    return a, b


def jittered_cube(n, step, jitter, seed):
    """Points filling a cube about evenly, as a volume's interior: a lattice
    of n^3 points `step` apart, each moved by up to `jitter` per axis."""
    r = random.Random(seed)
    return sorted({tuple(c * step + jitter + r.randint(-jitter, jitter) for c in (x, y, z))
                   for x in range(n) for y in range(n) for z in range(n)})


def hb_base_far():
    # BASE coder 5, far ranking: a jittered lattice filling a cube at q = 7,
    # neighbours 10, weight 16 mixed with weights 0-15 by depth, quadric
    # flags mixed (with weight 16 the quadric breaks ties), tables paired at
    # some depths; an exact lattice plus random points (many equally far
    # children), neighbours 15, weight 16 at every ranked depth, kind
    # surface; neighbours 1 (no point besides the node's own centre: g = 0,
    # weight 16 ranks by t, e, c alone).
    a = base_ranked_stream(0, 7, jittered_cube(7, 16, 5, 131), 10, [False, True, True, True, True, True, True],
                           classes=3, gaps=[0, 16, 3, 16, 16, 0, 16],
                           quadric=[False, False, True, True, False, True, True],
                           paired=lambda d, j: (d * 3 + j) % 4 != 1)
    b = base_ranked_stream(1, 6, lattice_pts(5, 12, (3, 5, 7)) + rand_pts(50, 6, 132), 15, [True] * 6, classes=2,
                           gaps=[16] * 6, quadric=[True, False, True, False, True, True],
                           paired=lambda d, j: d % 2 == 0)
    c = base_ranked_stream(0, 5, rand_pts(60, 5, 133), 1, [False, True, True, True, True], classes=1,
                           gaps=[0, 16, 2, 16, 16], quadric=[False, True, False, False, True],
                           paired=lambda d, j: False)
    return a, b, c


def hb_base_ranked_sphere():
    return base_ranked_stream(0, 8, sphere_pts(400, 8, 41), 10, [True] * 8, classes=4)


def hb_base_ranked_mixed():
    # neighbours 15, plain and ranked depths alternating, on a lattice (ties).
    return base_ranked_stream(0, 6, lattice_pts(5, 4, (3, 2, 5)) + rand_pts(30, 6, 42), 15,
                              [d % 2 == 1 for d in range(6)], classes=3)


def hb_base_ranked_small():
    # neighbours 0 and 1 (centroid only), q = 1 and q = 3, surface kind.
    a = base_ranked_stream(0, 1, [(0, 0, 0), (1, 1, 0), (1, 0, 1)], 1, [True])
    b = base_ranked_stream(1, 3, rand_pts(25, 3, 43), 0, [True] * 3, classes=2)
    return a, b


def hb_refn_tiny_coarse():
    pts = rand_pts(40, 6, 13)
    lv = nested(pts, [2, 5, 40], 14)
    return hand_stream(0, 6, lv, [(15, 1, True), (9, 4, True)])


def hb_refn_q1():
    lv = [[(0, 1, 1)], [(0, 0, 0), (0, 1, 1), (1, 0, 1)], [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]]
    return hand_stream(0, 1, lv, [(1, 1, True), (0, 2, True)])


def mixed_stream(kind, q, base, layers, rcons=None):
    """A stream with BASE `base` and refinement layers ("octree", added
    points, neighbours, classes). Returns (stream, levels decoded, coarsest
    first)."""
    levels = [sorted(set(base))]
    payloads = []
    for layer in layers:
        coarse = levels[-1]
        _, added, nb, cl = layer
        added = sorted(set(added) - set(coarse))
        payloads.append(refn_payload(coarse, added, q, nb, cl))
        levels.append(sorted(coarse + list(added)))
    ch = [["HEAD", head_payload(kind, [len(l) for l in levels])], ["SQNT", sqnt_payload(q)]]
    ch.append(["BASE", base_payload(levels[0], q)])
    if rcons:
        ch.append(["RCON", rcons[0]])
    for i, pl in enumerate(payloads):
        ch.append(["REFN", pl])
        if rcons:
            ch.append(["RCON", rcons[i + 1]])
    ch.append(["HEND", b""])
    return join(SIG + VERSION, ch), levels


HANDBUILT = [
    ("refn-tiny-coarse", hb_refn_tiny_coarse, P,
     "hand-built layers whose coarse level has fewer points than `neighbours` (k = |C|)", sec("refn")),
    ("refn-q1", hb_refn_q1, P,
     "hand-built layers at q = 1 (one depth; the last layer fills the grid)", sec("refn", "base")),
    ("refn-neighbours-0-2-15", hb_refn_neighbours, P,
     "hand-built refinement layers with neighbours = 0, 2 and 15 and 1, 2, 4 context classes", sec("refn", "huff")),
    ("refn-classes-unshared", hb_refn_classes, P,
     "hand-built layers: 4 and 3 context classes, a table at every depth (no sharing) and shared tables", sec("refn", "huff")),
    ("refn-lattice-ties", hb_refn_lattice_ties, P,
     "hand-built layers on a lattice: many equidistant neighbours and equal keys", sec("refn")),
    ("rcon-handbuilt-surface", hb_rcon_surface, F,
     "hand-written RCON: peel and repair off and on, filters 0, 2, 3 then all six, K = 3 and 2 (class bit streams), border, toggle and drop lists; origin and step not the encoder's", sec("rcon", "recon", "sqnt")),
    ("tables-delta-handbuilt", hb_delta_tables, F,
     "HEAD flag bit 0: every code-length table in the delta form (BASE, REFN with 4 and 3 classes and unshared tables, RCON class tables plain and grouped)", sec("head", "huff", "base", "refn", "rcon", "recon")),
    ("refn-planes", lambda: hb_refn_planes()[0], P,
     "REFN coder 7 with plane contexts: neighbours 4 with 4 and 2 classes, shared and unshared tables, then neighbours 0 (every node in plane context 0)", sec("refn", "huff")),
    ("refn-planes-delta-tables", lambda: hb_refn_planes()[1], P,
     "REFN coder 7 with plane contexts and three classes, its tables in the delta form", sec("head", "refn", "huff")),
    ("refn-gap", hb_refn_gap, P,
     "REFN coder 7, gap ranking: neighbours 4 with G = 6, plane contexts, 4 classes; G = 15 without plane contexts, 2 classes, unshared tables; neighbours 1 with G = 9 (no plane, the order of 8A.1); neighbours 15 with G = 1", sec("refn", "huff")),
    ("refn-depth-gaps", hb_refn_depth_gaps, P,
     "REFN coder 7, a gap weight per depth: neighbours 4 with weights 0-15 varying by depth, plane contexts, 3 classes; the same weight 5 at every depth without plane contexts; neighbours 1 with alternating weights (no plane: the order of 8A.1)", sec("refn", "huff")),
    ("refn-quadric", lambda: hb_refn_quadric()[0], P,
     "REFN coder 7, quadric ranking on a sphere: F = 10 with G = 6, plane contexts, 3 classes; F = 15 with a weight per depth, 2 classes, unshared tables; F = 5 (no quadric: the plane's ranking); neighbours 1 with F = 8 (no plane normal, no quadric)", sec("refn", "huff")),
    ("refn-quadric-lattice", lambda: hb_refn_quadric()[1], P,
     "REFN coder 7 with the quadric on lattice points plus random ones: F = 10 and 6 with neighbours 4, fits that fail (points on few planes and conics) and equal keys", sec("refn", "huff")),
    ("refn-paired", lambda: hb_refn_paired()[0], P,
     "REFN coder 7, paired tables on a sphere: every table paired and shared by all the depths of its slot (pending symbols carried across depths), escapes, the quadric with plane contexts; then tables paired at alternate depths and classes with a weight per depth and F = 0", sec("refn", "huff")),
    ("refn-paired-escapes", lambda: hb_refn_paired()[1], P,
     "REFN coder 7 with paired tables at q = 3: neighbours 0 with every table paired and shared across depths, many escaped pairs, an odd sequence whose unused last symbol is 5 (not the encoder's 0); neighbours 2 with G = 3, unshared tables", sec("refn", "huff")),
    ("refn-paired-single", lambda: hb_refn_paired()[2], P,
     "REFN coder 7 with paired tables at q = 2 adding one point: each paired table's pair code is the one-symbol form, and the layer's symbols cost no bits", sec("refn", "huff")),
    ("refn-far", lambda: hb_refn_far()[0], P,
     "REFN coder 7, far ranking on random points filling a cube, q = 8: neighbours 8 with weight 16 at four depths and 0, 3, 15 and 0 at the others, plane contexts, 3 classes, alternate tables paired; weight 16 at every depth with the quadric through 10 neighbours breaking ties, 2 classes; neighbours 0 with weight 16 (g = 0: the order of the child numbers)", sec("refn", "huff")),
    ("refn-far-lattice", lambda: hb_refn_far()[1], P,
     "REFN coder 7, far ranking, on lattice points plus random ones at q = 5: neighbours 4 and weight 16 at every depth, unshared tables, many children equally far from their nearest neighbour (ties by t, e, child number)", sec("refn", "huff")),
    ("base-gaps", lambda: hb_base_gaps()[0], P,
     "BASE coder 5, gap weights: points near a sphere on a lattice (ties), neighbours 10, depth 0 plain, weights 15, 3 and 8 at the ranked depths, 3 contexts", sec("base", "huff")),
    ("base-gaps-neighbours-1", lambda: hb_base_gaps()[1], P,
     "BASE coder 5 with neighbours 1 (no plane: the weights change nothing), 2 contexts, kind surface", sec("base", "huff")),
    ("base-causal", lambda: hb_base_causal()[0], P,
     "BASE coder 5, causal points: points on a sphere at q = 8, neighbours 10, depth 0 plain, quadric and plane depths mixed, weights 0-15, 3 contexts", sec("base", "huff")),
    ("base-causal-lattice", lambda: hb_base_causal()[1], P,
     "BASE coder 5 on lattice points plus random ones, neighbours 15 (lists cut at 32 points), every depth quadric: ties and fits that fail, 4 contexts", sec("base", "huff")),
    ("base-causal-few", lambda: hb_base_causal()[2], P,
     "BASE coder 5 with neighbours 3 (at most 24 points, some nodes fewer than 6: no quadric), kind surface, 2 contexts", sec("base", "huff")),
    ("base-causal-neighbours-1", lambda: hb_base_causal()[3], P,
     "BASE coder 5 with neighbours 1 (the node's own centre only: no plane, no quadric), a plain depth, 1 context", sec("base", "huff")),
    ("base-paired", lambda: hb_base_paired()[0], P,
     "BASE coder 5, paired tables on a sphere at q = 8: neighbours 10, every table paired, the plain depth 0's too, escapes, phantom pairs in sparse contexts, quadric and plane depths, 3 contexts", sec("base", "huff")),
    ("base-paired-lattice", lambda: hb_base_paired()[1], P,
     "BASE coder 5, paired tables, on lattice and random points, kind surface: neighbours 15, tables paired at alternate depths and contexts, 2 contexts", sec("base", "huff")),
    ("base-far", lambda: hb_base_far()[0], P,
     "BASE coder 5, far ranking on a jittered lattice filling a cube at q = 7: neighbours 10, weight 16 at four depths mixed with weights 0 and 3, quadric ties and plane ties, tables paired at some depths, 3 contexts", sec("base", "huff")),
    ("base-far-lattice", lambda: hb_base_far()[1], P,
     "BASE coder 5 on lattice points plus random ones, kind surface: neighbours 15, weight 16 at every depth (many equally far children), tables paired at even depths, 2 contexts", sec("base", "huff")),
    ("base-far-neighbours-1", lambda: hb_base_far()[2], P,
     "BASE coder 5 with neighbours 1 (no point besides the node's own centre: g = 0, weight 16 ranks by the plane-less t, e and c), no table paired, 1 context", sec("base", "huff")),
    ("base-causal-neighbours-0", lambda: hb_base_causal()[4], P,
     "BASE coder 5 with neighbours 0 (no points: every child ties, the order is the child number), weights and quadric flags that change nothing, 2 contexts", sec("base", "huff")),
    ("rcon-border-inherit", hb_rcon_border_inherit, F,
     "hand-written RCON flag bit 3 (inherit_border) over three levels: at the coarsest level (inherits the empty set), a level without it, then a level whose list removes two inherited border points and adds three", sec("rcon", "recon")),
    ("base-ranked-sphere", hb_base_ranked_sphere, P,
     "BASE coder 5 (ranked octree), weights 0 and no quadric: neighbours = 10, four contexts, every depth ranked, points on a sphere", sec("base", "refn")),
    ("base-ranked-mixed", hb_base_ranked_mixed, P,
     "BASE coder 5: neighbours = 15, three contexts, plain and ranked depths alternating, a lattice with equidistant node centres", sec("base", "refn", "huff")),
    ("base-ranked-q1", lambda: hb_base_ranked_small()[0], P,
     "BASE coder 5 at q = 1: one node, k = min(neighbours, nodes) = 1", sec("base", "refn")),
    ("base-ranked-surface-k0", lambda: hb_base_ranked_small()[1], F,
     "BASE coder 5 with neighbours = 0 (children by number, so every node in context 0) and two contexts, in a surface stream", sec("base", "refn", "rcon", "recon")),
    ("rcon-compact-surface", hb_rcon_compact_surface, F,
     "hand-written compact RCON (flag bit 2): classes in groups of 3 and 8 points, toggle ranks in five contexts, border and drop lists", sec("rcon", "recon")),
    ("rcon-class-list", hb_rcon_class_list, F,
     "hand-written compact RCON with class lists (flag bit 4): K = 3 around common class 1, K = 2 with no point listed, K = 64 around common class 40", sec("rcon", "recon")),
    ("rcon-candidate-contexts", hb_rcon_candidate_contexts, F,
     "hand-written compact RCON with candidate contexts (flag bit 5): toggle ranks in contexts 0-39 of two levels of a sphere", sec("rcon", "recon")),
    ("rcon-neighbour-contexts", hb_rcon_neighbour_contexts, F,
     "hand-written compact RCON with neighbour contexts (flag bits 5, 6 and 7): toggles in 240 contexts split by toggled earlier neighbours, inverted lists (one empty, toggling its whole context), two levels of a sphere", sec("rcon", "recon")),
    ("rcon-vertex-contexts", hb_rcon_vertex_contexts, F,
     "hand-written compact RCON with vertex contexts (flag bits 5 and 6): toggle ranks in contexts 37-79 of two levels of a sphere, one with a class list", sec("rcon", "recon")),
    ("rcon-compact-volume", hb_rcon_compact_volume, F,
     "hand-written compact RCON for a volume: repair then toggles by context, K = 64 in groups of 2 (4096 symbols)", sec("rcon", "recon")),
    ("rcon-filters-lone-ratio", hb_rcon_filters, F,
     "hand-written RCON where filters 3 (lone triangle, seen through the candidate contexts of toggle ranks) and 1 (min/max edge ratio, letting the flood in) each change the output, one per level of a sphere", sec("rcon", "recon")),
    ("rcon-handbuilt-volume", hb_rcon_volume, F,
     "hand-written RCON for a volume: repair, filters 1, 4 and 5, K = 1 and K = 64, scale rank 1 and 10, toggles", sec("rcon", "recon")),
]


# ---------------------------------------------------------------- negative cases


def small_points_stream():
    """A tiny valid stream of kind points: q = 3, two levels."""
    pts = rand_pts(20, 3, 11)
    return hand_stream(0, 3, nested(pts, [8, 20], 12), [(4, 1, True)])


def bits_payload(fn):
    bw = BitWriter()
    fn(bw)
    return bw.bytes()


def base_with_table(table_writer):
    """A BASE payload, q = 1, whose one table is written by table_writer."""
    return b"\x00" + bits_payload(table_writer)


def stream_q1(base, counts=(1,), kind=0, rcon=None, q=1, flags=0):
    ch = [["HEAD", head_payload(kind, list(counts), flags)], ["SQNT", sqnt_payload(q)], ["BASE", base]]
    if rcon is not None:
        ch.append(["RCON", rcon])
    ch.append(["HEND", b""])
    return join(SIG + VERSION, ch)


def neg_from(src, edits):
    return ("derived", src, edits)


def over_subscribed(bw):
    write_table(bw, 256, lengths={1: 1, 2: 1, 3: 2})


def incomplete(bw):
    write_table(bw, 256, lengths={1: 1, 2: 2})


def run_past(bw):
    bw.put(0, 1)
    bw.put(1, 4)      # symbol 0: length 1
    bw.put(1, 4)      # symbol 1: length 1
    bw.put(0, 4)
    bw.ue(254)        # a run of 255 zeros from symbol 2: passes 256


def one_length(bw):
    write_table(bw, 256, lengths={128: 1})


def single_too_big(bw):
    # REFN alphabet is 255: a single symbol 255 (8 bits) is out of range
    bw.put(1, 1)
    bw.put(255, 8)


def refn_single(sym):
    """A REFN payload, q = 1, neighbours 0, one class, table at depth 0: a single symbol."""
    return b"\x00" + bits_payload(lambda bw: (bw.put(0, 4), bw.put(0, 2), bw.put(1, 1), bw.put(1, 1), bw.put(sym, 8)))


def stream_q1_refn(refn, coarse=((0, 0, 0),), added=1, kind=0):
    counts = [len(coarse), len(coarse) + added]
    ch = [["HEAD", head_payload(kind, counts)], ["SQNT", sqnt_payload(1)], ["BASE", base_payload(list(coarse), 1)],
          ["REFN", refn], ["HEND", b""]]
    return join(SIG + VERSION, ch)


def surface_one_level(rcon, pts=None, q=4):
    pts = pts or rand_pts(30, q, 21)
    ch = [["HEAD", head_payload(1, [len(pts)])], ["SQNT", sqnt_payload(q)], ["BASE", base_payload(pts, q)],
          ["RCON", rcon], ["HEND", b""]]
    return join(SIG + VERSION, ch)


def f64(v):
    return struct.pack("<d", v)


NAN = struct.unpack("<d", bytes.fromhex("000000000000f87f"))[0]

# (name, error class, profile, description, sections, builder)
# builder: ("derived", source case, edits) or a function returning bytes.
NEGATIVE = [
    ("neg-bad-magic", "bad_magic", P, "first signature byte 0x88 instead of 0x89", ["2", "13"],
     neg_from("points-ball-q12-l1", [{"op": "patch", "offset": 0, "hex": "88"}])),
    ("neg-bad-magic-text", "bad_magic", P, "a signature altered by a text transfer (CR LF -> LF)", ["2", "13"],
     neg_from("points-ball-q12-l1", [{"op": "truncate", "length": 4}, {"op": "append", "hex": "0a1a0a000301"}])),
    ("neg-unsupported-version", "unsupported_version", P, "version_major 1", ["2", "13"],
     neg_from("points-ball-q12-l1", [{"op": "patch", "offset": 8, "hex": "01"}])),
    ("neg-crc-mismatch-base", "crc_mismatch", P, "one payload bit of BASE flipped, CRC kept", ["2", "13"],
     neg_from("points-ball-q12-l4", [{"op": "xor", "chunk": 3, "chunk_offset": 8 + 20, "mask": 0x10}])),
    ("neg-crc-mismatch-ancillary", "crc_mismatch", P, "an unknown ancillary chunk with a wrong CRC (CRCs are checked on every chunk)", ["2", "13"],
     neg_from("points-ball-q12-l1", [{"op": "insert_chunk", "at": 1, "type": "abcd", "payload": "0102"},
                                     {"op": "xor", "chunk": 1, "chunk_offset": 8, "mask": 0x01}])),
    ("neg-crc-mismatch-after-bad-header", "crc_mismatch", P,
     "a bad HEAD field and a later CRC mismatch: framing errors are found first", ["2", "13"],
     neg_from("points-ball-q12-l4", [{"op": "replace_payload", "at": 0, "payload": "07"}, {"op": "xor", "chunk": 5, "chunk_offset": 9, "mask": 0x80}])),
    ("neg-empty", "truncated", P, "an empty stream", ["12", "13"], lambda: b""),
    ("neg-truncated-preamble", "truncated", P, "the signature only (8 bytes)", ["2", "12", "13"],
     neg_from("points-ball-q12-l1", [{"op": "truncate", "length": 8}])),
    ("neg-truncated-in-base", "truncated", P, "cut inside the first level's BASE", ["12", "13"],
     neg_from("points-ball-q12-l4", [{"op": "truncate_in_chunk", "at": 3, "keep": 100}])),
    ("neg-truncated-before-first-rcon", "truncated", P,
     "surface stream cut after BASE, before its RCON: no complete level", ["3", "12", "13"],
     neg_from("surface-torus-q12-l4", [{"op": "truncate_in_chunk", "at": 4, "keep": 0}])),
    ("neg-chunk-length-too-big", "bad_chunk", P, "a chunk length of 2^31 (the stream ends right after)", ["2", "13"],
     neg_from("points-ball-q12-l4", [{"op": "truncate_in_chunk", "at": 4, "keep": 0}, {"op": "append", "hex": "5245464e00000080"}])),
    ("neg-chunk-length-max", "bad_chunk", P, "a chunk length of 2^32 - 1 in the middle of the stream", ["2", "13"],
     neg_from("points-ball-q12-l4", [{"op": "patch", "chunk": 4, "chunk_offset": 4, "hex": "ffffffff"}])),
    ("neg-chunk-type-not-letters", "bad_chunk", P, "chunk type 'RE4N' (a digit)", ["2", "13"],
     neg_from("points-ball-q12-l4", [{"op": "set_type", "at": 4, "type": "RE4N"}])),
    ("neg-unknown-critical", "bad_chunk", P, "an unknown critical chunk 'ABCD' with a correct CRC", ["2", "3", "13"],
     neg_from("points-ball-q12-l1", [{"op": "insert_chunk", "at": 2, "type": "ABCD", "payload": "00"}])),
    ("neg-refn-before-base", "bad_chunk", P, "REFN moved before BASE", ["3", "13"],
     neg_from("points-ball-q12-l4", [{"op": "move_chunk", "from": 4, "to": 3}])),
    ("neg-rcon-missing", "bad_chunk", P, "a surface stream whose first RCON was removed", ["3", "13"],
     neg_from("surface-torus-q12-l4", [{"op": "remove_chunk", "at": 4}])),
    ("neg-rcon-twice", "bad_chunk", P, "an RCON repeated", ["3", "13"],
     neg_from("surface-torus-q12-l4", [{"op": "copy_chunk", "from": 4, "to": 5}])),
    ("neg-rcon-in-points", "bad_chunk", P, "an RCON in a stream of kind points", ["3", "13"],
     neg_from("points-ball-q12-l1", [{"op": "insert_chunk", "at": 4, "type": "RCON", "payload": "010600018008000000"}])),
    ("neg-two-head", "bad_chunk", P, "HEAD twice", ["3", "13"],
     neg_from("points-ball-q12-l1", [{"op": "copy_chunk", "from": 0, "to": 1}])),
    ("neg-two-sqnt", "bad_chunk", P, "SQNT twice", ["3", "13"],
     neg_from("points-ball-q12-l1", [{"op": "copy_chunk", "from": 1, "to": 2}])),
    ("neg-head-not-first", "bad_chunk", P, "an ancillary chunk before HEAD", ["3", "13"],
     neg_from("points-ball-q12-l1", [{"op": "insert_chunk", "at": 0, "type": "abcd", "payload": ""}])),
    ("neg-base-before-sqnt", "bad_chunk", P, "BASE before SQNT", ["3", "13"],
     neg_from("points-ball-q12-l1", [{"op": "move_chunk", "from": 1, "to": 3}])),
    ("neg-sqnt-missing", "bad_chunk", P, "no SQNT", ["3", "13"],
     neg_from("points-ball-q12-l1", [{"op": "remove_chunk", "at": 1}])),
    ("neg-extra-refn", "bad_chunk", P, "one more REFN than the declared levels", ["3", "13"],
     neg_from("points-ball-q12-l4", [{"op": "copy_chunk", "from": 6, "to": 7}])),
    ("neg-hend-early", "bad_chunk", P, "HEND after two of four levels", ["3", "13"],
     neg_from("points-ball-q12-l4", [{"op": "remove_chunk", "at": 5}, {"op": "remove_chunk", "at": 5}])),
    ("neg-hend-nonempty", "bad_chunk", P, "HEND with a one-byte payload", ["9", "13"],
     neg_from("points-ball-q12-l1", [{"op": "replace_payload", "at": 4, "payload": "00"}])),
    ("neg-trailing-bytes", "bad_chunk", P, "two bytes after HEND", ["3", "13"],
     neg_from("points-ball-q12-l1", [{"op": "append", "hex": "0000"}])),
    ("neg-trailing-chunk", "bad_chunk", P, "a complete ancillary chunk after HEND", ["3", "13"],
     neg_from("points-ball-q12-l1", [{"op": "append", "hex": chunk_bytes("abcd", b"").hex()}])),
    # HEAD / SQNT
    ("neg-head-kind", "bad_header", P, "kind 3", ["4", "13"],
     lambda: stream_q1(base_payload([(0, 0, 0)], 1), kind=3)),
    ("neg-head-flags", "bad_header", P, "HEAD flags 2 (a reserved bit)", ["4", "13"],
     neg_from("points-one", [{"op": "replace_payload", "at": 0, "payload": "00020101"}])),
    ("neg-head-levels-0", "bad_header", P, "level_count 0", ["4", "13"],
     neg_from("points-one", [{"op": "replace_payload", "at": 0, "payload": "000000"}])),
    ("neg-head-levels-65", "bad_header", P, "level_count 65", ["4", "13"],
     neg_from("points-one", [{"op": "replace_payload", "at": 0, "payload": (bytes([0, 0, 65]) + bytes(range(1, 66))).hex()}])),
    ("neg-head-not-increasing", "bad_header", P, "level_points 5, 5", ["4", "13"],
     neg_from("points-one", [{"op": "replace_payload", "at": 0, "payload": "0000020505"}])),
    ("neg-head-zero-points", "bad_header", P, "level_points[0] = 0", ["4", "13"],
     neg_from("points-one", [{"op": "replace_payload", "at": 0, "payload": "00000100"}])),
    ("neg-head-trailing", "bad_header", P, "a byte after the last HEAD field", ["4", "13"],
     neg_from("points-one", [{"op": "replace_payload", "at": 0, "payload": "0000010100"}])),
    ("neg-head-varint-long", "bad_header", P, "a level count in a non-shortest varint (81 00)", ["1", "4", "13"],
     neg_from("points-one", [{"op": "replace_payload", "at": 0, "payload": "0000810001"}])),
    ("neg-grid-overflow", "bad_header", P, "9 points declared at q = 1 (the grid holds 8)", ["4", "13"],
     lambda: stream_q1(base_payload([(0, 0, 0)], 1), counts=(9,))),
    ("neg-sqnt-q0", "bad_header", P, "q = 0", ["5", "13"],
     lambda: stream_q1(base_payload([(0, 0, 0)], 1), q=0)),
    ("neg-sqnt-q22", "bad_header", P, "q = 22", ["5", "13"],
     None),
    ("neg-sqnt-step-nan", "bad_header", P, "step NaN", ["5", "13"], None),
    ("neg-sqnt-step-inf", "bad_header", P, "step +infinity", ["5", "13"], None),
    ("neg-sqnt-step-zero", "bad_header", P, "step 0", ["5", "13"], None),
    ("neg-sqnt-step-negative", "bad_header", P, "step -1", ["5", "13"], None),
    ("neg-sqnt-origin-inf", "bad_header", P, "origin y = -infinity", ["5", "13"], None),
    ("neg-sqnt-short", "bad_header", P, "SQNT payload of 32 bytes", ["5", "13"], None),
    # Huffman tables
    ("neg-huffman-oversubscribed", "bad_huffman_table", P, "BASE table with lengths 1, 1, 2", ["7.1", "13"],
     lambda: stream_q1(base_with_table(over_subscribed))),
    ("neg-huffman-incomplete", "bad_huffman_table", P, "BASE table with lengths 1, 2 (Kraft sum 3/4)", ["7.1", "13"],
     lambda: stream_q1(base_with_table(incomplete))),
    ("neg-huffman-run-past-alphabet", "bad_huffman_table", P, "a zero run of 255 from symbol 2 of 256", ["7.1", "13"],
     lambda: stream_q1(base_with_table(run_past))),
    ("neg-huffman-one-length", "bad_huffman_table", P, "one non-zero length in the multi-symbol form", ["7.1", "13"],
     lambda: stream_q1(base_with_table(one_length))),
    ("neg-huffman-single-out-of-range", "bad_huffman_table", P, "REFN single-symbol table with symbol 255 of 255", ["7.1", "8A", "13"],
     lambda: stream_q1_refn(refn_single(255))),
    ("neg-huffman-rcon-classes", "bad_huffman_table", P, "RCON class table (K = 2) with one symbol of length 1 only", ["7.1", "10", "13"], None),
    ("neg-refn-plane-slot-none", "bad_layer", P, "REFN coder 7 at q = 1 with plane contexts whose only slot with a table is plane context 1; the node is in context 0", ["8A.1", "13"],
     lambda: stream_q1_refn(b"\x07" + bits_payload(lambda bw: (bw.put(0, 4), bw.put(0, 2), bw.put(1, 1), bw.put(0, 4), bw.put(0, 1), bw.put(0, 5),
                                                                 bw.put(0, 1), bw.put(1, 1), bw.put(0, 1), bw.put(1, 1), bw.put(0, 8))))),
    ("neg-huffman-delta-length-0", "bad_huffman_table", P, "delta-form BASE table: 3 - 2 - 1 gives a length 0", ["4", "7.1", "13"],
     lambda: stream_q1(base_with_table(lambda bw: (bw.put(0, 1), bw.put(0b1101, 4), bw.put(0b101, 3))), flags=1)),
    ("neg-huffman-delta-length-16", "bad_huffman_table", P, "delta-form BASE table: a far token +13 gives a length 16", ["4", "7.1", "13"],
     lambda: stream_q1(base_with_table(lambda bw: (bw.put(0, 1), bw.put(0b1111, 4), bw.put(0, 1), bw.ue(10))), flags=1)),
    ("neg-huffman-delta-incomplete", "bad_huffman_table", P, "delta-form BASE table: lengths 1, 2, then the end token (Kraft sum 3/4)", ["4", "7.1", "13"],
     lambda: stream_q1(base_with_table(lambda bw: (bw.put(0, 1), bw.put(0b01, 2), bw.ue(0), bw.put(0b1101, 4), bw.put(0b100, 3), bw.put(0b1110, 4))), flags=1)),
    ("neg-huffman-delta-run-past", "bad_huffman_table", P, "delta-form BASE table: a zero run of 255 from symbol 2 of 256", ["4", "7.1", "13"],
     lambda: stream_q1(base_with_table(lambda bw: (bw.put(0, 1), bw.put(0b1101, 4), bw.put(0b00, 2), bw.put(0b01, 2), bw.ue(254))), flags=1)),
    ("neg-huffman-nibbles-as-deltas", "bad_huffman_table", P, "HEAD flag bit 0 set over a BASE table in the 4-bit form (lengths 1, 1 read as tokens)", ["4", "7.1", "13"],
     lambda: stream_q1(base_with_table(lambda bw: write_table(bw, 256, lengths={0: 1, 1: 1})), flags=1)),
    # layers
    ("neg-base-empty", "bad_layer", P, "empty BASE payload", ["8", "13"], lambda: stream_q1(b"")),
    ("neg-base-gaps-cut", "bad_layer", P, "BASE coder 5 at q = 1 whose payload ends inside the weight of its ranked depth", ["8.2", "13"],
     lambda: stream_q1(b"\x05" + bits_payload(lambda bw: (bw.put(10, 4), bw.put(0, 2), bw.put(1, 1), bw.put(1, 1))))),
    ("neg-base-coder", "bad_layer", P, "BASE coder 6", ["8", "13"],
     lambda: stream_q1(b"\x06" + base_payload([(0, 0, 0)], 1)[1:])),
    ("neg-base-coder-removed", "bad_layer", P, "BASE coder 3 (a ranked octree coder of versions before 0.25) over a payload that decodes as coder 5", ["8", "13", "15"],
     lambda: stream_q1(b"\x03" + base_ranked_payload(rand_pts(60, 3, 5), 3, 4, [True] * 3)[1:], counts=(60,), q=3)),
    ("neg-base-far-weight", "bad_layer", P, "BASE coder 5 at q = 1 whose ranked depth's weight is 17 (above 16)", ["8.2", "13"],
     lambda: stream_q1(b"\x05" + bits_payload(lambda bw: (bw.put(1, 4), bw.put(0, 2), bw.put(1, 1), bw.put(17, 5), bw.put(0, 1),
                                                            bw.put(0, 1), write_table(bw, 255, lengths={0: 1, 1: 1}), bw.put(0, 1))))),
    ("neg-base-paired-single", "bad_layer", P, "BASE coder 5 at q = 1 whose ranked depth's paired table has a one-symbol pair code (pairs would cost no bits)", ["7.4", "8.2", "13"],
     lambda: stream_q1(b"\x05" + bits_payload(lambda bw: (bw.put(1, 4), bw.put(0, 2), bw.put(1, 1), bw.put(0, 5), bw.put(0, 1),
                                                            bw.put(1, 1), bw.put(1, 1), bw.put(0, 7))))),
    ("neg-base-causal-cut", "bad_layer", P, "BASE coder 5 at q = 2 whose payload ends after the weight of its ranked depth 1, inside its flags and tables (depth 0 plain, its table 28 bits in the 4-bit form: 42 bits and 6 of padding)", ["8.2", "13"],
     lambda: stream_q1(b"\x05" + bits_payload(lambda bw: (bw.put(10, 4), bw.put(0, 2), bw.put(0, 1), bw.put(0, 1), write_table(bw, 256, lengths={0: 1, 1: 1}), bw.put(1, 1), bw.put(5, 5))), q=2)),
    ("neg-base-ranked-table", "bad_huffman_table", P, "BASE coder 5: a ranked depth's one-symbol table names symbol 255 (A = 255)", ["7.1", "8.2", "13"],
     lambda: stream_q1(b"\x05" + bits_payload(lambda bw: (bw.put(4, 4), bw.put(0, 2), bw.put(1, 1), bw.put(0, 5), bw.put(0, 1), bw.put(0, 1),
                                                            write_table(bw, 256, single=255))))),
    ("neg-base-ranked-single", "bad_layer", P, "BASE coder 5: a one-symbol code at a ranked depth (a 150-byte stream that would ask for 5.5 million nearest-neighbour searches)", ["8.2", "14", "13"],
     lambda: stream_q1(b"\x05" + bits_payload(lambda bw: (bw.put(10, 4), bw.put(0, 2), [(bw.put(1, 1), bw.put(0, 5), bw.put(0, 1), bw.put(0, 1),
                                                                                          write_table(bw, 255, single=(254 if d < 6 else 0))) for d in range(21)])), counts=(1 << 18,), q=21)),
    ("neg-base-ranked-zero", "bad_layer", P, "BASE coder 5: occupancy 0 at a plain depth", ["8.2", "13"],
     lambda: stream_q1(b"\x05" + bits_payload(lambda bw: (bw.put(4, 4), bw.put(0, 2), bw.put(0, 1), bw.put(0, 1), write_table(bw, 256, single=0))))),
    ("neg-base-ranked-overrun", "bad_layer", P, "BASE coder 5: the bit stream ends inside a code", ["7.3", "8.2", "13"],
     lambda: stream_q1(base_ranked_payload(rand_pts(60, 3, 5), 3, 4, [True] * 3)[:-2], counts=(60,), q=3)),
    ("neg-base-ranked-count", "bad_layer", P, "BASE coder 5 codes 60 points, HEAD declares 59", ["8.2", "13"],
     lambda: stream_q1(base_ranked_payload(rand_pts(60, 3, 5), 3, 4, [True] * 3), counts=(59,), q=3)),
    ("neg-base-zero-occupancy", "bad_layer", P, "occupancy 0 (single-symbol table)", ["8.1", "13"],
     lambda: stream_q1(b"\x00" + bits_payload(lambda bw: write_table(bw, 256, single=0)))),
    ("neg-base-count-mismatch", "bad_layer", P, "BASE codes 2 points, HEAD declares 3", ["8.1", "13"],
     lambda: stream_q1(base_payload([(0, 0, 0), (1, 1, 1)], 1), counts=(3,))),
    ("neg-base-too-many", "bad_layer", P, "BASE codes 3 points, HEAD declares 2", ["8.1", "13"],
     lambda: stream_q1(base_payload([(0, 0, 0), (1, 1, 1), (1, 0, 1)], 1), counts=(2,))),
    ("neg-base-padding", "bad_layer", P, "non-zero padding bits", ["1", "8.1", "13"],
     lambda: stream_q1(b"\x00" + (lambda bw: (write_table(bw, 256, single=1), bw.bytes(pad_bit=1)))(BitWriter())[1])),
    ("neg-base-trailing", "bad_layer", P, "a byte after the bit stream", ["1", "8.1", "13"],
     lambda: stream_q1(base_payload([(0, 0, 0)], 1) + b"\x00")),
    ("neg-base-overrun", "bad_layer", P, "the bit stream ends inside a code", ["7.3", "8.1", "13"],
     lambda: stream_q1(base_payload(rand_pts(60, 3, 5), 3)[:-2], counts=(60,), q=3)),
    ("neg-refn-coder", "bad_layer", P, "REFN coder 8", ["8A", "13"],
     lambda: stream_q1_refn(b"\x08" + refn_single(0)[1:])),
    ("neg-refn-coder-removed", "bad_layer", P, "REFN coder 6 (a conditional octree coder of versions before 0.25) over a payload that decodes as coder 7", ["8A", "13", "15"],
     lambda: stream_q1_refn(b"\x06" + bits_payload(lambda bw: (bw.put(1, 4), bw.put(0, 2), bw.put(0, 1), bw.put(0, 4), bw.put(0, 1),
                                                                 bw.put(0, 5), bw.put(1, 1), bw.put(0, 1), bw.put(1, 1), bw.put(7, 8))))),
    ("neg-refn-coder1-removed", "bad_layer", P, "REFN coder 1 (the anchored vector quantizer of versions 0.4-0.26, removed in 0.27), a layer those versions decoded when the stream had their VQTB", ["8A", "13", "15"],
     lambda: vq_neg()),
    ("neg-vqtb-removed", "bad_chunk", P, "a VQTB chunk (the codebook of versions 0.1-0.26, removed in 0.27) before BASE: an unknown critical chunk", ["3", "13", "15"], None),
    ("neg-refn-far-weight", "bad_layer", P, "REFN coder 7 at q = 1 whose one weight is 17 (above 16)", ["8A.1", "13"],
     lambda: stream_q1_refn(b"\x07" + bits_payload(lambda bw: (bw.put(1, 4), bw.put(0, 2), bw.put(0, 1), bw.put(0, 4), bw.put(0, 1),
                                                                 bw.put(17, 5), bw.put(1, 1), bw.put(0, 1), bw.put(1, 1), bw.put(1, 8))))),
    ("neg-refn-paired-cut", "bad_layer", P, "REFN coder 7 whose payload ends inside the escape code of a paired table (its pair code can give the escape)", ["7.4", "8A.1", "13"],
     lambda: stream_q1_refn(b"\x07" + bits_payload(lambda bw: (bw.put(1, 4), bw.put(0, 2), bw.put(0, 1), bw.put(0, 4), bw.put(0, 1),
                                                                 bw.put(0, 5), bw.put(1, 1), bw.put(1, 1), bw.put(1, 1), bw.put(64, 7), bw.put(0, 1))))),
    ("neg-refn-quadric-cut", "bad_layer", P, "REFN coder 7 whose payload ends inside the fit field (one data byte: neighbours, classes, planes and one bit of F)", ["8A.1", "13"],
     lambda: stream_q1_refn(b"\x07" + bits_payload(lambda bw: (bw.put(4, 4), bw.put(0, 2), bw.put(0, 1), bw.put(1, 1))))),
    ("neg-refn-depth-gaps-cut", "bad_layer", P, "REFN coder 7 at q = 1 whose payload ends inside the weight of depth 0 (two data bytes: neighbours, classes, planes, F, the per-depth flag and four bits of G_0)", ["8A.1", "13"],
     lambda: stream_q1_refn(b"\x07" + bits_payload(lambda bw: (bw.put(0, 4), bw.put(0, 2), bw.put(0, 1), bw.put(0, 4), bw.put(1, 1), bw.put(0, 4))))),
    ("neg-refn-gap-header-cut", "bad_layer", P, "REFN coder 7 whose payload ends inside its one weight (two data bytes: neighbours, classes, planes, F, the flag and four bits of G)", ["8A.1", "13"],
     lambda: stream_q1_refn(b"\x07" + bits_payload(lambda bw: (bw.put(0, 4), bw.put(0, 2), bw.put(1, 1), bw.put(0, 4), bw.put(0, 1), bw.put(0, 4))))),
    ("neg-refn-empty", "bad_layer", P, "empty REFN payload", ["8A", "13"], lambda: stream_q1_refn(b"")),
    ("neg-refn-no-table", "bad_layer", P, "a node needs a table slot that is none", ["8A.1", "13"],
     lambda: stream_q1_refn(b"\x00" + bits_payload(lambda bw: (bw.put(0, 4), bw.put(0, 2), bw.put(0, 1))))),
    ("neg-refn-coarse-point", "bad_layer", P, "an added point equal to a coarse point", ["8A.1", "13"],
     lambda: stream_q1_refn(refn_single(0))),
    ("neg-refn-count", "bad_layer", P, "a REFN adding two points where one is declared", ["8A.1", "13"],
     lambda: stream_q1_refn(refn_single(8))),
    # RCON
    ("neg-rcon-neighbour-loose", "bad_layer", P, "RCON flag bit 7 (neighbour_contexts) without vertex_contexts", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, compact=True, candidate_contexts=True, flags=128 | 1))),
    ("neg-rcon-vertex-loose", "bad_layer", P, "RCON flag bit 6 (vertex_contexts) without candidate_contexts", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, compact=True, flags=64 | 1))),
    ("neg-rcon-candidate-loose", "bad_layer", P, "RCON flag bit 5 (candidate_contexts) without compact", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, flags=32))),
    ("neg-rcon-class-list-loose", "bad_layer", P, "RCON flag bit 4 (class_list) without compact", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, flags=16))),
    ("neg-rcon-class-list-common", "bad_layer", P, "a class list whose common class is 3 of 3", ["10.1", "13"],
     lambda: surface_one_level(rcon_payload(30, multipliers=(300, 600, 900), compact=True, common=3, classes=[3] * 30))),
    ("neg-rcon-class-list-entry", "bad_layer", P, "a class list whose last entry is point 30 of 30", ["10.1", "13"],
     lambda: surface_one_level(rcon_payload(30, multipliers=(300, 600), compact=True, common=0,
                                            class_code_bits=bits_payload(lambda bw: (bw.put(0, 6), rice_bits(bw, [3, 30])))))),
    ("neg-rcon-class-alphabet", "bad_layer", P, "compact classes: K = 17 in groups of 3 (4913 symbols > 4096)", ["10.1", "13"],
     lambda: surface_one_level(rcon_payload(30, multipliers=tuple(range(300, 317)), compact=True,
                                            class_code_bits=bits_payload(lambda bw: (bw.put(2, 3), bw.put(1, 1), bw.put(0, 13)))))),
    ("neg-rcon-class-beyond-last", "bad_layer", P, "compact classes in groups of 4 over 30 points: the last group gives class 1 to a 31st point", ["10.1", "13"],
     lambda: surface_one_level(rcon_payload(30, multipliers=(300, 600), compact=True,
                                            class_code_bits=bits_payload(lambda bw: (bw.put(3, 3), bw.put(1, 1), bw.put(4, 4)))))),
    ("neg-rcon-toggle-count-bits", "bad_layer", P, "compact toggles: a count larger than the bits left", ["10.2", "13"],
     lambda: surface_one_level(rcon_payload(30, compact=True, toggle_bits=bits_payload(lambda bw: (bw.ue(0), bw.ue(40)))))),
    ("neg-rcon-toggle-rank-2e32", "bad_layer", P, "compact toggles: a rank of 2^32 - 1, Rice parameter 31", ["10.2", "13"],
     lambda: surface_one_level(rcon_payload(30, compact=True, toggle_bits=bits_payload(
         lambda bw: (bw.ue(1), bw.put(31, 5), bw.put(1, 1), bw.put(0, 1), bw.put(2**31 - 1, 31), [bw.ue(0) for _ in range(7)]))))),
    ("neg-rcon-toggle-unary-2e32", "bad_layer", P, "compact toggles: a Rice quotient that reaches 2^32 - 1 before its end (parameter 30, four 1 bits)", ["10.2", "13"],
     lambda: surface_one_level(rcon_payload(30, compact=True, toggle_bits=bits_payload(
         lambda bw: (bw.ue(1), bw.put(30, 5), bw.put(15, 4), bw.put(0, 31), [bw.ue(0) for _ in range(7)]))))),
    ("neg-rcon-toggle-cut", "bad_layer", P, "compact toggles: the bit stream ends inside the seventh context's count", ["10.2", "13"],
     lambda: surface_one_level(rcon_payload(30, compact=True, toggle_bits=bits_payload(
         lambda bw: ([bw.ue(0) for _ in range(6)], bw.put(0, 2)))))),
    ("neg-rcon-toggle-padding", "bad_layer", P, "compact toggles: one rank (Rice parameter 1), then non-zero padding", ["1", "10.2", "13"],
     lambda: surface_one_level(rcon_payload(30, compact=True, toggle_bits=(lambda bw: (
         bw.ue(1), bw.put(1, 5), bw.put(0, 2), [bw.ue(0) for _ in range(7)], bw.bytes(pad_bit=1)))(BitWriter())[-1]))),
    ("neg-rcon-toggle-trailing", "bad_layer", P, "compact toggles: a byte after the bit stream", ["10.2", "13"],
     lambda: surface_one_level(rcon_payload(30, compact=True) + b"\x00")),
    ("neg-rcon-filter-mask", "bad_layer", P, "RCON filter_mask bit 7 (reserved)", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, filters={0: 300}, mask=0x81))),
    ("neg-rcon-seal-empty", "bad_layer", P, "a seal box whose y range is empty (y0 = y1)", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, seal=(0, 5, 0, 16, 5, 16)))),
    ("neg-rcon-seal-beyond", "bad_layer", P, "a seal box reaching beyond 2^21", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, seal=(0, 0, 0, 16, 16, (1 << 21) + 1)))),
    ("neg-rcon-seal-cut", "bad_layer", P, "an RCON that ends inside its seal box", ["10", "13"],
     lambda: surface_one_level(bytes([1, 6, 0x40]) + varint(0) + varint(0) + varint(0))),
    ("neg-rcon-threshold-0", "bad_layer", P, "a filter threshold of 0", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, filters={1: 0}))),
    ("neg-rcon-threshold-range", "bad_layer", P, "a filter threshold of 65536", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, filters={2: 65536}))),
    ("neg-rcon-lone-threshold", "bad_layer", P, "threshold 2 for filter 3 (lone triangle), which must be 1", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, filters={3: 2}))),
    ("neg-rcon-scale-rank-0", "bad_layer", P, "scale_rank 0", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, scale_rank=0))),
    ("neg-rcon-scale-rank-65", "bad_layer", P, "scale_rank 65", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, scale_rank=65))),
    ("neg-rcon-class-count-0", "bad_layer", P, "class_count 0", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, multipliers=()))),
    ("neg-rcon-multipliers-order", "bad_layer", P, "multipliers 500, 500", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, multipliers=(500, 500), classes=[i % 2 for i in range(30)]))),
    ("neg-rcon-multiplier-range", "bad_layer", P, "a multiplier of 65536", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, multipliers=(65536,)))),
    ("neg-rcon-border-index", "bad_layer", P, "a border index equal to N", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, border=(3, 30)))),
    ("neg-rcon-border-count", "bad_layer", P, "border_count N + 1", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30, border=tuple(range(31))))),
    ("neg-rcon-count-past-payload", "bad_layer", P, "a drop count larger than the bytes left", ["10", "13"], None),
    ("neg-rcon-trailing", "bad_layer", P, "a byte after the last drop", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30) + b"\x00")),
    ("neg-rcon-class-padding", "bad_layer", P, "non-zero padding after the class bit stream", ["1", "10", "13"], None),
    ("neg-rcon-toggle-index-2e32", "bad_layer", P, "a toggle index of 2^32 - 1 (above the bound of section 10, checked without reconstruction)", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30)[:-2] + b"\x01" + varint(2**32 - 1) + b"\x00")),
    ("neg-rcon-drop-gap-2e32", "bad_layer", P, "two drop gaps summing past 2^32 - 1", ["10", "13"],
     lambda: surface_one_level(rcon_payload(30)[:-1] + b"\x02" + varint(2**31) + varint(2**31))),
    ("neg-huffman-table-overrun", "bad_layer", P, "the bit stream ends inside a code-length table", ["7.1", "8.1", "13"],
     lambda: stream_q1(b"\x00" + bits_payload(lambda bw: (bw.put(0, 1), bw.put(3, 4))))),
    ("neg-huffman-ue-prefix", "bad_layer", P, "an exp-Golomb zero run with 32 leading zeros", ["1", "7.1", "13"],
     lambda: stream_q1(b"\x00" + bits_payload(lambda bw: (bw.put(0, 1), bw.put(1, 4), bw.put(1, 4), bw.put(0, 4), bw.put(0, 32), bw.put(1, 1), bw.put(0, 32))))),
    ("neg-truncated-preamble-9", "truncated", P, "9 bytes: the signature and a version_major of 1; a cut preamble's version is not examined", ["2", "12", "13"],
     lambda: SIG + b"\x01"),
    ("neg-framing-first", "bad_chunk", P, "a bad HEAD and a byte after HEND: framing errors are found first", ["2", "13"],
     neg_from("points-ball-q12-l4", [{"op": "replace_payload", "at": 0, "payload": "07"}, {"op": "append", "hex": "00"}])),
    ("neg-rcon-vs-layer-order", "bad_chunk", P, "RCON before the level's layer chunk", ["3", "13"],
     lambda: join(SIG + VERSION, [["HEAD", head_payload(1, [1])], ["SQNT", sqnt_payload(1)], ["RCON", rcon_payload(1)],
                                      ["BASE", base_payload([(0, 0, 0)], 1)], ["HEND", b""]])),
    ("neg-rcon-toggle-range", "bad_layer", F, "a toggle index equal to the number of tetrahedra (full profile only)", ["10", "11.5", "13"], None),
    ("neg-rcon-toggle-rank-range", "bad_layer", F, "a compact toggle rank equal to the number of tetrahedra of its context (full profile only)", ["10.2", "11.5", "13"], None),
    ("neg-rcon-candidate-rank-range", "bad_layer", F, "candidate contexts: a toggle rank of context 17 equal to the number of tetrahedra (full profile only)", ["10.2", "11.5", "13"], None),
    ("neg-rcon-neighbour-rank-range", "bad_layer", F, "neighbour contexts: an inverted list naming rank 5000 of a context of fewer tetrahedra (full profile only)", ["10.2", "11.5", "13"],
     lambda: hb_rcon_neighbour_contexts(bad=True)),
    ("neg-rcon-vertex-rank-range", "bad_layer", F, "vertex contexts: a toggle rank of context 57 equal to the number of tetrahedra (full profile only)", ["10.2", "11.5", "13"], None),
    ("neg-rcon-drop-range", "bad_layer", F, "a drop index equal to four times the number of tetrahedra (full profile only)", ["10", "11.5", "13"], None),
]


def vq_neg():
    """A stream of kind points, q = 3: 8 coarse points and one layer of the
    removed REFN coder 1, as versions 0.4-0.26 wrote it (their VQTB left out,
    since a VQTB is itself refused: neg-vqtb-removed)."""
    q = 3
    coarse = rand_pts(8, q, 61)
    points = [(0, 1, (0, 0, 0)), (2, 2, (0, 0, 0))]
    counts = [len(coarse), len(coarse) + len(points)]
    ch = [["HEAD", head_payload(0, counts)], ["SQNT", sqnt_payload(q)], ["BASE", base_payload(coarse, q)],
          ["REFN", vq_payload(points, 3, 0)], ["HEND", b""]]
    return join(SIG + VERSION, ch)


def sqnt_bytes(q=1, origin=(0.0, 0.0, 0.0), step=1.0, extra=b""):
    return (bytes([q]) + f64(origin[0]) + f64(origin[1]) + f64(origin[2]) + f64(step) + extra)[:33 + len(extra)]


def stream_with_sqnt(sq):
    ch = [["HEAD", head_payload(0, [1])], ["SQNT", sq], ["BASE", base_payload([(0, 0, 0)], 1)], ["HEND", b""]]
    return join(SIG + VERSION, ch)


def stream_with_vqtb(vq):
    """A one-point stream with a VQTB chunk (removed in 0.27) before BASE."""
    ch = [["HEAD", head_payload(0, [1])], ["SQNT", sqnt_payload(1)], ["VQTB", vq], ["BASE", base_payload([(0, 0, 0)], 1)],
          ["HEND", b""]]
    return join(SIG + VERSION, ch)


# Builders that need the helpers above.
LATE = {
    "neg-sqnt-q22": lambda: stream_with_sqnt(sqnt_bytes(q=22)),
    "neg-vqtb-removed": lambda: stream_with_vqtb(vqtb_payload([(0, 1, 0), (1, 0, -1)])),
    "neg-sqnt-step-nan": lambda: stream_with_sqnt(sqnt_bytes(step=NAN)),
    "neg-sqnt-step-inf": lambda: stream_with_sqnt(sqnt_bytes(step=math.inf)),
    "neg-sqnt-step-zero": lambda: stream_with_sqnt(sqnt_bytes(step=0.0)),
    "neg-sqnt-step-negative": lambda: stream_with_sqnt(sqnt_bytes(step=-1.0)),
    "neg-sqnt-origin-inf": lambda: stream_with_sqnt(sqnt_bytes(origin=(0.0, -math.inf, 0.0))),
    "neg-sqnt-short": lambda: stream_with_sqnt(sqnt_bytes()[:32]),
    "neg-huffman-rcon-classes": lambda: surface_one_level(rcon_payload(
        30, multipliers=(300, 600), class_code_bits=bits_payload(lambda bw: (bw.put(0, 1), bw.put(1, 4), bw.put(0, 4), bw.ue(0)))))
    ,
    "neg-rcon-count-past-payload": lambda: surface_one_level(rcon_payload(30)[:-1] + b"\x05\x00\x00"),
    "neg-rcon-class-padding": lambda: surface_one_level(rcon_payload(
        30, multipliers=(300, 600), class_code_bits=(lambda bw: (write_table(bw, 2, single=1), bw.bytes(pad_bit=1)))(BitWriter())[1])),
}


def toggle_range_stream(drops=False, rank=False, candidates=False):
    """A surface on the 8 corners of the unit cube, whose tetrahedralization
    has 6 tetrahedra (delaunay.md §3.3): toggle 6 or drop 24 is out of range,
    and so is rank 6 in every context, since no context has more than 6."""
    pts = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    if drops:
        rc = rcon_payload(8, drops=(24,))
    elif candidates == "vertices":
        rc = rcon_payload(8, compact=True, candidate_contexts=True, vertex_contexts=True, toggles={57: (6,)})
    elif candidates:
        rc = rcon_payload(8, compact=True, candidate_contexts=True, toggles={17: (6,)})
    elif rank:
        rc = rcon_payload(8, compact=True, toggles={j: (6,) for j in range(8)})
    else:
        rc = rcon_payload(8, toggles=(6,))
    return surface_one_level(rc, pts=pts, q=1)


# ---------------------------------------------------------------- build


def spec_version_line():
    with open(SPEC, encoding="utf-8") as f:
        for line in f:
            if line.startswith("| Version |"):
                return line.strip()
    raise RuntimeError("no version line in spec/hmc.md")


def write_json(path, obj):
    with open(path, "w", newline="\n") as f:
        json.dump(obj, f, indent=2, sort_keys=False)
        f.write("\n")


def expected_dump(hmc, folder):
    exp = os.path.join(folder, "expected")
    if os.path.exists(exp):
        shutil.rmtree(exp)
    r = run([hmc, "dec", os.path.join(folder, "stream.hmc"), "--canonical", exp])
    levels = sorted(int(n[6:-7]) for n in os.listdir(exp) if n.endswith(".points"))
    return levels, "warning" in r.stderr


def build(hmc, out):
    if os.path.exists(out):
        shutil.rmtree(out)
    os.makedirs(out)
    version = spec_version_line()
    with open(os.path.join(out, "VERSION"), "w", newline="\n") as f:
        f.write(version + "\n")
    streams = {}
    index = []

    def finish(name, data, meta):
        folder = os.path.join(out, name)
        with open(os.path.join(folder, "stream.hmc"), "wb") as f:
            f.write(data)
        streams[name] = data
        if meta["expect"] == "decode":
            levels, warned = expected_dump(hmc, folder)
            with open(os.path.join(folder, "expected", "header.json")) as f:
                meta["levels_declared"] = json.load(f)["levels"]
            meta["levels_decoded"] = levels
            meta["truncated"] = not data.endswith(chunk_bytes("HEND", b""))
            meta["chunks"] = describe(data)
        write_json(os.path.join(folder, "case.json"), meta)
        index.append(meta)

    for name, inp, args, edit, covers, sections in ENCODED + EDITED:
        folder = os.path.join(out, name)
        os.makedirs(folder)
        fname = make_input(inp, folder, hmc)
        tmp = os.path.join(folder, "enc.tmp.hmc")
        run([hmc, "enc", os.path.join(folder, fname), "-o", tmp] + args)
        with open(tmp, "rb") as f:
            data = f.read()
        os.remove(tmp)
        edits = edit(data) if edit else []
        data = apply_edits(data, edits)
        kind = data[18] if len(data) > 18 else 0
        meta = {"name": name, "description": covers, "expect": "decode",
                "profile": "points" if kind == 0 else "full", "sections": sections,
                "encoder": {"input": fname, "args": args}, "edit": edits}
        finish(name, data, meta)
    for name, fn, profile, covers, sections in HANDBUILT:
        os.makedirs(os.path.join(out, name))
        meta = {"name": name, "description": covers, "expect": "decode", "profile": profile,
                "sections": sections, "built_by": "generate.py " + fn.__name__}
        finish(name, fn(), meta)
    for name, cls, profile, covers, sections, builder in NEGATIVE:
        os.makedirs(os.path.join(out, name))
        meta = {"name": name, "description": covers, "expect": "error", "error_class": cls, "profile": profile,
                "sections": sections}
        if builder is None and name in LATE:
            builder = LATE[name]
        if name == "neg-rcon-toggle-range":
            data = toggle_range_stream()
            meta["built_by"] = "generate.py toggle_range_stream"
        elif name == "neg-rcon-toggle-rank-range":
            data = toggle_range_stream(rank=True)
            meta["built_by"] = "generate.py toggle_range_stream"
        elif name == "neg-rcon-candidate-rank-range":
            data = toggle_range_stream(candidates=True)
            meta["built_by"] = "generate.py toggle_range_stream"
        elif name == "neg-rcon-vertex-rank-range":
            data = toggle_range_stream(candidates="vertices")
            meta["built_by"] = "generate.py toggle_range_stream"
        elif name == "neg-rcon-drop-range":
            data = toggle_range_stream(drops=True)
            meta["built_by"] = "generate.py toggle_range_stream"
        elif isinstance(builder, tuple):
            _, src, edits = builder
            data = apply_edits(streams[src], edits)
            meta["derived_from"] = src
            meta["edit"] = edits
        else:
            data = builder()
            meta["built_by"] = "generate.py"
        folder = os.path.join(out, name)
        with open(os.path.join(folder, "stream.hmc"), "wb") as f:
            f.write(data)
        r = run([hmc, "dec", os.path.join(folder, "stream.hmc"), "--canonical", os.path.join(tempfile.gettempdir(), "hmc-conf-neg")], check=False)
        shutil.rmtree(os.path.join(tempfile.gettempdir(), "hmc-conf-neg"), ignore_errors=True)
        if r.returncode == 0 or cls not in r.stderr:
            print("warning: %s: hmc exits %d: %s" % (name, r.returncode, r.stderr.strip()), file=sys.stderr)
        write_json(os.path.join(folder, "case.json"), meta)
        index.append(meta)
    return index


README_HEAD = """# HMC conformance suite

Vectors, a runner and a second decoder that let any HMC decoder check
itself bit for bit against the specification (`spec/hmc.md`, version in
`vectors/VERSION`). The rules (what a decoder outputs, the canonical dump,
profiles, the negative-case convention, versioning) are in
`spec/conformance.md`.

| path | what |
|---|---|
| `vectors/<case>/` | `stream.hmc`, `case.json`, `expected/` (the canonical dump of every decoded level, positive cases), the encoder's input (cases made by `hmc enc`) |
| `run.py` | the runner: `run.py --decoder 'CMD {in} {outdir}' [--profile points\\|full] [--cases DIR]` |
| `refdec.py` | a second decoder written from the spec alone (Python, points profile): `refdec.py IN.hmc OUTDIR` |
| `generate.py` | rebuilds every vector deterministically: `generate.py --hmc build/bin/hmc`; `--check` re-encodes every case and reports drift |

Python 3's standard library is all the scripts need.

```sh
python3 conformance/run.py --decoder 'build/bin/hmc dec {in} --canonical {outdir}'                  # full profile
python3 conformance/run.py --decoder 'python3 conformance/refdec.py {in} {outdir}' --profile points  # points profile
python3 conformance/generate.py --hmc build/bin/hmc                                                 # regenerate (after a spec version change)
```

CTest runs `conformance_hmc` (the reference decoder, full profile),
`conformance_refdec` (refdec.py, points profile) and `conformance_drift`
(re-encoding every case; fails if the bytes changed while the spec's
version line did not).

A negative case passes when the decoder exits with a non-zero status (not
by a signal) and names the expected error class as a whole word on
standard error. Negative cases of profile `full` need reconstruction to
detect and are skipped in the `points` profile; positive cases of profile
`full` are run in the `points` profile without comparing `.simplices`.

This file's tables are written by `generate.py`.
"""


def write_readme(path, index):
    def cell(t):
        return t.replace("|", "\\|")

    lines = [README_HEAD, "## Positive cases (%d)\n" % sum(1 for m in index if m["expect"] == "decode"),
             "| case | covers | profile | levels decoded | spec sections |", "|---|---|---|---|---|"]
    for m in index:
        if m["expect"] == "decode":
            lv = "%d of %d%s" % (len(m["levels_decoded"]), m["levels_declared"], ", cut" if m["truncated"] else "")
            lines.append("| `%s` | %s | %s | %s | %s |" % (m["name"], cell(m["description"]), m["profile"], lv, ", ".join(m["sections"])))
    lines += ["", "## Negative cases (%d)\n" % sum(1 for m in index if m["expect"] == "error"),
              "| case | defect | error class | profile | spec sections |", "|---|---|---|---|---|"]
    for m in index:
        if m["expect"] == "error":
            lines.append("| `%s` | %s | `%s` | %s | %s |" % (m["name"], cell(m["description"]), m["error_class"], m["profile"],
                                                             ", ".join(m["sections"])))
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


def check(hmc, cases):
    """Re-encodes every case recorded with encoder options (and re-derives
    every negative case from its source) and compares the bytes."""
    with open(os.path.join(cases, "VERSION")) as f:
        recorded = f.read().strip()
    current = spec_version_line()
    drift = []
    n = 0
    tmpdir = tempfile.mkdtemp(prefix="hmc-conf-check-")
    try:
        names = sorted(d for d in os.listdir(cases) if os.path.isfile(os.path.join(cases, d, "case.json")))
        metas = {}
        for name in names:
            with open(os.path.join(cases, name, "case.json")) as f:
                metas[name] = json.load(f)
        for name in names:
            meta = metas[name]
            folder = os.path.join(cases, name)
            with open(os.path.join(folder, "stream.hmc"), "rb") as f:
                committed = f.read()
            if "encoder" in meta:
                tmp = os.path.join(tmpdir, name + ".hmc")
                r = run([hmc, "enc", os.path.join(folder, meta["encoder"]["input"]), "-o", tmp] + meta["encoder"]["args"], check=False)
                if r.returncode != 0:
                    drift.append("%s: hmc enc failed: %s" % (name, r.stderr.strip()))
                    continue
                with open(tmp, "rb") as f:
                    data = apply_edits(f.read(), meta.get("edit", []))
            elif "derived_from" in meta:
                with open(os.path.join(cases, meta["derived_from"], "stream.hmc"), "rb") as f:
                    data = apply_edits(f.read(), meta["edit"])
            else:
                continue
            n += 1
            if data != committed:
                drift.append("%s: %d bytes re-encoded, %d committed, first difference at byte %d" % (
                    name, len(data), len(committed),
                    next((i for i, (a, b) in enumerate(zip(data, committed)) if a != b), min(len(data), len(committed)))))
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)
    for d in drift:
        print("DRIFT " + d)
    if drift and recorded == current:
        print("%d of %d re-encoded streams differ from the committed vectors while spec/hmc.md's version is unchanged "
              "(%s): the encoder changed the bitstream without a spec version change. Bump the spec version, or "
              "regenerate the vectors with conformance/generate.py if the change is intended and conforming." % (
                  len(drift), n, current))
        return 1
    if drift:
        print("spec version changed (%s -> %s): %d drifting streams accepted; regenerate the vectors." % (recorded, current, len(drift)))
    print("%d passed, %d failed" % (n - len(drift) if recorded == current else n, len(drift) if recorded == current else 0))
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hmc", required=True, help="path to the hmc command line")
    ap.add_argument("--out", default=os.path.join(HERE, "vectors"))
    ap.add_argument("--cases", default=None, help="with --check: the vectors folder")
    ap.add_argument("--check", action="store_true")
    a = ap.parse_args()
    if a.check:
        return check(a.hmc, a.cases or a.out)
    index = build(a.hmc, a.out)
    write_readme(os.path.join(os.path.dirname(os.path.abspath(a.out)), "README.md"), index)
    pos = sum(1 for m in index if m["expect"] == "decode")
    print("%d cases (%d positive, %d negative) in %s" % (len(index), pos, len(index) - pos, a.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
