#include "cvephands_bridge/mesh/marching_cubes.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "marching_cubes_cases.h"

// Vertex numbering and triangle counts are popcounts. Baseline x86-64 has no POPCNT
// instruction (GCC then calls a bit-twiddling routine, several times slower), so without a
// -march flag the two bit-heavy passes are cloned for POPCNT CPUs and picked at load time.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__POPCNT__)
#define CVEPHANDS_POPCNT_CLONES __attribute__((target_clones("popcnt", "default")))
#else
#define CVEPHANDS_POPCNT_CLONES
#endif

namespace cvephands {
namespace {

using Word = uint64_t;

inline int popcount(Word w) { return __builtin_popcountll(w); }
inline int lowestBit(Word w) { return __builtin_ctzll(w); }
inline Word bitsBelow(int n) { return n <= 0 ? 0 : n >= 64 ? ~Word(0) : (Word(1) << n) - 1; }

// Everything a pass needs. The lattice is the grid of samples the cells join: the voxel centres,
// plus with close_at_border a ring of zero samples around them (lattice index = voxel index + L).
// A lattice row is the x-line at fixed (q, r) = (y, z) lattice indices.
struct Pass {
  // input
  const uint8_t* data;
  int nx, ny, nz;
  Eigen::Vector3d origin;
  double voxel;
  // lattice
  int L, mx, my, mz, W;
  // classification: above iff value >= threshold (= floor(iso) + 1, the same as value > iso)
  uint8_t threshold;
  float iso;
  bool binary, normals;
  // scratch
  Word* above;
  Word* cross[3];
  uint32_t* word_offset;
  uint32_t* row_vertices;
  uint64_t* row_triangles;
  // output
  Eigen::Vector3f* out_vertices;
  Eigen::Vector3f* out_normals;
  uint32_t* out_triangles;

  size_t row(int q, int r) const { return static_cast<size_t>(q) + static_cast<size_t>(my) * r; }
  const Word* aboveRow(int q, int r) const { return above + row(q, r) * W; }
  // Bit x of the result is bit x + 1 of the row.
  Word next(const Word* row, int w) const {
    return (row[w] >> 1) | (w + 1 < W ? row[w + 1] << 63 : Word(0));
  }

  // Sample at lattice point (i, j, k): 0 outside the volume (only reached with close_at_border
  // or for the clamped neighbours below).
  float value(int i, int j, int k) const {
    i -= L;
    j -= L;
    k -= L;
    if (static_cast<unsigned>(i) >= static_cast<unsigned>(nx) ||
        static_cast<unsigned>(j) >= static_cast<unsigned>(ny) ||
        static_cast<unsigned>(k) >= static_cast<unsigned>(nz))
      return 0.0f;
    return sample(data[static_cast<size_t>(i) +
                       static_cast<size_t>(nx) * (static_cast<size_t>(j) + static_cast<size_t>(ny) * k)]);
  }
  float sample(uint8_t v) const {
    return binary ? (v >= threshold ? 1.0f : 0.0f) : static_cast<float>(v);
  }
  // Central differences in lattice units; one-sided at the outermost samples when the volume
  // is not closed (then there is nothing beyond them).
  Eigen::Vector3f gradient(const int p[3]) const {
    const int m[3] = {mx, my, mz};
    Eigen::Vector3f g;
    for (int a = 0; a < 3; ++a) {
      int lo[3] = {p[0], p[1], p[2]}, hi[3] = {p[0], p[1], p[2]};
      --lo[a];
      ++hi[a];
      if (L == 0) {
        lo[a] = std::max(lo[a], 0);
        hi[a] = std::min(hi[a], m[a] - 1);
      }
      g[a] = (value(hi[0], hi[1], hi[2]) - value(lo[0], lo[1], lo[2])) /
             static_cast<float>(hi[a] - lo[a]);
    }
    return g;
  }

