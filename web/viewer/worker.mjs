// Decoding runs here, off the main thread, so that a slow or hostile stream
// (a huge reconstruction, a long TetGen-free Delaunay in WASM) never freezes
// the page: the main thread only draws what this worker posts.
//
// The decoder module is written by another part of the project; everything
// that depends on its exact API lives in openDecoder() below, so that only
// this adapter changes if the API does.

// Where the module lives (web/src/index.mjs, the package's entry point; it
// loads web/dist/hmc.mjs and hmc.wasm itself); ?module=URL in the page's
// address overrides it (for another build of the module).
const MODULE_CANDIDATES = ['../src/index.mjs'];

let modPromise = null;
async function loadModule(override) {
  if (override) MODULE_CANDIDATES.unshift(override);
  if (!modPromise) {
    modPromise = (async () => {
      const errors = [];
      for (const p of MODULE_CANDIDATES) {
        try { return await import(new URL(p, import.meta.url).href); }
        catch (e) { errors.push(`${p}: ${e && e.message}`); }
      }
      throw Object.assign(new Error('HMC decoder module not found (' + errors.join('; ') + ')'),
                          { name: 'module_missing' });
    })();
  }
  return modPromise;
}

// Adapter: returns { feed(Uint8Array), finish() -> Promise } and calls
// onLevel(level) for each completed level, whatever the module's shape
// (callback option, event method, or async iterator of levels).
async function openDecoder(options, onLevel, moduleUrl) {
  const mod = await loadModule(moduleUrl);
  const create = mod.createDecoder || (mod.default && mod.default.createDecoder);
  if (!create) throw Object.assign(new Error('decoder module exports no createDecoder'), { name: 'module_missing' });
  const dec = await create({ ...options, onLevel });
  let iterDone = null;
  if (typeof dec.on === 'function') dec.on('level', onLevel);
  else if (!('onLevel' in options) && dec[Symbol.asyncIterator]) {
    iterDone = (async () => { for await (const lv of dec) onLevel(lv); })();
  } else if (typeof dec.levels === 'function') {
    iterDone = (async () => { for await (const lv of dec.levels()) onLevel(lv); })();
  }
  return {
    feed: (u8) => dec.feed(u8),
    async finish() {
      const r = await dec.finish();
      if (iterDone) await iterDone;
      // web/src/index.mjs resolves { incomplete: true, message } when the
      // stream stopped after a complete level (as `hmc dec` warns): for the
      // viewer that is the 'truncated' case, shown as an error message.
      if (r && (r.incomplete || r.truncated))
        throw Object.assign(new Error(r.message || 'the stream ends before its last level'), { name: 'truncated', code: 'truncated' });
      return r;
    },
    close() {
      for (const m of ['destroy', 'close', 'free']) { try { if (typeof dec[m] === 'function') { dec[m](); return; } } catch (_) { return; } }
    },
  };
}

// Normalise a level from the module into what the viewer draws; copies are
// transferred so that a level costs no second copy on the main thread.
function normaliseLevel(lv, bytesSoFar) {
  const out = {
    // web/src/index.mjs numbers levels 0 = coarsest in .index and gives the
    // level of detail (0 = finest, as `hmc` and the canonical dump) in .lod;
    // the viewer shows the level of detail.
    index: lv.lod ?? lv.index ?? lv.level ?? 0,
    pointCount: lv.pointCount ?? (lv.positions ? lv.positions.length / 3 : 0),
    kind: lv.kind,
    bytes: lv.bytes ?? lv.byteLength ?? bytesSoFar,
    positions: lv.positions ? new Float32Array(lv.positions) : new Float32Array(0),
    triangles: lv.triangles ? new Uint32Array(lv.triangles) : null,
    tetrahedra: lv.tetrahedra ? new Uint32Array(lv.tetrahedra) : null,
  };
  return out;
}

