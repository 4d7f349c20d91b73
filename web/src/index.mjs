// SPDX-License-Identifier: AGPL-3.0-or-later
// hmc-decoder: the HMC decoder (libhmc compiled to WebAssembly) as an ES
// module for browsers, Web Workers and Node 18+. See web/README.md.
//
// The module wraps hmc.h's streaming decoder: bytes go in as they arrive,
// and each level comes out, with its rebuilt triangles or tetrahedra, as
// soon as its last chunk is in. Decoding is exact: the points and simplices
// equal the native decoder's, bit for bit.
import createHmcModule from '../dist/hmc.mjs';

const KINDS = ['points', 'surface', 'volume'];
const HMC_OK = 0;
const HMC_INCOMPLETE = 100;
const HMC_MAX_LEVELS = 64;

let modulePromise = null;

/** Loads (once) and returns the WebAssembly module. `options` are passed to
 *  emscripten's factory the first time (e.g. `{ locateFile }` when hmc.wasm
 *  is not beside hmc.mjs). */
export function loadModule(options = {}) {
  if (!modulePromise) modulePromise = nodeShim(options).then((o) => createHmcModule(o));
  return modulePromise;
}

// Emscripten 3.1.6's ES module output still reads the wasm file in Node with
// CommonJS' `require` and `__dirname`, which an ES module does not have:
// give them to it (as globals, only in Node, only when absent). It would also
// fetch() hmc.wasm, which Node's fetch cannot do for a file: hand it the bytes.
async function nodeShim(options) {
  const isNode = typeof process === 'object' && process.versions && process.versions.node &&
    typeof window === 'undefined' && typeof importScripts === 'undefined';
  if (!isNode) return options;
  const { createRequire } = await import('node:module');
  const { fileURLToPath } = await import('node:url');
  if (typeof globalThis.require === 'undefined') globalThis.require = createRequire(import.meta.url);
  if (typeof globalThis.__dirname === 'undefined') {
    globalThis.__dirname = fileURLToPath(new URL('../dist/', import.meta.url)).replace(/\/$/, '');
  }
  if (options.wasmBinary || options.locateFile) return options;
  const { readFileSync } = await import('node:fs');
  return { ...options, wasmBinary: readFileSync(new URL('../dist/hmc.wasm', import.meta.url)) };
}

/** An error of the stream or of the decoder. `name` and `code` are the
 *  spec's error name (`crc_mismatch`, `truncated`, `bad_chunk`,
 *  `limit_exceeded`, ... as hmc_status_string() gives them); `status` is the
 *  numeric hmc_status; `levels` holds the levels completed before it. */
export class HmcError extends Error {
  constructor(code, message, status, levels = []) {
    // hmc_decoder_message() usually starts with the name already.
    super(message.startsWith(`${code}:`) ? message : `${code}: ${message}`);
    this.name = code;
    this.code = code;
    this.status = status;
    this.levels = levels;
  }
}

// Views of the module's memory are taken afresh after every call: a call
// may grow the memory, which detaches the previous buffer.
const u8 = (M) => M.HEAPU8;
const u32 = (M) => M.HEAPU32;
const f64 = (M) => M.HEAPF64;

/**
 * A streaming decoder.
 *
 *   const dec = await createDecoder({ maxPoints: 5e6 });
 *   dec.onLevel = (level) => draw(level);
 *   for await (const chunk of response.body) dec.feed(chunk);
 *   const { incomplete, message } = dec.finish();
 *   dec.destroy();
 *
 * Options (all optional): maxPoints, maxLevels, maxBytes, maxMemory (the C
 * API's limits; a stream over them fails with `limit_exceeded` before
 * anything is allocated for it), reconstruct (default true: rebuild
 * triangles or tetrahedra), rebuildCoarserLevels (default true; false
 * rebuilds only the finest level, at finish()), finestLevel (stop after that
 * level of detail, 0 = finest), errorOrder ('stream', the default: fail at
 * the first defect met; 'whole': as a whole-buffer decode reports),
 * float64 (also give `positions64`), onLevel, onHeader.
 */
