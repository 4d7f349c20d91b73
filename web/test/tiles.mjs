// SPDX-License-Identifier: AGPL-3.0-or-later
// Tiled models through the WebAssembly decoder (web/src/tiles.mjs): a
// generated torus cut into tiles by the native `hmc tile`, then decoded
// whole, by region and at a coarser level by `node web/cli.mjs dec TILED`
// and by `hmc dec TILED`; the canonical dumps must be the same bytes. Then
// the index checks and a damaged tile, and decodeTiled over HTTP range
// requests against a static server.
//
//   node web/test/tiles.mjs [--hmc PATH]
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { OUT_DIR, WEB_DIR, hmcBin, run } from './lib.mjs';
import { decodeTiled, openTiled, readTileIndex } from '../src/index.mjs';

const hmc = hmcBin(process.argv);
let failures = 0;
function check(cond, what) {
  console.log(`${cond ? 'ok' : 'FAILED'}: ${what}`);
  if (!cond) failures++;
}

const dir = path.join(OUT_DIR, 'tiles');
fs.rmSync(dir, { recursive: true, force: true });
fs.mkdirSync(dir, { recursive: true });
const torus = path.join(dir, 'torus.ply');
const model = path.join(dir, 'model');
const must = (r, what) => {
  if (r.code !== 0) throw new Error(`${what} failed (${r.code}): ${r.stderr}`);
  return r;
};
must(run(hmc, ['gen', 'torus', '--vertices', '8000', '-o', torus]), 'hmc gen');
const summary = JSON.parse(must(run(hmc, ['tile', torus, '-o', model, '--tile-points', '800', '--levels', '3',
  '--engine', 'pool', '--json']), 'hmc tile').stdout);
const index = readTileIndex(fs.readFileSync(path.join(model, 'tiles.json'), 'utf8'));
check(index.tiles.length === summary.tiles && index.tiles.length >= 8, `the torus is cut into ${index.tiles.length} tiles`);

// A corner of the model: the region of the first tile's bounds.
const b = index.tiles[0].bounds;
const at = (g, a) => index.origin[a] + g * index.step;
const corner = [at(b[0], 0), at(b[1], 1), at(b[2], 2), at(b[3], 0), at(b[4], 1), at(b[5], 2)].join(',');

function same(a, c) {
  const names = fs.readdirSync(a).sort();
  if (names.join() !== fs.readdirSync(c).sort().join()) return false;
  return names.every((n) => fs.readFileSync(path.join(a, n)).equals(fs.readFileSync(path.join(c, n))));
}
const cli = path.join(WEB_DIR, 'cli.mjs');
for (const [name, extra] of [['whole', []], ['level 1', ['--level', '1']], ['corner at level 2', ['--level', '2', '--region', corner]],
  ['corner at level 0', ['--region', corner]], ['points only', ['--level', '1', '--points-only']]]) {
  const nat = path.join(dir, `native-${name.replace(/ /g, '-')}`), js = path.join(dir, `wasm-${name.replace(/ /g, '-')}`);
  must(run(hmc, ['dec', model, '--canonical', nat, ...extra]), `hmc dec (${name})`);
  const r = must(run(process.execPath, [cli, 'dec', model, '--canonical', js, ...extra]), `web/cli.mjs dec (${name})`);
  const files = fs.readdirSync(js).length;
  check(same(nat, js), `${name}: the merged dump equals hmc dec's, byte for byte (${files} files; ${r.stderr.trim()})`);
}