  // The vertex on the grid edge from lattice point (x, q, r) to its +axis neighbour.
  void emitVertex(uint32_t id, int axis, int x, int q, int r) const {
    const int pa[3] = {x, q, r};
    const int d[3] = {x - L, q - L, r - L};  // voxel index of the edge's lower end
    float fa, fb;
    Eigen::Vector3f ga = Eigen::Vector3f::Zero(), gb = Eigen::Vector3f::Zero();
    // Fast path: both ends and all their neighbours are voxels of the volume.
    bool interior = true;
    const int n[3] = {nx, ny, nz};
    for (int c = 0; c < 3; ++c) interior &= d[c] >= 1 && d[c] + 1 + (c == axis) < n[c];
    if (interior) {
      const ptrdiff_t stride[3] = {1, nx, static_cast<ptrdiff_t>(nx) * ny};
      const uint8_t* a = data + d[0] + stride[1] * d[1] + stride[2] * d[2];
      const uint8_t* b = a + stride[axis];
      fa = sample(*a);
      fb = sample(*b);
      if (normals)
        for (int c = 0; c < 3; ++c) {
          ga[c] = 0.5f * (sample(a[stride[c]]) - sample(a[-stride[c]]));
          gb[c] = 0.5f * (sample(b[stride[c]]) - sample(b[-stride[c]]));
        }
    } else {
      int pb[3] = {x, q, r};
      ++pb[axis];
      fa = value(pa[0], pa[1], pa[2]);
      fb = value(pb[0], pb[1], pb[2]);
      if (normals) {
        ga = gradient(pa);
        gb = gradient(pb);
      }
    }
    // Exactly one end is above iso, so fa != fb and t lies strictly inside (0, 1).
    const float t = binary ? 0.5f : (iso - fa) / (fb - fa);
    Eigen::Vector3d s(d[0] + 0.5, d[1] + 0.5, d[2] + 0.5);
    s[axis] += t;
    out_vertices[id] = (origin + voxel * s).cast<float>();
    if (!normals) return;
    const Eigen::Vector3f g = ga + t * (gb - ga);
    const float g2 = g.squaredNorm();
    if (g2 > 1e-12f) {
      out_normals[id] = -g / std::sqrt(g2);  // probability falls outward
    } else {
      // Gradients cancel (e.g. a 1-0-1-0 pattern in the binary field): the edge itself still
      // says which way is out.
      Eigen::Vector3f nrm = Eigen::Vector3f::Zero();
      nrm[axis] = fa > fb ? 1.0f : -1.0f;
      out_normals[id] = nrm;
    }
  }
};

// The four lattice rows around cell row (q, r), one word at a time: the above bits of each row
// at x and at x + 1, and which cells have corners on both sides of the iso level.
struct CellWord {
  Word a0, a1, b0, b1, c0, c1, d0, d1, active;