function errorInfo(e) {
  // The module reports spec error names in .code or .name; keep both so the
  // page can say e.g. "truncated: ..." rather than a bare "Error".
  const code = (e && (e.code || (e.name && e.name !== 'Error' ? e.name : null))) || 'error';
  return { code: String(code), message: String((e && e.message) || e) };
}

// A tiled model (spec/tiles.md): its levels coarsest first, each the merged
// level of the tiles the region needs (all without one), fetched by range
// requests; a finer level fetches only the bytes after the coarser one's.
async function runTiled({ tiles, region, limits, moduleUrl }, post, t0) {
  const mod = await loadModule(moduleUrl);
  const { index, fetchPrefix, fetched } = await mod.openTiled(new URL(tiles, self.location.href).href);
  const which = region ? mod.tilesInRegion(index, region) : index.tiles.map((_, i) => i);
  const total = which.reduce((s, i) => s + index.tiles[i].bytes, 0);
  post({ type: 'progress', received: 0, total });
  let levelCount = 0;
  for (let lod = index.levels - 1; lod >= 0; --lod) {
    const r = await mod.decodeTiled(index, fetchPrefix, { ...limits, level: lod, region });
    const l = normaliseLevel({ ...r.levels[0], kind: index.kind, bytes: fetched() }, fetched());
    l.seconds = (performance.now() - t0) / 1000;
    l.tiles = r.tiles.length;
    levelCount++;
    const tr = [l.positions.buffer];
    if (l.triangles) tr.push(l.triangles.buffer);
    if (l.tetrahedra) tr.push(l.tetrahedra.buffer);
    post({ type: 'level', level: l }, tr);
    post({ type: 'progress', received: fetched(), total });
  }
  return { received: fetched(), levelCount };
}

self.onmessage = async (ev) => {
  const { src, file, limits, moduleUrl } = ev.data;
  const t0 = performance.now();
  if (ev.data.tiles) {
    const post = (m, tr) => self.postMessage(m, tr || []);
    try {
      const { received, levelCount } = await runTiled(ev.data, post, t0);
      post({ type: 'done', seconds: (performance.now() - t0) / 1000, received, levelCount });
    } catch (e) {
      post({ type: 'error', error: errorInfo(e), seconds: (performance.now() - t0) / 1000, received: 0, levelCount: 0 });
    }
    return;
  }
  let received = 0, total = 0, levelCount = 0;
  const post = (m, tr) => self.postMessage(m, tr || []);
  let dec = null;
  try {
    dec = await openDecoder({ ...limits, reconstruct: true }, (lv) => {
      levelCount++;
      const l = normaliseLevel(lv, received);
      l.seconds = (performance.now() - t0) / 1000;
      const tr = [l.positions.buffer];
      if (l.triangles) tr.push(l.triangles.buffer);
      if (l.tetrahedra) tr.push(l.tetrahedra.buffer);
      post({ type: 'level', level: l }, tr);
    }, moduleUrl);
    let stream;
    if (file) { total = file.size; stream = file.stream(); }
    else {
      const resp = await fetch(src);
      if (!resp.ok) throw Object.assign(new Error(`HTTP ${resp.status} fetching ${src}`), { name: 'fetch_failed' });
      total = Number(resp.headers.get('content-length')) || 0;
      stream = resp.body;
    }
    post({ type: 'progress', received, total });
    const reader = stream.getReader();
    for (;;) {
      const { value, done } = await reader.read();
      if (done) break;
      received += value.byteLength;
      // feed() may return a promise (it may decode a level right there).
      await dec.feed(value);
      post({ type: 'progress', received, total });
    }
    await dec.finish();
    post({ type: 'done', seconds: (performance.now() - t0) / 1000, received, levelCount });
  } catch (e) {
    post({ type: 'error', error: errorInfo(e), seconds: (performance.now() - t0) / 1000, received, levelCount });
  } finally {
    if (dec) dec.close();
  }
};
