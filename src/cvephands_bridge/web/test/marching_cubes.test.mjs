// Marching cubes: the generated case table, topology (watertight, Euler characteristic,
// winding) and geometry (distance to the analytic iso-surface, normals, enclosed volume) on a
// sphere, crack-freeness on random fields that meet every cell case, one vertex per crossed
// grid edge at the interpolated crossing, edge cases. Sameness with the C++ mesh (vertex order,
// positions) is cross_check.mjs's job.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { CASES, marchingCubes } from '../src/marching_cubes.js';
import { random } from './random.mjs';

const ISO = 153.5;
// Cell corners and edges (Bourke's numbering, as marching_cubes_cases.h).
const CORNER = [
  [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1],
];
const EDGE = [
  [0, 1], [1, 2], [3, 2], [0, 3], [4, 5], [5, 6], [7, 6], [4, 7], [0, 4], [1, 5], [2, 6], [3, 7],
];

// Bytes round(255 * clamp(0.5 - sd / width)) at the voxel centres (synthetic_volumes.h's
// sampleSdf).
function sampleSdf(dims, origin, voxelSize, sd, width) {
  const [nx, ny, nz] = dims;
  const data = new Uint8Array(nx * ny * nz);
  for (let z = 0, i = 0; z < nz; ++z)
    for (let y = 0; y < ny; ++y)
      for (let x = 0; x < nx; ++x, ++i) {
        const p = [x, y, z].map((v, a) => origin[a] + voxelSize * (v + 0.5));
        data[i] = Math.round(255 * Math.min(1, Math.max(0, 0.5 - sd(p) / width)));
      }
  return { data, dims, origin, voxelSize };
}

// Each sample above the iso with probability 1/2 (every cell case equally likely): 0 / 255, or
// any byte on its side.
function randomVolume(dims, seed, binary) {
  const rnd = random(seed);
  const side = (up) => (binary ? 255 * up : up ? 154 + rnd() * 102 : rnd() * 154);
  const data = new Uint8Array(dims[0] * dims[1] * dims[2]).map(() => side(rnd() < 0.5));
  return { data, dims, origin: [0.1, -0.2, 0.3], voxelSize: 0.004 };
}

const vertex = (m, i) => [m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]];
const sub = (a, b) => a.map((v, i) => v - b[i]);
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [
  a[1] * b[2] - a[2] * b[1],
  a[2] * b[0] - a[0] * b[2],
  a[0] * b[1] - a[1] * b[0],
];

// Edges used by one / more than two triangles, edges two triangles traverse the same way,
// degenerate triangles, unreferenced vertices, components (via shared vertices), Euler.
function topology(m) {
  const nv = m.positions.length / 3;
  const nf = m.indices.length / 3;
  const edges = new Map();
  const parent = Array.from({ length: nv }, (_, i) => i);
  const find = (a) => (parent[a] === a ? a : (parent[a] = find(parent[a])));
  const used = new Uint8Array(nv);
  let degenerate = 0;
  for (let f = 0; f < nf; ++f) {
    const v = [m.indices[3 * f], m.indices[3 * f + 1], m.indices[3 * f + 2]];
    if (v[0] === v[1] || v[1] === v[2] || v[0] === v[2]) ++degenerate;
    for (let i = 0; i < 3; ++i) {
      const a = v[i];
      const b = v[(i + 1) % 3];
      used[a] = 1;
      parent[find(a)] = find(b);
      const key = Math.min(a, b) * nv + Math.max(a, b);
      const e = edges.get(key) ?? [0, 0];
      e[0] += 1;
      e[1] += a < b ? 1 : 0;
      edges.set(key, e);
    }
  }
  const t = { degenerate, boundary: 0, nonmanifold: 0, misoriented: 0 };
  t.unreferenced = t.components = 0;
  for (const [uses, forward] of edges.values()) {
    if (uses === 1) ++t.boundary;
    if (uses > 2) ++t.nonmanifold;
    if (uses === 2 && forward !== 1) ++t.misoriented;
  }
  for (let i = 0; i < nv; ++i) {
    if (!used[i]) ++t.unreferenced;
    else if (find(i) === i) ++t.components;
  }
  t.euler = nv - t.unreferenced - edges.size + nf;
  t.watertight = t.boundary === 0 && t.nonmanifold === 0 && t.misoriented === 0 && degenerate === 0;
  return t;
}

