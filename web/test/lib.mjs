// Shared helpers of the browser tests and the screenshot script: generated
// inputs, the native reference, a static server over web/, and Chromium.
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import zlib from 'node:zlib';
import { fileURLToPath } from 'node:url';

export const TEST_DIR = path.dirname(fileURLToPath(import.meta.url));
export const WEB_DIR = path.resolve(TEST_DIR, '..');
export const REPO_DIR = path.resolve(WEB_DIR, '..');
// Outputs live under web/ so that the viewer can fetch them from the same server.
export const OUT_DIR = path.join(TEST_DIR, 'out');

export function hmcBin(argv) {
  const i = argv.indexOf('--hmc');
  const p = i >= 0 ? argv[i + 1] : process.env.HMC_BIN || path.join(REPO_DIR, 'build/bin/hmc');
  if (!fs.existsSync(p)) throw new Error(`native hmc not found at ${p} (set HMC_BIN or pass --hmc PATH)`);
  return path.resolve(p);
}

export function run(cmd, args) {
  const r = spawnSync(cmd, args, { encoding: 'utf8', maxBuffer: 64 << 20 });
  return { code: r.status, stdout: r.stdout || '', stderr: r.stderr || '' };
}

// A deterministic generator, so every run encodes the same inputs.
function rng(seed) {
  let s = seed >>> 0;
  return () => { s = (s + 0x6d2b79f5) >>> 0; let t = s; t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61); return ((t ^ (t >>> 14)) >>> 0) / 4294967296; };
}

// A torus as a triangulated (u, v) grid: nu*nv vertices, 2*nu*nv triangles.
export function writeTorusObj(file, nu = 72, nv = 36, R = 1, r = 0.4) {
  const lines = [];
  for (let i = 0; i < nu; i++) for (let j = 0; j < nv; j++) {
    const u = (2 * Math.PI * i) / nu, v = (2 * Math.PI * j) / nv;
    lines.push(`v ${((R + r * Math.cos(v)) * Math.cos(u)).toFixed(6)} ${((R + r * Math.cos(v)) * Math.sin(u)).toFixed(6)} ${(r * Math.sin(v)).toFixed(6)}`);
  }
  const id = (i, j) => ((i % nu) * nv + (j % nv)) + 1;
  for (let i = 0; i < nu; i++) for (let j = 0; j < nv; j++) {
    lines.push(`f ${id(i, j)} ${id(i + 1, j)} ${id(i + 1, j + 1)}`, `f ${id(i, j)} ${id(i + 1, j + 1)} ${id(i, j + 1)}`);
  }
  fs.writeFileSync(file, lines.join('\n') + '\n');
}

// A ball of a cubic lattice, each cube split into 6 tetrahedra around its
// main diagonal (Kuhn), vertices jittered a little so that Delaunay ties are
// not the whole story; written as MEDIT .mesh.
export function writeBallMesh(file, n = 12) {
  const rand = rng(7), h = 2 / n, idx = new Map(), verts = [], tets = [];
  const inside = (i, j, k) => { const x = i * h - 1, y = j * h - 1, z = k * h - 1; return x * x + y * y + z * z <= 1.0001; };
  const vid = (i, j, k) => {
    const key = `${i},${j},${k}`;
    if (!idx.has(key)) {
      idx.set(key, verts.length + 1);
      const jit = () => (rand() - 0.5) * 0.15 * h;
      verts.push([i * h - 1 + jit(), j * h - 1 + jit(), k * h - 1 + jit()]);
    }
    return idx.get(key);
  };
  const perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
  for (let i = 0; i < n; i++) for (let j = 0; j < n; j++) for (let k = 0; k < n; k++) {
    let all = true;
    for (let c = 0; c < 8; c++) if (!inside(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2))) all = false;
    if (!all) continue;
    for (const p of perms) {   // path from (0,0,0) to (1,1,1) along the axes in order p
      const q = [0, 0, 0], t = [vid(i, j, k)];
      for (const a of p) { q[a] = 1; t.push(vid(i + q[0], j + q[1], k + q[2])); }
      tets.push(t);
    }
  }
  const out = ['MeshVersionFormatted 1', 'Dimension 3', 'Vertices', String(verts.length)];
  for (const v of verts) out.push(`${v[0].toFixed(6)} ${v[1].toFixed(6)} ${v[2].toFixed(6)} 0`);
  out.push('Tetrahedra', String(tets.length));
  for (const t of tets) out.push(`${t.join(' ')} 0`);
  out.push('End');
  fs.writeFileSync(file, out.join('\n') + '\n');
}

// A point set: a noisy spherical shell with a band of denser points.
export function writePointsXyz(file, count = 4000) {
  const rand = rng(11), lines = [];
  for (let i = 0; i < count; i++) {
    const z = 2 * rand() - 1, a = 2 * Math.PI * rand(), s = Math.sqrt(1 - z * z);
    const r = 1 + 0.05 * Math.sin(6 * a) * s + 0.01 * (rand() - 0.5);
    lines.push(`${(r * s * Math.cos(a)).toFixed(6)} ${(r * s * Math.sin(a)).toFixed(6)} ${(r * z).toFixed(6)}`);
  }
  fs.writeFileSync(file, lines.join('\n') + '\n');
}