export class Decoder {
  constructor(M, options = {}) {
    this._M = M;
    this._dec = M._hmc_decoder_create(0);
    if (!this._dec) throw new HmcError('out_of_memory', 'cannot create a decoder', 24);
    this._scratch = M._malloc(8 * (12 + HMC_MAX_LEVELS));
    this._options = options;
    this.levels = [];
    this.header = null;
    this.onLevel = options.onLevel || null;
    this.onHeader = options.onHeader || null;
    this._finished = null;
    this._configure(options);
  }

  _configure(o) {
    const M = this._M;
    const d = this._scratch;
    M._hmc_web_default_limits(d);
    const def = f64(M).subarray(d >> 3, (d >> 3) + 4);
    const num = (v, dflt) => (v === undefined || v === null ? dflt : Number(v));
    const check = (s) => {
      if (s !== HMC_OK) this._throw(s);
    };
    check(M._hmc_web_set_limits(this._dec, num(o.maxPoints, def[0]), num(o.maxLevels, def[1]) >>> 0,
      num(o.maxBytes, def[2]), num(o.maxMemory, def[3])));
    check(M._hmc_decoder_set_reconstruct(this._dec, o.reconstruct === false ? 0 : 1));
    check(M._hmc_decoder_set_rebuild_coarser_levels(this._dec, o.rebuildCoarserLevels === false ? 0 : 1));
    if (o.finestLevel !== undefined) check(M._hmc_decoder_set_finest_level(this._dec, o.finestLevel | 0));
    if (o.errorOrder !== undefined) {
      if (o.errorOrder !== 'stream' && o.errorOrder !== 'whole') throw new TypeError("errorOrder: 'stream' or 'whole'");
      check(M._hmc_decoder_set_error_order(this._dec, o.errorOrder === 'whole' ? 1 : 0));
    }
  }

  _message() {
    return this._M.UTF8ToString(this._M._hmc_decoder_message(this._dec));
  }

  _throw(status) {
    const code = this._M.UTF8ToString(this._M._hmc_status_string(status));
    throw new HmcError(code, this._message(), status, this.levels);
  }

  _readHeader() {
    if (this.header) return;
    const M = this._M;
    if (M._hmc_web_stream_info(this._dec, this._scratch) !== HMC_OK) return;
    const v = f64(M).subarray(this._scratch >> 3, (this._scratch >> 3) + 12 + HMC_MAX_LEVELS);
    if (!v[0]) return;
    const levels = v[7];
    this.header = {
      kind: KINDS[v[1]] || String(v[1]),
      bits: v[2],
      origin: [v[3], v[4], v[5]],
      step: v[6],
      declaredLevels: levels,
      // Points per level, coarsest first (level index 0 = the coarsest).
      declaredPoints: Array.from(v.subarray(12, 12 + levels)),
    };
    if (this.onHeader) this.onHeader(this.header);
  }

  // Copies an array the C API hands out (allocated with malloc) and frees it.
  _take(fn, index, Type, width) {
    const M = this._M;
    const p = this._scratch;
    const s = fn(this._dec, index, p, p + 4);
    if (s !== HMC_OK) this._throw(s);
    const ptr = u32(M)[p >> 2];
    const count = u32(M)[(p + 4) >> 2];
    if (!ptr) return { data: new Type(0), count };
    const src = new Type(u8(M).buffer, ptr, count * width);
    const out = new Type(src);  // a copy, outside the module's memory
    M._hmc_free(0, ptr);
    return { data: out, count };
  }

