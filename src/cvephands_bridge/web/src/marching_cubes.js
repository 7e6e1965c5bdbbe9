// Marching cubes on a hand probability volume: a port of MarchingCubes::extract
// (src/mesh/marching_cubes.cpp) in its probabilistic, close_at_border mode. Same mesh as C++: one
// vertex per crossed grid edge, numbered in the same order, the same triangles from the same
// case table (generated here by the rules of src/mesh/marching_cubes_cases.cpp), positions and
// normals computed with C++'s float / double steps, so they come out bit-identical (as long as the
// C++ build does not contract them into FMAs: x86-64 without -march).
//
// Samples sit at the voxel centres, origin + (index + 0.5) * voxelSize; outside the volume they
// count as 0, so a hand touching a face of its cube is capped half a voxel outside it. Triangles
// are counter-clockwise seen from outside; normals point outward (down the probability gradient).

// ---- case table (marching_cubes_cases.cpp) ----------------------------------------------------
// Corners and edges in Lorensen & Cline / Bourke numbering; bit k of a case = corner k above iso.

const CORNER = [
  [0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1],
];
const EDGE = [
  [0, 1], [1, 2], [3, 2], [0, 3], [4, 5], [5, 6], [7, 6], [4, 7], [0, 4], [1, 5], [2, 6], [3, 7],
];
const MAX_TRIANGLES_PER_CELL = 5;

// Faces are numbered 2 * axis + side (side 1: the face at coordinate 1).
const onFace = (corner, face) => CORNER[corner][face >> 1] === (face & 1);
const edgeOnFace = (e, face) => onFace(EDGE[e][0], face) && onFace(EDGE[e][1], face);
function edgesShareFace(a, b) {
  for (let f = 0; f < 6; ++f) if (edgeOnFace(a, f) && edgeOnFace(b, f)) return true;
  return false;
}
function sharedCorner(a, b) {
  for (const i of EDGE[a]) if (EDGE[b].includes(i)) return i;
  return -1;
}
const edgeMid = (e) => [0, 1, 2].map((i) => 0.5 * (CORNER[EDGE[e][0]][i] + CORNER[EDGE[e][1]][i]));
const sub = (a, b) => a.map((v, i) => v - b[i]);
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [
  a[1] * b[2] - a[2] * b[1],
  a[2] * b[0] - a[0] * b[2],
  a[0] * b[1] - a[1] * b[0],
];

// The contour segments [from edge, to edge] of case c on face f, oriented so that, seen from
// outside the cell, the corners above the iso lie to the right: the loops then give triangles
// counter-clockwise seen from below the iso (outside the surface). An ambiguous face (two
// diagonal corners above) always separates the above corners, so both cells sharing a face cut
// it identically (no cracks).
function faceSegments(c, f, out) {
  const inside = (k) => (c >> k) & 1;
  const corners = [0, 1, 2, 3, 4, 5, 6, 7].filter((k) => onFace(k, f));
  const edges = [...Array(12).keys()].filter((e) => edgeOnFace(e, f));
  const nIn = corners.reduce((s, k) => s + inside(k), 0);
  if (nIn === 0 || nIn === 4) return;
  const around = (k) => edges.filter((e) => EDGE[e][0] === k || EDGE[e][1] === k);
  const pairs = [];
  if (nIn === 1 || nIn === 3) {
    const lone = nIn === 1 ? 1 : 0; // cut off the lone corner
    for (const k of corners) if (inside(k) === lone) pairs.push(around(k));
  } else {
    const crossed = edges.filter((e) => inside(EDGE[e][0]) !== inside(EDGE[e][1]));
    if (crossed.length === 2) pairs.push(crossed); // two adjacent corners above: one straight cut
    else for (const k of corners) if (inside(k)) pairs.push(around(k)); // ambiguous face
  }
  const normal = [0, 0, 0];
  normal[f >> 1] = f & 1 ? 1 : -1; // outward from the cell
  for (const [p0, p1] of pairs) {
    let ref = sharedCorner(p0, p1);
    if (ref < 0) ref = corners[0]; // a straight cut: any corner tells the sides apart
    const a = edgeMid(p0);
    const b = edgeMid(p1);
    const left = cross(normal, sub(b, a));
    const refLeft = dot(left, sub(CORNER[ref], a.map((v, i) => 0.5 * (v + b[i])))) > 0;
    const keep = inside(ref) ? !refLeft : refLeft; // above corners to the right
    out.push(keep ? [p0, p1] : [p1, p0]);
  }
}

