// HMC progressive viewer: streams a .hmc file through a Web Worker
// (worker.mjs, which owns the decoder) and draws each level with three.js as
// soon as the worker posts it. The main thread never decodes, so a hostile
// or slow stream cannot freeze the tab.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const BACKGROUND = 0x1b1d22;

// Decoder limits: a stream declaring more than this is refused by the
// decoder itself (limit_exceeded) instead of exhausting the tab's memory.
// Overridable from the URL, e.g. ?maxPoints=1000 to see the refusal.
const limits = {
  maxPoints: Number(params.get('maxPoints')) || 4_000_000,
  maxLevels: Number(params.get('maxLevels')) || 64,
  maxMemory: Number(params.get('maxMemory')) || 1024 * 1024 * 1024,
};

// State for people and for tests (web/test/browser.mjs reads it).
const state = { done: false, error: null, received: 0, total: 0, seconds: null,
                kind: null, drawn: null, levels: [] };
window.hmcViewerState = state;
function publish() { document.body.dataset.hmcState = JSON.stringify(state); }
publish();

// ---------- three.js scene ----------
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(Math.min(2, window.devicePixelRatio || 1));
renderer.setClearColor(BACKGROUND);
renderer.localClippingEnabled = true;
$('view').appendChild(renderer.domElement);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, 1, 0.001, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
controls.addEventListener('change', render);
scene.add(new THREE.HemisphereLight(0xffffff, 0x303840, 0.6));
const sun = new THREE.DirectionalLight(0xffffff, 2.2);
camera.add(sun); sun.position.set(1, 1.5, 2);   // light follows the camera: the side we see is lit
scene.add(camera);
let root = null;        // the group of the level currently shown
let fitted = false;     // the camera is fitted once, on the first level, and kept

function resize() {
  const el = $('view');
  const w = el.clientWidth || 1, h = el.clientHeight || 1;
  renderer.setSize(w, h, false);
  renderer.domElement.style.width = w + 'px'; renderer.domElement.style.height = h + 'px';
  camera.aspect = w / h; camera.updateProjectionMatrix(); render();
}
window.addEventListener('resize', resize);
function render() { renderer.render(scene, camera); }

// ---------- levels ----------
const levelData = new Map();  // index -> level as posted by the worker
let shownIndex = null, followFinest = true;

function kindOf(l) {
  if (l.tetrahedra && l.tetrahedra.length) return 'volume';
  if (l.triangles && l.triangles.length) return 'surface';
  return 'points';
}

// Faces of a tetrahedron subset that appear once: the boundary of that subset.
// Each is oriented away from the tetrahedron's fourth vertex, so that the
// computed normals point outwards whatever the decoder's vertex order.
// keep(t) selects tetrahedra; returns { outer, cut } index arrays: faces on
// the whole mesh's boundary, and faces exposed by the selection (the cut).
function boundaryFaces(tets, pos, keep, wholeBoundary) {
  const faces = new Map();
  const nt = tets.length / 4;
  const F = [[0, 1, 2, 3], [0, 3, 1, 2], [0, 2, 3, 1], [1, 3, 2, 0]];
  for (let t = 0; t < nt; t++) {
    if (keep && !keep(t)) continue;
    for (const f of F) {
      const a = tets[4 * t + f[0]], b = tets[4 * t + f[1]], c = tets[4 * t + f[2]], d = tets[4 * t + f[3]];
      const s = [a, b, c].sort((x, y) => x - y);
      const key = s[0] + ',' + s[1] + ',' + s[2];
      const e = faces.get(key);
      if (e) e.n++; else faces.set(key, { n: 1, a, b, c, d, key });
    }
  }
  const outer = [], cut = [];
  for (const e of faces.values()) {
    if (e.n !== 1) continue;
    let { a, b, c } = e;
    // orientation: (b-a)x(c-a) must point away from d
    const ax = pos[3 * a], ay = pos[3 * a + 1], az = pos[3 * a + 2];
    const ux = pos[3 * b] - ax, uy = pos[3 * b + 1] - ay, uz = pos[3 * b + 2] - az;
    const vx = pos[3 * c] - ax, vy = pos[3 * c + 1] - ay, vz = pos[3 * c + 2] - az;
    const wx = pos[3 * e.d] - ax, wy = pos[3 * e.d + 1] - ay, wz = pos[3 * e.d + 2] - az;
    const det = wx * (uy * vz - uz * vy) + wy * (uz * vx - ux * vz) + wz * (ux * vy - uy * vx);
    if (det > 0) { const t = b; b = c; c = t; }
    (!wholeBoundary || wholeBoundary.has(e.key) ? outer : cut).push(a, b, c);
  }
  return { outer, cut, keys: keep ? null : new Set([...faces.values()].filter((e) => e.n === 1).map((e) => e.key)) };
}

