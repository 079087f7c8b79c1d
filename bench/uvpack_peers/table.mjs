#!/usr/bin/env node
// Prints the Markdown tables of bench/uvpack_peers.sh from its runs.jsonl: one line per
// packing, { input, charts, size, padding, packer: "meso" | "xatlas", variant, wall_ms,
// failed, pack_json, check_json, compare_json }: the packer's JSON report, the report of
// `meso uvpack check` on the result (same size and padding) and compare.mjs's.
import { readFileSync } from 'node:fs';

const runs = readFileSync(process.argv[2], 'utf8').split('\n').filter((l) => l.trim()).map((l) => {
  const r = JSON.parse(l);
  if (!r.failed) {
    r.pack = JSON.parse(readFileSync(r.pack_json, 'utf8'));
    r.check = JSON.parse(readFileSync(r.check_json, 'utf8'));
    r.compare = JSON.parse(readFileSync(r.compare_json, 'utf8'));
  }
  return r;
});
const variants = [...new Set(runs.filter((r) => r.packer === 'xatlas').map((r) => r.variant))];
const inputs = [...new Set(runs.map((r) => r.input))];
const qualities = [...new Set(runs.filter((r) => r.packer === 'meso').map((r) => r.variant))];
// meso's row in the comparison: its default preset when it ran, else the first one.
const mesoMain = qualities.includes('balanced') ? 'balanced' : qualities[0];
const find = (input, size, padding, packer, variant) =>
  runs.find((r) => r.input === input && r.size === size && r.padding === padding && r.packer === packer && r.variant === (packer === 'meso' ? variant ?? mesoMain : variant));

const pct = (x) => `${(100 * x).toFixed(1)} %`;
const secs = (ms) => `${(ms / 1000).toFixed(2)} s`;
// The checker's verdict: overlaps (exact), texels shared by two charts, chart pairs closer
// than the padding; and whether the charts survived (same count as the input).
function verdict(r, charts) {
  if (!r || r.failed) return 'failed';
  const c = r.check;
  const issues = [];
  if (c.overlap_pairs.length) issues.push(`${c.overlap_pairs.length} overlapping face pairs`);
  if (c.texels_shared) issues.push(`${c.texels_shared} shared texels`);
  if (c.padding_violations.length) issues.push(`${c.padding_violations.length} chart pairs < ${c.padding} texels apart (min ${Math.min(...c.padding_violations.map((g) => g.distance)).toFixed(2)})`);
  if (c.outside_faces.length) issues.push(`${c.outside_faces.length} faces outside [0,1]`);
  if (c.flipped_faces.length) issues.push(`${c.flipped_faces.length} flipped faces`);
  if (c.charts !== charts) issues.push(`${c.charts} charts (input ${charts})`);
  return issues.length ? issues.join(', ') : 'clean';
}
const util = (r) => (r && !r.failed ? r.check.utilization : NaN);
const coverage = (r) => (r && !r.failed ? r.check.texel_coverage : NaN);

const main = variants[0];
const lines = [];
lines.push(`### meso uvpack pack (--quality ${mesoMain}) vs xatlas (${main})`, '');
// meso --clamp: no border margin, as xatlas (whose atlases are right for clamp-to-edge sampling only).
const clampVariant = 'balanced --clamp';
const hasClamp = qualities.includes(clampVariant);
lines.push(`| input | charts | size | padding | meso utilization (texel coverage) | meso time (packings) | xatlas utilization (texel coverage) | xatlas time (packings; one packing) | utilization ratio meso / xatlas |${hasClamp ? ' meso --clamp utilization | ratio meso --clamp / xatlas |' : ''} meso check | xatlas check |`);
lines.push(`|---|---:|---:|---:|---:|---:|---:|---:|---:|${hasClamp ? '---:|---:|' : ''}---|---|`);
for (const input of inputs)
  for (const size of [...new Set(runs.filter((r) => r.input === input).map((r) => r.size))])
    for (const padding of [...new Set(runs.filter((r) => r.input === input && r.size === size).map((r) => r.padding))]) {
      const m = find(input, size, padding, 'meso');
      const x = find(input, size, padding, 'xatlas', main);
      const charts = m?.charts ?? x?.charts;
      const mt = m && !m.failed ? `${secs(m.wall_ms)} (${m.pack.attempts})` : '-';
      const xt = x && !x.failed ? `${secs(x.wall_ms)} (${x.pack.attempts}; ${secs(x.pack.ms.final_pack)})` : '-';
      const k = hasClamp ? find(input, size, padding, 'meso', clampVariant) : null;
      const kc = hasClamp ? ` ${pct(util(k))}${verdict(k, charts) === 'clean' ? '' : ' **' + verdict(k, charts) + '**'} | ${(util(k) / util(x)).toFixed(3)} |` : '';
      lines.push(`| ${input} | ${charts} | ${size} | ${padding} | ${pct(util(m))} (${pct(coverage(m))}) | ${mt} | ${pct(util(x))} (${pct(coverage(x))}) | ${xt} | ${(util(m) / util(x)).toFixed(3)} |${kc} ${verdict(m, charts)} | ${verdict(x, charts)} |`);
    }