  CellWord(const Pass& p, const Word* a, const Word* b, const Word* c, const Word* d, int w)
      : a0(a[w]), a1(p.next(a, w)), b0(b[w]), b1(p.next(b, w)), c0(c[w]), c1(p.next(c, w)),
        d0(d[w]), d1(p.next(d, w)) {
    const Word any = a0 | a1 | b0 | b1 | c0 | c1 | d0 | d1;
    const Word all = a0 & a1 & b0 & b1 & c0 & c1 & d0 & d1;
    active = any & ~all & bitsBelow(p.mx - 1 - 64 * w);  // cells x <= mx - 2
  }
  // Corner bits in the case table's order: rows a = (q, r), b = (q+1, r), c = (q, r+1),
  // d = (q+1, r+1); corners 0, 1 on a; 3, 2 on b; 4, 5 on c; 7, 6 on d.
  int cellCase(int s) const {
    return static_cast<int>(((a0 >> s) & 1) | ((a1 >> s) & 1) << 1 | ((b1 >> s) & 1) << 2 |
                            ((b0 >> s) & 1) << 3 | ((c0 >> s) & 1) << 4 | ((c1 >> s) & 1) << 5 |
                            ((d1 >> s) & 1) << 6 | ((d0 >> s) & 1) << 7);
  }
};

// Crossed edges along one axis of one lattice row, numbered: each row numbers its crossed
// x-edges, then y-edges, then z-edges, each by increasing x.
struct EdgeRow {
  const Word* mask;
  const uint32_t* offset;
  uint32_t base;
  EdgeRow() = default;
  EdgeRow(const Pass& p, int axis, int q, int r) {
    const size_t rw = p.row(q, r);
    mask = p.cross[axis] + rw * p.W;
    offset = p.word_offset + (rw * 3 + axis) * p.W;
    base = p.row_vertices[rw];
  }
  uint32_t id(int x) const {
    const int w = x >> 6;
    return base + offset[w] + popcount(mask[w] & ((Word(1) << (x & 63)) - 1));
  }
};

// Pass 1: one bit per lattice sample. The bytes are compared 16 at a time (SSE2 is baseline on
// x86-64); most of a hand volume is below iso and leaves its words zero.
void classifyLayer(const Pass& p, int r) {
  for (int q = 0; q < p.my; ++q) {
    Word* bits = p.above + p.row(q, r) * p.W;
    std::fill(bits, bits + p.W, Word(0));
    const int j = q - p.L, k = r - p.L;
    if (j < 0 || j >= p.ny || k < 0 || k >= p.nz) continue;  // the zero ring
    const uint8_t* src = p.data + static_cast<size_t>(p.nx) *
                                      (static_cast<size_t>(j) + static_cast<size_t>(p.ny) * k);
    int x = 0;
#ifdef __SSE2__
    const __m128i t = _mm_set1_epi8(static_cast<char>(p.threshold));
    for (; x + 16 <= p.nx; x += 16) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + x));
      const Word m = static_cast<uint32_t>(
          _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_max_epu8(v, t), v)));  // v >= threshold
      if (!m) continue;
      const int pos = x + p.L, w = pos >> 6, s = pos & 63;
      bits[w] |= m << s;
      if (s > 48) bits[w + 1] |= m >> (64 - s);
    }
#endif
    for (; x < p.nx; ++x)
      if (src[x] >= p.threshold) bits[(x + p.L) >> 6] |= Word(1) << ((x + p.L) & 63);
  }
}

// Pass 2: crossed edges (a sample differs from its +x, +y or +z neighbour) with their numbering
// inside the row, and the triangle count of the cell row.
CVEPHANDS_POPCNT_CLONES void countLayer(const Pass& p, int r) {
  const mc::CaseTable& table = mc::caseTable();
  for (int q = 0; q < p.my; ++q) {
    const size_t rw = p.row(q, r);
    const Word* a = p.aboveRow(q, r);
    const Word* b = q + 1 < p.my ? p.aboveRow(q + 1, r) : nullptr;
    const Word* c = r + 1 < p.mz ? p.aboveRow(q, r + 1) : nullptr;
    Word* cx = p.cross[0] + rw * p.W;
    Word* cy = p.cross[1] + rw * p.W;
    Word* cz = p.cross[2] + rw * p.W;
    uint32_t* offset = p.word_offset + rw * 3 * p.W;
    // Most rows of a hand volume: this row and the rows after it in y and z are all below.
    Word any = 0;
    for (int w = 0; w < p.W; ++w) any |= a[w] | (b ? b[w] : 0) | (c ? c[w] : 0);
    if (!any) {
      const Word* d = b && c ? p.aboveRow(q + 1, r + 1) : nullptr;
      for (int w = 0; w < p.W && d; ++w) any |= d[w];
      if (!any) {
        // Nothing crosses here; fill never reads this row's masks or offsets.
        p.row_vertices[rw] = 0;
        p.row_triangles[rw] = 0;
        continue;
      }
    }
    uint32_t n[3] = {0, 0, 0};
    for (int w = 0; w < p.W; ++w) {
      cx[w] = (a[w] ^ p.next(a, w)) & bitsBelow(p.mx - 1 - 64 * w);
      cy[w] = b ? a[w] ^ b[w] : 0;
      cz[w] = c ? a[w] ^ c[w] : 0;
      offset[w] = n[0];
      offset[p.W + w] = n[1];
      offset[2 * p.W + w] = n[2];
      n[0] += popcount(cx[w]);
      n[1] += popcount(cy[w]);
      n[2] += popcount(cz[w]);
    }
    for (int w = 0; w < p.W; ++w) {  // x-edges first, then y, then z
      offset[p.W + w] += n[0];
      offset[2 * p.W + w] += n[0] + n[1];
    }
    p.row_vertices[rw] = n[0] + n[1] + n[2];

    uint64_t tris = 0;
    if (b && c) {
      const Word* d = p.aboveRow(q + 1, r + 1);
      for (int w = 0; w < p.W; ++w) {
        const CellWord cw(p, a, b, c, d, w);
        for (Word m = cw.active; m; m &= m - 1) tris += table.num_triangles[cw.cellCase(lowestBit(m))];
      }
    }
    p.row_triangles[rw] = tris;
  }
}