// The decoder's triangles carry no orientation, and vertex normals averaged
// over inconsistently oriented triangles cancel into noise. So orient each
// edge-connected patch consistently (neighbours across a manifold edge run it
// in opposite directions), then turn each patch so that its signed volume is
// positive (outwards for a closed surface).
function orientTriangles(tri, pos) {
  const n = tri.length / 3, out = new Uint32Array(tri), edges = new Map();
  const key = (a, b) => (a < b ? a * 4294967296 + b : b * 4294967296 + a);
  for (let t = 0; t < n; t++) for (let k = 0; k < 3; k++) {
    const e = key(tri[3 * t + k], tri[3 * t + (k + 1) % 3]);
    const l = edges.get(e); if (l) l.push(t); else edges.set(e, [t]);
  }
  const seen = new Uint8Array(n), flip = (t) => { const x = out[3 * t + 1]; out[3 * t + 1] = out[3 * t + 2]; out[3 * t + 2] = x; };
  const runs = (t, a, b) => { for (let k = 0; k < 3; k++) if (out[3 * t + k] === a && out[3 * t + (k + 1) % 3] === b) return true; return false; };
  for (let s = 0; s < n; s++) {
    if (seen[s]) continue;
    const patch = [s], stack = [s]; seen[s] = 1;
    while (stack.length) {
      const t = stack.pop();
      for (let k = 0; k < 3; k++) {
        const a = out[3 * t + k], b = out[3 * t + (k + 1) % 3], l = edges.get(key(a, b));
        if (l.length !== 2) continue;            // border or non-manifold: do not propagate
        const u = l[0] === t ? l[1] : l[0];
        if (seen[u]) continue;
        if (runs(u, a, b)) flip(u);              // same direction as t: flip u
        seen[u] = 1; patch.push(u); stack.push(u);
      }
    }
    let vol = 0;
    for (const t of patch) {
      const a = 3 * out[3 * t], b = 3 * out[3 * t + 1], c = 3 * out[3 * t + 2];
      vol += pos[a] * (pos[b + 1] * pos[c + 2] - pos[b + 2] * pos[c + 1]) - pos[a + 1] * (pos[b] * pos[c + 2] - pos[b + 2] * pos[c])
           + pos[a + 2] * (pos[b] * pos[c + 1] - pos[b + 1] * pos[c]);
    }
    if (vol < 0) for (const t of patch) flip(t);
  }
  return out;
}

function meshFrom(pos, index, color, extra = {}) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.setIndex(new THREE.BufferAttribute(index instanceof Uint32Array ? index : new Uint32Array(index), 1));
  g.computeVertexNormals();
  return new THREE.Mesh(g, new THREE.MeshStandardMaterial({ color, roughness: 0.6, metalness: 0.05, ...extra }));
}

// Volume drawing state: the whole boundary is computed once per level; the
// clip slider recomputes the boundary of the tetrahedra on the near side.
let volume = null;

function buildLevel(l) {
  const group = new THREE.Group();
  const kind = kindOf(l);
  volume = null;
  $('clipRow').hidden = kind !== 'volume';
  if (kind === 'points') {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(l.positions, 3));
    g.computeBoundingSphere();
    const r = g.boundingSphere ? g.boundingSphere.radius : 1;
    group.add(new THREE.Points(g, new THREE.PointsMaterial({ color: 0x9fd3ff, size: Math.max(r / 150, 1e-6) })));
  } else if (kind === 'surface') {
    // Both sides: open surfaces show their back too.
    group.add(meshFrom(l.positions, orientTriangles(l.triangles, l.positions), 0xd8c8a8, { side: THREE.DoubleSide }));
  } else {
    const whole = boundaryFaces(l.tetrahedra, l.positions, null, null);
    const cen = new Float32Array(l.tetrahedra.length / 4);
    let lo = Infinity, hi = -Infinity;
    for (let t = 0; t < cen.length; t++) {   // x of each centroid, for the clip
      let x = 0; for (let k = 0; k < 4; k++) x += l.positions[3 * l.tetrahedra[4 * t + k]];
      cen[t] = x / 4; lo = Math.min(lo, cen[t]); hi = Math.max(hi, cen[t]);
    }
    volume = { l, whole, cen, lo, hi, group };
    drawVolume();
  }
  return group;
}