lines.push('', '### meso\'s quality presets (utilization / texel coverage / wall time (packings))', '');
lines.push(`| input | size | padding | ${qualities.map((q) => `meso ${q}`).join(' | ')} |`);
lines.push(`|---|---:|---:|${qualities.map(() => '---:').join('|')}|`);
for (const input of inputs)
  for (const size of [...new Set(runs.filter((r) => r.input === input).map((r) => r.size))])
    for (const padding of [...new Set(runs.filter((r) => r.input === input && r.size === size).map((r) => r.padding))]) {
      const cell = (r) => (r && !r.failed ? `${pct(util(r))} / ${pct(coverage(r))} / ${secs(r.wall_ms)} (${r.pack.attempts})${verdict(r, r.charts) === 'clean' ? '' : ' **' + verdict(r, r.charts) + '**'}` : 'failed');
      lines.push(`| ${input} | ${size} | ${padding} | ${qualities.map((q) => cell(find(input, size, padding, 'meso', q))).join(' | ')} |`);
    }

lines.push('', '### xatlas variants (utilization per meso\'s checker / wall time; "clean" = no overlap, no shared texel, no padding violation)', '');
lines.push(`| input | size | padding | meso | ${variants.map((v) => `xatlas ${v}`).join(' | ')} |`);
lines.push(`|---|---:|---:|---:|${variants.map(() => '---:').join('|')}|`);
for (const input of inputs)
  for (const size of [...new Set(runs.filter((r) => r.input === input).map((r) => r.size))])
    for (const padding of [...new Set(runs.filter((r) => r.input === input && r.size === size).map((r) => r.padding))]) {
      const m = find(input, size, padding, 'meso');
      const charts = m?.charts;
      const cell = (r) => (r && !r.failed ? `${pct(util(r))} / ${secs(r.wall_ms)}${verdict(r, charts) === 'clean' ? '' : ' **' + verdict(r, charts) + '**'}` : 'failed');
      lines.push(`| ${input} | ${size} | ${padding} | ${cell(m)} | ${variants.map((v) => cell(find(input, size, padding, 'xatlas', v))).join(' | ')} |`);
    }

lines.push('', '### What the packing did to the charts: common scale (texels per input UV unit), per-chart scale factor, mirrored charts', '');
lines.push('(per chart: its linear scale in the result / the packer\'s common scale, min / median / max over the charts; mirrored: charts whose UV winding was reversed)', '');
lines.push(`| input | size | padding | meso | ${variants.map((v) => `xatlas ${v}`).join(' | ')} |`);
lines.push(`|---|---:|---:|---|${variants.map(() => '---|').join('')}`);
for (const input of inputs)
  for (const size of [...new Set(runs.filter((r) => r.input === input).map((r) => r.size))])
    for (const padding of [...new Set(runs.filter((r) => r.input === input && r.size === size).map((r) => r.padding))]) {
      const cell = (r) => {
        if (!r || r.failed) return 'failed';
        const s = r.compare.scale_rel;
        return `${r.pack.scale.toFixed(1)}; ${s.min.toFixed(3)} / ${s.median.toFixed(3)} / ${s.max.toFixed(3)}; ${r.compare.mirrored} mirrored`;
      };
      lines.push(`| ${input} | ${size} | ${padding} | ${cell(find(input, size, padding, 'meso'))} | ${variants.map((v) => cell(find(input, size, padding, 'xatlas', v))).join(' | ')} |`);
    }
console.log(lines.join('\n'));