// Triangulates loop v with no diagonal joining two vertices on a common cell face (the
// neighbour across that face could choose it too: an edge of four triangles). Fans first (apex
// 0..n-1), then any triangulation.
function triangulate(v, tris) {
  const n = v.length;
  for (let apex = 0; apex < n; ++apex) {
    let ok = true;
    for (let j = 2; j <= n - 2 && ok; ++j) ok = !edgesShareFace(v[apex], v[(apex + j) % n]);
    if (!ok) continue;
    for (let j = 1; j <= n - 2; ++j) tris.push(v[apex], v[(apex + j) % n], v[(apex + j + 1) % n]);
    return true;
  }
  if (n === 3) {
    tris.push(...v);
    return true;
  }
  // Triangle (v0, v1, vk) splits the polygon into two smaller ones.
  for (let k = 2; k < n; ++k) {
    if (k > 2 && edgesShareFace(v[1], v[k])) continue;
    if (k < n - 1 && edgesShareFace(v[0], v[k])) continue;
    const t = [v[0], v[1], v[k]];
    const right = v.slice(1, k + 1); // v1..vk
    const left = [...v.slice(k), v[0]]; // vk..v(n-1), v0
    if (right.length >= 3 && !triangulate(right, t)) continue;
    if (left.length >= 3 && !triangulate(left, t)) continue;
    tris.push(...t);
    return true;
  }
  return false;
}

// Per case: triangle count and 3 cell edges per triangle (MAX_TRIANGLES_PER_CELL slots).
function buildCaseTable() {
  const count = new Uint8Array(256);
  const edges = new Uint8Array(256 * 3 * MAX_TRIANGLES_PER_CELL);
  for (let c = 0; c < 256; ++c) {
    const segs = [];
    for (let f = 0; f < 6; ++f) faceSegments(c, f, segs);
    // Every crossed edge lies on two faces: it ends one segment and starts the next.
    const next = new Array(12).fill(-1);
    for (const [from, to] of segs) {
      if (next[from] !== -1) throw new Error('marching cubes table: edge starts twice');
      next[from] = to;
    }
    const tris = [];
    const seen = new Array(12).fill(false);
    for (let e = 0; e < 12; ++e) {
      if (next[e] < 0 || seen[e]) continue;
      const loop = [];
      for (let v = e; !seen[v]; v = next[v]) {
        if (next[v] < 0) throw new Error('marching cubes table: open contour');
        seen[v] = true;
        loop.push(v);
      }
      if (!triangulate(loop, tris))
        throw new Error('marching cubes table: loop without a valid triangulation');
    }
    if (tris.length > 3 * MAX_TRIANGLES_PER_CELL)
      throw new Error('marching cubes table: too many triangles in a cell');
    count[c] = tris.length / 3;
    edges.set(tris, c * 3 * MAX_TRIANGLES_PER_CELL);
  }
  return { count, edges };
}

export const CASES = buildCaseTable();

// ---- extraction -------------------------------------------------------------------------------

// Case of a cell from its two corner columns (bits: rows (q, r), (q+1, r), (q, r+1), (q+1, r+1)),
// the column at x in the low nibble, at x + 1 in the high one.
const CASE_OF_COLUMNS = (() => {
  const t = new Uint8Array(256);
  const low = [0, 3, 4, 7]; // corners at x of the four rows
  const high = [1, 2, 5, 6]; // at x + 1
  for (let i = 0; i < 256; ++i)
    for (let row = 0; row < 4; ++row)
      t[i] |= (((i >> row) & 1) << low[row]) | (((i >> (4 + row)) & 1) << high[row]);
  return t;
})();

// Growable typed array (output sizes are known only at the end).
class Growable {
  constructor(Type, capacity) {
    this.a = new Type(capacity);
    this.n = 0;
  }
  reserve(k) {
    if (this.n + k <= this.a.length) return;
    const b = new this.a.constructor(Math.max(2 * this.a.length, this.n + k));
    b.set(this.a);
    this.a = b;
  }
  result() {
    return this.a.slice(0, this.n);
  }
}

const f32 = Math.fround;
const TINY_GRADIENT2 = f32(1e-12); // C++: g2 > 1e-12f

// Scratch of the last dims meshed (a hand stream repeats its dims: ~2 MB not allocated and
// zeroed per frame). Only the samples' part is written, so the zero rings stay zero.
let scratch = null;
function scratchFor(nx, ny, nz) {
  if (scratch && scratch.nx === nx && scratch.ny === ny && scratch.nz === nz) return scratch;
  // The lattice the cells join: the voxel centres and a ring of zero samples around them
  // (lattice index = voxel index + 1). The samples are copied with two rings of zeros, so the
  // central differences at the outer ring read zeros without bounds checks.
  const mx = nx + 2;
  const my = ny + 2;
  const mz = nz + 2;
  const px = nx + 4;
  const pxy = px * (ny + 4);
  const size = pxy * (nz + 4);
  scratch = {
    nx, ny, nz, mx, my, mz, px, pxy,
    vol: new Uint8Array(size),
    above: new Uint8Array(size), // 0 / 1 per lattice point
    // rowAny[q + my * r]: some sample of lattice row (q, r) is above (padded for r + 1, q + 1)
    rowAny: new Uint8Array(my * (mz + 1) + 1),
    // Vertex ids of the crossed edges of two lattice layers (by parity): [axis][q][x].
    ids: new Int32Array(2 * 3 * mx * my),
  };
  return scratch;
}

