// SPDX-License-Identifier: AGPL-3.0-or-later
// Tiled models (spec/tiles.md) in the browser and in Node: the index
// (tiles.json), the tiles a region needs, each fetched as the prefix of its
// stream that decodes the level asked for (one HTTP range request per
// tile), decoded by the WebAssembly decoder and merged by the border rule
// (spec/tiles.md section 5), exactly as `hmc dec TILED` merges them.
import { createDecoder, HmcError } from './index.mjs';

const KINDS = ['points', 'surface', 'volume'];

function bad(message) {
  return new HmcError('bad_header', `tiles.json: ${message}`, 6);
}

const isInt = (v) => Number.isInteger(v);

/** Reads and checks a tiled model's index (the text or the parsed object of
 *  tiles.json): spec/tiles.md section 4. Throws an HmcError (`bad_header`)
 *  on an index a reader must reject. */
export function readTileIndex(json) {
  let ix;
  try {
    ix = typeof json === 'string' ? JSON.parse(json) : json;
  } catch (e) {
    throw bad(`not JSON: ${e.message}`);
  }
  if (!ix || typeof ix !== 'object' || Array.isArray(ix)) throw bad('not an object');
  if (ix.format !== 'hmc-tiles') throw bad('format is not "hmc-tiles"');
  if (typeof ix.version !== 'string' || ix.version.split('.')[0] !== '0') throw bad(`version ${ix.version} is not 0.x`);
  if (!KINDS.includes(ix.kind)) throw bad(`unknown kind ${ix.kind}`);
  if (!isInt(ix.q) || ix.q < 1 || ix.q > 21) throw bad('q must be an integer from 1 to 21');
  if (!Array.isArray(ix.origin) || ix.origin.length !== 3 || !ix.origin.every(Number.isFinite)) throw bad('origin must be 3 numbers');
  if (!Number.isFinite(ix.step) || !(ix.step > 0)) throw bad('step must be a positive number');
  if (!isInt(ix.margin) || ix.margin < 0) throw bad('margin must be an integer >= 0');
  if (!isInt(ix.levels) || ix.levels < 1) throw bad('levels must be an integer >= 1');
  if (!Array.isArray(ix.tiles) || ix.tiles.length === 0) throw bad('tiles must be a non-empty array');
  const cells = 2 ** ix.q;
  let volume = 0n, points = 0;
  ix.tiles.forEach((t, i) => {
    const where = `tile ${i}`;
    if (typeof t.file !== 'string' || !t.file || t.file.includes('/') || t.file === '.' || t.file === '..') {
      throw bad(`${where}: file must be a plain file name`);
    }
    const six = (b) => Array.isArray(b) && b.length === 6 && b.every((v) => isInt(v) && v >= 0 && v <= cells);
    if (!six(t.box) || !(t.box[0] < t.box[3] && t.box[1] < t.box[4] && t.box[2] < t.box[5])) throw bad(`${where}: bad box`);
    if (!six(t.bounds)) throw bad(`${where}: bad bounds`);
    for (let a = 0; a < 3; ++a) {
      if (!(t.box[a] <= t.bounds[a] && t.bounds[a] <= t.bounds[3 + a] && t.bounds[3 + a] < t.box[3 + a])) {
        throw bad(`${where}: bounds outside its box`);
      }
    }
    if (!isInt(t.points) || t.points < 1) throw bad(`${where}: points must be >= 1`);
    if (!isInt(t.levels) || t.levels < ix.levels) throw bad(`${where}: fewer levels than the model`);
    if (!Array.isArray(t.level_bytes) || t.level_bytes.length !== t.levels || !t.level_bytes.every(isInt)) {
      throw bad(`${where}: level_bytes must hold one integer per level`);
    }
    if (!isInt(t.bytes) || t.level_bytes.some((b) => b < 1 || b > t.bytes)) throw bad(`${where}: bad bytes`);
    if (typeof t.crc32 !== 'string' || !/^[0-9a-f]{8}$/.test(t.crc32)) throw bad(`${where}: crc32 must be 8 hex digits`);
    volume += BigInt(t.box[3] - t.box[0]) * BigInt(t.box[4] - t.box[1]) * BigInt(t.box[5] - t.box[2]);
    points += t.points;
  });
  // The boxes partition the lattice: pairwise disjoint, volumes summing to it.
  for (let i = 0; i < ix.tiles.length; ++i) {
    for (let j = i + 1; j < ix.tiles.length; ++j) {
      const u = ix.tiles[i].box, v = ix.tiles[j].box;
      if (u[0] < v[3] && v[0] < u[3] && u[1] < v[4] && v[1] < u[4] && u[2] < v[5] && v[2] < u[5]) {
        throw bad(`the boxes of tiles ${i} and ${j} overlap`);
      }
    }
  }
  if (volume !== BigInt(cells) ** 3n) throw bad("the tiles' boxes do not cover the lattice");
  if (points !== ix.points) throw bad("points is not the sum of the tiles' points");
  return ix;
}

