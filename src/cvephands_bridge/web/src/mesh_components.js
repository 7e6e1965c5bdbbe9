// Drops the connected components of a hand's mesh that HandMesher drops for rviz and the CVE
// (src/mesh/mesh_components.cpp keepHandComponents, same rule): specks (components with fewer
// than minTriangles triangles: a voxel or two of skin-coloured noise that enough views agree on)
// and, with keepRadius > 0, the components with no vertex within keepRadius of `centre` (the
// face, the other hand or skin-coloured clutter in the hand's cube). Kept vertices and
// triangles keep their order.
export function keepHandComponents(mesh, minTriangles = 64, centre = null, keepRadius = 0) {
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
  const byDistance = centre !== null && keepRadius > 0;
  const nearest = new Float64Array(n).fill(Infinity);
  if (byDistance) {
    for (const v of indices) {
      const dx = positions[3 * v] - centre[0], dy = positions[3 * v + 1] - centre[1];
      const dz = positions[3 * v + 2] - centre[2];
      const r = root(v);
      nearest[r] = Math.min(nearest[r], Math.sqrt(dx * dx + dy * dy + dz * dz));
    }
  }
  const keep = (r) => triangles[r] >= minTriangles && (!byDistance || nearest[r] <= keepRadius);
  let drop = false;
  for (let v = 0; v < n && !drop; ++v) drop = parent[v] === v && triangles[v] > 0 && !keep(v);
  if (!drop) return mesh;
  const newIndex = new Int32Array(n).fill(-1);
  let kept = 0;
  for (let v = 0; v < n; ++v) if (keep(root(v))) newIndex[v] = kept++;
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

// Specks only (keepHandComponents without the distance rule).
export function removeSmallComponents(mesh, minTriangles = 64) {
  return keepHandComponents(mesh, minTriangles);
}