// Lattice of a volume with its ring of zeros (lattice index = voxel index + 1).
function lattice({ data, dims }) {
  const m = dims.map((d) => d + 2);
  const value = (p) => {
    const [x, y, z] = p.map((v) => v - 1);
    if (x < 0 || y < 0 || z < 0 || x >= dims[0] || y >= dims[1] || z >= dims[2]) return 0;
    return data[x + dims[0] * (y + dims[1] * z)];
  };
  const inside = (p) => p.every((v, a) => v >= 0 && v < m[a]);
  return { m, value, inside, above: (p) => value(p) > ISO };
}

test('case table: at most 5 triangles, exactly the crossed edges of each case', () => {
  assert.equal(CASES.count.length, 256);
  for (let c = 0; c < 256; ++c) {
    const isCrossed = (e) => ((c >> EDGE[e][0]) ^ (c >> EDGE[e][1])) & 1;
    const crossed = new Set([...EDGE.keys()].filter(isCrossed));
    const used = new Set(CASES.edges.subarray(15 * c, 15 * c + 3 * CASES.count[c]));
    assert.ok(CASES.count[c] <= 5);
    assert.deepEqual(used, crossed, `case ${c}`);
  }
});

test('sphere: closed, accurate, outward', () => {
  const centre = [20.3, 19.6, 20.1];
  const radius = 12;
  const width = 3; // voxels: the probability ramp
  const sd = (p) => Math.hypot(p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]) - radius;
  const v = sampleSdf([41, 40, 42], [0, 0, 0], 1, sd, width);
  const m = marchingCubes(v);
  const t = topology(m);
  assert.ok(t.watertight, JSON.stringify(t));
  assert.equal(t.euler, 2);
  assert.equal(t.components, 1);
  assert.equal(t.unreferenced, 0);

  // The vertices against the level set the iso selects (sd = width * (0.5 - iso / 255)): linear
  // interpolation of a linear ramp is exact up to the sphere's curvature along an edge (~1/(8R)
  // voxel) and byte rounding (~width / 510): the C++ test's bounds.
  const level = width * (0.5 - ISO / 255);
  const n = m.positions.length / 3;
  let max = 0;
  let mean = 0;
  for (let i = 0; i < n; ++i) {
    const e = Math.abs(sd(vertex(m, i)) - level);
    max = Math.max(max, e);
    mean += e / n;
  }
  assert.ok(max < 0.05, `max ${max} voxel`);
  assert.ok(mean < 0.02, `mean ${mean} voxel`);

  // Enclosed volume (divergence theorem) within 1 % of the ball's.
  let volume = 0;
  let inward = 0;
  for (let f = 0; f < m.indices.length / 3; ++f) {
    const [a, b, c] = [0, 1, 2].map((k) => vertex(m, m.indices[3 * f + k]));
    volume += dot(a, cross(b, c)) / 6;
    const centroid = [0, 1, 2].map((k) => (a[k] + b[k] + c[k]) / 3);
    if (dot(cross(sub(b, a), sub(c, a)), sub(centroid, centre)) <= 0) ++inward;
  }
  const r = radius + level;
  assert.ok(Math.abs(volume / ((4 / 3) * Math.PI * r ** 3) - 1) < 0.01, `volume ${volume}`);
  assert.equal(inward, 0, 'triangles wound clockwise seen from outside');

  // Unit normals along the ramp's gradient: radial within 5 degrees.
  let offRadial = 0;
  for (let i = 0; i < n; ++i) {
    const nrm = [0, 1, 2].map((k) => m.normals[3 * i + k]);
    assert.ok(Math.abs(Math.hypot(...nrm) - 1) < 1e-5);
    const radial = sub(vertex(m, i), centre);
    if (dot(nrm, radial) < Math.cos((5 * Math.PI) / 180) * Math.hypot(...radial)) ++offRadial;
  }
  assert.equal(offRadial, 0, 'normals more than 5 degrees off the sphere normal');
});

