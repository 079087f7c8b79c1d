#!/usr/bin/env node
// Packs the existing UV charts of an OBJ with xatlas (npm xatlasjs, its Node build of jpcy/xatlas
// compiled to WebAssembly), the "pack only" path: AddUvMesh (the mesh's UVs are the charts,
// nothing is re-unwrapped) + ComputeCharts (which for UV meshes only finds the connected
// pieces) + PackCharts into one square atlas of --size texels with --padding.
//
// xatlas packs at a given scale (texelsPerUnit, texels per input UV unit; for UV meshes every
// chart gets this same scale, then each chart's extents are rounded up to whole texels) and
// spills charts into further atlases when they do not fit (or shrinks a chart larger than the
// atlas), so the scale is searched here: the largest for which everything fits one atlas with
// no chart shrunk.
//   --search scan (default): every scale from the area bound (the charts' UV area filling the
//     atlas; no larger scale can fit) down in 1 % steps until one packs, then bisection up to
//     the failed step above it, to within 0.1 %. Generous to xatlas:
//     whether a scale packs is not monotonic in the scale (random or greedy placement), and a
//     bisection can stop well below a scale that packs (up to 14 points of utilization here).
//   --search bisect: meso uvpack pack's own search (uvpack/src/uv_pack.cpp): halve from the
//     area bound until it packs, then bisect to within 1 %; about 9 packings.
//
// usage: node xatlas_pack.mjs IN.obj -o OUT.obj --size N --padding P
//          [--bilinear 0|1] [--brute-force] [--axis] [--search scan|bisect] [--json FILE]
//   --bilinear 0|1   PackOptions::bilinear (default 1, xatlas's default): add the texels that
//                    bilinear filtering reads around each chart before the padding
//   --brute-force    PackOptions::bruteForce (slower, better placement); default: random
//   --axis           PackOptions::rotateChartsToAxis (xatlas's default is on: charts are first
//                    turned by any angle onto their principal axes); default off, so that, like
//                    meso, charts only turn by multiples of 90 degrees (rotateCharts is on;
//                    xatlas's "rotation" swaps u and v, which mirrors the chart)
// Writes OUT.obj (same positions, normals and faces; new UVs) and a JSON report (stdout or
// --json FILE) with the scale, the attempts and the times.
import { createRequire } from 'node:module';
import { writeFileSync } from 'node:fs';
import { performance } from 'node:perf_hooks';
import { readObj, writeObj, uvCharts } from './obj.mjs';

const t_start = performance.now();
const require = createRequire(import.meta.url);

function parseArgs(argv) {
  const a = { input: null, output: null, size: 1024, padding: 2, bilinear: true, bruteForce: false, axis: false, search: 'scan', json: null };
  for (let i = 0; i < argv.length; ++i) {
    const s = argv[i];
    const next = () => {
      if (i + 1 >= argv.length) throw new Error(`${s} needs a value`);
      return argv[++i];
    };
    if (s === '-o' || s === '--output') a.output = next();
    else if (s === '--size') a.size = parseInt(next(), 10);
    else if (s === '--padding') a.padding = parseInt(next(), 10);
    else if (s === '--bilinear') a.bilinear = next() !== '0';
    else if (s === '--brute-force') a.bruteForce = true;
    else if (s === '--axis') a.axis = true;
    else if (s === '--json') a.json = next();
    else if (s === '--search') a.search = next();
    else if (s.startsWith('-')) throw new Error(`unknown option ${s}`);
    else a.input = s;
  }
  if (!a.input || !a.output) throw new Error('usage: xatlas_pack.mjs IN.obj -o OUT.obj --size N --padding P [--bilinear 0|1] [--brute-force] [--axis] [--search scan|bisect] [--json FILE]');
  if (!(a.size > 0) || !(a.padding >= 0)) throw new Error('bad --size or --padding');
  if (!['bisect', 'scan'].includes(a.search)) throw new Error('--search: bisect or scan');
  return a;
}

const args = parseArgs(process.argv.slice(2));
const mesh = readObj(args.input);
if (mesh.faces.some((f) => !f.vt)) throw new Error(`${args.input}: every face needs texture coordinates`);
const { chart, count: chartCount } = uvCharts(mesh);

