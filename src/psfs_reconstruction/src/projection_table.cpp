#include "psfs_reconstruction/projection_table.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <stdexcept>
#include <string>

#include "cpu_dispatch.h"
#include "tabletop_capture/rig_description.h"

#if PSFS_HAVE_X86_DISPATCH
#include <immintrin.h>
#endif

namespace psfs {
namespace {

// Nearest depth (m) at which a point still counts as in front of a camera.
constexpr float kMinDepth = 1e-4f;

// Per camera constants of the row projection, folded for few operations: PackedUV stores
// 16 (u + 0.5), so U = fx16 * xd + cx16 with fx16 = 16 fx, cx16 = 16 (cx + 0.5).
struct RowParams {
  float a[3], b[3];  // camera-frame position of voxel x: a + x * b
  float fx16, fy16, cx16, cy16;
  float k1, k2, k3, p1, p2, p1x2, p2x2;
  float r2_max;
  float u_max, v_max;  // 16 * width, 16 * height
  uint32_t not_observed;
  int nx, nxp;
  // Footprint levels: voxel x is at level #{j : lev_lo[j] <= x < lev_hi[j]}, added to the packed
  // centre as that many lev_step (= (height + 1) rows). Integer bounds computed once per row in
  // double, so every copy of the loop gives the same levels.
  int nlev = 0;
  int lev_lo[ProjectionTable::kMaxFootprintLevels - 1], lev_hi[ProjectionTable::kMaxFootprintLevels - 1];
  uint32_t lev_step = 0;
};

// The row projection: full plumb_bob model in float (portable copy; the AVX2 copy below does
// the same steps 8 voxels at a time, with FMA, so results may differ in the last float bit).
inline void projectRowBody(const RowParams& p, uint32_t* out) {
  for (int x = 0; x < p.nx; ++x) {
    const float fxv = static_cast<float>(x);
    const float X = p.a[0] + fxv * p.b[0];
    const float Y = p.a[1] + fxv * p.b[1];
    const float Z = p.a[2] + fxv * p.b[2];
    const int front = Z > kMinDepth;
    const float iz = 1.0f / (front ? Z : 1.0f);
    const float xn = X * iz, yn = Y * iz;
    const float xx = xn * xn, yy = yn * yn, xy = xn * yn;
    const float r2 = xx + yy;
    const float radial = 1.0f + r2 * (p.k1 + r2 * (p.k2 + r2 * p.k3));
    // plumb_bob: xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2), yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
    const float xd = xn * radial + (p.p1x2 * xy + (p.p2x2 * xx + p.p2 * r2));
    const float yd = yn * radial + (p.p2x2 * xy + (p.p1x2 * yy + p.p1 * r2));
    const float U = p.fx16 * xd + p.cx16;
    const float V = p.fy16 * yd + p.cy16;
    // Bitwise & (not &&): no control flow.
    const int ok = front & (r2 <= p.r2_max) & (U >= 0.0f) & (U < p.u_max) & (V >= 0.0f) &
                   (V < p.v_max);
    const uint32_t pu = static_cast<uint32_t>(static_cast<int>(ok ? U : 0.0f));
    const uint32_t pv = static_cast<uint32_t>(static_cast<int>(ok ? V : 0.0f));
    uint32_t level = 0;
    for (int j = 0; j < p.nlev; ++j) level += (x >= p.lev_lo[j]) & (x < p.lev_hi[j]);
    out[x] = ok ? (pu | (pv << 16)) + level * p.lev_step : p.not_observed;
  }
  for (int x = p.nx; x < p.nxp; ++x) out[x] = p.not_observed;
}

#if PSFS_HAVE_X86_DISPATCH
__attribute__((target("avx2,fma"))) void projectRowAvx2(const RowParams& p, uint32_t* out) {
  const __m256 a0 = _mm256_set1_ps(p.a[0]), a1 = _mm256_set1_ps(p.a[1]), a2 = _mm256_set1_ps(p.a[2]);
  const __m256 b0 = _mm256_set1_ps(p.b[0]), b1 = _mm256_set1_ps(p.b[1]), b2 = _mm256_set1_ps(p.b[2]);
  const __m256 zmin = _mm256_set1_ps(kMinDepth), fone = _mm256_set1_ps(1.0f);
  const __m256i sentinel = _mm256_set1_epi32(static_cast<int>(p.not_observed));
  const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (int x0 = 0; x0 < p.nxp; x0 += 8) {
    const __m256i xi = _mm256_add_epi32(_mm256_set1_epi32(x0), lanes);
    const __m256 xs = _mm256_cvtepi32_ps(xi);
    const __m256 X = _mm256_fmadd_ps(xs, b0, a0), Y = _mm256_fmadd_ps(xs, b1, a1);
    const __m256 Z = _mm256_fmadd_ps(xs, b2, a2);
    const __m256 front = _mm256_cmp_ps(Z, zmin, _CMP_GT_OQ);
    const __m256 iz = _mm256_div_ps(fone, _mm256_blendv_ps(fone, Z, front));
    const __m256 xn = _mm256_mul_ps(X, iz), yn = _mm256_mul_ps(Y, iz);
    const __m256 xx = _mm256_mul_ps(xn, xn), yy = _mm256_mul_ps(yn, yn), xy = _mm256_mul_ps(xn, yn);
    const __m256 r2 = _mm256_add_ps(xx, yy);
    const __m256 radial = _mm256_fmadd_ps(
        r2, _mm256_fmadd_ps(r2, _mm256_fmadd_ps(r2, _mm256_set1_ps(p.k3), _mm256_set1_ps(p.k2)),
                            _mm256_set1_ps(p.k1)),
        fone);
    const __m256 p1 = _mm256_set1_ps(p.p1), p2 = _mm256_set1_ps(p.p2);
    const __m256 p1x2 = _mm256_set1_ps(p.p1x2), p2x2 = _mm256_set1_ps(p.p2x2);
    const __m256 tx = _mm256_fmadd_ps(p1x2, xy, _mm256_fmadd_ps(p2x2, xx, _mm256_mul_ps(p2, r2)));
    const __m256 ty = _mm256_fmadd_ps(p2x2, xy, _mm256_fmadd_ps(p1x2, yy, _mm256_mul_ps(p1, r2)));
    const __m256 xd = _mm256_fmadd_ps(xn, radial, tx), yd = _mm256_fmadd_ps(yn, radial, ty);
    const __m256 U = _mm256_fmadd_ps(_mm256_set1_ps(p.fx16), xd, _mm256_set1_ps(p.cx16));
    const __m256 V = _mm256_fmadd_ps(_mm256_set1_ps(p.fy16), yd, _mm256_set1_ps(p.cy16));
    const __m256 zero = _mm256_setzero_ps();
    __m256 ok = _mm256_and_ps(front, _mm256_cmp_ps(r2, _mm256_set1_ps(p.r2_max), _CMP_LE_OQ));
    ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_cmp_ps(U, zero, _CMP_GE_OQ),
                                         _mm256_cmp_ps(U, _mm256_set1_ps(p.u_max), _CMP_LT_OQ)));
    ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_cmp_ps(V, zero, _CMP_GE_OQ),
                                         _mm256_cmp_ps(V, _mm256_set1_ps(p.v_max), _CMP_LT_OQ)));
    // Padding lanes (x >= nx) are not observed.
    ok = _mm256_and_ps(ok, _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(p.nx), xi)));
    const __m256i pu = _mm256_cvttps_epi32(_mm256_and_ps(U, ok));
    const __m256i pv = _mm256_cvttps_epi32(_mm256_and_ps(V, ok));
    __m256i packed = _mm256_or_si256(pu, _mm256_slli_epi32(pv, 16));
    for (int j = 0; j < p.nlev; ++j) {
      const __m256i in = _mm256_and_si256(_mm256_cmpgt_epi32(xi, _mm256_set1_epi32(p.lev_lo[j] - 1)),
                                          _mm256_cmpgt_epi32(_mm256_set1_epi32(p.lev_hi[j]), xi));
      packed = _mm256_add_epi32(packed, _mm256_and_si256(in, _mm256_set1_epi32(static_cast<int>(p.lev_step))));
    }
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + x0),
                        _mm256_blendv_epi8(sentinel, packed, _mm256_castps_si256(ok)));
  }
}
#endif