function drawVolume() {
  if (!volume) return;
  const { l, whole, cen, lo, hi, group } = volume;
  while (group.children.length) { const c = group.children.pop(); c.geometry.dispose(); c.material.dispose(); }
  const f = Number($('clip').value) / 1000;
  let outer, cut;
  if (f >= 1) { outer = whole.outer; cut = []; }
  else {
    // Keep tetrahedra whose centroid lies left of the plane: the faces they
    // expose are the tetrahedra inside, drawn in another colour with edges.
    const c = lo + f * (hi - lo);
    ({ outer, cut } = boundaryFaces(l.tetrahedra, l.positions, (t) => cen[t] <= c, whole.keys));
  }
  if (outer.length) group.add(meshFrom(l.positions, outer, 0xc9d6e8));
  if (cut.length) {
    group.add(meshFrom(l.positions, cut, 0xe8925a, { polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 }));
    const eg = new THREE.BufferGeometry();
    const idx = new Uint32Array(cut.length * 2);
    for (let i = 0, j = 0; i < cut.length; i += 3) {
      idx[j++] = cut[i]; idx[j++] = cut[i + 1]; idx[j++] = cut[i + 1]; idx[j++] = cut[i + 2]; idx[j++] = cut[i + 2]; idx[j++] = cut[i];
    }
    eg.setAttribute('position', new THREE.BufferAttribute(l.positions, 3));
    eg.setIndex(new THREE.BufferAttribute(idx, 1));
    group.add(new THREE.LineSegments(eg, new THREE.LineBasicMaterial({ color: 0x402010 })));
  }
  render();
}
let clipPending = false;
$('clip').addEventListener('input', () => {
  // coalesce slider events to one recomputation per frame
  if (clipPending) return; clipPending = true;
  requestAnimationFrame(() => { clipPending = false; drawVolume(); });
});

function fitCamera(obj) {
  const box = new THREE.Box3().setFromObject(obj);
  if (box.isEmpty()) return;
  const c = box.getCenter(new THREE.Vector3()), r = box.getSize(new THREE.Vector3()).length() / 2 || 1;
  const d = r / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2));
  camera.near = d / 100; camera.far = d * 10; camera.updateProjectionMatrix();
  camera.position.copy(c).add(new THREE.Vector3(0.55, 0.45, 1).normalize().multiplyScalar(d));
  controls.target.copy(c); controls.update();
  fitted = true;
}

function show(index) {
  const l = levelData.get(index);
  if (!l) return;
  if (root) { scene.remove(root); root.traverse((o) => { o.geometry && o.geometry.dispose(); o.material && o.material.dispose(); }); }
  root = buildLevel(l);
  scene.add(root);
  if (!fitted) fitCamera(root);
  shownIndex = index;
  $('level').value = String(index);
  for (const tr of document.querySelectorAll('#levels tbody tr')) tr.classList.toggle('shown', tr.dataset.index === String(index));
  render();
  // Drawn: tests wait for this to equal the last level's index.
  state.drawn = index; publish();
}

$('level').addEventListener('change', () => { followFinest = false; show(Number($('level').value)); });

function addLevel(l) {
  l.kind = l.kind || kindOf(l);
  levelData.set(l.index, l);
  const row = { index: l.index, points: l.pointCount, triangles: l.triangles ? l.triangles.length / 3 : 0,
                tetrahedra: l.tetrahedra ? l.tetrahedra.length / 4 : 0, bytes: l.bytes, seconds: l.seconds };
  state.levels.push(row); state.kind = l.kind;
  const opt = document.createElement('option');
  opt.value = String(l.index); opt.textContent = `${l.index} (${row.points.toLocaleString()} points)`;
  $('level').appendChild(opt); $('level').disabled = false;
  const tr = document.createElement('tr'); tr.dataset.index = String(l.index);
  for (const v of [row.index, row.points, row.triangles, row.tetrahedra, row.bytes, row.seconds.toFixed(3)]) {
    const td = document.createElement('td'); td.textContent = typeof v === 'number' ? v.toLocaleString() : v; tr.appendChild(td);
  }
  $('levels').querySelector('tbody').appendChild(tr);
  // Levels arrive coarse to fine: follow the newest unless the user chose one.
  if (followFinest) show(l.index); else publish();
}

