// The hand mesh's component rule (keepHandComponents, as the C++ HandMesher's): two balls in one
// cube, a one-voxel speck; specks go, and of the balls only the one near the hand's centre stays.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { marchingCubes } from '../src/marching_cubes.js';
import { keepHandComponents, removeSmallComponents } from '../src/mesh_components.js';

// 1 cm voxels, 30^3; balls of radius 4 voxels centred at voxels 8 and 22 on each axis (0.085 and
// 0.225 m), a single voxel at (27, 2, 2).
function twoBallsAndSpeck() {
  const n = 30;
  const data = new Uint8Array(n * n * n);
  for (let z = 0, i = 0; z < n; ++z)
    for (let y = 0; y < n; ++y)
      for (let x = 0; x < n; ++x, ++i)
        for (const c of [8, 22])
          if (Math.hypot(x - c, y - c, z - c) < 4) data[i] = 255;
  data[27 + n * (2 + n * 2)] = 255;
  return marchingCubes({ data, dims: [n, n, n], origin: [0, 0, 0], voxelSize: 0.01 },
    { iso: 153.5, computeNormals: true });
}

const near = (mesh, c, r) => {
  let k = 0;
  for (let v = 0; v < mesh.positions.length / 3; ++v)
    k += Math.hypot(mesh.positions[3 * v] - c[0], mesh.positions[3 * v + 1] - c[1],
      mesh.positions[3 * v + 2] - c[2]) < r;
  return k;
};

test('specks go, both balls stay without a radius', () => {
  const all = twoBallsAndSpeck();
  const m = removeSmallComponents(all, 64);
  assert.equal(m.indices.length, all.indices.length - 8 * 3);  // the speck's octahedron
  assert.equal(m.normals.length, m.positions.length);
});

test('the ball near the hand stays, the far one goes', () => {
  const a = [0.085, 0.085, 0.085], b = [0.225, 0.225, 0.225];
  const all = twoBallsAndSpeck();
  const m = keepHandComponents(all, 64, a, 0.08);
  const vertices = m.positions.length / 3;
  assert.ok(vertices > 0);
  assert.equal(near(m, a, 0.05), vertices);
  const other = keepHandComponents(all, 64, [0.295, 0.225, 0.225], 0.08);  // 3 cm off ball b
  assert.equal(near(other, b, 0.05), other.positions.length / 3);
  // Nothing within the radius: an empty mesh.
  const none = keepHandComponents(all, 64, [0.155, 0.155, 0.155], 0.02);
  assert.equal(none.indices.length, 0);
  assert.equal(none.positions.length, 0);
});