// The index checks and a damaged tile.
const bad = (mutate) => {
  const ix = JSON.parse(fs.readFileSync(path.join(model, 'tiles.json'), 'utf8'));
  mutate(ix);
  try {
    readTileIndex(ix);
    return 'accepted';
  } catch (e) {
    return e.code;
  }
};
check(bad((ix) => { ix.tiles[1].box[3] += 1; }) === 'bad_header', 'overlapping boxes are refused');
check(bad((ix) => { ix.tiles.pop(); }) === 'bad_header', 'boxes that do not cover the lattice are refused');
check(bad((ix) => { ix.tiles[0].file = '../x.hmc'; }) === 'bad_header', 'a file name with a path is refused');
check(bad((ix) => { ix.version = '1.0'; }) === 'bad_header', 'another major version is refused');
check(bad(() => {}) === 'accepted', 'the index as written is accepted');
const damaged = path.join(dir, 'damaged');
fs.cpSync(model, damaged, { recursive: true });
const victim = path.join(damaged, index.tiles[3].file);
const bytes = fs.readFileSync(victim);
bytes[bytes.length - 10] ^= 0x40;
fs.writeFileSync(victim, bytes);
for (const [tool, args] of [['hmc', [hmc, ['dec', damaged, '--canonical', path.join(dir, 'd1')]]],
  ['web/cli.mjs', [process.execPath, [cli, 'dec', damaged, '--canonical', path.join(dir, 'd2')]]]]) {
  const r = run(...args);
  check(r.code === 3 && /crc_mismatch/.test(r.stderr), `${tool}: a damaged tile fails with crc_mismatch, exit 3 (${r.code})`);
}
check(!fs.existsSync(path.join(dir, 'd2')), 'and writes no dump');

// Over HTTP: one range request per tile, for the level's prefix only.
const requests = [];
const server = http.createServer((req, res) => {
  const file = path.join(model, decodeURIComponent(new URL(req.url, 'http://x').pathname));
  if (!file.startsWith(model) || !fs.existsSync(file)) { res.writeHead(404); res.end(); return; }
  const data = fs.readFileSync(file);
  const m = /^bytes=(\d+)-(\d+)$/.exec(req.headers.range || '');
  requests.push({ url: req.url, range: req.headers.range || null });
  if (m) {
    const from = Number(m[1]), to = Math.min(Number(m[2]), data.length - 1);
    res.writeHead(206, { 'Content-Range': `bytes ${from}-${to}/${data.length}` });
    res.end(data.subarray(from, to + 1));
  } else {
    res.writeHead(200);
    res.end(data);
  }
});
await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
try {
  const { index: remote, fetchPrefix, fetched } = await openTiled(`http://127.0.0.1:${server.address().port}/`);
  const region = corner.split(',').map(Number);
  const r = await decodeTiled(remote, fetchPrefix, { level: 2, region });
  const wanted = r.tiles.reduce((s, t) => s + remote.tiles[t].level_bytes[2], 0);
  const total = remote.tiles.reduce((s, t) => s + t.bytes, 0);
  const ranged = requests.filter((q) => q.range);
  check(ranged.length === r.tiles.length && r.tiles.length < remote.tiles.length,
    `the corner at level 2: ${r.tiles.length} of ${remote.tiles.length} tiles, one range request each`);
  check(r.bytesRead === wanted && wanted < total / 4, `and ${wanted} of ${total} bytes`);
  const nat = fs.readFileSync(path.join(dir, 'native-corner-at-level-2', 'level-2.points'), 'utf8').trim().split('\n');
  check(r.levels.length === 1 && r.levels[0].pointCount === nat.length && r.levels[0].triangles.length > 0,
    `its level 2: ${r.levels[0].pointCount} points, ${r.levels[0].triangles.length / 3} triangles, as hmc dec's`);
  // Then level 0 of the same corner: only the bytes after level 2's prefix.
  const f = await decodeTiled(remote, fetchPrefix, { level: 0, region });
  const more = requests.filter((q) => q.range).slice(ranged.length);
  const whole = f.tiles.reduce((s, t) => s + remote.tiles[t].bytes, 0);
  check(more.length === f.tiles.length && more.every((q, i) => q.range === `bytes=${remote.tiles[f.tiles[i]].level_bytes[2]}-${remote.tiles[f.tiles[i]].bytes - 1}`),
    `level 0 next: one range request per tile for the rest (${more.map((q) => q.range).join(', ')})`);
  check(fetched() === whole, `${fetched()} bytes fetched in all, the tiles' ${whole}`);
  const nat0 = fs.readFileSync(path.join(dir, 'native-corner-at-level-0', 'level-0.points'), 'utf8').trim().split('\n');
  check(f.levels[0].pointCount === nat0.length, `its level 0: ${f.levels[0].pointCount} points, as hmc dec's`);
} finally {
  server.close();
}
if (failures) {
  console.error(`tiles: ${failures} checks FAILED`);
  process.exit(1);
}
console.log('tiles: all checks passed');