#if PSFS_HAVE_X86_DISPATCH
// The same steps 16 voxels at a time (same float operations per lane: identical results).
// GCC 12's AVX-512 intrinsics trip -Wmaybe-uninitialized when inlined (GCC bug 105593).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
__attribute__((target("avx512f,avx2,fma"))) void projectRowAvx512(const RowParams& p, uint32_t* out) {
  const __m512 a0 = _mm512_set1_ps(p.a[0]), a1 = _mm512_set1_ps(p.a[1]), a2 = _mm512_set1_ps(p.a[2]);
  const __m512 b0 = _mm512_set1_ps(p.b[0]), b1 = _mm512_set1_ps(p.b[1]), b2 = _mm512_set1_ps(p.b[2]);
  const __m512 zmin = _mm512_set1_ps(kMinDepth), fone = _mm512_set1_ps(1.0f);
  const __m512i sentinel = _mm512_set1_epi32(static_cast<int>(p.not_observed));
  const __m512i lanes = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  for (int x0 = 0; x0 < p.nxp; x0 += 16) {
    const __mmask16 store = x0 + 16 <= p.nxp ? __mmask16(0xFFFF) : __mmask16(0x00FF);  // nxp: multiple of 8
    const __m512i xi = _mm512_add_epi32(_mm512_set1_epi32(x0), lanes);
    const __m512 xs = _mm512_cvtepi32_ps(xi);
    const __m512 X = _mm512_fmadd_ps(xs, b0, a0), Y = _mm512_fmadd_ps(xs, b1, a1);
    const __m512 Z = _mm512_fmadd_ps(xs, b2, a2);
    const __mmask16 front = _mm512_cmp_ps_mask(Z, zmin, _CMP_GT_OQ);
    const __m512 iz = _mm512_div_ps(fone, _mm512_mask_blend_ps(front, fone, Z));
    const __m512 xn = _mm512_mul_ps(X, iz), yn = _mm512_mul_ps(Y, iz);
    const __m512 xx = _mm512_mul_ps(xn, xn), yy = _mm512_mul_ps(yn, yn), xy = _mm512_mul_ps(xn, yn);
    const __m512 r2 = _mm512_add_ps(xx, yy);
    const __m512 radial = _mm512_fmadd_ps(
        r2, _mm512_fmadd_ps(r2, _mm512_fmadd_ps(r2, _mm512_set1_ps(p.k3), _mm512_set1_ps(p.k2)),
                            _mm512_set1_ps(p.k1)),
        fone);
    const __m512 p1 = _mm512_set1_ps(p.p1), p2 = _mm512_set1_ps(p.p2);
    const __m512 p1x2 = _mm512_set1_ps(p.p1x2), p2x2 = _mm512_set1_ps(p.p2x2);
    const __m512 tx = _mm512_fmadd_ps(p1x2, xy, _mm512_fmadd_ps(p2x2, xx, _mm512_mul_ps(p2, r2)));
    const __m512 ty = _mm512_fmadd_ps(p2x2, xy, _mm512_fmadd_ps(p1x2, yy, _mm512_mul_ps(p1, r2)));
    const __m512 xd = _mm512_fmadd_ps(xn, radial, tx), yd = _mm512_fmadd_ps(yn, radial, ty);
    const __m512 U = _mm512_fmadd_ps(_mm512_set1_ps(p.fx16), xd, _mm512_set1_ps(p.cx16));
    const __m512 V = _mm512_fmadd_ps(_mm512_set1_ps(p.fy16), yd, _mm512_set1_ps(p.cy16));
    const __m512 zero = _mm512_setzero_ps();
    __mmask16 ok = front & _mm512_cmp_ps_mask(r2, _mm512_set1_ps(p.r2_max), _CMP_LE_OQ);
    ok &= _mm512_cmp_ps_mask(U, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(U, _mm512_set1_ps(p.u_max), _CMP_LT_OQ);
    ok &= _mm512_cmp_ps_mask(V, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(V, _mm512_set1_ps(p.v_max), _CMP_LT_OQ);
    ok &= _mm512_cmpgt_epi32_mask(_mm512_set1_epi32(p.nx), xi);  // padding lanes: not observed
    const __m512i pu = _mm512_cvttps_epi32(_mm512_maskz_mov_ps(ok, U));
    const __m512i pv = _mm512_cvttps_epi32(_mm512_maskz_mov_ps(ok, V));
    __m512i packed = _mm512_or_si512(pu, _mm512_slli_epi32(pv, 16));
    for (int j = 0; j < p.nlev; ++j) {
      const __mmask16 in = _mm512_cmpgt_epi32_mask(xi, _mm512_set1_epi32(p.lev_lo[j] - 1)) &
                           _mm512_cmpgt_epi32_mask(_mm512_set1_epi32(p.lev_hi[j]), xi);
      packed = _mm512_mask_add_epi32(packed, in, packed, _mm512_set1_epi32(static_cast<int>(p.lev_step)));
    }
    _mm512_mask_storeu_epi32(out + x0, store, _mm512_mask_blend_epi32(ok, sentinel, packed));
  }
}
#pragma GCC diagnostic pop
#endif

[[noreturn]] void badCamera(int index, const std::string& name, const std::string& why) {
  throw std::invalid_argument("psfs::ProjectionTable: camera " + std::to_string(index) + " ('" +
                              name + "'): " + why);
}

bool sameCamera(const tabletop_capture::CameraModel& a, const tabletop_capture::CameraModel& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
         a.cx == b.cx && a.cy == b.cy && a.distortion == b.distortion &&
         a.world_T_camera.matrix() == b.world_T_camera.matrix();
}

}  // namespace

ProjectionTable::Camera ProjectionTable::prepareCamera(const tabletop_capture::CameraModel& m,
                                                       int index) {
  try {
    tabletop_capture::validateCamera(m, "psfs::ProjectionTable", index);
  } catch (const std::exception& e) {
    throw std::invalid_argument(e.what());
  }
  if (m.width > PackedUV::kMaxImageSide || m.height > PackedUV::kMaxImageSide)
    badCamera(index, m.name, "image side above " + std::to_string(PackedUV::kMaxImageSide) + " px");
  Camera c;
  c.model = m;
  c.camera_R_world = m.world_T_camera.linear().transpose();
  c.position = m.world_T_camera.translation();
  c.fx = float(m.fx), c.fy = float(m.fy), c.cx = float(m.cx), c.cy = float(m.cy);
  c.k1 = float(m.distortion[0]), c.k2 = float(m.distortion[1]), c.p1 = float(m.distortion[2]);
  c.p2 = float(m.distortion[3]), c.k3 = float(m.distortion[4]);
  c.distorted = m.hasDistortion();
  c.width = m.width;
  c.height = m.height;
  c.focal = std::sqrt(m.fx * m.fy);
  c.r2_max = FLT_MAX;
  if (c.distorted) {
    // The polynomial lens model is only valid near the image: far outside, barrel distortion
    // folds back and would map points behind the image border into it. Limit projections to
    // the squared normalised radius of the image border (undistorted) plus 10 %, and to where
    // the radial map r -> r * radial(r^2) is still increasing.
    double r2 = 0.0;
    auto edge = [&](double u, double v) {
      const Eigen::Vector2d xn = m.undistort(Eigen::Vector2d((u - m.cx) / m.fx, (v - m.cy) / m.fy));
      if (xn.allFinite()) r2 = std::max(r2, xn.squaredNorm());
    };
    const double u0 = -0.5, u1 = m.width - 0.5, v0 = -0.5, v1 = m.height - 0.5;
    for (int i = 0; i <= 64; ++i) {
      const double s = i / 64.0;
      edge(u0 + s * (u1 - u0), v0), edge(u0 + s * (u1 - u0), v1);
      edge(u0, v0 + s * (v1 - v0)), edge(u1, v0 + s * (v1 - v0));
    }
    double limit = 1.1 * 1.1 * r2;
    const double k1 = m.distortion[0], k2 = m.distortion[1], k3 = m.distortion[4];
    for (int i = 1; i <= 1000; ++i) {
      const double q = limit * i / 1000.0;  // r^2
      if (1.0 + 3.0 * k1 * q + 5.0 * k2 * q * q + 7.0 * k3 * q * q * q <= 0.0) {
        limit = 0.95 * 0.95 * q;
        break;
      }
    }
    if (!(limit > 0.0) || !std::isfinite(limit)) badCamera(index, m.name, "lens model has no valid range");
    c.r2_max = static_cast<float>(limit);
  }
  return c;
}

ProjectionTable::ProjectionTable(const VoxelGrid& grid,
                                 const std::vector<tabletop_capture::CameraModel>& cameras,
                                 const ProjectionTableOptions& options)
    : options_(options) {
  grid.validate();
  if (cameras.empty()) throw std::invalid_argument("psfs::ProjectionTable: no cameras");
  if (options.threads < 0) throw std::invalid_argument("psfs::ProjectionTable: threads < 0");
  if (options.footprint_levels != 0) {
    if (options.footprint_levels < 2 || options.footprint_levels > kMaxFootprintLevels)
      throw std::invalid_argument("psfs::ProjectionTable: footprint_levels must be 0 or in 2.." +
                                  std::to_string(kMaxFootprintLevels));
    if (options.multi_projection)
      throw std::invalid_argument("psfs::ProjectionTable: footprint_levels and multi_projection are exclusive");
    if (!std::isfinite(options.footprint_scale) || !(options.footprint_scale > 0.0))
      throw std::invalid_argument("psfs::ProjectionTable: footprint_scale must be > 0");
  }
  grid_ = grid;
  for (size_t i = 0; i < cameras.size(); ++i)
    cameras_.push_back(prepareCamera(cameras[i], static_cast<int>(i)));
  checkFootprintRows(cameras_);
  build();
}

bool ProjectionTable::update(const VoxelGrid& grid,
                             const std::vector<tabletop_capture::CameraModel>& cameras) {
  bool same = grid == grid_ && cameras.size() == cameras_.size() && !cameras_.empty();
  for (size_t i = 0; same && i < cameras.size(); ++i) same = sameCamera(cameras[i], cameras_[i].model);
  if (same) return false;
  grid.validate();
  if (cameras.empty()) throw std::invalid_argument("psfs::ProjectionTable: no cameras");
  std::vector<Camera> prepared;
  for (size_t i = 0; i < cameras.size(); ++i)
    prepared.push_back(prepareCamera(cameras[i], static_cast<int>(i)));
  checkFootprintRows(prepared);
  grid_ = grid;
  cameras_ = std::move(prepared);
  build();
  return true;
}

size_t ProjectionTable::precomputedBytes(const VoxelGrid& grid, int num_cameras, bool multi) {
  const size_t nxp = (static_cast<size_t>(grid.dims.x()) + kChunk - 1) / kChunk * kChunk;
  const size_t per_row = nxp * 4 + (multi ? nxp / kChunk * 3 * 4 : 0);
  return per_row * grid.numRows() * static_cast<size_t>(num_cameras);
}

size_t ProjectionTable::memoryBytes() const {
  return (centres_.size() + offsets_.size()) * sizeof(uint32_t);
}

void ProjectionTable::checkFootprintRows(const std::vector<Camera>& cams) const {
  const int L = options_.footprint_levels;
  for (size_t i = 0; i < cams.size() && L > 0; ++i)
    if ((cams[i].height + 1) * L > (0xFFFF >> PackedUV::kFracBits))
      badCamera(static_cast<int>(i), cams[i].model.name,
                "image too high for " + std::to_string(L) + " footprint levels");
}

void ProjectionTable::build() {
  nxp_ = (grid_.dims.x() + kChunk - 1) / kChunk * kChunk;
  const size_t bytes = precomputedBytes(grid_, numCameras(), options_.multi_projection);
  precomputed_ = options_.storage == TableStorage::kPrecomputed ||
                 (options_.storage == TableStorage::kAuto && bytes <= options_.auto_max_bytes);
  centres_.clear();
  offsets_.clear();
  centres_.shrink_to_fit();
  offsets_.shrink_to_fit();
  if (!precomputed_) return;
  const size_t C = cameras_.size(), rows = grid_.numRows();
  const size_t cs = centreScratchSize(), os = offsetScratchSize();
  centres_.resize(rows * cs);
  if (options_.multi_projection) offsets_.resize(rows * os);
  const int ny = grid_.dims.y();
  const long long nrows = static_cast<long long>(rows);
  const int threads = options_.threads;
#pragma omp parallel for schedule(dynamic, 16) num_threads(resolveThreads(threads))
  for (long long r = 0; r < nrows; ++r) {
    const int y = static_cast<int>(r % ny), z = static_cast<int>(r / ny);
    for (size_t c = 0; c < C; ++c) {
      projectRow(cameras_[c], y, z, &centres_[size_t(r) * cs + c * nxp_]);
      if (options_.multi_projection)
        sampleOffsets(cameras_[c], y, z, &offsets_[size_t(r) * os + c * chunksPerRow() * 3]);
    }
  }
}

void ProjectionTable::projectRow(const Camera& cam, int y, int z, uint32_t* out) const {
  RowParams p;
  const Eigen::Vector3d p0 = grid_.centre(0, y, z);
  // Row start in double (camera-frame offsets are up to metres), the per-voxel step in float.
  const Eigen::Vector3d a = cam.camera_R_world * (p0 - cam.position);
  const Eigen::Vector3d b = cam.camera_R_world.col(0) * grid_.voxel_size;
  for (int r = 0; r < 3; ++r) {
    p.a[r] = static_cast<float>(a[r]);
    p.b[r] = static_cast<float>(b[r]);
  }
  const float one = static_cast<float>(PackedUV::kOne);
  p.fx16 = one * cam.fx, p.fy16 = one * cam.fy;
  p.cx16 = one * (cam.cx + 0.5f), p.cy16 = one * (cam.cy + 0.5f);
  p.k1 = cam.k1, p.k2 = cam.k2, p.k3 = cam.k3, p.p1 = cam.p1, p.p2 = cam.p2;
  p.p1x2 = 2.0f * cam.p1, p.p2x2 = 2.0f * cam.p2;
  p.r2_max = cam.r2_max;
  p.u_max = static_cast<float>(PackedUV::kOne * cam.width);
  p.v_max = static_cast<float>(PackedUV::kOne * cam.height);
  p.not_observed = PackedUV::notObserved(cam.height);
  p.nx = grid_.dims.x();
  p.nxp = nxp_;
  if (options_.footprint_levels > 0) {
    // level >= j  <=>  round(scale * f s / Z) >= j  <=>  Z <= scale f s / (j - 1/2), with
    // Z(x) = a_z + x b_z (camera frame); the x range where that holds, as integers.
    p.nlev = options_.footprint_levels - 1;
    p.lev_step = static_cast<uint32_t>(PackedUV::kOne * (cam.height + 1)) << 16;
    for (int j = 1; j <= p.nlev; ++j) {
      const double zj = options_.footprint_scale * cam.focal * grid_.voxel_size / (j - 0.5);
      double lo = 0.0, hi = nxp_;  // [lo, hi)
      if (b[2] > 0.0) {
        hi = std::floor((zj - a[2]) / b[2]) + 1.0;
      } else if (b[2] < 0.0) {
        lo = std::ceil((zj - a[2]) / b[2]);
      } else if (!(a[2] <= zj)) {
        hi = 0.0;
      }
      p.lev_lo[j - 1] = static_cast<int>(std::clamp(lo, 0.0, double(nxp_)));
      p.lev_hi[j - 1] = static_cast<int>(std::clamp(hi, 0.0, double(nxp_)));
    }
  }
#if PSFS_HAVE_X86_DISPATCH
  if (avx512KernelsActive()) {
    projectRowAvx512(p, out);
    return;
  }
  if (cpuHasAvx2()) {
    projectRowAvx2(p, out);
    return;
  }
#endif
  projectRowBody(p, out);
}

void ProjectionTable::sampleOffsets(const Camera& cam, int y, int z, uint32_t* out) const {
  const Eigen::Isometry3d cTw = cam.model.world_T_camera.inverse();
  auto project = [&](const Eigen::Vector3d& pw, Eigen::Vector2d* px) {
    const Eigen::Vector3d pc = cTw * pw;
    if (!(pc.z() > kMinDepth)) return false;
    const double r2 = (pc.x() * pc.x() + pc.y() * pc.y()) / (pc.z() * pc.z());
    if (!(r2 <= cam.r2_max)) return false;
    return cam.model.projectCamera(pc, px);
  };
  const int nx = grid_.dims.x();
  const double s = grid_.voxel_size;
  const int lim = kMaxSampleOffsetPx * PackedUV::kOne;
  for (int ch = 0; ch < chunksPerRow(); ++ch) {
    const int first = ch * kChunk, n = std::min(kChunk, nx - first);
    const Eigen::Vector3d mid =
        grid_.origin + s * Eigen::Vector3d(first + 0.5 * n, y + 0.5, z + 0.5);
    uint32_t packed[3] = {0, 0, 0};
    bool ok = true;
    for (int axis = 0; axis < 3 && ok; ++axis) {
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      d[axis] = 0.25 * s;  // +-1/4 voxel around the chunk's middle: a - b spans half a voxel
      Eigen::Vector2d a, b;
      ok = project(mid + d, &a) && project(mid - d, &b);
      if (!ok) break;
      const Eigen::Vector2d j = (a - b) * PackedUV::kOne;  // centre -> face centre
      const int du = std::clamp(static_cast<int>(std::lround(j.x())), -lim, lim);
      const int dv = std::clamp(static_cast<int>(std::lround(j.y())), -lim, lim);
      packed[axis] = (static_cast<uint32_t>(du) & 0xFFFFu) | (static_cast<uint32_t>(dv) << 16);
    }
    // A chunk whose sample points leave the valid lens range is (nearly) outside the image:
    // sample its voxels at the centre only.
    for (int axis = 0; axis < 3; ++axis) out[ch * 3 + axis] = ok ? packed[axis] : 0u;
  }
}

const uint32_t* ProjectionTable::rowCentres(size_t row, uint32_t* scratch) const {
  const size_t cs = centreScratchSize();
  if (precomputed_) return &centres_[row * cs];
  const int ny = grid_.dims.y();
  const int y = static_cast<int>(row % ny), z = static_cast<int>(row / ny);
  for (size_t c = 0; c < cameras_.size(); ++c) projectRow(cameras_[c], y, z, scratch + c * nxp_);
  return scratch;
}

const uint32_t* ProjectionTable::rowOffsets(size_t row, uint32_t* scratch) const {
  if (!options_.multi_projection)
    throw std::logic_error("psfs::ProjectionTable: built without multi_projection");
  const size_t os = offsetScratchSize();
  if (precomputed_) return &offsets_[row * os];
  const int ny = grid_.dims.y();
  const int y = static_cast<int>(row % ny), z = static_cast<int>(row / ny);
  for (size_t c = 0; c < cameras_.size(); ++c)
    sampleOffsets(cameras_[c], y, z, scratch + c * chunksPerRow() * 3);
  return scratch;
}

uint32_t ProjectionTable::centre(int c, int x, int y, int z) const {
  const size_t row = static_cast<size_t>(y) + static_cast<size_t>(grid_.dims.y()) * z;
  uint32_t packed;
  if (precomputed_) {
    packed = centres_[row * centreScratchSize() + size_t(c) * nxp_ + x];
  } else {
    std::vector<uint32_t> tmp(nxp_);
    projectRow(cameras_[c], y, z, tmp.data());
    packed = tmp[x];
  }
  return withoutLevel(c, packed);
}

int ProjectionTable::footprintLevel(int c, int x, int y, int z) const {
  const size_t row = static_cast<size_t>(y) + static_cast<size_t>(grid_.dims.y()) * z;
  if (precomputed_) return footprintLevelOf(c, centres_[row * centreScratchSize() + size_t(c) * nxp_ + x]);
  std::vector<uint32_t> tmp(nxp_);
  projectRow(cameras_[c], y, z, tmp.data());
  return footprintLevelOf(c, tmp[x]);
}

}  // namespace psfs