test('random fields meeting every cell case give watertight meshes', () => {
  for (const binary of [true, false]) {
    const v = randomVolume([16, 15, 14], binary ? 3 : 4, binary);
    const lat = lattice(v);
    const seen = new Set();
    for (let z = 0; z + 1 < lat.m[2]; ++z)
      for (let y = 0; y + 1 < lat.m[1]; ++y)
        for (let x = 0; x + 1 < lat.m[0]; ++x) {
          const corner = ([a, b, d], k) => lat.above([x + a, y + b, z + d]) << k;
          seen.add(CORNER.reduce((c, o, k) => c | corner(o, k), 0));
        }
    assert.equal(seen.size, 256);
    const t = topology(marchingCubes(v));
    assert.ok(t.watertight, JSON.stringify(t));
    assert.equal(t.unreferenced, 0);
  }
});

test('one vertex per crossed grid edge, at the interpolated crossing', () => {
  const v = randomVolume([9, 8, 7], 11, false);
  const m = marchingCubes(v);
  const lat = lattice(v);
  let crossed = 0;
  for (let z = 0; z < lat.m[2]; ++z)
    for (let y = 0; y < lat.m[1]; ++y)
      for (let x = 0; x < lat.m[0]; ++x)
        for (let a = 0; a < 3; ++a) {
          const q = [x, y, z];
          ++q[a];
          if (lat.inside(q) && lat.above([x, y, z]) !== lat.above(q)) ++crossed;
        }
  assert.equal(m.positions.length / 3, crossed);
  const edges = new Set();
  let bad = 0;
  for (let i = 0; i < crossed; ++i) {
    // Lattice coordinates: two are integers, the third carries the crossing.
    const u = vertex(m, i).map((c, a) => (c - v.origin[a]) / v.voxelSize + 0.5);
    const axis = u.findIndex((c) => Math.abs(c - Math.round(c)) > 1e-3);
    const p = u.map((c, a) => (a === axis ? Math.floor(c) : Math.round(c)));
    const q = p.slice();
    ++q[axis];
    const [fa, fb] = [lat.value(p), lat.value(q)];
    const key = `${p}:${axis}`;
    const t = (ISO - fa) / (fb - fa);
    if (axis < 0 || lat.above(p) === lat.above(q) || Math.abs(u[axis] - p[axis] - t) > 1e-4) ++bad;
    if (edges.has(key)) ++bad;
    edges.add(key);
  }
  assert.equal(bad, 0, 'vertices off their crossed edge or sharing one');
});

test('edge cases: empty volumes, one voxel, a full box capped at the border, bad input', () => {
  const volume = (data, dims, origin, voxelSize) => ({ data, dims, origin, voxelSize });
  const below = volume(new Uint8Array(27).fill(153), [3, 3, 3], [0, 0, 0], 1);
  assert.equal(marchingCubes(volume(new Uint8Array(0), [0, 4, 4], [0, 0, 0], 1)).indices.length, 0);
  const empty = marchingCubes(below);
  assert.deepEqual([empty.positions.length, empty.normals.length, empty.indices.length], [0, 0, 0]);

  const one = { ...below, data: below.data.map((_, i) => (i === 13 ? 154 : 0)) };
  const octahedron = marchingCubes(one);
  assert.deepEqual([octahedron.positions.length / 3, octahedron.indices.length / 3], [6, 8]);
  assert.equal(topology(octahedron).euler, 2);

  // All above: the box closed where the samples end, (255 - iso) / 255 voxel outside the outer
  // voxel centres.
  const full = volume(new Uint8Array(60).fill(255), [3, 4, 5], [1, 2, 3], 0.5);
  const box = marchingCubes(full, { computeNormals: false });
  assert.equal(box.normals, null);
  const t = topology(box);
  assert.ok(t.watertight);
  assert.equal(t.euler, 2);
  const inset = 0.5 - (255 - ISO) / 255;
  for (let a = 0; a < 3; ++a) {
    const c = Array.from({ length: box.positions.length / 3 }, (_, i) => box.positions[3 * i + a]);
    assert.ok(Math.abs(Math.min(...c) - (full.origin[a] + inset * 0.5)) < 1e-6);
    assert.ok(Math.abs(Math.max(...c) - (full.origin[a] + (full.dims[a] - inset) * 0.5)) < 1e-6);
  }

  assert.throws(() => marchingCubes(below, { iso: 255 }), RangeError);
  assert.throws(() => marchingCubes({ ...below, dims: [3, 3, 2] }), RangeError);
  assert.throws(() => marchingCubes({ ...below, voxelSize: 0 }), RangeError);
});
