// Private: the projection of voxel centres and of the multi-projection sample offsets, written
// once for the CPU table build (ProjectionTable) and the GPU (volume_fusion.cu), so a table
// projected on the device holds the bytes of one built on the host.
//  * projectionRow: a row's constants (double, then float), as the table build computes them
//    per row and camera. The sums follow the order Eigen's products used before this code
//    replaced them (rows 0 and 1 of a 3x3 product ((a + b) + c), row 2 (a + (b + c))), so
//    tables kept their bytes.
//  * projectVoxel: one voxel's packed centre, the float steps of the AVX2 / AVX-512 row
//    kernels lane by lane (same FMAs, written out as fmaf), which remain the CPU's fast path.
//  * chunkOffsets: one chunk's half-voxel image offsets (double, the arithmetic of
//    CameraModel::projectCamera and Eigen's Isometry3d product).
// Plain C++ with PSFS_HD; no Eigen, no CUDA types.
#pragma once

#include <cmath>
#include <cstdint>

#include "host_device.h"
#include "psfs_reconstruction/projection_constants.h"

namespace psfs {
namespace detail {

constexpr float kMinDepth = 1e-4f;        // nearest depth (m) still in front of a camera
constexpr int kProjChunk = 8;             // ProjectionTable::kChunk (static_assert in the .cpp)
constexpr int kProjMaxOffsetPx = 7;       // ProjectionTable::kMaxSampleOffsetPx
constexpr int kProjMaxLevels = 3;         // ProjectionTable::kMaxFootprintLevels
constexpr int kProjOne = 16;              // PackedUV::kOne
constexpr int kProjFracBits = 4;          // PackedUV::kFracBits

// A row's per-camera constants: camera-frame position of voxel x = a + x * b; footprint level
// of voxel x = #{j : lev_lo[j] <= x < lev_hi[j]}, added to its packed centre as that many
// lev_step (= height + 1 rows).
struct ProjectionRow {
  float a[3], b[3];
  int nlev;
  int lev_lo[kProjMaxLevels - 1], lev_hi[kProjMaxLevels - 1];
  uint32_t lev_step;
};

// r0 * v0 + r1 * v1 + r2 * v2 of row `row` of a row-major 3x3 in Eigen's order (see above).
PSFS_HD double rowDot3(const double* r, int row, const double* v) {
  const double p0 = r[3 * row] * v[0], p1 = r[3 * row + 1] * v[1], p2 = r[3 * row + 2] * v[2];
  return row < 2 ? (p0 + p1) + p2 : p0 + (p1 + p2);
}

PSFS_HD double clampD(double v, double lo, double hi) { return v < lo ? lo : (hi < v ? hi : v); }
PSFS_HD int clampI(int v, int lo, int hi) { return v < lo ? lo : (hi < v ? hi : v); }

PSFS_HD ProjectionRow projectionRow(const ProjectionCamera& cam, const ProjectionGrid& g, int y, int z) {
  ProjectionRow r;
  // Row start in double (camera-frame offsets are up to metres), the per-voxel step in float.
  const double c[3] = {0.5, y + 0.5, z + 0.5};
  double d[3];
  for (int i = 0; i < 3; ++i) d[i] = (g.origin[i] + g.voxel_size * c[i]) - cam.position[i];
  double a[3], b[3];
  for (int i = 0; i < 3; ++i) {
    a[i] = rowDot3(cam.camera_R_world, i, d);
    b[i] = cam.camera_R_world[3 * i] * g.voxel_size;
    r.a[i] = static_cast<float>(a[i]);
    r.b[i] = static_cast<float>(b[i]);
  }
  r.nlev = 0;
  r.lev_step = 0;
  for (int j = 0; j < kProjMaxLevels - 1; ++j) r.lev_lo[j] = r.lev_hi[j] = 0;
  if (g.footprint_levels > 0) {
    // level >= j  <=>  round(scale * f s / Z) >= j  <=>  Z <= scale f s / (j - 1/2), with
    // Z(x) = a_z + x b_z (camera frame); the x range where that holds, as integers.
    r.nlev = g.footprint_levels - 1;
    r.lev_step = static_cast<uint32_t>(kProjOne * (cam.height + 1)) << 16;
    for (int j = 1; j <= r.nlev; ++j) {
      const double zj = g.footprint_scale * cam.focal * g.voxel_size / (j - 0.5);
      double lo = 0.0, hi = g.nxp;  // [lo, hi)
      if (b[2] > 0.0) {
        hi = floor((zj - a[2]) / b[2]) + 1.0;
      } else if (b[2] < 0.0) {
        lo = ceil((zj - a[2]) / b[2]);
      } else if (!(a[2] <= zj)) {
        hi = 0.0;
      }
      r.lev_lo[j - 1] = static_cast<int>(clampD(lo, 0.0, double(g.nxp)));
      r.lev_hi[j - 1] = static_cast<int>(clampD(hi, 0.0, double(g.nxp)));
    }
  }
  return r;
}

// Packed centre (PackedUV, with its footprint level) of voxel x < nx of a row: the full
// plumb_bob model in float, the operations of projectRowAvx2 lane by lane.
PSFS_HD uint32_t projectVoxel(const ProjectionCamera& cam, const ProjectionRow& r, int x) {
  const float xs = static_cast<float>(x);
  const float X = fmaf(xs, r.b[0], r.a[0]);
  const float Y = fmaf(xs, r.b[1], r.a[1]);
  const float Z = fmaf(xs, r.b[2], r.a[2]);
  const bool front = Z > kMinDepth;
  const float iz = 1.0f / (front ? Z : 1.0f);
  const float xn = X * iz, yn = Y * iz;
  const float xx = xn * xn, yy = yn * yn, xy = xn * yn;
  const float r2 = xx + yy;
  const float radial = fmaf(r2, fmaf(r2, fmaf(r2, cam.k3, cam.k2), cam.k1), 1.0f);
  // plumb_bob: xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2), yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
  const float tx = fmaf(cam.p1x2, xy, fmaf(cam.p2x2, xx, cam.p2 * r2));
  const float ty = fmaf(cam.p2x2, xy, fmaf(cam.p1x2, yy, cam.p1 * r2));
  const float xd = fmaf(xn, radial, tx), yd = fmaf(yn, radial, ty);
  const float U = fmaf(cam.fx16, xd, cam.cx16);
  const float V = fmaf(cam.fy16, yd, cam.cy16);
  const bool ok = front && r2 <= cam.r2_max && U >= 0.0f && U < cam.u_max && V >= 0.0f && V < cam.v_max;
  if (!ok) return cam.not_observed;
  const uint32_t pu = static_cast<uint32_t>(static_cast<int>(U));
  const uint32_t pv = static_cast<uint32_t>(static_cast<int>(V));
  uint32_t level = 0;
  for (int j = 0; j < r.nlev; ++j) level += (x >= r.lev_lo[j]) & (x < r.lev_hi[j]);
  return (pu | (pv << 16)) + level * r.lev_step;
}

// World point -> pixel with the double camera model (CameraModel::projectCamera behind
// camera_T_world and the lens range check of the offsets). False: no valid projection.
PSFS_HD bool projectForOffsets(const ProjectionCamera& cam, const double pw[3], double* u, double* v) {
  double pc[3];
  for (int i = 0; i < 3; ++i) {
    const double* r = cam.camera_T_world_R + 3 * i;
    pc[i] = ((r[0] * pw[0] + r[1] * pw[1]) + r[2] * pw[2]) + cam.camera_T_world_t[i];
  }
  if (!(pc[2] > kMinDepth)) return false;
  const double r2_check = (pc[0] * pc[0] + pc[1] * pc[1]) / (pc[2] * pc[2]);
  if (!(r2_check <= cam.r2_max)) return false;
  if (!(pc[2] > 1e-9)) return false;
  const double x = pc[0] / pc[2], y = pc[1] / pc[2];
  const double k1 = cam.distortion[0], k2 = cam.distortion[1], p1 = cam.distortion[2],
               p2 = cam.distortion[3], k3 = cam.distortion[4];
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
  *u = cam.fx * xd + cam.cx;
  *v = cam.fy * yd + cam.cy;
  return true;
}

// The sample offsets of chunk `ch` of row (y, z): per axis the image displacement of +1/2
// voxel, packed as int16 du (low) and dv (high) in 1/16 px, clamped to kProjMaxOffsetPx; all 0
// when a sample point leaves the valid lens range (the chunk is then sampled at the centre).
PSFS_HD void chunkOffsets(const ProjectionCamera& cam, const ProjectionGrid& g, int y, int z, int ch,
                          uint32_t out[3]) {
  const double s = g.voxel_size;
  const int first = ch * kProjChunk;
  const int n = g.nx - first < kProjChunk ? g.nx - first : kProjChunk;
  const double c[3] = {first + 0.5 * n, y + 0.5, z + 0.5};
  double mid[3];
  for (int i = 0; i < 3; ++i) mid[i] = g.origin[i] + s * c[i];
  const int lim = kProjMaxOffsetPx * kProjOne;
  uint32_t packed[3] = {0, 0, 0};
  bool ok = true;
  for (int axis = 0; axis < 3 && ok; ++axis) {
    // +-1/4 voxel around the chunk's middle: a - b spans half a voxel.
    double pa[3], pb[3];
    for (int i = 0; i < 3; ++i) {
      const double d = i == axis ? 0.25 * s : 0.0;
      pa[i] = mid[i] + d;
      pb[i] = mid[i] - d;
    }
    double ua, va, ub, vb;
    ok = projectForOffsets(cam, pa, &ua, &va) && projectForOffsets(cam, pb, &ub, &vb);
    if (!ok) break;
    const double ju = (ua - ub) * kProjOne, jv = (va - vb) * kProjOne;  // centre -> face centre
    const int du = clampI(static_cast<int>(lround(ju)), -lim, lim);
    const int dv = clampI(static_cast<int>(lround(jv)), -lim, lim);
    packed[axis] = (static_cast<uint32_t>(du) & 0xFFFFu) | (static_cast<uint32_t>(dv) << 16);
  }
  for (int axis = 0; axis < 3; ++axis) out[axis] = ok ? packed[axis] : 0u;
}

}  // namespace detail
}  // namespace psfs