  _collect() {
    const M = this._M;
    this._readHeader();
    const fresh = [];
    const n = M._hmc_decoder_level_count(this._dec);
    while (this.levels.length < n) {
      const index = this.levels.length;
      if (M._hmc_web_level_info(this._dec, index, this._scratch) !== HMC_OK) break;
      const info = f64(M).slice(this._scratch >> 3, (this._scratch >> 3) + 5);
      const grid = this._take(M._hmc_decoder_level_points, index, Uint32Array, 3);
      const pos = this._take(M._hmc_decoder_level_positions, index, Float64Array, 3);
      const level = {
        index,                   // 0 = the coarsest level
        lod: info[0],            // level of detail: 0 = the finest of the stream
        pointCount: info[1],
        positions: Float32Array.from(pos.data),  // x y z per point, input coordinates
        gridPoints: grid.data,   // grid coordinates, canonical order (ascending x, y, z)
        bytes: info[4],          // stream prefix that decodes this level
      };
      if (this._options.float64) level.positions64 = pos.data;
      const kind = this.header ? this.header.kind : null;
      if (kind === 'surface') level.triangles = this._take(M._hmc_decoder_level_triangles, index, Uint32Array, 3).data;
      if (kind === 'volume') level.tetrahedra = this._take(M._hmc_decoder_level_tetrahedra, index, Uint32Array, 4).data;
      this.levels.push(level);
      fresh.push(level);
      if (this.onLevel) this.onLevel(level);
    }
    return fresh;
  }

  _bytes(chunk) {
    if (chunk instanceof Uint8Array) return chunk;
    if (chunk instanceof ArrayBuffer) return new Uint8Array(chunk);
    if (ArrayBuffer.isView(chunk)) return new Uint8Array(chunk.buffer, chunk.byteOffset, chunk.byteLength);
    throw new TypeError('expected a Uint8Array, an ArrayBuffer, a typed array or a Buffer');
  }

  // Runs one C call on bytes copied into the module's memory.
  _withBytes(chunk, call) {
    const M = this._M;
    const bytes = this._bytes(chunk);
    const ptr = bytes.length ? M._malloc(bytes.length) : 0;
    if (bytes.length && !ptr) throw new HmcError('out_of_memory', 'cannot copy the bytes into the decoder', 24);
    try {
      if (bytes.length) u8(M).set(bytes, ptr);
      return call(ptr, bytes.length);
    } finally {
      if (ptr) M._free(ptr);
    }
  }

  /** Gives the decoder the next bytes. Returns the levels they completed
   *  (each also passed to onLevel); throws an HmcError on a defect. */
  feed(chunk) {
    if (!this._dec) throw new HmcError('invalid_argument', 'the decoder was destroyed', 20);
    const s = this._withBytes(chunk, (p, n) => this._M._hmc_decoder_feed(this._dec, p, n));
    const fresh = this._collect();
    if (s !== HMC_OK) this._throw(s);
    return fresh;
  }

  /** The stream has ended. Returns `{ levels, incomplete, message }`:
   *  incomplete when the stream stopped after a complete level (the levels
   *  so far are the result); throws an HmcError otherwise (`truncated`
   *  when no level was complete). */
  finish() {
    if (this._finished) return this._finished;
    if (!this._dec) throw new HmcError('invalid_argument', 'the decoder was destroyed', 20);
    const s = this._M._hmc_decoder_finish(this._dec);
    this._collect();
    if (s !== HMC_OK && s !== HMC_INCOMPLETE) this._throw(s);
    this._finished = { levels: this.levels, header: this.header, incomplete: s === HMC_INCOMPLETE,
      message: s === HMC_INCOMPLETE ? this._message() : '' };
    return this._finished;
  }

  /** Decodes a whole stream held in memory at once (what `hmc dec` does:
   *  errors ranked as spec section 13 ranks them for a whole stream).
   *  Only on a decoder not fed yet. Returns what finish() returns. */
  decodeAll(bytes) {
    const s = this._withBytes(bytes, (p, n) => this._M._hmc_decoder_decode(this._dec, p, n));
    this._collect();
    if (s !== HMC_OK && s !== HMC_INCOMPLETE) this._throw(s);
    this._finished = { levels: this.levels, header: this.header, incomplete: s === HMC_INCOMPLETE,
      message: s === HMC_INCOMPLETE ? this._message() : '' };
    return this._finished;
  }

