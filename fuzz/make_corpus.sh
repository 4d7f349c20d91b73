#!/bin/sh
# SPDX-License-Identifier: AGPL-3.0-or-later
# Regenerates the seed corpora fuzz/corpus/<target>/ (see fuzz/README.md).
#
# Valid streams come from the built command line: `hmc gen` samples of 3
# to ~2,000 points encoded by `hmc enc` at q = 1, 2, 12 and 21, with and
# without the info chunk. The other targets' seeds are cut from those
# streams, and hand-made edge cases are added (empty and cut streams, bad
# CRC, unknown and out-of-order chunks (VQTB among them), single-symbol octree codes,
# NaN and halfway coordinates, ...). The mesh readers' seeds (meshio) are
# the writers' output for a small torus and hand-made files in every format
# the library reads. Deterministic: running it again gives the same files.
#
# usage: fuzz/make_corpus.sh            (uses build/bin/hmc, or $HMC)
set -eu

ROOT=$(cd "$(dirname "$0")/.." && pwd)
HMC=${HMC:-$ROOT/build/bin/hmc}
CORPUS=$ROOT/fuzz/corpus
if [ ! -x "$HMC" ]; then
  echo "make_corpus: $HMC not found; build first (scripts/setup.sh) or set HMC" >&2
  exit 1
fi

WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT INT TERM

