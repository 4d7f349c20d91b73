// SPDX-License-Identifier: AGPL-3.0-or-later
// bench/wasm.py's Node side: decodes each stream RUNS times with the
// WebAssembly module (all levels, connectivity rebuilt, one thread: wasm has
// none) and prints one JSON line per stream: seconds of each run, in-process
// (module load excluded), and the per-level counts for the native check.
//   node bench/wasm_time.mjs RUNS A.hmc [B.hmc ...]
import fs from 'node:fs';
import { decode, loadModule } from '../web/src/index.mjs';

const [runs, ...files] = process.argv.slice(2);
await loadModule();
for (const f of files) {
  const bytes = fs.readFileSync(f);
  const seconds = [];
  let levels = null;
  for (let i = 0; i < Number(runs); i++) {
    const t = process.hrtime.bigint();
    levels = await decode(bytes, { maxPoints: 1e8, maxMemory: 3.5 * 2 ** 30 });
    seconds.push(Number(process.hrtime.bigint() - t) / 1e9);
  }
  const counts = levels.map((l) => [l.lod, l.pointCount, l.triangles ? l.triangles.length / 3 : 0,
    l.tetrahedra ? l.tetrahedra.length / 4 : 0]);
  console.log(JSON.stringify({ file: f, seconds, counts }));
}
