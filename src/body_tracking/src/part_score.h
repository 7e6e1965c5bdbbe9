// Private: the arithmetic of the PAPF observation's per-part score (volume_observation.h), once,
// for the CPU path and the GPU particle weights (issue 20, thesis figure 6.4). Plain structs and
// pointers only, so g++ and nvcc compile the same functions:
//   setupPart    the part's row-invariant quantities (its voxel rows, Q at the grid's base);
//   rowTerms     one voxel row's weight and likelihood terms (GPU: one thread per row): its
//                intervals (rowSpan; the CPU computes a SIMD vector of rows at once,
//                part_spans.h), then the terms they give (rowTermsOf);
//   accumulateRow  adds a row's terms to the part's sums, rows in order (GPU: one thread per
//                part walks its rows' terms in order, so the sums round exactly as on the CPU);
//   finishPart   the part's weighted mean, less its shell's contrast term (trunk parts, below);
//                particleScore the particle's sum over its parts.
// The expressions keep the operation order of the Eigen code they replaced (Vector4d::dot in
// SSE2 pairs, Matrix4d * Vector4d column by column), so the scores are the same bytes as before.
// Build with no FMA contraction on either side (--fmad=false, -ffp-contract=off).
#pragma once

#include <math.h>

#include "host_device.h"