// xatlas's UV-mesh vertices: one per (position, UV, chart), so that faces share an xatlas edge
// exactly when meso sees them in the same chart (xatlas finds UV-mesh charts by shared edges).
const keyToVertex = new Map();
const uvIn = [];
const cornerUv = mesh.faces.map((f, fi) =>
  [0, 1, 2].map((k) => {
    const t = mesh.vt[f.vt[k]];
    const u = Math.fround(t[0]), v = Math.fround(t[1]);
    const key = `${f.v[k]}|${u}|${v}|${chart[fi]}`;
    let idx = keyToVertex.get(key);
    if (idx === undefined) {
      idx = uvIn.length / 2;
      keyToVertex.set(key, idx);
      uvIn.push(u, v);
    }
    return idx;
  }));
const vertexCount = uvIn.length / 2, indexCount = mesh.faces.length * 3;
if (vertexCount > 65535) throw new Error(`${vertexCount} UV vertices: xatlasjs takes 16-bit indices`);
const indices = new Uint16Array(indexCount);
cornerUv.forEach((c, fi) => indices.set(c, fi * 3));

// Per chart: UV area (input units), to search the scale and to tell a shrunk chart.
const chartArea = new Float64Array(chartCount);
const triArea = (uv, a, b, c) => 0.5 * Math.abs((uv[2 * b] - uv[2 * a]) * (uv[2 * c + 1] - uv[2 * a + 1]) - (uv[2 * b + 1] - uv[2 * a + 1]) * (uv[2 * c] - uv[2 * a]));
cornerUv.forEach((c, fi) => { chartArea[chart[fi]] += triArea(uvIn, c[0], c[1], c[2]); });
const totalArea = chartArea.reduce((s, x) => s + x, 0);
// Largest chart side (UV box, as xatlas measures it when rotateChartsToAxis is off): xatlas
// shrinks a chart whose side exceeds size - 1 texels.
const boxMin = new Float64Array(chartCount * 2).fill(Infinity), boxMax = new Float64Array(chartCount * 2).fill(-Infinity);
cornerUv.forEach((c, fi) => {
  const ci = chart[fi];
  for (const k of c)
    for (let d = 0; d < 2; ++d) {
      boxMin[2 * ci + d] = Math.min(boxMin[2 * ci + d], uvIn[2 * k + d]);
      boxMax[2 * ci + d] = Math.max(boxMax[2 * ci + d], uvIn[2 * k + d]);
    }
});
let maxSide = 0;
for (let i = 0; i < 2 * chartCount; ++i) maxSide = Math.max(maxSide, boxMax[i] - boxMin[i]);

const t_loaded = performance.now();
const createXAtlasModule = require('xatlasjs/dist/node/xatlas.js');
const xa = await createXAtlasModule({ onAtlasProgress: () => {} });
const t_module = performance.now();

const N = args.size;
let packMs = 0;
// One packing at texelsPerUnit tpu, in a fresh atlas so that every attempt starts from the
// input UVs.
function packAt(tpu) {
  // A chart larger than the atlas would be shrunk: not a packing at this scale.
  if (!args.axis && Math.ceil(maxSide * tpu) > N - 1) return { ok: false, ms: 0 };
  const t0 = performance.now();
  xa.createAtlas();
  const d = xa.createUvMesh(vertexCount, indexCount);
  xa.HEAPU16.set(indices, d.indexOffset / 2);
  xa.HEAPF32.set(uvIn, d.uvOffset / 4);
  const err = xa.addUvMesh();
  if (err !== 0) throw new Error(`xatlas AddUvMesh failed: error ${err}`);
  xa.computeCharts(xa.defaultChartOptions());
  xa.packCharts({
    ...xa.defaultPackOptions(),
    resolution: N,
    padding: args.padding,
    texelsPerUnit: tpu,
    bilinear: args.bilinear,
    bruteForce: args.bruteForce,
    rotateCharts: true,
    rotateChartsToAxis: args.axis,
  });
  const atlas = xa.getAtlas();
  const md = xa.getMeshData(0);
  const ok0 = md.newVertexCount === vertexCount && md.newIndexCount === indexCount;
  const uv = new Float64Array(xa.HEAPF32.subarray(md.uvOffset / 4, md.uvOffset / 4 + md.newVertexCount * 2));
  const xref = new Uint32Array(xa.HEAPU32.subarray(md.originalIndexOffset / 4, md.originalIndexOffset / 4 + md.newVertexCount));
  const outIdx = new Uint32Array(xa.HEAPU32.subarray(md.indexOffset / 4, md.indexOffset / 4 + md.newIndexCount));
  xa.destroyMeshData(md);
  md.subMeshes.delete();
  xa.destroyAtlas();
  const ms = performance.now() - t0;
  packMs += ms;
  // Charts spilled into further atlases: not a packing into one atlas (xatlasjs then also
  // sorts the index array by atlas, so the checks below do not apply).
  if (atlas.atlasCount !== 1) return { ok: false, atlas, ms };
  if (!ok0) throw new Error('xatlas changed the UV mesh\'s vertex or index count');
  for (let i = 0; i < vertexCount; ++i) if (xref[i] !== i) throw new Error('xatlas reordered the UV mesh\'s vertices');
  for (let i = 0; i < indexCount; ++i) if (outIdx[i] !== indices[i]) throw new Error('xatlas changed the UV mesh\'s indices');
  // Scale each chart got, relative to tpu (sqrt of the UV area ratio): below 1 means xatlas
  // shrank a chart that did not fit the atlas (a failure here); above 1 is xatlas's rounding
  // of every chart's extents up to whole texels.
  const outArea = new Float64Array(chartCount);
  cornerUv.forEach((c, fi) => { outArea[chart[fi]] += triArea(uv, c[0], c[1], c[2]); });
  const rel = [];
  for (let ci = 0; ci < chartCount; ++ci) if (chartArea[ci] > 0) rel.push(Math.sqrt(outArea[ci] / chartArea[ci]) * N / tpu);
  rel.sort((p, q) => p - q);
  const shrunk = rel.length > 0 && rel[0] < 0.999;
  return { ok: atlas.atlasCount === 1 && atlas.width === N && atlas.height === N && !shrunk, atlas, uv, rel, ms };
}

