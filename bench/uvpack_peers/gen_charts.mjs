#!/usr/bin/env node
// Test meshes with many UV charts for the packer comparison. Every chart's UVs start near the
// UV origin, so the charts overlap each other before packing (both packers must move all of
// them). Deterministic for a given --seed.
//
//   node gen_charts.mjs torus -o OUT.obj [--charts 200] [--seed 1]
//     A torus whose quad grid is tiled with pieces of varied shapes and sizes: rectangles
//     (1x1 to 6x6 cells), L-shapes, and right triangles (squares cut along their diagonal;
//     1x1 gives single-triangle charts). Each piece is its own chart with its own texel density
//     (cell size in UV log-uniform over 6x) and a quarter of them turned by a random angle.
//     Neighbouring pieces share positions but not UVs (UV seams), as an artist's cut would.
//     The grid size giving the piece count closest to --charts is searched (193 for 200, seed 1).
//
//   node gen_charts.mjs split IN.obj -o OUT.obj [--charts 150] [--seed 1]
//     Cuts an existing mesh with UVs into about --charts charts: face-connected regions grown
//     from random seeds at random speeds (so of varied sizes and irregular outlines). Each
//     region keeps its own part of the input's UV layout (shape and scale), moved so that its
//     UV box starts at a random point of [0, 0.1]^2.
import { readObj, writeObj, uvCharts } from './obj.mjs';

function parseArgs(argv) {
  const a = { mode: argv[0], input: null, output: null, charts: null, seed: 1 };
  for (let i = 1; i < argv.length; ++i) {
    const s = argv[i];
    if (s === '-o') a.output = argv[++i];
    else if (s === '--charts') a.charts = parseInt(argv[++i], 10);
    else if (s === '--seed') a.seed = parseInt(argv[++i], 10);
    else if (s.startsWith('-')) throw new Error(`unknown option ${s}`);
    else a.input = s;
  }
  if (!['torus', 'split'].includes(a.mode) || !a.output || (a.mode === 'split' && !a.input))
    throw new Error('usage: gen_charts.mjs torus -o OUT.obj [--charts 200] [--seed 1] | split IN.obj -o OUT.obj [--charts 150] [--seed 1]');
  return a;
}