// Pass 3: vertices of the row's crossed edges and triangles of its cells, into the slots the
// prefix sums gave them.
CVEPHANDS_POPCNT_CLONES void fillLayer(const Pass& p, int r) {
  const mc::CaseTable& table = mc::caseTable();
  for (int q = 0; q < p.my; ++q) {
    const size_t rw = p.row(q, r);
    uint32_t id = p.row_vertices[rw];
    if (id != p.row_vertices[rw + 1]) {  // skipped rows (none) hold stale masks
      for (int axis = 0; axis < 3; ++axis)
        for (int w = 0; w < p.W; ++w)
          for (Word m = p.cross[axis][rw * p.W + w]; m; m &= m - 1)
            p.emitVertex(id++, axis, 64 * w + lowestBit(m), q, r);
    }

    if (q + 1 >= p.my || r + 1 >= p.mz) continue;
    if (p.row_triangles[rw + 1] == p.row_triangles[rw]) continue;  // no surface in this cell row
    // The (lattice row, axis) pairs whose crossed edges the cells of this row use.
    EdgeRow edge_rows[8];
    for (int s = 0; s < 8; ++s)
      edge_rows[s] = EdgeRow(p, table.slot[s][2], q + table.slot[s][0], r + table.slot[s][1]);
    const Word *a = p.aboveRow(q, r), *b = p.aboveRow(q + 1, r), *c = p.aboveRow(q, r + 1),
               *d = p.aboveRow(q + 1, r + 1);
    uint32_t* out = p.out_triangles + 3 * p.row_triangles[rw];
    for (int w = 0; w < p.W; ++w) {
      const CellWord cw(p, a, b, c, d, w);
      for (Word m = cw.active; m; m &= m - 1) {
        const int s = lowestBit(m), x = 64 * w + s;
        const int cs = cw.cellCase(s);
        uint32_t ids[12];
        for (unsigned e_mask = table.edge_mask[cs]; e_mask; e_mask &= e_mask - 1) {
          const int e = __builtin_ctz(e_mask);
          ids[e] = edge_rows[table.edge_slot[e]].id(x + table.edge_offset[e][0]);
        }
        const uint8_t* edges = table.edges[cs];
        for (int i = 0; i < 3 * table.num_triangles[cs]; ++i) *out++ = ids[edges[i]];
      }
    }
  }
}

}  // namespace

