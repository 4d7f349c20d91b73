#!/usr/bin/env node
// SPDX-License-Identifier: AGPL-3.0-or-later
// The WebAssembly decoder from the command line, for the conformance suite:
//
//   node web/cli.mjs dec IN.hmc --canonical DIR [--points-only]
//                    [--max-points N] [--max-levels N] [--max-memory BYTES]
//
//   node web/cli.mjs dec TILED --canonical DIR [--level K]
//                    [--region xmin,ymin,zmin,xmax,ymax,zmax]
//
// writes the canonical dump of spec/conformance.md section 2 as
// `hmc dec IN.hmc --canonical DIR` does (for a tiled model, TILED its
// directory or its tiles.json: the merged levels of spec/tiles.md, from
// the coarsest down to level K, of the tiles the region needs), and exits as `hmc` does: 0 (a cut
// stream that still decodes prints a warning), 1 bad command line, 2 input
// unreadable, 3 invalid stream, 4 output not written, 5 a limit exceeded,
// 6 out of memory, 70 internal error. An error names the spec's error class
// on standard error: `hmc: IN: crc_mismatch: ...`.
import { closeSync, mkdirSync, openSync, readFileSync, readSync, statSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { decode, decodeTiled, formatG17, HmcError } from './src/index.mjs';

const usage = 'usage: node web/cli.mjs dec IN.hmc --canonical DIR [--points-only] [--max-points N] [--max-levels N] [--max-memory BYTES]\n' +
  '       node web/cli.mjs dec TILED --canonical DIR [--level K] [--region xmin,ymin,zmin,xmax,ymax,zmax] [--points-only]';

function parse(argv) {
  if (argv[0] !== 'dec') return null;
  const a = { in: null, canonical: null, reconstruct: true };
  for (let i = 1; i < argv.length; ++i) {
    const k = argv[i];
    const value = () => {
      if (i + 1 >= argv.length) throw new Error(`${k} needs a value`);
      return argv[++i];
    };
    if (k === '--canonical') a.canonical = value();
    else if (k === '--points-only') a.reconstruct = false;
    else if (k === '--max-points') a.maxPoints = Number(value());
    else if (k === '--max-levels') a.maxLevels = Number(value());
    else if (k === '--max-memory') a.maxMemory = Number(value());
    else if (k === '--level') a.level = Number(value());
    else if (k === '--region') {
      a.region = value().split(',').map(Number);
      if (a.region.length !== 6 || a.region.some((v) => !Number.isFinite(v)) || a.region[0] > a.region[3] ||
          a.region[1] > a.region[4] || a.region[2] > a.region[5]) {
        throw new Error('--region takes xmin,ymin,zmin,xmax,ymax,zmax (min <= max)');
      }
    }
    else if (k.startsWith('-')) throw new Error(`unknown option ${k}`);
    else if (a.in === null) a.in = k;
    else throw new Error('need one input stream');
  }
  if (a.in === null || a.canonical === null) throw new Error('need IN.hmc and --canonical DIR');
  return a;
}

// header.json: exactly the text of spec/conformance.md 2.1.
async function headerJson(h) {
  const g = async (v) => formatG17(v);
  const origin = [];
  for (const v of h.origin) origin.push(await g(v));
  const finestFirst = h.declaredPoints.slice().reverse();
  return '{\n' +
    `  "kind": "${h.kind}",\n` +
    `  "q": ${h.bits},\n` +
    `  "origin": [${origin.join(', ')}],\n` +
    `  "step": ${await g(h.step)},\n` +
    `  "levels": ${h.declaredLevels},\n` +
    `  "level_points": [${finestFirst.join(', ')}]\n` +
    '}\n';
}

function pointsText(grid) {
  const lines = new Array(grid.length / 3);
  for (let i = 0, j = 0; i < grid.length; i += 3, ++j) lines[j] = `${grid[i]} ${grid[i + 1]} ${grid[i + 2]}\n`;
  return lines.join('');
}

// Indices sorted within each simplex, simplices sorted by their integers.
function simplicesText(indices, width) {
  const n = indices.length / width;
  const s = new Uint32Array(indices);
  for (let t = 0; t < n; ++t) s.subarray(t * width, (t + 1) * width).sort();
  const order = new Uint32Array(n);
  for (let t = 0; t < n; ++t) order[t] = t;
  order.sort((a, b) => {
    for (let k = 0; k < width; ++k) {
      const d = s[a * width + k] - s[b * width + k];
      if (d) return d;
    }
    return 0;
  });
  const lines = new Array(n);
  for (let j = 0; j < n; ++j) {
    const o = order[j] * width;
    lines[j] = width === 3 ? `${s[o]} ${s[o + 1]} ${s[o + 2]}\n` : `${s[o]} ${s[o + 1]} ${s[o + 2]} ${s[o + 3]}\n`;
  }
  return lines.join('');
}

const EXIT = { limit_exceeded: 5, out_of_memory: 6, internal_error: 70, invalid_argument: 1 };

async function main(argv) {
  let a;
  try {
    a = parse(argv);
  } catch (e) {
    process.stderr.write(`hmc dec: ${e.message}\n${usage}\n`);
    return 1;
  }
  if (!a) {
    process.stderr.write(`${usage}\n`);
    return 1;
  }
  let tiled = null;  // the directory of a tiled model
  try {
    tiled = statSync(a.in).isDirectory() ? a.in : a.in.endsWith('tiles.json') ? dirname(a.in) : null;
  } catch (e) {
    // not there: reading it below says so
  }
  if (!tiled && (a.level !== undefined || a.region)) {
    process.stderr.write(`hmc dec: --level and --region are for a tiled model here\n${usage}\n`);
    return 1;
  }
  let levels;
  if (tiled) {
    let index;
    try {
      index = readFileSync(join(tiled, 'tiles.json'), 'utf8');
    } catch (e) {
      process.stderr.write(`hmc: cannot read ${a.in}: io_error: ${e.message}\n`);
      return 2;
    }
    // A tile's prefix, as a client's range request would fetch it.
    const fetchPrefix = async (file, bytes, whole) => {
      const path = join(tiled, file);
      if (whole) return readFileSync(path);
      const buf = Buffer.alloc(bytes);
      const fd = openSync(path, 'r');
      try {
        return buf.subarray(0, readSync(fd, buf, 0, bytes, 0));
      } finally {
        closeSync(fd);
      }
    };
    try {
      const r = await decodeTiled(index, fetchPrefix, { level: a.level, region: a.region, allLevels: true,
        reconstruct: a.reconstruct, maxPoints: a.maxPoints, maxLevels: a.maxLevels, maxMemory: a.maxMemory });
      levels = r.levels;
      levels.header = r.header;
      process.stderr.write(`hmc dec: ${a.in}: ${r.tiles.length} tiles, ${r.bytesRead} bytes read\n`);
    } catch (e) {
      if (!(e instanceof HmcError)) throw e;
      process.stderr.write(`hmc: ${a.in}: ${e.message}\n`);
      return e.code === 'io_error' ? 2 : e.code === 'invalid_argument' ? 1 : EXIT[e.code] || 3;
    }
  } else {
    let bytes;
    try {
      bytes = readFileSync(a.in);
    } catch (e) {
      process.stderr.write(`hmc: cannot read ${a.in}: io_error: ${e.message}\n`);
      return 2;
    }
    try {
      levels = await decode(bytes, { reconstruct: a.reconstruct, maxPoints: a.maxPoints, maxLevels: a.maxLevels,
        maxMemory: a.maxMemory });
    } catch (e) {
      if (!(e instanceof HmcError)) throw e;
      process.stderr.write(`hmc: ${a.in}: ${e.message}\n`);
      return EXIT[e.code] || 3;
    }
  }
  if (levels.incomplete) process.stderr.write(`hmc: warning: ${a.in}: ${levels.message}\n`);
  const h = levels.header;
  const files = [['header.json', await headerJson(h)]];
  for (const l of levels) {
    const stem = `level-${l.lod}`;
    files.push([`${stem}.points`, pointsText(l.gridPoints)]);
    if (!a.reconstruct) continue;
    if (h.kind === 'surface') files.push([`${stem}.simplices`, simplicesText(l.triangles, 3)]);
    if (h.kind === 'volume') files.push([`${stem}.simplices`, simplicesText(l.tetrahedra, 4)]);
  }
  try {
    mkdirSync(a.canonical, { recursive: true });
    for (const [name, text] of files) writeFileSync(join(a.canonical, name), text);
  } catch (e) {
    process.stderr.write(`hmc: cannot write the canonical dump: io_error: ${e.message}\n`);
    return 4;
  }
  return 0;
}

main(process.argv.slice(2)).then((code) => { process.exitCode = code; }, (e) => {
  process.stderr.write(`hmc: internal_error: ${e && e.stack ? e.stack : e}\n`);
  process.exitCode = 70;
});