function setError(err) {
  state.error = err;
  const finest = state.levels.length ? state.levels[state.levels.length - 1].index : null;
  const what = {
    truncated: 'The stream ends before its last level: showing the finest complete level.',
    bad_crc: 'The stream is corrupt (a chunk\'s CRC does not match): showing the finest level decoded before it.',
    limit_exceeded: 'The stream exceeds this viewer\'s decoder limits (points, levels or memory) and was refused.',
  }[err.code] || 'The stream could not be decoded.';
  $('error').hidden = false;
  $('error').textContent = `${what}\n[${err.code}] ${err.message}` +
    (finest !== null ? `\nShown: level ${finest}.` : '\nNo level could be decoded.');
}

// ---------- streaming ----------
function start(input) {
  const worker = new Worker(new URL('./worker.mjs', import.meta.url), { type: 'module' });
  worker.onmessage = (ev) => {
    const m = ev.data;
    if (m.type === 'progress') {
      state.received = m.received; state.total = m.total;
      $('bar').style.width = m.total ? `${Math.min(100, (100 * m.received) / m.total)}%` : '50%';
      $('status').textContent = `${m.received.toLocaleString()}${m.total ? ' / ' + m.total.toLocaleString() : ''} bytes received`;
      publish();
    } else if (m.type === 'level') {
      addLevel(m.level);
    } else if (m.type === 'done' || m.type === 'error') {
      state.seconds = m.seconds; state.received = m.received;
      if (m.type === 'error') setError(m.error);
      state.done = true;
      $('bar').style.width = '100%';
      $('time').textContent = `decode time ${m.seconds.toFixed(3)} s, ${m.received.toLocaleString()} bytes, ${state.levels.length} levels`;
      $('status').textContent = m.type === 'done' ? 'done' : 'stopped on an error';
      publish(); worker.terminate();
    }
  };
  worker.onerror = (e) => {
    // a worker that fails to load (e.g. no decoder module) is an error too
    setError({ code: 'worker_failed', message: e.message || 'the decoder worker failed' });
    state.done = true; publish();
  };
  worker.postMessage({ ...input, limits, moduleUrl: params.get('module') ? new URL(params.get('module'), location.href).href : null });
}

window.addEventListener('dragover', (e) => { e.preventDefault(); $('drop').hidden = false; });
window.addEventListener('dragleave', () => { $('drop').hidden = true; });
window.addEventListener('drop', (e) => {
  e.preventDefault(); $('drop').hidden = true;
  const f = e.dataTransfer.files && e.dataTransfer.files[0];
  if (f) { reset(); start({ file: f }); }
});
function reset() {
  levelData.clear(); state.levels = []; state.done = false; state.error = null; state.drawn = null;
  fitted = false; followFinest = true; $('error').hidden = true;
  $('level').innerHTML = ''; $('levels').querySelector('tbody').innerHTML = ''; publish();
}

// For tests: how many pixels of the canvas differ from the background.
window.hmcViewerPixelStats = () => {
  render();
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight, px = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  const br = (BACKGROUND >> 16) & 255, bg = (BACKGROUND >> 8) & 255, bb = BACKGROUND & 255;
  let diff = 0;
  for (let i = 0; i < px.length; i += 4)
    if (Math.abs(px[i] - br) + Math.abs(px[i + 1] - bg) + Math.abs(px[i + 2] - bb) > 24) diff++;
  return { width: w, height: h, nonBackground: diff };
};
// For tests and screenshots: choose a level / clip position programmatically.
window.hmcViewerShow = (index, clip) => {
  followFinest = false;
  if (clip !== undefined) $('clip').value = String(Math.round(clip * 1000));
  show(index);
  if (clip !== undefined) drawVolume();
};

resize();
if (params.get('src')) start({ src: params.get('src') });
// A tiled model: ?tiles=DIR/ (or its tiles.json), optionally
// &region=xmin,ymin,zmin,xmax,ymax,zmax in model coordinates.
else if (params.get('tiles')) {
  const region = params.get('region') ? params.get('region').split(',').map(Number) : null;
  start({ tiles: params.get('tiles'), region: region && region.length === 6 && region.every(Number.isFinite) ? region : null });
}