/** The indices of the tiles whose bounds, in model coordinates, meet the
 *  closed box `[xmin, ymin, zmin, xmax, ymax, zmax]` (spec/tiles.md 7). */
export function tilesInRegion(index, region) {
  const out = [];
  index.tiles.forEach((t, i) => {
    let meet = true;
    for (let a = 0; a < 3; ++a) {
      const lo = index.origin[a] + t.bounds[a] * index.step, hi = index.origin[a] + t.bounds[3 + a] * index.step;
      meet = meet && lo <= region[3 + a] && region[a] <= hi;
    }
    if (meet) out.push(i);
  });
  return out;
}

let crcTable = null;
/** CRC-32 (hmc.md section 2: the reflected 0xEDB88320 polynomial). */
export function crc32(bytes) {
  if (!crcTable) {
    crcTable = new Uint32Array(256);
    for (let n = 0; n < 256; ++n) {
      let c = n;
      for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
      crcTable[n] = c >>> 0;
    }
  }
  let c = 0xffffffff;
  for (let i = 0; i < bytes.length; ++i) c = crcTable[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

const owns = (t, g, i) => g[i] >= t.box[0] && g[i] < t.box[3] && g[i + 1] >= t.box[1] && g[i + 1] < t.box[4] &&
  g[i + 2] >= t.box[2] && g[i + 2] < t.box[5];

// Lattice points in canonical order (x, then y, then z), as flat triples.
function compare(a, i, b, j) {
  return a[i] - b[j] || a[i + 1] - b[j + 1] || a[i + 2] - b[j + 2];
}

/** Decodes a tiled model, or the tiles a region needs, at one level and
 *  merges them by the border rule.
 *
 *  `fetchPrefix(file, bytes, whole)` resolves to the first `bytes` bytes of
 *  the tile stream `file` (a Uint8Array or ArrayBuffer; `whole` when that
 *  is the whole file, which is then checked against the index's size and
 *  CRC-32). Options: `level` (0 = finest, the default), `region` (model
 *  coordinates, as tilesInRegion), `allLevels` (also the coarser levels,
 *  rebuilt, as `hmc dec TILED --canonical` dumps them), `reconstruct`
 *  (false: points only), and the Decoder's limits.
 *
 *  Resolves to `{ header, levels, tiles, bytesRead }`: levels coarsest first,
 *  each `{ lod, pointCount, gridPoints, positions, triangles | tetrahedra }`
 *  as a single stream's; `header` as a Decoder's (declaredPoints: the merged
 *  levels' points). Rejects with an HmcError. */
export async function decodeTiled(index, fetchPrefix, options = {}) {
  const ix = index.tiles && index.format ? index : readTileIndex(index);
  const level = options.level === undefined ? 0 : options.level;
  if (!isInt(level) || level < 0 || level >= ix.levels) {
    throw new HmcError('invalid_argument', `level ${level} is not in the model (levels 0 to ${ix.levels - 1})`, 20);
  }
  const reconstruct = options.reconstruct !== false;
  const which = options.region ? tilesInRegion(ix, options.region) : ix.tiles.map((_, i) => i);
  const coarsest = options.allLevels ? ix.levels - 1 : level;
  const lods = [];
  for (let lod = coarsest; lod >= level; --lod) lods.push(lod);
  const width = ix.kind === 'surface' ? 3 : ix.kind === 'volume' ? 4 : 0;
  // Per merged level: owned points and kept simplices' corners (flat triples).
  const owned = lods.map(() => []), corners = lods.map(() => []);
  let bytesRead = 0;
  for (const w of which) {
    const t = ix.tiles[w];
    const whole = level === 0;
    const want = whole ? t.bytes : t.level_bytes[level];
    let bytes = await fetchPrefix(t.file, want, whole);
    bytes = bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes);
    if (bytes.length < want) throw new HmcError('truncated', `${t.file}: shorter than the index says`, 4);
    if (whole && bytes.length > want) throw new HmcError('bad_header', `${t.file}: longer than the index says`, 6);
    if (bytes.length > want) bytes = bytes.subarray(0, want);
    if (whole && crc32(bytes).toString(16).padStart(8, '0') !== t.crc32) {
      throw new HmcError('crc_mismatch', `${t.file}: CRC-32 differs from the index's`, 3);
    }
    bytesRead += want;
    const dec = await createDecoder({ ...options, finestLevel: level, reconstruct,
      rebuildCoarserLevels: !!options.allLevels && reconstruct, onLevel: null, onHeader: null });
    let r;
    try {
      r = dec.decodeAll(bytes);
    } catch (e) {
      if (e instanceof HmcError) e.message = `${t.file}: ${e.message}`;
      throw e;
    } finally {
      dec.destroy();
    }
    const h = r.header;
    if (h.kind !== ix.kind) throw bad(`${t.file}: kind differs from the index's`);
    if (h.bits !== ix.q || h.step !== ix.step || h.origin.some((v, a) => v !== ix.origin[a])) {
      throw bad(`${t.file}: lattice (SQNT) differs from the index's`);
    }
    lods.forEach((lod, k) => {
      const l = r.levels.find((x) => x.lod === lod);
      if (!l) throw new HmcError('truncated', `${t.file}: level ${lod} missing`, 4);
      const g = l.gridPoints;
      let n = 0;
      for (let i = 0; i < g.length; i += 3) if (owns(t, g, i)) owned[k].push(g[i], g[i + 1], g[i + 2]), ++n;
      if (lod === 0 && n !== t.points) throw bad(`${t.file}: owns ${n} points, the index says ${t.points}`);
      // The border rule: keep a simplex whose first corner in canonical
      // order (its smallest index) this tile owns.
      const s = width === 3 ? l.triangles : width === 4 ? l.tetrahedra : null;
      if (!s) return;
      for (let i = 0; i < s.length; i += width) {
        let first = s[i];
        for (let c = 1; c < width; ++c) first = Math.min(first, s[i + c]);
        if (!owns(t, g, 3 * first)) continue;
        for (let c = 0; c < width; ++c) corners[k].push(g[3 * s[i + c]], g[3 * s[i + c] + 1], g[3 * s[i + c] + 2]);
      }
    });
  }
  const levels = lods.map((lod, k) => {
    // The merged points: owned ones and kept simplices' corners, distinct,
    // in canonical order; the simplices renumbered into them.
    const all = owned[k].concat(corners[k]);
    const order = Array.from({ length: all.length / 3 }, (_, i) => 3 * i);
    order.sort((i, j) => compare(all, i, all, j));
    const uniq = [];
    for (const i of order) {
      if (uniq.length && compare(all, i, all, uniq[uniq.length - 1]) === 0) continue;
      uniq.push(i);
    }
    const gridPoints = new Uint32Array(3 * uniq.length);
    uniq.forEach((i, j) => gridPoints.set([all[i], all[i + 1], all[i + 2]], 3 * j));
    const find = (c, i) => {
      let lo = 0, hi = uniq.length - 1;
      while (lo < hi) {
        const mid = (lo + hi) >> 1;
        if (compare(gridPoints, 3 * mid, c, i) < 0) lo = mid + 1;
        else hi = mid;
      }
      return lo;
    };
    const positions = new Float32Array(gridPoints.length);
    for (let i = 0; i < gridPoints.length; ++i) positions[i] = ix.origin[i % 3] + gridPoints[i] * ix.step;
    const out = { index: k, lod, pointCount: uniq.length, gridPoints, positions };
    if (width) {
      const c = corners[k];
      const simplices = new Uint32Array(c.length / 3);
      for (let i = 0; i < simplices.length; ++i) simplices[i] = find(c, 3 * i);
      out[width === 3 ? 'triangles' : 'tetrahedra'] = simplices;
    }
    return out;
  });
  const header = { kind: ix.kind, bits: ix.q, origin: ix.origin.slice(), step: ix.step, declaredLevels: levels.length,
    declaredPoints: levels.map((l) => l.pointCount) };
  return { header, levels, tiles: which, bytesRead };
}

/** A tiled model over HTTP: fetches `url` (its tiles.json, or the
 *  directory holding it) and resolves to `{ index, fetchPrefix, fetched }`
 *  for decodeTiled. fetchPrefix asks for a tile's prefix with a range
 *  request and keeps what it got, so that decoding a finer level next
 *  fetches only the bytes after it (a server that ignores ranges sends the
 *  whole file, which is then kept). `fetched()` is the bytes received so
 *  far. `fetchImpl` defaults to the global fetch. */
export async function openTiled(url, fetchImpl = globalThis.fetch) {
  const base = new URL(url, globalThis.location ? globalThis.location.href : undefined);
  const indexUrl = base.pathname.endsWith('.json') ? base : new URL('tiles.json', base.href.endsWith('/') ? base : base.href + '/');
  const res = await fetchImpl(indexUrl.href);
  if (!res.ok) throw new HmcError('io_error', `${indexUrl.href}: HTTP ${res.status}`, 21);
  const index = readTileIndex(await res.text());
  const kept = new Map();
  let received = 0;
  const fetchPrefix = async (file, bytes) => {
    let have = kept.get(file) || new Uint8Array(0);
    if (have.length < bytes) {
      const r = await fetchImpl(new URL(file, indexUrl).href, { headers: { Range: `bytes=${have.length}-${bytes - 1}` } });
      if (!r.ok) throw new HmcError('io_error', `${file}: HTTP ${r.status}`, 21);
      const got = new Uint8Array(await r.arrayBuffer());
      received += got.length;
      if (r.status === 206) {
        const joined = new Uint8Array(have.length + got.length);
        joined.set(have);
        joined.set(got, have.length);
        have = joined;
      } else {
        have = got;  // the whole file
      }
      kept.set(file, have);
    }
    return have.length > bytes ? have.subarray(0, bytes) : have;
  };
  return { index, fetchPrefix, fetched: () => received };
}