// Encode, then read the native decoder's per-level counts from its canonical
// dump (level-K.points / level-K.simplices, one line each) and the byte
// offsets from `hmc info --json`.
export function encodeAndReference(hmc, input, out, extra = []) {
  const e = run(hmc, ['enc', input, '-o', out, '--levels', '4', ...extra]);
  if (e.code !== 0) throw new Error(`hmc enc ${input} failed (${e.code}): ${e.stderr}`);
  const dump = out + '.canonical';
  fs.rmSync(dump, { recursive: true, force: true });
  const d = run(hmc, ['dec', out, '--canonical', dump]);
  if (d.code !== 0) throw new Error(`hmc dec --canonical failed (${d.code}): ${d.stderr}`);
  const header = JSON.parse(fs.readFileSync(path.join(dump, 'header.json'), 'utf8'));
  const info = JSON.parse(run(hmc, ['info', out, '--json']).stdout);
  const lines = (f) => { if (!fs.existsSync(f)) return 0; const s = fs.readFileSync(f, 'utf8'); return s ? s.split('\n').filter(Boolean).length : 0; };
  const levels = [];
  for (let k = header.levels - 1; k >= 0; k--) {
    const simplices = lines(path.join(dump, `level-${k}.simplices`));
    levels.push({ index: k, points: lines(path.join(dump, `level-${k}.points`)),
      triangles: header.kind === 'surface' ? simplices : 0, tetrahedra: header.kind === 'volume' ? simplices : 0,
      stream_bytes: info.levels.find((l) => l.level === k).stream_bytes });
  }
  return { kind: header.kind, levels, info, bytes: fs.statSync(out).size };
}

// A copy of a stream whose HEAD declares `huge` points at the finest level
// (CRC recomputed, so only the limits can refuse it).
export function withHugeDeclaredCount(buf, huge) {
  const chunk = (type, payload) => {
    const head = Buffer.alloc(8); head.write(type, 0, 'latin1'); head.writeUInt32LE(payload.length, 4);
    const crc = Buffer.alloc(4); crc.writeUInt32LE(zlib.crc32(Buffer.concat([Buffer.from(type, 'latin1'), payload])) >>> 0);
    return Buffer.concat([head, payload, crc]);
  };
  const len = buf.readUInt32LE(14), p = buf.subarray(18, 18 + len);
  if (buf.toString('latin1', 10, 14) !== 'HEAD') throw new Error('first chunk is not HEAD');
  let o = 2; const readV = () => { let v = 0, s = 0, b; do { b = p[o++]; v += (b & 127) * 2 ** s; s += 7; } while (b & 128); return v; };
  const L = readV(), counts = []; for (let i = 0; i < L; i++) counts.push(readV());
  counts[L - 1] = huge;
  const writeV = (v) => { const out = []; do { let b = v % 128; v = Math.floor(v / 128); if (v) b |= 128; out.push(b); } while (v); return out; };
  const np = Buffer.from([p[0], p[1], ...writeV(L), ...counts.flatMap(writeV)]);
  return Buffer.concat([buf.subarray(0, 10), chunk('HEAD', np), buf.subarray(18 + len + 4)]);
}

const MIME = { '.html': 'text/html', '.mjs': 'text/javascript', '.js': 'text/javascript', '.css': 'text/css',
  '.wasm': 'application/wasm', '.json': 'application/json', '.png': 'image/png' };

// A static server over web/ (Node's own, so the port is ours and the MIME
// types of .mjs and .wasm are right; python3 -m http.server works as well).
// HMC_WEB_ROOT serves another folder laid out like web/ (for trying the
// viewer against another build of the module).
export function serve(root = process.env.HMC_WEB_ROOT || WEB_DIR) {
  return new Promise((resolve) => {
    const server = http.createServer((req, res) => {
      const u = decodeURIComponent(new URL(req.url, 'http://x').pathname);
      const f = path.join(root, path.normalize(u));
      if (!f.startsWith(root) || !fs.existsSync(f) || fs.statSync(f).isDirectory()) { res.writeHead(404); res.end('not found'); return; }
      const body = fs.readFileSync(f);
      res.writeHead(200, { 'content-type': MIME[path.extname(f)] || 'application/octet-stream', 'content-length': body.length });
      res.end(body);
    });
    server.listen(0, '127.0.0.1', () => resolve({ server, base: `http://127.0.0.1:${server.address().port}` }));
  });
}

export async function launchChromium() {
  const { chromium } = await import('playwright-core');
  return chromium.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    // no GPU here: WebGL through SwiftShader
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
}

// Open the viewer on `src` and wait until the decoder is done (or failed),
// checking meanwhile that the page keeps answering (no frozen tab).
export async function openViewer(browser, base, src, query = '', timeoutMs = 180000) {
  const page = await browser.newPage({ viewport: { width: 960, height: 600 } });
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') pageErrors.push('console: ' + m.text()); });
  // src null: the query says what to open (e.g. '&tiles=...').
  await page.goto(`${base}/viewer/index.html?${src === null ? '' : `src=${encodeURIComponent(src)}`}${query}`);
  const t0 = Date.now();
  let worstPing = 0;
  for (;;) {
    const p0 = Date.now();
    const st = await page.evaluate(() => window.hmcViewerState);
    worstPing = Math.max(worstPing, Date.now() - p0);
    if (st && st.done) return { page, state: st, pageErrors, worstPing, wallSeconds: (Date.now() - t0) / 1000 };
    if (Date.now() - t0 > timeoutMs) return { page, state: st, pageErrors, worstPing, timedOut: true, wallSeconds: (Date.now() - t0) / 1000 };
    await new Promise((r) => setTimeout(r, 100));
  }
}
