// Minimal Wavefront OBJ reading and writing for the packer comparison: positions, texture
// coordinates and normals as written in the file (kept as text, so a round trip does not
// change them), polygons fanned into triangles. Groups, materials and smoothing are dropped.
import { readFileSync, writeFileSync } from 'node:fs';

// Returns { v: [text], vt: [[u, v]], vn: [text], faces: [{ v: [i,j,k], vt: [..] | null, vn: [..] | null }] }
// with 0-based indices (negative OBJ indices resolved).
export function readObj(path) {
  const v = [], vt = [], vn = [], faces = [];
  const text = readFileSync(path, 'utf8');
  for (const raw of text.split('\n')) {
    const line = raw.trim();
    if (line === '' || line[0] === '#') continue;
    const parts = line.split(/\s+/);
    switch (parts[0]) {
      case 'v': v.push(parts.slice(1, 4).join(' ')); break;
      case 'vn': vn.push(parts.slice(1, 4).join(' ')); break;
      case 'vt': vt.push([Number(parts[1]), Number(parts[2] ?? 0)]); break;
      case 'f': {
        const corners = parts.slice(1).map((c) => {
          const [a, b, n] = c.split('/');
          const idx = (s, count) => {
            if (s === undefined || s === '') return -1;
            const k = parseInt(s, 10);
            return k < 0 ? count + k : k - 1;
          };
          return { v: idx(a, v.length), vt: idx(b, vt.length), vn: idx(n, vn.length) };
        });
        for (let k = 1; k + 1 < corners.length; ++k) {
          const tri = [corners[0], corners[k], corners[k + 1]];
          faces.push({
            v: tri.map((c) => c.v),
            vt: tri.every((c) => c.vt >= 0) ? tri.map((c) => c.vt) : null,
            vn: tri.every((c) => c.vn >= 0) ? tri.map((c) => c.vn) : null,
          });
        }
        break;
      }
      default: break;
    }
  }
  return { v, vt, vn, faces };
}

// Writes the mesh with new texture coordinates: uvs is a flat array [u0, v0, u1, v1, ...] and
// cornerUv[f][k] the index of face f's corner k in it.
export function writeObj(path, mesh, uvs, cornerUv, comment = '') {
  const out = [];
  if (comment) out.push(`# ${comment}`);
  out.push(`# ${mesh.v.length} vertices, ${mesh.faces.length} faces`);
  for (const p of mesh.v) out.push(`v ${p}`);
  for (let i = 0; i < uvs.length; i += 2) out.push(`vt ${uvs[i]} ${uvs[i + 1]}`);
  for (const n of mesh.vn) out.push(`vn ${n}`);
  mesh.faces.forEach((f, fi) => {
    const c = [0, 1, 2].map((k) => {
      const base = `${f.v[k] + 1}/${cornerUv[fi][k] + 1}`;
      return f.vn ? `${base}/${f.vn[k] + 1}` : base;
    });
    out.push(`f ${c.join(' ')}`);
  });
  writeFileSync(path, out.join('\n') + '\n');
}

// Charts as meso defines them (core/mesh.hpp, uv_charts): faces connected through edges whose
// two sides carry the same UVs (float32 values) at both ends. Returns { chart: Int32Array per
// face, count }, numbered by first face in face order.
export function uvCharts(mesh) {
  const n = mesh.faces.length;
  const parent = new Int32Array(n);
  for (let i = 0; i < n; ++i) parent[i] = i;
  const find = (x) => {
    while (parent[x] !== x) {
      parent[x] = parent[parent[x]];
      x = parent[x];
    }
    return x;
  };
  const f32 = (x) => Math.fround(x);
  const uvKey = (t) => `${f32(mesh.vt[t][0])},${f32(mesh.vt[t][1])}`;
  const edges = new Map();
  mesh.faces.forEach((f, fi) => {
    if (!f.vt) return;
    for (let k = 0; k < 3; ++k) {
      const a = f.v[k], b = f.v[(k + 1) % 3];
      if (a === b) continue;
      const [lo, hi, tlo, thi] = a < b ? [a, b, f.vt[k], f.vt[(k + 1) % 3]] : [b, a, f.vt[(k + 1) % 3], f.vt[k]];
      const key = `${lo},${hi}`;
      const side = { face: fi, uv: `${uvKey(tlo)};${uvKey(thi)}` };
      const list = edges.get(key);
      if (list) list.push(side);
      else edges.set(key, [side]);
    }
  });
  for (const list of edges.values()) {
    if (list.length !== 2) continue;  // boundary, or non-manifold (split apart by OpenMesh)
    if (list[0].uv !== list[1].uv) continue;  // a UV seam
    const a = find(list[0].face), b = find(list[1].face);
    if (a !== b) parent[Math.max(a, b)] = Math.min(a, b);
  }
  const chart = new Int32Array(n), label = new Int32Array(n).fill(-1);
  let count = 0;
  for (let f = 0; f < n; ++f) {
    const r = find(f);
    if (label[r] < 0) label[r] = count++;
    chart[f] = label[r];
  }
  return { chart, count };
}
