// Headless Chromium test of the HMC viewer (issue 51, "Must show"):
//   node web/test/browser.mjs [--hmc PATH] [--keep]
// Generates a surface, a volume and a point set, encodes each with the native
// `hmc enc --levels 4`, opens web/viewer/ on each stream and checks the counts
// the page reports against the native decoder's canonical dump, that the last
// level was drawn and that the canvas is not all background; then hostile
// streams: truncated, one corrupted byte, a huge declared point count, and a
// point limit. Exits non-zero on any failure.
import fs from 'node:fs';
import path from 'node:path';
import { OUT_DIR, hmcBin, run, writeTorusObj, writeBallMesh, writePointsXyz, encodeAndReference,
         withHugeDeclaredCount, serve, launchChromium, openViewer } from './lib.mjs';

const argv = process.argv.slice(2);
const hmc = hmcBin(argv);
fs.mkdirSync(OUT_DIR, { recursive: true });
const failures = [];
const check = (ok, what) => { console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`); if (!ok) failures.push(what); };
const T0 = Date.now();

// ---- inputs and native references
const cases = [
  { name: 'surface', input: 'torus.obj', write: writeTorusObj, extra: [] },
  { name: 'volume', input: 'ball.mesh', write: writeBallMesh, extra: [] },
  { name: 'points', input: 'shell.xyz', write: writePointsXyz, extra: ['--kind', 'points'] },
];
for (const c of cases) {
  c.write(path.join(OUT_DIR, c.input));
  c.file = `${c.name}.hmc`;
  c.ref = encodeAndReference(hmc, path.join(OUT_DIR, c.input), path.join(OUT_DIR, c.file), c.extra);
  console.log(`     ${c.name}: ${c.ref.bytes} bytes, kind ${c.ref.kind}, levels ` +
    c.ref.levels.map((l) => `${l.index}:${l.points}p/${l.triangles || l.tetrahedra}s`).join(' '));
}
const tNative = (Date.now() - T0) / 1000;

// The page's rows against the native ones (same order: coarsest first).
function compareLevels(name, got, want) {
  check(got.length === want.length, `${name}: ${got.length} levels reported, native ${want.length}`);
  for (let i = 0; i < Math.min(got.length, want.length); i++) {
    const g = got[i], w = want[i];
    const same = g.index === w.index && g.points === w.points && g.triangles === w.triangles && g.tetrahedra === w.tetrahedra;
    check(same, `${name}: level ${w.index} page ${g.index}:${g.points}p/${g.triangles}t/${g.tetrahedra}T ` +
      `native ${w.index}:${w.points}p/${w.triangles}t/${w.tetrahedra}T (bytes ${g.bytes}, native stream_bytes ${w.stream_bytes})`);
  }
}

const { server, base } = await serve();
const browser = await launchChromium();
const timings = {};
try {
  // ---- the three kinds, whole streams
  for (const c of cases) {
    const r = await openViewer(browser, base, `../test/out/${c.file}`);
    timings[c.name] = r.wallSeconds;
    check(!r.timedOut, `${c.name}: viewer finished in ${r.wallSeconds.toFixed(1)} s (decode ${r.state && r.state.seconds} s)`);
    check(r.state && !r.state.error, `${c.name}: no error (${JSON.stringify(r.state && r.state.error)})`);
    compareLevels(c.name, r.state ? r.state.levels : [], c.ref.levels);
    check(r.state && r.state.kind === c.ref.kind, `${c.name}: kind ${r.state && r.state.kind} = native ${c.ref.kind}`);
    check(r.state && r.state.drawn === 0, `${c.name}: last level drawn (drawn = ${r.state && r.state.drawn})`);
    const dataset = JSON.parse(await r.page.evaluate(() => document.body.dataset.hmcState));
    check(dataset.levels.length === (r.state ? r.state.levels.length : -1), `${c.name}: data-hmc-state agrees with window.hmcViewerState`);
    const px = await r.page.evaluate(() => window.hmcViewerPixelStats());
    check(px.nonBackground > 0.01 * px.width * px.height,
      `${c.name}: ${px.nonBackground} of ${px.width * px.height} pixels are not background`);
    const shot = path.join(OUT_DIR, `${c.name}.png`);
    await r.page.screenshot({ path: shot });
    check(fs.statSync(shot).size > 1000, `${c.name}: screenshot ${path.relative(process.cwd(), shot)}`);
    check(r.worstPing < 2000, `${c.name}: page answered within ${r.worstPing} ms while decoding`);
    check(r.pageErrors.length === 0, `${c.name}: no page errors ${r.pageErrors.join(' | ')}`);
    await r.page.close();
  }

  // ---- a tiled model (spec/tiles.md): the surface cut into tiles, its
  // merged levels streamed by range requests, against hmc dec's merged dump
  {
    const tiled = path.join(OUT_DIR, 'tiled');
    fs.rmSync(tiled, { recursive: true, force: true });
    const t = run(hmc, ['tile', path.join(OUT_DIR, cases[0].input), '-o', tiled, '--tile-points', '800', '--levels', '3',
      '--engine', 'pool', '--json']);
    check(t.code === 0, `tiled: hmc tile (${t.code}) ${t.code ? t.stderr : ''}`);
    const dump = path.join(OUT_DIR, 'tiled.canonical');
    fs.rmSync(dump, { recursive: true, force: true });
    run(hmc, ['dec', tiled, '--canonical', dump]);
    const lines = (f) => fs.readFileSync(path.join(dump, f), 'utf8').split('\n').filter(Boolean).length;
    const want = [2, 1, 0].map((k) => ({ index: k, points: lines(`level-${k}.points`), triangles: lines(`level-${k}.simplices`),
      tetrahedra: 0, stream_bytes: '-' }));
    const r = await openViewer(browser, base, null, `&tiles=${encodeURIComponent('../test/out/tiled/')}`);
    check(!r.timedOut && r.state && !r.state.error, `tiled: viewer finished without error (${JSON.stringify(r.state && r.state.error)})`);
    compareLevels('tiled', r.state ? r.state.levels : [], want);
    const total = JSON.parse(fs.readFileSync(path.join(tiled, 'tiles.json'), 'utf8')).tiles.reduce((n, x) => n + x.bytes, 0);
    check(r.state && r.state.drawn === 0 && r.state.received === total,
      `tiled: level 0 drawn, ${r.state && r.state.received} bytes fetched, the tiles' ${total}`);
    const px = await r.page.evaluate(() => window.hmcViewerPixelStats());
    check(px.nonBackground > 0.01 * px.width * px.height, `tiled: ${px.nonBackground} pixels are not background`);
    await r.page.screenshot({ path: path.join(OUT_DIR, 'tiled.png') });
    check(r.pageErrors.length === 0, `tiled: no page errors ${r.pageErrors.join(' | ')}`);
    await r.page.close();
  }

  // ---- hostile streams, on the surface
  const s = cases[0], bytes = fs.readFileSync(path.join(OUT_DIR, s.file));
  const lv = s.ref.levels; // coarsest first; stream_bytes = end of that level's chunks
  // (a) truncated in the middle of the finest level's layer
  const cut = Math.floor((lv[lv.length - 2].stream_bytes + lv[lv.length - 1].stream_bytes) / 2);
  fs.writeFileSync(path.join(OUT_DIR, 'truncated.hmc'), bytes.subarray(0, cut));
  const nt = run(hmc, ['dec', path.join(OUT_DIR, 'truncated.hmc'), '--canonical', path.join(OUT_DIR, 'truncated.canonical')]);
  {
    const r = await openViewer(browser, base, '../test/out/truncated.hmc');
    const want = lv.slice(0, lv.length - 1);
    console.log(`     truncated at ${cut} of ${bytes.length} bytes; native dec exit ${nt.code}: ${nt.stderr.trim().split('\n').pop()}`);
    compareLevels('truncated', r.state.levels, want);
    check(r.state.error && /truncat/i.test(r.state.error.code + r.state.error.message),
      `truncated: error shown (${JSON.stringify(r.state.error)})`);
    check(r.state.drawn === want[want.length - 1].index, `truncated: finest complete level ${want[want.length - 1].index} drawn (drawn = ${r.state.drawn})`);
    const msg = await r.page.evaluate(() => !document.getElementById('error').hidden && document.getElementById('error').textContent);
    check(!!msg, `truncated: message on the page: ${JSON.stringify(msg)}`);
    await r.page.screenshot({ path: path.join(OUT_DIR, 'truncated.png') });
    await r.page.close();
  }
  // (b) one corrupted byte inside level 1's layer
  {
    const bad = Buffer.from(bytes);
    const at = Math.floor((lv[lv.length - 3].stream_bytes + lv[lv.length - 2].stream_bytes) / 2);
    bad[at] ^= 0x5a;
    fs.writeFileSync(path.join(OUT_DIR, 'corrupt.hmc'), bad);
    const nc = run(hmc, ['dec', path.join(OUT_DIR, 'corrupt.hmc'), '-o', path.join(OUT_DIR, 'corrupt.ply')]);
    console.log(`     corrupted byte ${at}; native dec exit ${nc.code}: ${nc.stderr.trim().split('\n').pop()}`);
    const r = await openViewer(browser, base, '../test/out/corrupt.hmc');
    check(!!r.state.error, `corrupt: error shown (${JSON.stringify(r.state.error)})`);
    check(r.state.levels.length < lv.length, `corrupt: ${r.state.levels.length} levels shown, fewer than ${lv.length}`);
    compareLevels('corrupt (levels before the damage)', r.state.levels, lv.slice(0, r.state.levels.length));
    check(r.pageErrors.length === 0, `corrupt: no page errors ${r.pageErrors.join(' | ')}`);
    await r.page.close();
  }
  // (c) a HEAD declaring 4e9 points: refused by the viewer's limits
  {
    fs.writeFileSync(path.join(OUT_DIR, 'huge.hmc'), withHugeDeclaredCount(bytes, 4_000_000_000));
    const nh = run(hmc, ['dec', path.join(OUT_DIR, 'huge.hmc'), '-o', path.join(OUT_DIR, 'huge.ply')]);
    console.log(`     huge declared count; native dec exit ${nh.code}: ${nh.stderr.trim().split('\n').pop()}`);
    const r = await openViewer(browser, base, '../test/out/huge.hmc', '', 60000);
    check(!r.timedOut, `huge: finished in ${r.wallSeconds.toFixed(1)} s`);
    check(r.state.error && r.state.error.code === 'limit_exceeded', `huge: refused with limit_exceeded (${JSON.stringify(r.state.error)})`);
    await r.page.close();
  }
  // (d) a caller-set point limit below the coarsest level
  {
    const r = await openViewer(browser, base, `../test/out/${s.file}`, `&maxPoints=${lv[0].points - 1}`, 60000);
    check(r.state.error && r.state.error.code === 'limit_exceeded', `maxPoints=${lv[0].points - 1}: refused with limit_exceeded (${JSON.stringify(r.state.error)})`);
    await r.page.close();
  }
} finally {
  await browser.close();
  server.close();
}
console.log(`native encode+reference ${tNative.toFixed(1)} s; viewer runs ${Object.entries(timings).map(([k, v]) => `${k} ${v.toFixed(1)} s`).join(', ')}; total ${((Date.now() - T0) / 1000).toFixed(1)} s`);
if (failures.length) { console.log(`${failures.length} failure(s)`); process.exit(1); }
console.log('all browser checks passed');
