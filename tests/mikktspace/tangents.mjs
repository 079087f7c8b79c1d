// Runs the MikkTSpace reference on a triangle list and prints its per-corner tangents.
//
// Usage: node tangents.mjs IN.json
//   IN.json: {"positions": [x,y,z, ...], "normals": [x,y,z, ...], "uvs": [u,v, ...]},
//   3 corners per triangle, unindexed (MikkTSpace welds corners whose position, normal and
//   UV are all equal). UVs as meso stores them (OpenGL: v grows up).
// Prints one line per corner, in input order: "tx ty tz w", w = +1 or -1 (the sign of the
// bitangent, b = w * cross(n, t)), each number in the shortest form that reads back to the
// same float32. Exit code 2 on bad usage or input, 3 when the `mikktspace` package is
// missing (run `npm ci` here, or scripts/setup-deps).
//
// The reference is the npm package `mikktspace` (a WebAssembly build of the Rust port of
// Morten Mikkelsen's mikktspace.c, genTangSpaceDefault: no angular splitting).
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);

function fail(code, message) {
  process.stderr.write(`tangents.mjs: ${message}\n`);
  process.exit(code);
}

if (process.argv.length !== 3) fail(2, 'usage: node tangents.mjs IN.json');

let generateTangents;
try {
  // The package's CommonJS entry loads the WebAssembly synchronously.
  ({ generateTangents } = require('mikktspace'));
} catch (e) {
  fail(3, `cannot load the npm package "mikktspace" (${e.code || e.message}); run "npm ci" in ${new URL('.', import.meta.url).pathname}`);
}

let input;
try {
  input = JSON.parse(readFileSync(process.argv[2], 'utf8'));
} catch (e) {
  fail(2, `${process.argv[2]}: ${e.message}`);
}
const positions = Float32Array.from(input.positions ?? []);
const normals = Float32Array.from(input.normals ?? []);
const uvs = Float32Array.from(input.uvs ?? []);
const corners = positions.length / 3;
if (positions.length % 9 !== 0 || normals.length !== positions.length || uvs.length !== 2 * corners) {
  fail(2, `${process.argv[2]}: need 9 position floats per triangle and as many normal floats, 6 UV floats per triangle`);
}

const tangents = corners > 0 ? generateTangents(positions, normals, uvs) : new Float32Array(0);
if (tangents.length !== 4 * corners) fail(4, `the reference returned ${tangents.length} floats for ${corners} corners`);

const lines = [];
for (let c = 0; c < corners; ++c) lines.push(Array.from(tangents.subarray(4 * c, 4 * c + 4)).join(' '));
process.stdout.write(lines.length ? lines.join('\n') + '\n' : '');