// vol index of lattice point (x, q, r).
const at = (s, x, q, r) => x + 1 + s.px * (q + 1) + s.pxy * (r + 1);

// Copies the samples in and marks those above the iso (value >= threshold).
function classify(s, data, threshold) {
  const { nx, ny, nz, my, vol, above, rowAny } = s;
  for (let z = 0; z < nz; ++z)
    for (let y = 0; y < ny; ++y) {
      const src = nx * (y + ny * z);
      const dst = at(s, 1, y + 1, z + 1);
      vol.set(data.subarray(src, src + nx), dst);
      let any = 0;
      for (let x = 0; x < nx; ++x) any |= above[dst + x] = data[src + x] >= threshold ? 1 : 0;
      rowAny[y + 1 + my * (z + 1)] = any;
    }
}

// The vertex on the edge from lattice point (x, q, r) to its +axis neighbour (C++ emitVertex).
function emitVertex(m, axis, x, q, r) {
  const { vol, px, pxy } = m.s;
  const stride = axis === 0 ? 1 : axis === 1 ? px : pxy;
  const a = at(m.s, x, q, r);
  const b = a + stride;
  const fa = vol[a];
  const fb = vol[b];
  // Exactly one end is above the iso, so fa != fb and t lies strictly inside (0, 1).
  const t = f32((m.iso - fa) / (fb - fa));
  const pos = m.positions;
  pos.reserve(3);
  // Voxel index (lattice - 1) + 0.5, plus t along the axis, in doubles; the point in float.
  pos.a[pos.n++] = f32(m.origin[0] + m.voxelSize * (x - 0.5 + (axis === 0 ? t : 0)));
  pos.a[pos.n++] = f32(m.origin[1] + m.voxelSize * (q - 0.5 + (axis === 1 ? t : 0)));
  pos.a[pos.n++] = f32(m.origin[2] + m.voxelSize * (r - 0.5 + (axis === 2 ? t : 0)));
  if (!m.normals) return;
  // Central differences (exact in float: halves of integers), interpolated along the edge like
  // the position, with C++'s float roundings.
  const lerp = (da, db) => {
    const ga = 0.5 * (vol[a + da] - vol[a - da]);
    const gb = 0.5 * (vol[b + db] - vol[b - db]);
    return f32(ga + f32(t * (gb - ga)));
  };
  const g0 = lerp(1, 1);
  const g1 = lerp(px, px);
  const g2 = lerp(pxy, pxy);
  // Eigen's squaredNorm of a Vector3f sums (unrolled by halves) as g0^2 + (g1^2 + g2^2).
  const n2 = f32(f32(g0 * g0) + f32(f32(g1 * g1) + f32(g2 * g2)));
  const nrm = m.normals;
  nrm.reserve(3);
  if (n2 > TINY_GRADIENT2) {
    const len = f32(Math.sqrt(n2));
    nrm.a[nrm.n++] = f32(-g0 / len); // probability falls outward
    nrm.a[nrm.n++] = f32(-g1 / len);
    nrm.a[nrm.n++] = f32(-g2 / len);
  } else {
    // Gradients cancel: the edge itself still says which way is out.
    const out = fa > fb ? 1 : -1;
    nrm.a[nrm.n++] = axis === 0 ? out : 0;
    nrm.a[nrm.n++] = axis === 1 ? out : 0;
    nrm.a[nrm.n++] = axis === 2 ? out : 0;
  }
}

// Crossed edges of lattice layer r, numbered as C++ does: row by row (q), in each row the
// x-edges, then the y-edges, then the z-edges, each by increasing x.
function emitLayer(m, r) {
  const { mx, my, mz, px, pxy, above, rowAny, ids } = m.s;
  const base = (r & 1) * 3 * mx * my;
  for (let q = 0; q < my; ++q) {
    const row = q + my * r;
    if (!(rowAny[row] | rowAny[row + 1] | rowAny[row + my])) continue; // nothing crosses here
    const i0 = at(m.s, 0, q, r);
    for (let x = 0; x + 1 < mx; ++x)
      if (above[i0 + x] !== above[i0 + x + 1]) {
        ids[base + q * mx + x] = m.vertexCount++;
        emitVertex(m, 0, x, q, r);
      }
    if (q + 1 < my)
      for (let x = 0; x < mx; ++x)
        if (above[i0 + x] !== above[i0 + x + px]) {
          ids[base + mx * my + q * mx + x] = m.vertexCount++;
          emitVertex(m, 1, x, q, r);
        }
    if (r + 1 < mz)
      for (let x = 0; x < mx; ++x)
        if (above[i0 + x] !== above[i0 + x + pxy]) {
          ids[base + 2 * mx * my + q * mx + x] = m.vertexCount++;
          emitVertex(m, 2, x, q, r);
        }
  }
}

