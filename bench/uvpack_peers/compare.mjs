#!/usr/bin/env node
// What a packer did to each chart: node compare.mjs IN.obj PACKED.obj SIZE SCALE
// Prints JSON { charts, mirrored, scale_rel: { min, median, max } }: charts (as meso counts
// them, on IN) whose UV winding the packing reversed (a mirror image rather than a rotation),
// and per chart the linear scale it got (sqrt of the UV area ratio, in texels per input UV
// unit) relative to SCALE, the packer's common scale. Faces must correspond one to one.
import { readObj, uvCharts } from './obj.mjs';

const [inPath, outPath, sizeArg, scaleArg] = process.argv.slice(2);
const a = readObj(inPath), b = readObj(outPath);
if (a.faces.length !== b.faces.length) throw new Error('the meshes do not have the same faces');
const size = Number(sizeArg), scale = Number(scaleArg);
const { chart, count } = uvCharts(a);
const signed = (m, f) => {
  const [p, q, r] = f.vt.map((t) => m.vt[t]);
  return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
};
const sa = new Float64Array(count), sb = new Float64Array(count), aa = new Float64Array(count), ab = new Float64Array(count);
a.faces.forEach((f, i) => {
  const x = signed(a, f), y = signed(b, b.faces[i]);
  sa[chart[i]] += x;
  sb[chart[i]] += y;
  aa[chart[i]] += Math.abs(x);
  ab[chart[i]] += Math.abs(y);
});
let mirrored = 0;
const rel = [];
for (let c = 0; c < count; ++c) {
  if (sa[c] !== 0 && sb[c] !== 0 && Math.sign(sa[c]) !== Math.sign(sb[c])) ++mirrored;
  if (aa[c] > 0) rel.push((Math.sqrt(ab[c] / aa[c]) * size) / scale);
}
rel.sort((p, q) => p - q);
console.log(JSON.stringify({
  charts: count,
  mirrored,
  scale_rel: rel.length ? { min: rel[0], median: rel[rel.length >> 1], max: rel[rel.length - 1] } : null,
}));