  /** Frees the decoder's WebAssembly memory (the levels already returned
   *  stay valid: they are copies). */
  destroy() {
    if (!this._dec) return;
    this._M._hmc_decoder_destroy(this._dec);
    this._M._free(this._scratch);
    this._dec = 0;
  }
}

/** Creates a streaming decoder (see Decoder for the options). */
export async function createDecoder(options = {}) {
  const M = await loadModule(options.moduleOptions);
  return new Decoder(M, options);
}

/** Decodes a whole stream (ArrayBuffer, Uint8Array, Buffer). Resolves to the
 *  array of levels, coarsest first, with `header`, `incomplete` and
 *  `message` properties; rejects with an HmcError. */
export async function decode(bytes, options = {}) {
  const dec = await createDecoder(options);
  try {
    const r = dec.decodeAll(bytes);
    const levels = r.levels.slice();
    levels.header = r.header;
    levels.incomplete = r.incomplete;
    levels.message = r.message;
    return levels;
  } finally {
    dec.destroy();
  }
}

async function* chunksOf(source) {
  if (source instanceof ArrayBuffer || ArrayBuffer.isView(source)) {
    yield source;
  } else if (source && typeof source.getReader === 'function') {  // a WHATWG ReadableStream (fetch)
    const reader = source.getReader();
    try {
      for (;;) {
        const { done, value } = await reader.read();
        if (done) return;
        yield value;
      }
    } finally {
      reader.releaseLock();
    }
  } else if (source && typeof source[Symbol.asyncIterator] === 'function') {  // Node streams
    for await (const c of source) yield c;
  } else if (source && typeof source[Symbol.iterator] === 'function') {
    for (const c of source) yield c;
  } else {
    throw new TypeError('expected a ReadableStream, an async iterable of bytes, an ArrayBuffer or a Uint8Array');
  }
}

/** Decodes a stream as its bytes arrive, yielding each level as soon as it
 *  is complete:
 *
 *    for await (const level of decodeStream((await fetch(url)).body)) draw(level);
 *
 *  Throws (rejects the iteration with) an HmcError on a defect, after the
 *  levels completed before it were yielded. A stream cut after a complete
 *  level ends the iteration normally; `options.onFinish({ incomplete,
 *  message })` says so. */
export async function* decodeStream(source, options = {}) {
  const dec = await createDecoder(options);
  try {
    let yielded = 0;
    for await (const chunk of chunksOf(source)) {
      // A chunk may complete levels and then meet a defect: the levels
      // come first, then the error.
      let error = null;
      try {
        dec.feed(chunk);
      } catch (e) {
        error = e;
      }
      while (yielded < dec.levels.length) yield dec.levels[yielded++];
      if (error) throw error;
    }
    const r = dec.finish();
    while (yielded < r.levels.length) yield r.levels[yielded++];
    if (options.onFinish) options.onFinish(r);
  } finally {
    dec.destroy();
  }
}

// Tiled models (spec/tiles.md): the index, region queries, merging.
export { readTileIndex, tilesInRegion, decodeTiled, openTiled, crc32 } from './tiles.mjs';

/** The status name of a numeric hmc_status (as hmc_status_string()). */
export async function statusName(status) {
  const M = await loadModule();
  return M.UTF8ToString(M._hmc_status_string(status));
}

/** libhmc's version string. */
export async function version() {
  const M = await loadModule();
  return M.UTF8ToString(M._hmc_version_string());
}

/** C's printf("%.17g", v), as the canonical dump's header.json writes numbers. */
export async function formatG17(v) {
  const M = await loadModule();
  const p = M._malloc(32);
  try {
    M._hmc_web_format_g17(v, p);
    return M.UTF8ToString(p);
  } finally {
    M._free(p);
  }
}
