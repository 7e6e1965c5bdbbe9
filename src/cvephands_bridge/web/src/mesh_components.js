// Drops the small connected components of a mesh (specks: a voxel or two of skin-coloured noise
// that enough views agree on), as the HandMesher does for rviz (src/mesh/mesh_components.cpp, same
// rule: components with fewer than minTriangles triangles go; kept vertices and triangles keep
// their order).
export function removeSmallComponents(mesh, minTriangles = 64) {
  const { positions, normals, indices } = mesh;
  const n = positions.length / 3;
  const parent = new Uint32Array(n);
  for (let v = 0; v < n; ++v) parent[v] = v;
  const root = (v) => {
    while (parent[v] !== v) {
      parent[v] = parent[parent[v]];
      v = parent[v];
    }
    return v;
  };
  for (let t = 0; t + 2 < indices.length; t += 3) {
    const a = root(indices[t]);
    for (let k = 1; k < 3; ++k) {
      const b = root(indices[t + k]);
      if (a !== b) parent[b] = a;
    }
  }
  const triangles = new Uint32Array(n);
  for (let t = 0; t < indices.length; t += 3) ++triangles[root(indices[t])];
  let small = false;
  for (let v = 0; v < n && !small; ++v) small = parent[v] === v && triangles[v] > 0 && triangles[v] < minTriangles;
  if (!small) return mesh;
  const newIndex = new Int32Array(n).fill(-1);
  let kept = 0;
  for (let v = 0; v < n; ++v) if (triangles[root(v)] >= minTriangles) newIndex[v] = kept++;
  const p = new Float32Array(3 * kept);
  const nm = normals ? new Float32Array(3 * kept) : null;
  for (let v = 0; v < n; ++v) {
    const w = newIndex[v];
    if (w < 0) continue;
    p.set(positions.subarray(3 * v, 3 * v + 3), 3 * w);
    if (nm) nm.set(normals.subarray(3 * v, 3 * v + 3), 3 * w);
  }
  const out = [];
  for (let t = 0; t + 2 < indices.length; t += 3) {
    if (newIndex[indices[t]] < 0) continue;
    out.push(newIndex[indices[t]], newIndex[indices[t + 1]], newIndex[indices[t + 2]]);
  }
  return { positions: p, normals: nm, indices: Uint32Array.from(out) };
}
