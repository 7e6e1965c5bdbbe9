// Cross-check of the browser decoder and marching cubes against the C++ ones, on a fixture that
// test/test_web_decoder.cpp writes:  node cross_check.mjs DIR
// DIR holds one sequence, numbered NNNN: msg_NNNN.bin (a message to accept) with
// msg_NNNN.vol (the C++-decoded volume) and msg_NNNN.mesh (the C++ mesh: u32 vertex count,
// u32 triangle count, f32 positions, u32 indices, f32 normals), or bad_NNNN.bin (a message to
// reject) with bad_NNNN.txt (the C++ decoder's reason). One decoder reads the whole sequence in
// order, as a client would (rejections leave its references as they were). Prints one JSON
// line; exits 0 only if everything matches.
import fs from 'node:fs';
import path from 'node:path';

import { HandStreamDecoder } from '../src/hand_decoder.js';
import { marchingCubes } from '../src/marching_cubes.js';

function readMesh(file) {
  const b = fs.readFileSync(file);
  const nv = b.readUInt32LE(0);
  const nt = b.readUInt32LE(4);
  // Copies: the Buffer's offset in its pool need not be 4-byte aligned.
  const floats = (off, n) => new Float32Array(new Uint8Array(b.subarray(off, off + 4 * n)).buffer);
  return {
    positions: floats(8, 3 * nv),
    indices: new Uint32Array(new Uint8Array(b.subarray(8 + 12 * nv, 8 + 12 * (nv + nt))).buffer),
    normals: floats(8 + 12 * (nv + nt), 3 * nv),
  };
}

const maxAbsDiff = (a, b) => a.reduce((m, v, i) => Math.max(m, Math.abs(v - b[i])), 0);
const equal = (a, b) => a.length === b.length && a.every((v, i) => v === b[i]);

const dir = process.argv[2];
if (!dir) {
  console.error('usage: node cross_check.mjs FIXTURE_DIR');
  process.exit(2);
}
const entries = fs
  .readdirSync(dir)
  .map((f) => /^(msg|bad)_(\d+)\.bin$/.exec(f))
  .filter(Boolean)
  .sort((a, b) => Number(a[2]) - Number(b[2]));

const s = {
  messages: 0,
  decoded: 0,
  volumes_identical: 0,
  meshes_identical_topology: 0,
  max_vertex_error_m: 0,
  max_vertex_error_voxels: 0,
  max_normal_error: 0,
  bad: 0,
  rejected_bad: 0,
  reasons_identical: 0,
  decode_ms_mean: 0,
  mesh_ms_mean: 0,
  failures: [],
};
const decoder = new HandStreamDecoder();
let decodeMs = 0;
let meshMs = 0;
for (const [file, kind] of entries) {
  const stem = path.join(dir, file.slice(0, -4));
  const bytes = new Uint8Array(fs.readFileSync(`${stem}.bin`));
  const t0 = performance.now();
  const r = decoder.decode(bytes);
  decodeMs += performance.now() - t0;
  if (kind === 'bad') {
    ++s.bad;
    if (r.ok) {
      s.failures.push(`${file}: accepted`);
      continue;
    }
    ++s.rejected_bad;
    const want = fs.readFileSync(`${stem}.txt`, 'utf8');
    if (r.reason === want) ++s.reasons_identical;
    else s.failures.push(`${file}: reason "${r.reason}", C++ "${want}"`);
    continue;
  }
  ++s.messages;
  if (!r.ok) {
    s.failures.push(`${file}: rejected: ${r.reason}`);
    continue;
  }
  ++s.decoded;
  const f = r.frame;
  if (equal(f.data, fs.readFileSync(`${stem}.vol`))) ++s.volumes_identical;
  else s.failures.push(`${file}: volume differs`);
  const t1 = performance.now();
  const m = marchingCubes(f, { iso: f.isoByte + 0.5 });
  meshMs += performance.now() - t1;
  const want = readMesh(`${stem}.mesh`);
  if (m.positions.length !== want.positions.length || !equal(m.indices, want.indices)) {
    s.failures.push(
      `${file}: mesh ${m.positions.length / 3} vertices / ${m.indices.length / 3} triangles, ` +
        `C++ ${want.positions.length / 3} / ${want.indices.length / 3}` +
        (m.indices.length === want.indices.length ? ', indices differ' : ''),
    );
    continue;
  }
  ++s.meshes_identical_topology;
  const e = maxAbsDiff(m.positions, want.positions);
  s.max_vertex_error_m = Math.max(s.max_vertex_error_m, e);
  s.max_vertex_error_voxels = Math.max(s.max_vertex_error_voxels, e / f.voxelSize);
  s.max_normal_error = Math.max(s.max_normal_error, maxAbsDiff(m.normals, want.normals));
}
s.decode_ms_mean = Number((decodeMs / Math.max(1, s.messages + s.bad)).toFixed(3));
s.mesh_ms_mean = Number((meshMs / Math.max(1, s.decoded)).toFixed(3));
s.failures = s.failures.slice(0, 10);

const ok =
  s.messages > 0 &&
  s.volumes_identical === s.messages &&
  s.meshes_identical_topology === s.messages &&
  s.max_vertex_error_voxels <= 1e-4 &&
  s.max_normal_error <= 1e-5 &&
  s.rejected_bad === s.bad &&
  s.reasons_identical === s.bad;
console.log(JSON.stringify(s));
process.exit(ok ? 0 : 1);
