// Screenshots of a surface, a volume and a point set at their coarsest and
// finest levels, into web/viewer/screenshots/:
//   node web/test/screenshots.mjs [--hmc PATH] [--models]
// By default from the generated inputs of browser.mjs; with --models from the
// shared models in /work/shared/data (only the PNGs are written to the repo).
import fs from 'node:fs';
import path from 'node:path';
import { OUT_DIR, WEB_DIR, hmcBin, writeTorusObj, writeBallMesh, writePointsXyz, encodeAndReference,
         serve, launchChromium, openViewer } from './lib.mjs';

const argv = process.argv.slice(2);
const hmc = hmcBin(argv);
const SHOTS = path.join(WEB_DIR, 'viewer', 'screenshots');
fs.mkdirSync(OUT_DIR, { recursive: true });
fs.mkdirSync(SHOTS, { recursive: true });
const DATA = process.env.HMC_DATA || '/work/shared/data';
const cases = argv.includes('--models')
  ? [{ name: 'surface', input: `${DATA}/surface/stanford_bunny.obj`, extra: [] },
     { name: 'volume', input: `${DATA}/volume/hand_libigl.mesh`, extra: [] },
     { name: 'points', input: `${DATA}/surface/horse.ply`, extra: ['--kind', 'points'] }]
  : [{ name: 'surface', input: path.join(OUT_DIR, 'torus.obj'), write: writeTorusObj, extra: [] },
     { name: 'volume', input: path.join(OUT_DIR, 'ball.mesh'), write: writeBallMesh, extra: [] },
     { name: 'points', input: path.join(OUT_DIR, 'shell.xyz'), write: writePointsXyz, extra: ['--kind', 'points'] }];

const { server, base } = await serve();
const browser = await launchChromium();
let failed = false;
try {
  for (const c of cases) {
    if (c.write) c.write(c.input);
    const file = `shot-${c.name}.hmc`;
    const ref = encodeAndReference(hmc, c.input, path.join(OUT_DIR, file), c.extra);
    const r = await openViewer(browser, base, `../test/out/${file}`, '', 600000);
    if (!r.state || !r.state.done || r.state.error) { console.log(`FAIL ${c.name}: ${JSON.stringify(r.state && r.state.error)}`); failed = true; continue; }
    await r.page.setViewportSize({ width: 370 + 480, height: 360 });
    const levels = r.state.levels.map((l) => l.index);
    for (const [tag, idx] of [['coarsest', Math.max(...levels)], ['finest', Math.min(...levels)]]) {
      // volumes: clip at 55 % so that the tetrahedra inside show
      await r.page.evaluate(([i, clip]) => window.hmcViewerShow(i, clip), [idx, c.name === 'volume' ? 0.55 : undefined]);
      const l = r.state.levels.find((x) => x.index === idx);
      const out = path.join(SHOTS, `${c.name}-${tag}.png`);
      await r.page.locator('#view canvas').screenshot({ path: out });
      console.log(`${path.relative(process.cwd(), out)}: level ${idx}, ${l.points} points, ${l.triangles} triangles, ` +
                  `${l.tetrahedra} tetrahedra, ${fs.statSync(out).size} bytes (${path.basename(c.input)}, native ${ref.bytes}-byte stream)`);
    }
    await r.page.close();
  }
} finally { await browser.close(); server.close(); }
process.exit(failed ? 1 : 0);