// The scale search (see the top of the file).
const areaBound = totalArea > 0 ? Math.sqrt((N * N) / totalArea) : N;
let attempts = 0, lo = 0, best = null;
if (args.search === 'scan') {
  let s = areaBound, fail = 0;
  for (let k = 0; k < 1000 && !best; ++k, s *= 0.99) {
    const r = packAt(s);
    if (r.ms > 0) ++attempts;  // (scales at which a chart would be shrunk are not tried)
    if (r.ok) { lo = s; best = r; } else fail = s;
  }
  // Then between that scale and the step above it, to within 0.1 %.
  while (best && fail / lo > 1.001) {
    const mid = Math.sqrt(lo * fail);
    const r = packAt(mid);
    if (r.ms > 0) ++attempts;
    if (r.ok) { lo = mid; best = r; } else fail = mid;
  }
} else {
  let hi = areaBound;
  for (let k = 0; k < 40; ++k) {
    ++attempts;
    const r = packAt(hi);
    if (r.ok) { lo = hi; best = r; break; }
    hi *= 0.5;
  }
  let fail = lo * 2;
  while (best && fail / lo > 1.01 && attempts < 60) {
    const mid = Math.sqrt(lo * fail);
    ++attempts;
    const r = packAt(mid);
    if (r.ok) { lo = mid; best = r; } else fail = mid;
  }
}
if (!best) throw new Error('xatlas: the charts do not fit one atlas at any scale tried');

writeObj(args.output, mesh, Array.from(best.uv, (x) => Math.fround(x)), cornerUv,
  `xatlas (xatlasjs) PackCharts: size ${N}, padding ${args.padding}, bilinear ${args.bilinear}, bruteForce ${args.bruteForce}, rotateChartsToAxis ${args.axis}, texelsPerUnit ${lo}`);
const t_end = performance.now();
const rel = best.rel;
const report = {
  command: 'xatlas_pack',
  input: args.input,
  output: args.output,
  size: N,
  padding: args.padding,
  bilinear: args.bilinear,
  bruteForce: args.bruteForce,
  rotateChartsToAxis: args.axis,
  search: args.search,
  charts: chartCount,
  uv_vertices: vertexCount,
  faces: mesh.faces.length,
  scale: lo,
  attempts,
  chart_scale_rel: rel.length ? { min: rel[0], median: rel[rel.length >> 1], max: rel[rel.length - 1] } : null,
  ms: {
    load: t_loaded - t_start,
    wasm_init: t_module - t_loaded,
    search: packMs,
    final_pack: best.ms,  // the packing at the scale found, alone
    total_in_process: t_end - t_start,
  },
};
if (args.json) writeFileSync(args.json, JSON.stringify(report, null, 2) + '\n');
else console.log(JSON.stringify(report, null, 2));
