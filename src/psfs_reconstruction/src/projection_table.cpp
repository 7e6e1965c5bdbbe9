#include "psfs_reconstruction/projection_table.h"

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <stdexcept>
#include <string>

#include "cpu_dispatch.h"
#include "tabletop_capture/rig_description.h"
#include "voxel_projection.h"

#if PSFS_HAVE_X86_DISPATCH
#include <immintrin.h>
#endif

namespace psfs {
static_assert(detail::kProjChunk == ProjectionTable::kChunk &&
                  detail::kProjMaxOffsetPx == ProjectionTable::kMaxSampleOffsetPx &&
                  detail::kProjMaxLevels == ProjectionTable::kMaxFootprintLevels &&
                  detail::kProjOne == PackedUV::kOne && detail::kProjFracBits == PackedUV::kFracBits,
              "voxel_projection.h's constants must be the table's");
namespace {

// The row projection's fast paths: projectVoxel (voxel_projection.h) 8 or 16 voxels at a time,
// the same float operations per lane (FMAs included), so every path writes the same table; the
// portable path is projectVoxel itself. Voxels x in [nx, nxp) are padding: not observed.
// Voxels [begin, end) of a row (whole chunks, end <= nxp) into out[begin, end).
inline void projectRowBody(const ProjectionCamera& cam, const detail::ProjectionRow& p, int nx, int begin,
                           int end, uint32_t* out) {
  for (int x = begin; x < std::min(nx, end); ++x) out[x] = detail::projectVoxel(cam, p, x);
  for (int x = std::max(nx, begin); x < end; ++x) out[x] = cam.not_observed;
}

#if PSFS_HAVE_X86_DISPATCH
__attribute__((target("avx2,fma"))) void projectRowAvx2(const ProjectionCamera& cam, const detail::ProjectionRow& p,
                                                        int nx, int begin, int end, uint32_t* out) {
  const __m256 a0 = _mm256_set1_ps(p.a[0]), a1 = _mm256_set1_ps(p.a[1]), a2 = _mm256_set1_ps(p.a[2]);
  const __m256 b0 = _mm256_set1_ps(p.b[0]), b1 = _mm256_set1_ps(p.b[1]), b2 = _mm256_set1_ps(p.b[2]);
  const __m256 zmin = _mm256_set1_ps(detail::kMinDepth), fone = _mm256_set1_ps(1.0f);
  const __m256i sentinel = _mm256_set1_epi32(static_cast<int>(cam.not_observed));
  const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (int x0 = begin; x0 < end; x0 += 8) {
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
        r2, _mm256_fmadd_ps(r2, _mm256_fmadd_ps(r2, _mm256_set1_ps(cam.k3), _mm256_set1_ps(cam.k2)),
                            _mm256_set1_ps(cam.k1)),
        fone);
    const __m256 p1 = _mm256_set1_ps(cam.p1), p2 = _mm256_set1_ps(cam.p2);
    const __m256 p1x2 = _mm256_set1_ps(cam.p1x2), p2x2 = _mm256_set1_ps(cam.p2x2);
    const __m256 tx = _mm256_fmadd_ps(p1x2, xy, _mm256_fmadd_ps(p2x2, xx, _mm256_mul_ps(p2, r2)));
    const __m256 ty = _mm256_fmadd_ps(p2x2, xy, _mm256_fmadd_ps(p1x2, yy, _mm256_mul_ps(p1, r2)));
    const __m256 xd = _mm256_fmadd_ps(xn, radial, tx), yd = _mm256_fmadd_ps(yn, radial, ty);
    const __m256 U = _mm256_fmadd_ps(_mm256_set1_ps(cam.fx16), xd, _mm256_set1_ps(cam.cx16));
    const __m256 V = _mm256_fmadd_ps(_mm256_set1_ps(cam.fy16), yd, _mm256_set1_ps(cam.cy16));
    const __m256 zero = _mm256_setzero_ps();
    __m256 ok = _mm256_and_ps(front, _mm256_cmp_ps(r2, _mm256_set1_ps(cam.r2_max), _CMP_LE_OQ));
    ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_cmp_ps(U, zero, _CMP_GE_OQ),
                                         _mm256_cmp_ps(U, _mm256_set1_ps(cam.u_max), _CMP_LT_OQ)));
    ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_cmp_ps(V, zero, _CMP_GE_OQ),
                                         _mm256_cmp_ps(V, _mm256_set1_ps(cam.v_max), _CMP_LT_OQ)));
    // Padding lanes (x >= nx) are not observed.
    ok = _mm256_and_ps(ok, _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(nx), xi)));
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
__attribute__((target("avx512f,avx2,fma"))) void projectRowAvx512(const ProjectionCamera& cam,
                                                                  const detail::ProjectionRow& p, int nx,
                                                                  int begin, int end, uint32_t* out) {
  const __m512 a0 = _mm512_set1_ps(p.a[0]), a1 = _mm512_set1_ps(p.a[1]), a2 = _mm512_set1_ps(p.a[2]);
  const __m512 b0 = _mm512_set1_ps(p.b[0]), b1 = _mm512_set1_ps(p.b[1]), b2 = _mm512_set1_ps(p.b[2]);
  const __m512 zmin = _mm512_set1_ps(detail::kMinDepth), fone = _mm512_set1_ps(1.0f);
  const __m512i sentinel = _mm512_set1_epi32(static_cast<int>(cam.not_observed));
  const __m512i lanes = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  for (int x0 = begin; x0 < end; x0 += 16) {
    const __mmask16 store = x0 + 16 <= end ? __mmask16(0xFFFF) : __mmask16(0x00FF);  // end: multiple of 8
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
        r2, _mm512_fmadd_ps(r2, _mm512_fmadd_ps(r2, _mm512_set1_ps(cam.k3), _mm512_set1_ps(cam.k2)),
                            _mm512_set1_ps(cam.k1)),
        fone);
    const __m512 p1 = _mm512_set1_ps(cam.p1), p2 = _mm512_set1_ps(cam.p2);
    const __m512 p1x2 = _mm512_set1_ps(cam.p1x2), p2x2 = _mm512_set1_ps(cam.p2x2);
    const __m512 tx = _mm512_fmadd_ps(p1x2, xy, _mm512_fmadd_ps(p2x2, xx, _mm512_mul_ps(p2, r2)));
    const __m512 ty = _mm512_fmadd_ps(p2x2, xy, _mm512_fmadd_ps(p1x2, yy, _mm512_mul_ps(p1, r2)));
    const __m512 xd = _mm512_fmadd_ps(xn, radial, tx), yd = _mm512_fmadd_ps(yn, radial, ty);
    const __m512 U = _mm512_fmadd_ps(_mm512_set1_ps(cam.fx16), xd, _mm512_set1_ps(cam.cx16));
    const __m512 V = _mm512_fmadd_ps(_mm512_set1_ps(cam.fy16), yd, _mm512_set1_ps(cam.cy16));
    const __m512 zero = _mm512_setzero_ps();
    __mmask16 ok = front & _mm512_cmp_ps_mask(r2, _mm512_set1_ps(cam.r2_max), _CMP_LE_OQ);
    ok &= _mm512_cmp_ps_mask(U, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(U, _mm512_set1_ps(cam.u_max), _CMP_LT_OQ);
    ok &= _mm512_cmp_ps_mask(V, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(V, _mm512_set1_ps(cam.v_max), _CMP_LT_OQ);
    ok &= _mm512_cmpgt_epi32_mask(_mm512_set1_epi32(nx), xi);  // padding lanes: not observed
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
  ProjectionCamera& k = c.proj;
  const Eigen::Matrix3d camera_R_world = m.world_T_camera.linear().transpose();
  const Eigen::Isometry3d camera_T_world = m.world_T_camera.inverse();
  for (int r = 0; r < 3; ++r) {
    for (int col = 0; col < 3; ++col) {
      k.camera_R_world[3 * r + col] = camera_R_world(r, col);
      k.camera_T_world_R[3 * r + col] = camera_T_world.linear()(r, col);
    }
    k.position[r] = m.world_T_camera.translation()[r];
    k.camera_T_world_t[r] = camera_T_world.translation()[r];
  }
  const float one = static_cast<float>(PackedUV::kOne);
  k.fx16 = one * float(m.fx), k.fy16 = one * float(m.fy);
  k.cx16 = one * (float(m.cx) + 0.5f), k.cy16 = one * (float(m.cy) + 0.5f);
  k.k1 = float(m.distortion[0]), k.k2 = float(m.distortion[1]), k.p1 = float(m.distortion[2]);
  k.p2 = float(m.distortion[3]), k.k3 = float(m.distortion[4]);
  k.p1x2 = 2.0f * k.p1, k.p2x2 = 2.0f * k.p2;
  k.u_max = static_cast<float>(PackedUV::kOne * m.width);
  k.v_max = static_cast<float>(PackedUV::kOne * m.height);
  k.not_observed = PackedUV::notObserved(m.height);
  k.width = m.width;
  k.height = m.height;
  k.focal = std::sqrt(m.fx * m.fy);
  k.fx = m.fx, k.fy = m.fy, k.cx = m.cx, k.cy = m.cy;
  for (int i = 0; i < 5; ++i) k.distortion[i] = m.distortion[i];
  k.r2_max = FLT_MAX;
  if (m.hasDistortion()) {
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
    k.r2_max = static_cast<float>(limit);
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
  bool same_cameras = cameras.size() == cameras_.size() && !cameras_.empty();
  for (size_t i = 0; same_cameras && i < cameras.size(); ++i) same_cameras = sameCamera(cameras[i], cameras_[i].model);
  if (same_cameras && grid == grid_) return false;
  grid.validate();
  if (cameras.empty()) throw std::invalid_argument("psfs::ProjectionTable: no cameras");
  // A grid that moves (a hand's cube, every frame) keeps the cameras' constants: preparing one
  // searches the lens model's valid range (undistorting the image border).
  if (!same_cameras) {
    std::vector<Camera> prepared;
    for (size_t i = 0; i < cameras.size(); ++i)
      prepared.push_back(prepareCamera(cameras[i], static_cast<int>(i)));
    checkFootprintRows(prepared);
    cameras_ = std::move(prepared);
  }
  grid_ = grid;
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
    if ((cams[i].proj.height + 1) * L > (0xFFFF >> PackedUV::kFracBits))
      badCamera(static_cast<int>(i), cams[i].model.name,
                "image too high for " + std::to_string(L) + " footprint levels");
}

void ProjectionTable::build() {
  static std::atomic<uint64_t> builds{0};
  revision_ = ++builds;
  nxp_ = (grid_.dims.x() + kChunk - 1) / kChunk * kChunk;
  const size_t bytes = precomputedBytes(grid_, numCameras(), options_.multi_projection);
  precomputed_ = options_.storage == TableStorage::kPrecomputed ||
                 (options_.storage == TableStorage::kAuto && bytes <= options_.auto_max_bytes);
  const size_t C = cameras_.size(), rows = grid_.numRows();
  const size_t cs = centreScratchSize(), os = offsetScratchSize();
  // A rebuild of the same size (a grid that moves) keeps the memory: fresh pages cost a fault
  // each, more than projecting a small table.
  const size_t n_centres = precomputed_ ? rows * cs : 0, n_offsets = precomputed_ && options_.multi_projection ? rows * os : 0;
  if (centres_.size() != n_centres) {
    centres_.clear();
    centres_.shrink_to_fit();
  }
  if (offsets_.size() != n_offsets) {
    offsets_.clear();
    offsets_.shrink_to_fit();
  }
  if (!precomputed_) return;
  centres_.resize(rows * cs);
  if (options_.multi_projection) offsets_.resize(rows * os);
  const int ny = grid_.dims.y();
  const long long nrows = static_cast<long long>(rows);
  const int threads = options_.threads;
#pragma omp parallel for schedule(dynamic, 16) num_threads(resolveThreads(threads))
  for (long long r = 0; r < nrows; ++r) {
    const int y = static_cast<int>(r % ny), z = static_cast<int>(r / ny);
    for (size_t c = 0; c < C; ++c) {
      projectRow(cameras_[c], y, z, &centres_[size_t(r) * cs + c * nxp_], 0, nxp_);
      if (options_.multi_projection)
        sampleOffsets(cameras_[c], y, z, &offsets_[size_t(r) * os + c * chunksPerRow() * 3]);
    }
  }
}

ProjectionGrid ProjectionTable::projectionGrid() const {
  ProjectionGrid g;
  for (int i = 0; i < 3; ++i) g.origin[i] = grid_.origin[i];
  g.voxel_size = grid_.voxel_size;
  g.nx = grid_.dims.x(), g.ny = grid_.dims.y(), g.nz = grid_.dims.z();
  g.nxp = nxp_;
  g.chunks = chunksPerRow();
  g.footprint_levels = options_.footprint_levels;
  g.footprint_scale = options_.footprint_scale;
  return g;
}

void ProjectionTable::projectRow(const Camera& cam, int y, int z, uint32_t* out, int begin, int end) const {
  const detail::ProjectionRow p = detail::projectionRow(cam.proj, projectionGrid(), y, z);
#if PSFS_HAVE_X86_DISPATCH
  if (avx512KernelsActive()) {
    projectRowAvx512(cam.proj, p, grid_.dims.x(), begin, end, out);
    return;
  }
  if (cpuHasAvx2()) {
    projectRowAvx2(cam.proj, p, grid_.dims.x(), begin, end, out);
    return;
  }
#endif
  projectRowBody(cam.proj, p, grid_.dims.x(), begin, end, out);
}

void ProjectionTable::sampleOffsets(const Camera& cam, int y, int z, uint32_t* out) const {
  const ProjectionGrid g = projectionGrid();
  for (int ch = 0; ch < g.chunks; ++ch) detail::chunkOffsets(cam.proj, g, y, z, ch, out + ch * 3);
}

const uint32_t* ProjectionTable::rowCentres(size_t row, uint32_t* scratch) const {
  const size_t cs = centreScratchSize();
  if (precomputed_) return &centres_[row * cs];
  const int ny = grid_.dims.y();
  const int y = static_cast<int>(row % ny), z = static_cast<int>(row / ny);
  for (size_t c = 0; c < cameras_.size(); ++c) projectRow(cameras_[c], y, z, scratch + c * nxp_, 0, nxp_);
  return scratch;
}

const uint32_t* ProjectionTable::rowCentres(size_t row, uint32_t* scratch, int begin, int end) const {
  if (begin < 0 || end > nxp_ || begin % kChunk != 0 || end % kChunk != 0)
    throw std::invalid_argument("psfs::ProjectionTable::rowCentres: x range must be whole chunks of the row");
  if (precomputed_) return &centres_[row * centreScratchSize()];
  const int ny = grid_.dims.y();
  const int y = static_cast<int>(row % ny), z = static_cast<int>(row / ny);
  for (size_t c = 0; c < cameras_.size(); ++c) projectRow(cameras_[c], y, z, scratch + c * nxp_, begin, end);
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
    projectRow(cameras_[c], y, z, tmp.data(), 0, nxp_);
    packed = tmp[x];
  }
  return withoutLevel(c, packed);
}

int ProjectionTable::footprintLevel(int c, int x, int y, int z) const {
  const size_t row = static_cast<size_t>(y) + static_cast<size_t>(grid_.dims.y()) * z;
  if (precomputed_) return footprintLevelOf(c, centres_[row * centreScratchSize() + size_t(c) * nxp_ + x]);
  std::vector<uint32_t> tmp(nxp_);
  projectRow(cameras_[c], y, z, tmp.data(), 0, nxp_);
  return footprintLevelOf(c, tmp[x]);
}

}  // namespace psfs