// Per cell edge: the id slot of its grid edge relative to the cell's (x, q) in the id layer of
// its lower corner, and whether that layer is r + 1.
const EDGE_AXIS = EDGE.map(([c0, c1]) => [0, 1, 2].find((i) => CORNER[c0][i] !== CORNER[c1][i]));
const EDGE_UPPER = new Uint8Array(EDGE.map(([c0]) => CORNER[c0][2]));

// Triangles of the cells of layer r (between lattice layers r and r + 1), row by row, by x.
function emitCells(m, r) {
  const { mx, my, px, pxy, above, rowAny, ids } = m.s;
  const layer = 3 * mx * my;
  const lower = (r & 1) * layer;
  const upper = ((r + 1) & 1) * layer;
  const slot = new Int32Array(12);
  for (let e = 0; e < 12; ++e) {
    const [ox, oy] = CORNER[EDGE[e][0]];
    slot[e] = (EDGE_UPPER[e] ? upper : lower) + EDGE_AXIS[e] * mx * my + oy * mx + ox;
  }
  const count = CASES.count;
  const edges = CASES.edges;
  const out = m.indices;
  for (let q = 0; q + 1 < my; ++q) {
    const row = q + my * r;
    if (!(rowAny[row] | rowAny[row + 1] | rowAny[row + my] | rowAny[row + my + 1])) continue;
    const a = at(m.s, 0, q, r); // rows (q, r), (q+1, r), (q, r+1), (q+1, r+1)
    const b = a + px;
    const c = a + pxy;
    const d = c + px;
    const columnAt = (x) => above[a + x] | (above[b + x] << 1) | (above[c + x] << 2) | (above[d + x] << 3);
    let column = columnAt(0);
    for (let x = 0; x + 1 < mx; ++x) {
      const next = columnAt(x + 1);
      const cs = CASE_OF_COLUMNS[column | (next << 4)];
      column = next;
      const nt = count[cs];
      if (!nt) continue;
      const cell = q * mx + x;
      const e0 = cs * 3 * MAX_TRIANGLES_PER_CELL;
      out.reserve(3 * nt);
      for (let i = 0; i < 3 * nt; ++i) out.a[out.n++] = ids[slot[edges[e0 + i]] + cell];
    }
  }
}

// Meshes the volume (data: dims[0]*dims[1]*dims[2] bytes, x fastest). Positions in metres
// (Float32, as C++'s Eigen::Vector3f), 3 per vertex; normals likewise (null without
// computeNormals); indices 3 per triangle. Throws RangeError for an invalid volume or iso.
export function marchingCubes(
  { data, dims, origin, voxelSize },
  { iso = 153.5, computeNormals = true } = {},
) {
  iso = f32(iso); // C++'s MarchingCubesOptions::iso is a float
  if (!(iso > 0 && iso < 255)) throw new RangeError(`marchingCubes: iso ${iso} outside (0, 255)`);
  const [nx, ny, nz] = dims;
  if (![nx, ny, nz].every((d) => Number.isInteger(d) && d >= 0))
    throw new RangeError('marchingCubes: dims must be integers >= 0');
  if (data.length !== nx * ny * nz)
    throw new RangeError(`marchingCubes: data has ${data.length} bytes, dims say ${nx * ny * nz}`);
  if (!origin.every(Number.isFinite) || !(voxelSize > 0 && Number.isFinite(voxelSize)))
    throw new RangeError('marchingCubes: origin and voxelSize must be finite, voxelSize > 0');
  const m = {
    s: null,
    iso,
    origin,
    voxelSize,
    positions: new Growable(Float32Array, 3 * 4096),
    normals: computeNormals ? new Growable(Float32Array, 3 * 4096) : null,
    indices: new Growable(Uint32Array, 3 * 8192),
    vertexCount: 0,
  };
  if (nx * ny * nz > 0) {
    m.s = scratchFor(nx, ny, nz);
    // Above iso iff value >= floor(iso) + 1, i.e. value > iso for bytes (C++'s threshold).
    classify(m.s, data, Math.floor(iso) + 1);
    emitLayer(m, 0);
    for (let r = 0; r + 1 < m.s.mz; ++r) {
      emitLayer(m, r + 1);
      emitCells(m, r);
    }
  }
  return {
    positions: m.positions.result(),
    normals: m.normals ? m.normals.result() : null,
    indices: m.indices.result(),
  };
}