// mulberry32
function rng(seed) {
  let s = seed >>> 0;
  return () => {
    s = (s + 0x6d2b79f5) >>> 0;
    let t = s;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

const fmt = (x) => Number(x.toFixed(7)).toString();

// The grid size is searched for the piece count closest to the target.
function torus(target, seed) {
  let best = null;
  for (let cells = 2 * target; cells <= 20 * target; cells += Math.max(1, Math.round(target / 20))) {
    const mesh = torusGrid(cells, seed);
    if (!best || Math.abs(mesh.pieces - target) < Math.abs(best.pieces - target)) best = mesh;
    if (best.pieces === target) break;
  }
  return best;
}

function torusGrid(cells, seed) {
  const rand = rng(seed);
  const randInt = (lo, hi) => lo + Math.floor(rand() * (hi - lo + 1));
  const U = Math.round(Math.sqrt(cells * 1.5)), V = Math.round(cells / U);
  const R = 1.0, r = 0.4;
  const mesh = { v: [], vt: [], vn: [], faces: [], pieces: 0 };
  for (let j = 0; j < V; ++j)
    for (let i = 0; i < U; ++i) {
      const a = (2 * Math.PI * i) / U, b = (2 * Math.PI * j) / V;
      const x = (R + r * Math.cos(b)) * Math.cos(a), y = (R + r * Math.cos(b)) * Math.sin(a), z = r * Math.sin(b);
      mesh.v.push(`${fmt(x)} ${fmt(y)} ${fmt(z)}`);
    }
  const vid = (i, j) => (j % V) * U + (i % U);
  // Each cell is split along its (0,0)-(1,1) diagonal: lower triangle 0 = (00,10,11), upper
  // triangle 1 = (00,11,01). owner[(cell * 2 + tri)] = piece.
  const owner = new Int32Array(U * V * 2).fill(-1);
  const free = (i, j) => i < U && j < V && owner[(j * U + i) * 2] < 0 && owner[(j * U + i) * 2 + 1] < 0;
  const pieces = [];  // { i0, j0, tris: [[i, j, t]] }
  for (let j = 0; j < V; ++j)
    for (let i = 0; i < U; ++i) {
      if (!free(i, j)) continue;
      let maxW = 0;
      while (free(i + maxW, j)) ++maxW;
      const fits = (w, h) => {
        for (let y = 0; y < h; ++y) for (let x = 0; x < w; ++x) if (!free(i + x, j + y)) return false;
        return true;
      };
      const kind = rand();
      const claim = (tris) => {
        const id = pieces.length;
        for (const [x, y, t] of tris) owner[((j + y) * U + i + x) * 2 + t] = id;
        pieces.push({ i0: i, j0: j, tris });
      };
      if (kind < 0.3) {  // two right triangles from a k x k square
        let k = randInt(1, 6);
        while (k > 1 && !fits(k, k)) --k;
        const lower = [], upper = [];
        for (let y = 0; y < k; ++y)
          for (let x = 0; x < k; ++x) {
            if (x > y) lower.push([x, y, 0], [x, y, 1]);
            else if (x < y) upper.push([x, y, 0], [x, y, 1]);
            else { lower.push([x, y, 0]); upper.push([x, y, 1]); }
          }
        claim(lower);
        claim(upper);
      } else if (kind < 0.55) {  // L-shape: a w x h box less its top-right (w-a) x (h-b) corner
        let w = randInt(2, 6), h = randInt(2, 6);
        w = Math.min(w, maxW);
        while (h > 1 && !fits(w, h)) --h;
        if (w < 2 || h < 2) {
          const tris = [];
          for (let y = 0; y < h; ++y) for (let x = 0; x < w; ++x) tris.push([x, y, 0], [x, y, 1]);
          claim(tris);
        } else {
          const a = randInt(1, w - 1), b = randInt(1, h - 1);
          const tris = [];
          for (let y = 0; y < h; ++y) for (let x = 0; x < w; ++x) if (x < a || y < b) tris.push([x, y, 0], [x, y, 1]);
          claim(tris);
        }
      } else {  // rectangle
        let w = Math.min(randInt(1, 6), maxW), h = randInt(1, 6);
        while (h > 1 && !fits(w, h)) --h;
        const tris = [];
        for (let y = 0; y < h; ++y) for (let x = 0; x < w; ++x) tris.push([x, y, 0], [x, y, 1]);
        claim(tris);
      }
    }
  // UVs per piece: grid coordinates relative to the piece, scaled, maybe turned, offset.
  for (const p of pieces) {
    const cell = 0.01 * Math.exp(Math.log(6) * rand());  // UV units per cell, 0.01 .. 0.06
    const angle = rand() < 0.25 ? rand() * 2 * Math.PI : 0;
    const ox = 0.05 * rand(), oy = 0.05 * rand();
    const ca = Math.cos(angle), sa = Math.sin(angle);
    const uvOf = new Map();
    const uvIndex = (x, y) => {
      const key = `${x},${y}`;
      let k = uvOf.get(key);
      if (k === undefined) {
        const u = x * cell, v = y * cell;
        k = mesh.vt.length;
        mesh.vt.push([Number(fmt(ox + ca * u - sa * v)), Number(fmt(oy + sa * u + ca * v))]);
        uvOf.set(key, k);
      }
      return k;
    };
    for (const [x, y, t] of p.tris) {
      const corners = t === 0 ? [[0, 0], [1, 0], [1, 1]] : [[0, 0], [1, 1], [0, 1]];
      mesh.faces.push({
        v: corners.map(([dx, dy]) => vid(p.i0 + x + dx, p.j0 + y + dy)),
        vt: corners.map(([dx, dy]) => uvIndex(x + dx, y + dy)),
        vn: null,
      });
    }
  }
  mesh.pieces = pieces.length;
  return mesh;
}

function split(mesh, target, seed) {
  const rand = rng(seed);
  const n = mesh.faces.length;
  if (mesh.faces.some((f) => !f.vt)) throw new Error('split: the input needs UVs on every face');
  // Face adjacency through shared (position) edges.
  const edgeFaces = new Map();
  mesh.faces.forEach((f, fi) => {
    for (let k = 0; k < 3; ++k) {
      const a = f.v[k], b = f.v[(k + 1) % 3];
      const key = a < b ? `${a},${b}` : `${b},${a}`;
      (edgeFaces.get(key) ?? edgeFaces.set(key, []).get(key)).push(fi);
    }
  });
  const nbr = Array.from({ length: n }, () => []);
  for (const list of edgeFaces.values())
    for (const a of list) for (const b of list) if (a !== b) nbr[a].push(b);
  // Regions grown from seeds, each at its own speed: a seed steps with probability speed.
  const region = new Int32Array(n).fill(-1);
  const fronts = [], speeds = [];
  const seeds = new Set();
  while (seeds.size < Math.min(target, n)) seeds.add(Math.floor(rand() * n));
  for (const s of seeds) {
    region[s] = fronts.length;
    fronts.push([s]);
    speeds.push(0.1 + 0.9 * rand() ** 2);
  }
  let active = true;
  while (active) {
    active = false;
    fronts.forEach((front, id) => {
      if (front.length === 0) return;
      active = true;
      if (rand() > speeds[id]) return;
      const next = [];
      for (const f of front)
        for (const g of nbr[f])
          if (region[g] < 0) {
            region[g] = id;
            next.push(g);
          }
      fronts[id] = next;
    });
  }
  for (let f = 0; f < n; ++f) if (region[f] < 0) region[f] = 0;  // unreachable faces (other components)
  // New UVs: each region's own copy of its corners' UVs, translated.
  const count = fronts.length;
  const box = Array.from({ length: count }, () => [Infinity, Infinity]);
  mesh.faces.forEach((f, fi) => {
    for (const t of f.vt) {
      const b = box[region[fi]];
      b[0] = Math.min(b[0], mesh.vt[t][0]);
      b[1] = Math.min(b[1], mesh.vt[t][1]);
    }
  });
  const shift = box.map(() => [0.1 * rand(), 0.1 * rand()]);
  const out = { v: mesh.v, vt: [], vn: mesh.vn, faces: [] };
  const uvOf = new Map();
  mesh.faces.forEach((f, fi) => {
    const id = region[fi];
    out.faces.push({
      v: f.v,
      vt: f.vt.map((t) => {
        const key = `${id}|${t}`;
        let k = uvOf.get(key);
        if (k === undefined) {
          k = out.vt.length;
          out.vt.push([Number(fmt(mesh.vt[t][0] - box[id][0] + shift[id][0])), Number(fmt(mesh.vt[t][1] - box[id][1] + shift[id][1]))]);
          uvOf.set(key, k);
        }
        return k;
      }),
      vn: f.vn,
    });
  });
  return out;
}

const args = parseArgs(process.argv.slice(2));
const mesh = args.mode === 'torus' ? torus(args.charts ?? 200, args.seed) : split(readObj(args.input), args.charts ?? 150, args.seed);
const uvs = mesh.vt.flat();
const cornerUv = mesh.faces.map((f) => f.vt);
const { count } = uvCharts(mesh);
writeObj(args.output, mesh, uvs, cornerUv, `gen_charts.mjs ${args.mode}, seed ${args.seed}: ${count} charts`);
console.log(`${args.output}: ${mesh.faces.length} faces, ${count} charts`);