MarchingCubes::MarchingCubes(const MarchingCubesOptions& options) : options_(options) {
  if (!(options_.iso > 0.0f && options_.iso < 255.0f))
    throw std::invalid_argument(
        "cvephands::MarchingCubes: 'iso' must lie strictly inside (0, 255) (got " +
        std::to_string(options_.iso) + ")");
  if (options_.threads < 0)
    throw std::invalid_argument("cvephands::MarchingCubes: 'threads' must be >= 0");
}

void MarchingCubes::extract(const ProbabilityGridView& grid, TriangleMesh* mesh) {
  if (mesh == nullptr) throw std::invalid_argument("cvephands::MarchingCubes: 'mesh' is null");
  grid.validate();
  mesh->clear();
  if (grid.empty()) return;

  Pass p{};
  p.data = grid.data;
  p.nx = grid.dims.x();
  p.ny = grid.dims.y();
  p.nz = grid.dims.z();
  p.origin = grid.origin;
  p.voxel = grid.voxel_size;
  p.L = options_.close_at_border ? 1 : 0;
  p.mx = p.nx + 2 * p.L;
  p.my = p.ny + 2 * p.L;
  p.mz = p.nz + 2 * p.L;
  if (p.mx < 2 || p.my < 2 || p.mz < 2) return;  // no cell
  // 3 edges per lattice point must fit the 32-bit vertex indices.
  const double points = double(p.mx) * double(p.my) * double(p.mz);
  if (points > double(1u << 30))
    throw std::invalid_argument("cvephands::MarchingCubes: grid too large (over 2^30 samples)");
  p.W = (p.mx + 63) / 64;
  p.threshold = static_cast<uint8_t>(std::floor(options_.iso) + 1.0f);
  p.iso = options_.iso;
  p.binary = options_.mode == MeshingMode::kBinary;
  p.normals = options_.compute_normals;

  const size_t rows = static_cast<size_t>(p.my) * p.mz;
  above_.resize(rows * p.W);
  for (auto& c : cross_) c.resize(rows * p.W);
  word_offset_.resize(rows * 3 * p.W);
  row_vertices_.resize(rows + 1);
  row_triangles_.resize(rows + 1);
  p.above = above_.data();
  for (int a = 0; a < 3; ++a) p.cross[a] = cross_[a].data();
  p.word_offset = word_offset_.data();
  p.row_vertices = row_vertices_.data();
  p.row_triangles = row_triangles_.data();
  mc::caseTable();  // build outside the parallel region

  const int threads = options_.threads > 0 ? options_.threads : omp_get_max_threads();
  // Slabs of one lattice layer, handed out dynamically: the surface occupies few of them.
#pragma omp parallel num_threads(threads)
  {
#pragma omp for schedule(dynamic, 1)
    for (int r = 0; r < p.mz; ++r) classifyLayer(p, r);
#pragma omp for schedule(dynamic, 1)
    for (int r = 0; r < p.mz; ++r) countLayer(p, r);
  }

  // Exclusive prefix sums: the first vertex and triangle of every row.
  uint64_t nv = 0, nt = 0;
  for (size_t i = 0; i <= rows; ++i) {
    const uint64_t v = i < rows ? row_vertices_[i] : 0, t = i < rows ? row_triangles_[i] : 0;
    row_vertices_[i] = static_cast<uint32_t>(nv);
    row_triangles_[i] = nt;
    nv += v;
    nt += t;
  }
  mesh->vertices.resize(nv);
  if (p.normals) mesh->normals.resize(nv);
  mesh->triangles.resize(3 * nt);
  if (nt == 0) {
    mesh->clear();
    return;
  }
  p.out_vertices = mesh->vertices.data();
  p.out_normals = mesh->normals.data();
  p.out_triangles = mesh->triangles.data();

#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int r = 0; r < p.mz; ++r) fillLayer(p, r);
}

TriangleMesh marchingCubes(const ProbabilityGridView& grid, const MarchingCubesOptions& options) {
  TriangleMesh mesh;
  MarchingCubes(options).extract(grid, &mesh);
  return mesh;
}

}  // namespace cvephands