# Sample name, generator, vertex count.
for spec in ball3:ball:3 ball40:ball:40 lattice64:lattice:64 sphere100:sphere:100 torus500:torus:500 \
            ball2000:ball:2000; do
  name=${spec%%:*}
  rest=${spec#*:}
  "$HMC" gen "${rest%%:*}" --vertices "${rest#*:}" --seed 7 -o "$WORK/$name.ply" >/dev/null
  for q in 1 2 12 21; do
    "$HMC" enc "$WORK/$name.ply" -o "$WORK/$name-q$q.hmc" --bits "$q" >/dev/null
    "$HMC" enc "$WORK/$name.ply" -o "$WORK/$name-q$q-noinfo.hmc" --bits "$q" --no-info >/dev/null
  done
done

# Small multi-level streams with their canonical dumps:
# seeds for the layer and RCON targets (cut out below) and for decode.
for spec in ball64:ball:64:volume sphere90:sphere:90:surface sphere50:sphere:50:surface ball36:ball:36:volume \
            sphere36:sphere:36:surface; do
  name=${spec%%:*}
  rest=${spec#*:}
  gen=${rest%%:*}
  rest=${rest#*:}
  "$HMC" gen "$gen" --vertices "${rest%%:*}" --seed 3 -o "$WORK/$name.ply" >/dev/null
  levels=2
  case $name in *36) levels=1 ;; esac
  "$HMC" enc "$WORK/$name.ply" -o "$WORK/$name-exact.hmc" --bits 8 --kind "${rest#*:}" --levels $levels --no-info \
    --canonical "$WORK/$name-exact.dump" >/dev/null
done

# Mesh files as the library writes them: seeds for the readers (meshio).
"$HMC" gen torus --vertices 30 --seed 7 -o "$WORK/mesh-torus.ply" >/dev/null
for ext in obj xyz vtk mesh; do
  "$HMC" gen torus --vertices 30 --seed 7 -o "$WORK/mesh-torus.$ext" >/dev/null
done

rm -rf "$CORPUS"
mkdir -p "$CORPUS"
python3 - "$WORK" "$CORPUS" "$ROOT" <<'EOF'
import glob, math, os, struct, sys, zlib

work, corpus, root = sys.argv[1], sys.argv[2], sys.argv[3]
MAX_FILE = 64 * 1024
SIG = bytes([0x89, 0x48, 0x4D, 0x43, 0x0D, 0x0A, 0x1A, 0x0A])

def put(target, name, data):
    d = os.path.join(corpus, target)
    os.makedirs(d, exist_ok=True)
    if len(data) > MAX_FILE:
        return
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)

def chunk(t, payload):
    t = t.encode()
    return t + struct.pack("<I", len(payload)) + payload + struct.pack("<I", zlib.crc32(t + payload))

def varint(v):
    out = bytearray()
    while v >= 0x80:
        out.append((v & 0x7F) | 0x80)
        v >>= 7
    out.append(v)
    return bytes(out)

def svarint(v):
    return varint(2 * v if v >= 0 else -2 * v - 1)   # zigzag

def chunks(stream):
    pos, out = 10, []
    while pos + 8 <= len(stream):
        t = stream[pos:pos + 4].decode()
        n = struct.unpack("<I", stream[pos + 4:pos + 8])[0]
        out.append((t, stream[pos + 8:pos + 8 + n]))
        pos += 12 + n
    return out

def head(kind, counts):
    return chunk("HEAD", bytes([kind, 0]) + varint(len(counts)) + b"".join(varint(c) for c in counts))

def sqnt(q, origin=(0.0, 0.0, 0.0), step=1.0):
    return chunk("SQNT", bytes([q]) + struct.pack("<4d", *origin, step))

class Bits:
    def __init__(self):
        self.bits = []
    def put(self, v, n):
        self.bits += [(v >> i) & 1 for i in range(n - 1, -1, -1)]
    def ue(self, v):
        x, z = v + 1, 0
        while (x >> (z + 1)) > 0:
            z += 1
        self.put(0, z)
        self.put(x, z + 1)
    def bytes(self):
        b = self.bits + [0] * (-len(self.bits) % 8)
        return bytes(int("".join(map(str, b[i:i + 8])), 2) for i in range(0, len(b), 8))

PRE = SIG + bytes([0, 1])
END = chunk("HEND", b"")

# --- decode and container: the encoded samples and hand-made streams -----
streams = {}
for path in sorted(glob.glob(os.path.join(work, "*.hmc"))):
    name = os.path.basename(path)[:-4]
    data = open(path, "rb").read()
    streams[name] = data
    put("decode", name, data)
    if name.endswith("-noinfo") or name.startswith(("ball3-", "torus500-q12")):
        put("container", name, data)

def single_symbol_octree(q, occ_per_depth):
    b = Bits()
    for occ in occ_per_depth:
        b.put(1, 1)
        b.put(occ, 8)
    return bytes([0]) + b.bytes()

s = streams["ball3-q2"]
hand = {
    "empty": b"",
    "sig-only": SIG,
    "sig-short": SIG[:5],
    "preamble": PRE,
    "bad-magic": b"\x89PNG\r\n\x1a\n" + s[8:],
    "version-1": SIG + bytes([1, 0]) + s[10:],
    "minor-99": SIG + bytes([0, 99]) + s[10:],
    "hend-only": PRE + END,
    "head-hend": PRE + head(0, [1]) + END,
    "crc-flip": s[:-5] + bytes([s[-5] ^ 1]) + s[-4:],
    "trailing-byte": s + b"\x00",
    "cut-in-header": s[:14],
    "cut-in-base": s[:len(s) - 20],
    "cut-before-hend": s[:len(s) - 12],
    "lowercase-critical": PRE + head(0, [1]) + chunk("zzzz", b"ancillary") + s[len(PRE) + len(head(0, [1])):],
    "unknown-critical": PRE + chunk("ABCD", b""),
    "bad-type": PRE + b"HE\x00D" + s[14:],
    "huge-length": PRE + b"HEAD" + struct.pack("<I", 0x80000000) + b"\x00" * 8,
    "second-head": PRE + head(0, [1]) + head(0, [1]) + END,
    "two-levels": PRE + head(1, [1, 2]) + sqnt(1) + chunk("BASE", single_symbol_octree(1, [1])) + END,
    "single-symbol-octree": PRE + head(2, [1]) + sqnt(3) + chunk("BASE", single_symbol_octree(3, [1, 2, 4])) + END,
    "single-symbol-full": PRE + head(0, [512]) + sqnt(3) + chunk("BASE", single_symbol_octree(3, [255] * 3)) + END,
    "single-symbol-many": PRE + head(0, [4096]) + sqnt(21)
                          + chunk("BASE", single_symbol_octree(21, [255] * 4 + [1] * 17)) + END,
    "too-many-points": PRE + head(0, [9]) + sqnt(1) + END,
    "base-empty": PRE + head(0, [1]) + sqnt(1) + chunk("BASE", b"") + END,
    "base-coder-1": PRE + head(0, [1]) + sqnt(1) + chunk("BASE", b"\x01") + END,
    "sqnt-nan": PRE + head(0, [1]) + chunk("SQNT", bytes([1]) + struct.pack("<4d", float("nan"), 0, 0, 1)) + END,
    "sqnt-q22": PRE + head(0, [1]) + sqnt(22) + END,
    # VQTB was removed in 0.27: an unknown critical chunk (bad_chunk)
    "vqtb": PRE + head(0, [1]) + sqnt(1) + chunk("VQTB", bytes([3]) + varint(2) +
            b"".join(svarint(v) for v in (1, -1, 0, 2097151, -2097151, 5)))
            + chunk("BASE", single_symbol_octree(1, [1])) + END,
    "vqtb-huge": PRE + head(0, [1]) + sqnt(1) + chunk("VQTB", bytes([3]) + varint(65536) + b"\x00" * 9) + END,
    "varint-long": PRE + chunk("HEAD", bytes([0, 0]) + b"\x81\x80\x80\x80\x80\x80\x80\x80\x80\x00") + END,
    "info-only": PRE + head(0, [1]) + chunk("info", b"no equals\n=x\nk=v\n\xff\xfe=\n") + sqnt(1)
                 + chunk("BASE", single_symbol_octree(1, [128])) + END,
}
for name, data in hand.items():
    put("decode", "hand-" + name, data)
    put("container", "hand-" + name, data)

# --- base_layer: q, n - 1 (u24), BASE payload with its coder byte --------
def base_input(q, n, bits):
    return bytes([q - 1]) + struct.pack("<I", n - 1)[:3] + bits

def base_points(head):
    """The first level_points of a HEAD payload (the base layer's count)."""
    n, shift, i = 0, 0, 3
    while True:
        n |= (head[i] & 0x7F) << shift
        shift += 7
        if not head[i] & 0x80:
            return n
        i += 1

for name, data in sorted(streams.items()):
    if not name.endswith("-noinfo"):
        continue
    parts = dict(chunks(data))
    q = parts["SQNT"][0]
    n = base_points(parts["HEAD"])
    put("base_layer", name, base_input(q, n, parts["BASE"]))
    # The same stream declared one point short and one point long.
    if name.startswith("ball40"):
        if n > 1:  # a base level of one point (the default's preview levels) has no shorter count
            put("base_layer", name + "-n-1", base_input(q, n - 1, parts["BASE"]))
        put("base_layer", name + "-n+1", base_input(q, n + 1, parts["BASE"]))
put("base_layer", "single-full-q3", base_input(3, 512, single_symbol_octree(3, [255] * 3)))
put("base_layer", "single-chain-q21", base_input(21, 1, single_symbol_octree(21, [1] * 21)))
put("base_layer", "empty-q1", base_input(1, 1, b""))
put("base_layer", "coder1-empty-q1", base_input(1, 1, b"\x01"))
# Coders 4 (paired tables) and 5 (far ranking) from the conformance
# vectors: the samples' base layers pair none and are surfaces.
for case in ("base-paired", "base-paired-lattice", "base-far", "base-far-lattice"):
    with open(os.path.join(root, "conformance", "vectors", case, "stream.hmc"), "rb") as f:
        parts = dict(chunks(f.read()))
    put("base_layer", case, base_input(parts["SQNT"][0], base_points(parts["HEAD"]), parts["BASE"]))

# --- huffman: table form (u8), alphabet - 1 (u16), then a table and symbols
def huff_input(alphabet, bits, form=0):
    return struct.pack("<BH", form, alphabet - 1) + bits

for name in ("ball40-q12-noinfo", "torus500-q12-noinfo", "lattice64-q2-noinfo"):
    base = dict(chunks(streams[name]))["BASE"][1:]
    put("huffman", name, huff_input(256, base[:512], 1))  # the encoder writes delta tables
b = Bits(); b.put(1, 1); b.put(5, 3)
put("huffman", "single-a8", huff_input(8, b.bytes()))
b = Bits(); b.put(1, 1); b.put(9, 4)
put("huffman", "single-out-of-range", huff_input(9, b.bytes()))
b = Bits(); b.put(0, 1); b.put(1, 4); b.put(1, 4); b.put(0b0110, 4)
put("huffman", "two-symbols", huff_input(2, b.bytes()))
b = Bits(); b.put(0, 1)
for l in (2, 1, 3, 3):
    b.put(l, 4)
for code, n in ((0b10, 2), (0b0, 1), (0b110, 3), (0b111, 3)):
    b.put(code, n)
put("huffman", "spec-example", huff_input(4, b.bytes()))
b = Bits(); b.put(0, 1); b.put(0, 4); b.ue(9); b.put(1, 4); b.put(0, 4); b.ue(300); b.put(1, 4)
put("huffman", "zero-runs", huff_input(312, b.bytes()))
b = Bits(); b.put(0, 1)
for l in list(range(1, 15)) + [15, 15]:              # Kraft sum exactly 2^15
    b.put(l, 4)
b.put(0xFFFF, 16); b.put(0xFFFF, 16); b.put(0b1110, 4)
put("huffman", "long-codes", huff_input(16, b.bytes()))
b = Bits(); b.put(0, 1); b.put(0, 4); b.put(0, 31); b.put(1, 1)
put("huffman", "ue-31-zeros", huff_input(65536, b.bytes()))
# Delta form: lengths 2, 1, 3, 3 (3-1, -1, +2, same), then the spec example's symbols.
b = Bits(); b.put(0, 1); b.put(0b101, 3); b.put(0b101, 3); b.put(0b1100, 4); b.put(0b00, 2)
for code, n in ((0b10, 2), (0b0, 1), (0b110, 3), (0b111, 3)):
    b.put(code, n)
put("huffman", "delta-spec-example", huff_input(4, b.bytes(), 1))
# Delta form: far tokens (+12, -13), a zero run and the end token.
b = Bits(); b.put(0, 1); b.put(0b1111, 4); b.put(0, 1); b.ue(9); b.put(0b01, 2); b.ue(4)
b.put(0b1111, 4); b.put(1, 1); b.ue(10); b.put(0b1110, 4)
put("huffman", "delta-far-end", huff_input(40, b.bytes(), 1))

# --- refine_layer, recon: cut from the small streams ---------------------
def dump_points(path):
    with open(path) as f:
        return [tuple(int(v) for v in line.split()) for line in f if line.strip()]

def u24s(pts):
    return b"".join(b"".join((v & 0xFFFFFF).to_bytes(3, "little") for v in p) for p in pts)

for path in sorted(glob.glob(os.path.join(work, "*-*.hmc"))):
    name = os.path.basename(path)[:-4]
    dump = os.path.join(work, name + ".dump")
    if not os.path.isdir(dump):
        continue
    cs = chunks(streams[name])
    kind = cs[0][1][0]
    q = next(p for t, p in cs if t == "SQNT")[0]
    refn = [p for t, p in cs if t == "REFN"]
    rcon = [p for t, p in cs if t == "RCON"]
    if refn:
        coarse = dump_points(os.path.join(dump, "level-1.points"))
        fine = dump_points(os.path.join(dump, "level-0.points"))
        n = len(fine) - len(coarse)
        if len(coarse) > 64:
            continue
        common = bytes([q - 1, len(coarse) - 1]) + u24s(coarse)
        coder = bytes([{0: 0, 7: 1}[refn[0][0]]])  # the target's coder byte mod 2: 0 coder 0, 1 coder 7
        put("refine_layer", name, common + (n - 1).to_bytes(2, "little") + coder + refn[0][1:])
    if rcon and q == 8:
        pts = dump_points(os.path.join(dump, "level-0.points"))
        if 4 <= len(pts) <= 40:
            put("recon", name, bytes([1 if kind == 2 else 0, len(pts) - 4]) + bytes(v for p in pts for v in p) + rcon[-1])

# Coder 7 with paired tables and far ranking from the conformance vectors:
# the small samples' layers do not use them.
for case in ("refn-paired-escapes", "refn-paired-single", "refn-far-lattice"):
    folder = os.path.join(root, "conformance", "vectors", case)
    with open(os.path.join(folder, "stream.hmc"), "rb") as f:
        cs = chunks(f.read())
    q = next(p for t, p in cs if t == "SQNT")[0]
    refn = [p for t, p in cs if t == "REFN"]
    levels = len(refn) + 1
    coarse = dump_points(os.path.join(folder, "expected", "level-%d.points" % (levels - 1)))
    fine = dump_points(os.path.join(folder, "expected", "level-%d.points" % (levels - 2)))
    common = bytes([q - 1, len(coarse) - 1]) + u24s(coarse)
    coder = bytes([{0: 0, 7: 1}[refn[0][0]]])
    put("refine_layer", case, common + (len(fine) - len(coarse) - 1).to_bytes(2, "little") + coder + refn[0][1:])

# A class list (RCON flag bit 4) over 30 points of a sphere: K = 3 around
# common class 1, points 4 and 20 listed (Rice parameter 3), classes 0 and 2.
sphere = sorted({(128 + round(90 * math.cos(a) * math.cos(b)), 128 + round(90 * math.sin(a) * math.cos(b)),
                  128 + round(90 * math.sin(b))) for a, b in ((i * 2.4, (i % 7 - 3) * 0.4) for i in range(30))})
b = Bits()
b.put(1, 6); b.ue(2); b.put(3, 5)
b.put(0, 1); b.put(4, 3); b.put(0b10, 2); b.put(7, 3)  # gap 4, then gap 15 = 1·8 + 7
b.put(0, 1); b.put(1, 4); b.put(1, 4)                 # 4-bit table with A = 2: lengths 1, 1
b.put(0, 1); b.put(1, 1)                              # point 4 class 0, point 20 class 2
rc = bytes([1 | 4 | 16, 6, 0, 3]) + varint(400) + varint(900) + varint(3000) + b.bytes() + bytes([0, 0, 0xff])
put("recon", "class-list", bytes([0, len(sphere) - 4]) + bytes(v for p in sphere for v in p) + rc)

# Candidate contexts (RCON flag bit 5): 40 toggle lists, rank 1 in context
# 9; vertex contexts (bits 5 and 6): 80 lists, rank 0 in context 60;
# neighbour contexts (bits 5, 6 and 7): 240 lists, the one of context 180
# inverted (every tetrahedron of it but rank 0 toggled; counts 2n + inverted).
def one_toggle_rcon(flags, contexts, at, rank):
    b = Bits()
    for j in range(contexts):
        if j == at:
            b.ue(3 if flags & 128 else 1); b.put(0, 5); b.put((1 << (rank + 1)) - 2, rank + 1)  # Rice parameter 0: rank 1s, a 0
        else:
            b.ue(0)
    return bytes([flags, 6, 0, 1]) + varint(900) + bytes([0, 0]) + b.bytes()

for name, flags, contexts, at, rank in (("candidate-contexts", 1 | 4 | 32, 40, 9, 1),
                                        ("vertex-contexts", 1 | 4 | 32 | 64, 80, 60, 0),
                                        ("neighbour-contexts", 1 | 4 | 32 | 64 | 128, 240, 180, 0)):
    put("recon", name, bytes([0, len(sphere) - 4]) + bytes(v for p in sphere for v in p) +
        one_toggle_rcon(flags, contexts, at, rank))

# --- roundtrip: q - 1, flags, seed, then 12 bytes per point --------------
def rt(q, flags, seed, coords, fmt):
    return bytes([q - 1, flags, seed]) + b"".join(struct.pack("<3" + fmt, *c) for c in coords)

import random
rnd = random.Random(5)
ints = [(rnd.randrange(-1000, 1000), rnd.randrange(-1000, 1000), rnd.randrange(-1000, 1000)) for _ in range(200)]
for q in (1, 2, 12, 21):
    put("roundtrip", f"ints-q{q}", rt(q, 0x04 | 3, q, ints, "i"))            # mode 0, info, auto kind
    put("roundtrip", f"small-q{q}", rt(q, 0x10 | 1, q, [(x << 20, y << 20, z << 20) for x, y, z in ints[:60]], "i"))
floats = [(rnd.uniform(-1, 1), rnd.uniform(-1e3, 1e3), rnd.uniform(0, 1e-3)) for _ in range(100)]
put("roundtrip", "floats-q12", rt(12, 0x08 | 0x04 | 2, 1, floats, "f"))
put("roundtrip", "floats-nan", rt(12, 0x08, 1, floats[:5] + [(float("nan"), 0, 0)], "f"))
put("roundtrip", "floats-inf", rt(12, 0x08, 1, [(float("inf"), 0, 0)] + floats[:5], "f"))
put("roundtrip", "floats-tiny", rt(21, 0x08, 1, [(1e-45, 0, 0), (0, 0, 0), (-1e-45, 1e-45, 0)], "f"))
put("roundtrip", "floats-huge", rt(21, 0x08, 1, [(3.4e38, -3.4e38, 0), (-3.4e38, 3.4e38, 1)], "f"))
half = [(i, 2 * i + 1, 3 * i) for i in range(0, 1 << 12, 97)]                      # multiples of 2^-30
put("roundtrip", "halves-q2", rt(2, 0x18, 3, half, "i"))
put("roundtrip", "one-point", rt(5, 0x04, 0, [(7, 7, 7)], "i"))
put("roundtrip", "duplicates", rt(3, 0x00, 9, [(1, 2, 3)] * 20 + [(4, 5, 6)] * 3, "i"))
put("roundtrip", "no-points", bytes([11, 0, 0]))
put("roundtrip", "extremes", rt(21, 0x03, 4, [(-2**31, -2**31, -2**31), (2**31 - 1, 2**31 - 1, 2**31 - 1), (0, 0, 0)], "i"))

# --- meshio: the reader (0 PLY, 1 OBJ, 2 OFF, 3 XYZ, 4 STL, 5 MEDIT, 6 Gmsh,
# 7 VTK), then the file ------------------------------------------------------
for ext, reader in (("ply", 0), ("obj", 1), ("xyz", 3), ("mesh", 5), ("vtk", 7)):
    with open(os.path.join(work, "mesh-torus." + ext), "rb") as f:
        put("meshio", "torus-" + ext, bytes([reader]) + f.read())
tet4 = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
put("meshio", "ply-ascii", b"\x00" + ("ply\nformat ascii 1.0\ncomment hand-made\nelement vertex 4\nproperty float x\n"
    "property float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n" +
    tet4 + "3 0 1 2\n4 0 1 3 2\n").encode())
put("meshio", "ply-big-endian", b"\x00" + b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n"
    b"property double y\nproperty double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n" +
    struct.pack(">9d", 0, 0, 0, 1, 0, 0, 0, 1, 0) + bytes([3]) + struct.pack(">3I", 0, 1, 2))
put("meshio", "obj-polygons", b"\x01# comment\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n"
    b"f 1/1/1 2/1/1 3/1/1\nf -4 -3 -1 -2\n")
put("meshio", "off", b"\x02OFF\n4 3 0\n" + tet4.encode() + b"3 0 1 2\n3 0 1 3\n4 0 2 3 1\n")
put("meshio", "stl-ascii", b"\x04solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
    b"vertex 0 1 0\nendloop\nendfacet\nendsolid x\n")
put("meshio", "stl-binary", b"\x04" + b"binary".ljust(80, b" ") + struct.pack("<I", 2) +
    struct.pack("<12f", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0) + b"\0\0" +
    struct.pack("<12f", 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 0) + b"\0\0")
put("meshio", "medit-tet", b"\x05MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n"
    b"0 0 1 0\nTetrahedra\n1\n1 2 3 4 0\nTriangles\n1\n1 2 3 0\nEnd\n")
put("meshio", "gmsh-2.2", b"\x06$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n"
    b"4 0 0 1\n$EndNodes\n$Elements\n2\n1 4 2 0 0 1 2 3 4\n2 2 2 0 0 1 2 3\n$EndElements\n")
put("meshio", "gmsh-4.1", b"\x06$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n"
    b"0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n")
put("meshio", "vtk-ascii-tet", b"\x07# vtk DataFile Version 3.0\nhand-made\nASCII\nDATASET UNSTRUCTURED_GRID\n"
    b"POINTS 4 double\n" + tet4.encode() + b"CELLS 2 9\n4 0 1 2 3\n3 0 1 2\nCELL_TYPES 2\n10\n5\n")
EOF

du -sh "$CORPUS"
for d in "$CORPUS"/*; do echo "$(basename "$d"): $(ls "$d" | wc -l) files"; done