namespace body_tracking {
namespace part_score {

// The observation grid at the working resolution, and the likelihood read outside it.
struct ObservationGrid {
  double origin[3];
  double voxel_size;
  int dims[3];
  double unknown;
};

// Per-row prefix sums of y, x y and x^2 y (VolumeObservation::RowSums): dims[0] + 1 entries per
// row, row index y + dims[1] * z.
struct RowSumsView {
  const double* s0;
  const double* s1;
  const double* s2;
};

// A TruncatedQuadric as the score reads it.
// The shell (trunk parts, ObservationParams::trunk_shell_weight > 0): shell_Q is the part grown
// sideways (same clipping planes), and the score is the part's weighted mean less shell_weight
// times the plain mean likelihood of the voxels between the two (within the grid's x range; rows
// outside the grid read the nearest grid row, like the trunk's own). The part's mean alone
// cannot tell a trunk that fills the person's trunk from one sunk inside the larger blob of
// trunk, arms and halo (any pose inside scores ~0.9); the shell is empty only on the real
// boundary. Without a shell, shell_weight is 0 and lo / hi are the part's own bounds; with
// one, the grown part's.
struct PartQuadric {
  double Q[16];         // column-major (Eigen's layout): Q(i, k) = Q[4 k + i]
  double shell_Q[16];   // the grown part (same layout); unused when shell_weight is 0
  double planes[2][4];  // inside where planes[i] . v >= 0
  double lo[3], hi[3];  // axis-aligned bounds (world)
  double shell_weight;
  int num_planes;
  int skin;             // reads the blended (skin-weighted) likelihood
  int extrapolate;      // trunk: rows outside the grid read the nearest grid row
  int pad_;
};

// The part's row-invariant quantities: its lattice (x range, rows y0..y1 x z0..z1) and, along a
// row, v(x) = v0 + x h e_x with v^T Q v = A + B x + C x^2.
struct PartSetup {
  double bx0, bx1;
  int y0, y1, z0, z1;
  double C;
  double base[4], q_base[4], q_dy[4], q_dz[4];
  double shell_C, shell_q_base[4], shell_q_dy[4], shell_q_dz[4];  // the same for shell_Q
};

// One row's contribution: `w` to the weight sum, then to the weighted likelihood sum, in this
// order, those of its terms present in `mask` (bit k: terms[k]): the grid's voxels (or the
// unknown value for the whole row), the lattice left of the grid, right of it. mask < 0: the
// row misses the part. Fixed slots, no running index: the GPU keeps them in registers.
// shell_sum / shell_count: the row's voxels in the shell (likelihood sum, number).
struct RowTerms {
  double w;
  double terms[3];
  double shell_sum, shell_count;
  int mask;
};

struct PartSums {
  double sw, swy;
  double shell_sum, shell_count;
};

BT_HD double dmax(double a, double b) { return a < b ? b : a; }  // std::max's NaN behaviour
BT_HD double dmin(double a, double b) { return b < a ? b : a; }
BT_HD long lmax(long a, long b) { return a < b ? b : a; }
BT_HD long lmin(long a, long b) { return b < a ? b : a; }
BT_HD int iclamp(int v, int lo, int hi) { return v < lo ? lo : (hi < v ? hi : v); }

// Eigen's Vector4d::dot with SSE2 or AVX packets: lanes (0, 2) and (1, 3), then the two sums.
BT_HD double dot4(const double* a, const double* b) {
  return (a[0] * b[0] + a[2] * b[2]) + (a[1] * b[1] + a[3] * b[3]);
}

// Eigen's Matrix4d * Vector4d (column-major, lazy product): column by column.
BT_HD void matVec4(const double* Q, const double* v, double* out) {
  for (int i = 0; i < 4; ++i)
    out[i] = ((Q[i] * v[0] + Q[4 + i] * v[1]) + Q[8 + i] * v[2]) + Q[12 + i] * v[3];
}

// Sums of 1, x and x^2 over the integers lo..hi (lo <= hi).
BT_HD double sumPow0(long lo, long hi) { return static_cast<double>(hi - lo + 1); }
BT_HD double sumPow1(long lo, long hi) {
  return 0.5 * (static_cast<double>(hi) * (hi + 1) - static_cast<double>(lo - 1) * lo);
}
BT_HD double sumPow2Upto(double n) { return n * (n + 1) * (2 * n + 1) / 6.0; }  // sum 0..n of x^2
BT_HD double sumPow2(long lo, long hi) {
  // Valid for negative bounds too: sum_{lo..hi} x^2 = F(hi) - F(lo - 1) with F(n) for n < 0
  // defined by the same cubic (it is odd-symmetric about -1/2).
  return sumPow2Upto(static_cast<double>(hi)) - sumPow2Upto(static_cast<double>(lo - 1));
}

// Tightens [lo, hi] to the integers x with a + b x >= 0.
BT_HD void clipLinear(double a, double b, double* lo, double* hi) {
  if (fabs(b) < 1e-15) {
    if (a < 0) *hi = *lo - 1;
    return;
  }
  const double r = -a / b;
  if (b > 0) *lo = dmax(*lo, ceil(r - 1e-9));
  else *hi = dmin(*hi, floor(r + 1e-9));
}

BT_HD PartSetup setupPart(const PartQuadric& q, const ObservationGrid& g) {
  PartSetup s;
  const double h = g.voxel_size;
  // The voxel lattice over the part's bounds, extended past the grid where the part is.
  const double lo_x = (q.lo[0] - g.origin[0]) / h, hi_x = (q.hi[0] - g.origin[0]) / h;
  const double lo_y = (q.lo[1] - g.origin[1]) / h, hi_y = (q.hi[1] - g.origin[1]) / h;
  const double lo_z = (q.lo[2] - g.origin[2]) / h, hi_z = (q.hi[2] - g.origin[2]) / h;
  s.bx0 = floor(lo_x);
  s.bx1 = floor(hi_x);
  s.y0 = static_cast<int>(floor(lo_y));
  s.y1 = static_cast<int>(floor(hi_y));
  s.z0 = static_cast<int>(floor(lo_z));
  s.z1 = static_cast<int>(floor(hi_z));
  s.C = h * h * q.Q[0];
  // Q v0 is affine in the row's (y, z): one 4x4 product per part, then additions.
  s.base[0] = g.origin[0] + 0.5 * h;
  s.base[1] = g.origin[1] + 0.5 * h;
  s.base[2] = g.origin[2] + 0.5 * h;
  s.base[3] = 1.0;
  matVec4(q.Q, s.base, s.q_base);
  for (int i = 0; i < 4; ++i) {
    s.q_dy[i] = h * q.Q[4 + i];
    s.q_dz[i] = h * q.Q[8 + i];
  }
  s.shell_C = h * h * q.shell_Q[0];
  matVec4(q.shell_Q, s.base, s.shell_q_base);
  for (int i = 0; i < 4; ++i) {
    s.shell_q_dy[i] = h * q.shell_Q[4 + i];
    s.shell_q_dz[i] = h * q.shell_Q[8 + i];
  }
  return s;
}

// Weight sum over x = lo..hi of 1 + A + B x + C x^2.
BT_HD double rowWeights(double A, double B, double C, long lo, long hi) {
  return (1.0 + A) * sumPow0(lo, hi) + B * sumPow1(lo, hi) + C * sumPow2(lo, hi);
}

// The row's voxels x in [*xlo, *xhi] (bx0..bx1 to start) inside the quadric, whose
// v^T Q v = A + B x + C x^2 along the row, and inside the clipping planes. False when none.
BT_HD bool rowInterval(double A, double B, double C, const PartQuadric& q, const double* v0,
                       double h, double* xlo, double* xhi) {
  if (C > 1e-15) {
    const double disc = B * B - 4.0 * A * C;
    if (disc < 0) return false;
    const double sq = sqrt(disc);
    *xlo = dmax(*xlo, ceil((-B - sq) / (2.0 * C) - 1e-9));
    *xhi = dmin(*xhi, floor((-B + sq) / (2.0 * C) + 1e-9));
  } else {
    clipLinear(-A, -B, xlo, xhi);  // A + B x <= 0
  }
  for (int i = 0; i < q.num_planes; ++i)
    clipLinear(dot4(q.planes[i], v0), q.planes[i][0] * h, xlo, xhi);
  return *xlo <= *xhi;
}

// Sum and number of row r's grid voxels lo..hi (clipped to the grid) into *sum, *count.
BT_HD void gridRowSum(const RowSumsView& sums, long r, int nx, long lo, long hi, double sign,
                      double* sum, double* count) {
  const long a = lmax(lo, 0), b = lmin(hi, nx - 1);
  if (a > b) return;
  *sum += sign * (sums.s0[r + b + 1] - sums.s0[r + a]);
  *count += sign * static_cast<double>(b - a + 1);
}

// A row's intervals (rowSpan): the part's voxels xlo..xhi (ok), those of its grown shell
// olo..ohi (shell_ok; computed only when the part has a shell), and the part's A, B (rowInterval).
// The CPU computes them for many rows at once (part_spans.h): the same scores.
struct RowSpan {
  double A, B, xlo, xhi, olo, ohi;
  int ok, shell_ok;
};

// Row (yy, z)'s intervals.
BT_HD RowSpan rowSpan(const PartSetup& s, const PartQuadric& q, const ObservationGrid& g, int yy, int z) {
  RowSpan sp;
  const double h = g.voxel_size;
  double v0[4], qv[4];
  v0[0] = s.base[0] + 0.0;
  v0[1] = s.base[1] + yy * h;
  v0[2] = s.base[2] + z * h;
  v0[3] = s.base[3] + 0.0;
  sp.shell_ok = 0;
  sp.olo = s.bx0;
  sp.ohi = s.bx1;
  if (q.shell_weight > 0) {
    double sv[4];
    for (int i = 0; i < 4; ++i) sv[i] = s.shell_q_base[i] + yy * s.shell_q_dy[i] + z * s.shell_q_dz[i];
    sp.shell_ok = rowInterval(dot4(v0, sv), 2.0 * h * sv[0], s.shell_C, q, v0, h, &sp.olo, &sp.ohi);
  }
  for (int i = 0; i < 4; ++i) qv[i] = s.q_base[i] + yy * s.q_dy[i] + z * s.q_dz[i];
  sp.A = dot4(v0, qv);
  sp.B = 2.0 * h * qv[0];
  sp.xlo = s.bx0;
  sp.xhi = s.bx1;
  sp.ok = rowInterval(sp.A, sp.B, s.C, q, v0, h, &sp.xlo, &sp.xhi);
  return sp;
}

// Row (yy, z)'s terms, given its intervals.
BT_HD RowTerms rowTermsOf(const PartSetup& s, const PartQuadric& q, const ObservationGrid& g,
                          const RowSumsView& sums, int yy, int z, const RowSpan& sp) {
  RowTerms t;
  t.mask = -1;
  t.shell_sum = 0.0;
  t.shell_count = 0.0;
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  const bool row_in_grid = yy >= 0 && yy < ny && z >= 0 && z < nz;
  // The shell: the grown part's voxels in this row within the grid's x range, less the part's
  // (below). Rows outside the grid read the nearest grid row, as the trunk's own voxels do
  // (extrapolate): counted in the grid only, a trunk that sank below the desk plane or behind the
  // back face hid its shell there and kept the clamped rows' full likelihood inside (generated
  // wide people: the trunk 5-8 cm low, the head 50-86 mm off).
  const long shell_row =
      static_cast<long>(iclamp(yy, 0, ny - 1) + ny * iclamp(z, 0, nz - 1)) * (nx + 1);
  const bool shell = q.shell_weight > 0 && (row_in_grid || q.extrapolate);
  if (shell && sp.shell_ok)
    gridRowSum(sums, shell_row, nx, static_cast<long>(sp.olo), static_cast<long>(sp.ohi), 1.0,
               &t.shell_sum, &t.shell_count);
  if (!sp.ok) return t;
  const double A = sp.A, B = sp.B, C = s.C;
  const long a = static_cast<long>(sp.xlo), b = static_cast<long>(sp.xhi);
  if (shell) gridRowSum(sums, shell_row, nx, a, b, -1.0, &t.shell_sum, &t.shell_count);
  const double w_all = rowWeights(A, B, C, a, b);
  t.w = w_all;
  t.mask = 0;
  if (!row_in_grid && !q.extrapolate) {
    t.terms[0] = g.unknown * w_all;
    t.mask = 1;
    return t;
  }
  // The row's values: its own inside the grid, else the nearest row's (clamp to edge), and
  // beyond its ends the end values (trunk) or the unknown value (the rest).
  const int cy = iclamp(yy, 0, ny - 1), cz = iclamp(z, 0, nz - 1);
  const long r = static_cast<long>(cy + ny * cz) * (nx + 1);
  const long ga = lmax(a, 0), gb = lmin(b, nx - 1);
  if (ga <= gb) {
    t.terms[0] = (1.0 + A) * (sums.s0[r + gb + 1] - sums.s0[r + ga]) +
                 B * (sums.s1[r + gb + 1] - sums.s1[r + ga]) +
                 C * (sums.s2[r + gb + 1] - sums.s2[r + ga]);
    t.mask |= 1;
  }
  if (a < 0) {
    t.terms[1] = rowWeights(A, B, C, a, lmin(b, -1)) *
                 (q.extrapolate ? sums.s0[r + 1] - sums.s0[r] : g.unknown);
    t.mask |= 2;
  }
  if (b >= nx) {
    t.terms[2] = rowWeights(A, B, C, lmax(a, nx), b) *
                 (q.extrapolate ? sums.s0[r + nx] - sums.s0[r + nx - 1] : g.unknown);
    t.mask |= 4;
  }
  return t;
}

// Row (yy, z) of the part's lattice.
BT_HD RowTerms rowTerms(const PartSetup& s, const PartQuadric& q, const ObservationGrid& g,
                        const RowSumsView& sums, int yy, int z) {
  return rowTermsOf(s, q, g, sums, yy, z, rowSpan(s, q, g, yy, z));
}

// Rows of the part's lattice; row k is (y0 + k % ny, z0 + k / ny), z outer as on the CPU.
BT_HD int rowCount(const PartSetup& s) {
  const int ny = s.y1 - s.y0 + 1, nz = s.z1 - s.z0 + 1;
  return ny > 0 && nz > 0 ? ny * nz : 0;
}
BT_HD RowTerms rowTermsAt(const PartSetup& s, const PartQuadric& q, const ObservationGrid& g,
                          const RowSumsView& sums, int k) {
  const int ny = s.y1 - s.y0 + 1;
  return rowTerms(s, q, g, sums, s.y0 + k % ny, s.z0 + k / ny);
}

BT_HD void accumulateRow(const RowTerms& t, PartSums* acc) {
  acc->shell_sum += t.shell_sum;
  acc->shell_count += t.shell_count;
  if (t.mask < 0) return;
  acc->sw += t.w;
  if (t.mask & 1) acc->swy += t.terms[0];
  if (t.mask & 2) acc->swy += t.terms[1];
  if (t.mask & 4) acc->swy += t.terms[2];
}

// A part thinner than the lattice may catch no voxel centre: its evidence is unknown. A shell
// with no grid voxel takes nothing off.
BT_HD double finishPart(const PartSums& acc, double unknown, double shell_weight) {
  const double mean = acc.sw > 1e-12 ? acc.swy / acc.sw : unknown;
  if (shell_weight > 0 && acc.shell_count > 0.5) return mean - shell_weight * (acc.shell_sum / acc.shell_count);
  return mean;
}

// The whole part on one thread: the reference. The CPU's VolumeObservation::partScore computes
// the same bytes with part_spans::scorePart; the GPU kernel and its emulation run these rows
// (rowTermsAt) and sums (accumulateRow, finishPart) too.
BT_HD double scorePart(const PartQuadric& q, const ObservationGrid& g, const RowSumsView& sums) {
  const PartSetup s = setupPart(q, g);
  PartSums acc = {0.0, 0.0, 0.0, 0.0};
  for (int z = s.z0; z <= s.z1; ++z)
    for (int yy = s.y0; yy <= s.y1; ++yy) accumulateRow(rowTerms(s, q, g, sums, yy, z), &acc);
  return finishPart(acc, g.unknown, q.shell_weight);
}

// A particle's score: its parts' scores summed in order, 0 for a self-colliding pose
// (Papf::scoreState).
BT_HD double particleScore(const double* part_scores, int count, bool collides) {
  if (collides) return 0.0;
  double sum = 0;
  for (int k = 0; k < count; ++k) sum += part_scores[k];
  return sum;
}

}  // namespace part_score
}  // namespace body_tracking
