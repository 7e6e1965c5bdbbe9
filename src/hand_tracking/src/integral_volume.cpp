#include "hand_tracking/integral_volume.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hand_tracking {

namespace {

// Largest voxel count whose byte total still fits a 32-bit table entry.
constexpr size_t kMaxVoxels32 = 0xFFFFFFFFull / 255ull;

}  // namespace

template <typename T>
void IntegralVolume::buildTable(const psfs::ProbabilityVolume& v, std::vector<T>* table) {
  const int nx = grid_.dims.x(), ny = grid_.dims.y(), nz = grid_.dims.z();
  table->resize(sz_ * static_cast<size_t>(nz + 1));
  T* t = table->data();
  // Slice z = 0 and row y = 0 of every slice are 0 (empty prefix).
  std::fill(t, t + sz_, T(0));
  const uint8_t* src = v.data.data();
  for (int z = 1; z <= nz; ++z) {
    T* slice = t + sz_ * static_cast<size_t>(z);
    const T* below = slice - sz_;
    std::fill(slice, slice + sy_, T(0));
    for (int y = 1; y <= ny; ++y) {
      T* row = slice + sy_ * static_cast<size_t>(y);
      const T* row_prev = row - sy_;           // same slice, y - 1
      const T* row_below = below + sy_ * y;    // slice z - 1, same y
      const T* row_below_prev = row_below - sy_;
      row[0] = 0;
      T run = 0;  // prefix sum along x of the voxel row (y - 1, z - 1)
      for (int x = 1; x <= nx; ++x) {
        run += *src++;
        row[x] = run + row_prev[x] + row_below[x] - row_below_prev[x];
      }
    }
  }
}

void IntegralVolume::build(const psfs::ProbabilityVolume& v) {
  v.grid.validate();
  if (v.data.size() != v.grid.numVoxels())
    throw std::invalid_argument("hand_tracking::IntegralVolume: volume has " +
                                std::to_string(v.data.size()) + " bytes but its grid " +
                                v.grid.describe() + " needs " +
                                std::to_string(v.grid.numVoxels()));
  grid_ = v.grid;
  sy_ = static_cast<size_t>(grid_.dims.x()) + 1;
  sz_ = sy_ * (static_cast<size_t>(grid_.dims.y()) + 1);
  wide_ = grid_.numVoxels() > kMaxVoxels32;
  if (wide_) {
    t32_.clear();
    t32_.shrink_to_fit();
    buildTable(v, &t64_);
  } else {
    t64_.clear();
    t64_.shrink_to_fit();
    buildTable(v, &t32_);
  }
}

uint64_t IntegralVolume::boxSum(const Eigen::Vector3i& lo_in, const Eigen::Vector3i& hi_in) const {
  if (empty()) return 0;
  Eigen::Vector3i lo, hi;
  for (int i = 0; i < 3; ++i) {
    lo[i] = std::clamp(lo_in[i], 0, grid_.dims[i]);
    hi[i] = std::clamp(hi_in[i], 0, grid_.dims[i]);
    if (hi[i] <= lo[i]) return 0;
  }
  // Unsigned wrap-around: intermediate terms may "underflow", the final difference is exact.
  const uint64_t s = corner(hi.x(), hi.y(), hi.z()) - corner(lo.x(), hi.y(), hi.z()) -
                     corner(hi.x(), lo.y(), hi.z()) - corner(hi.x(), hi.y(), lo.z()) +
                     corner(lo.x(), lo.y(), hi.z()) + corner(lo.x(), hi.y(), lo.z()) +
                     corner(hi.x(), lo.y(), lo.z()) - corner(lo.x(), lo.y(), lo.z());
  return wide_ ? s : (s & 0xFFFFFFFFull);
}

double IntegralVolume::boxMean(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                               int* voxels) const {
  if (voxels) *voxels = 0;
  if (empty() || !min.allFinite() || !max.allFinite()) return 0.0;
  Eigen::Vector3i lo, hi;
  for (int i = 0; i < 3; ++i) {
    // Voxel k's centre origin + (k + 0.5) s lies in [min, max] iff
    // (min - origin)/s - 0.5 <= k <= (max - origin)/s - 0.5. Clamp in floating point first so
    // far-away boxes cannot overflow the int conversion.
    const double n = grid_.dims[i];
    const double a = std::clamp((min[i] - grid_.origin[i]) / grid_.voxel_size - 0.5, -1.0, n + 1);
    const double b = std::clamp((max[i] - grid_.origin[i]) / grid_.voxel_size - 0.5, -2.0, n + 1);
    lo[i] = std::max(0, static_cast<int>(std::ceil(a)));
    hi[i] = std::min(grid_.dims[i], static_cast<int>(std::floor(b)) + 1);
    if (hi[i] <= lo[i]) return 0.0;
  }
  const int count = (hi - lo).prod();
  if (voxels) *voxels = count;
  return static_cast<double>(boxSum(lo, hi)) / (255.0 * count);
}

template <typename T>
double IntegralVolume::boxIntegralImpl(const std::vector<T>& table, const Eigen::Vector3d& min,
                                       const Eigen::Vector3d& max) const {
  // Per axis: the table coordinates and coefficients of the two ends. The cumulative integral
  // F(u) of a piecewise-constant field is multilinear inside each voxel, so F at a continuous
  // table coordinate u is the linear interpolation of T between floor(u) and floor(u) + 1;
  // the box integral is the 8-corner alternating sum of F, i.e. 4 x 4 x 4 weighted reads.
  int idx[3][4];
  double coef[3][4];
  for (int i = 0; i < 3; ++i) {
    const double n = grid_.dims[i];
    const double lo = std::clamp((min[i] - grid_.origin[i]) / grid_.voxel_size, 0.0, n);
    const double hi = std::clamp((max[i] - grid_.origin[i]) / grid_.voxel_size, 0.0, n);
    if (!(hi > lo)) return 0.0;
    const int lo0 = std::min(static_cast<int>(lo), grid_.dims[i] - 1);
    const int hi0 = std::min(static_cast<int>(hi), grid_.dims[i] - 1);
    const double flo = lo - lo0, fhi = hi - hi0;
    idx[i][0] = lo0;
    idx[i][1] = lo0 + 1;
    idx[i][2] = hi0;
    idx[i][3] = hi0 + 1;
    coef[i][0] = -(1.0 - flo);
    coef[i][1] = -flo;
    coef[i][2] = 1.0 - fhi;
    coef[i][3] = fhi;
  }
  const T* t = table.data();
  double sum = 0.0;
  for (int c = 0; c < 4; ++c) {
    const size_t oz = sz_ * static_cast<size_t>(idx[2][c]);
    double sy = 0.0;
    for (int b = 0; b < 4; ++b) {
      const T* row = t + oz + sy_ * static_cast<size_t>(idx[1][b]);
      // Differences of neighbouring entries first: exact in integers, small in magnitude.
      const double lo_part = coef[0][0] * static_cast<double>(row[idx[0][0]]) +
                             coef[0][1] * static_cast<double>(row[idx[0][1]]);
      const double hi_part = coef[0][2] * static_cast<double>(row[idx[0][2]]) +
                             coef[0][3] * static_cast<double>(row[idx[0][3]]);
      sy += coef[1][b] * (lo_part + hi_part);
    }
    sum += coef[2][c] * sy;
  }
  return std::max(0.0, sum);
}

double IntegralVolume::boxIntegral(const Eigen::Vector3d& min, const Eigen::Vector3d& max) const {
  if (empty() || !min.allFinite() || !max.allFinite()) return 0.0;
  return wide_ ? boxIntegralImpl(t64_, min, max) : boxIntegralImpl(t32_, min, max);
}

double IntegralVolume::boxMeanSmooth(const Eigen::Vector3d& min,
                                     const Eigen::Vector3d& max) const {
  if (empty() || !min.allFinite() || !max.allFinite()) return 0.0;
  const Eigen::Vector3d size = (max - min) / grid_.voxel_size;
  if (!(size.array() > 0.0).all()) return 0.0;
  return boxIntegral(min, max) / (255.0 * size.prod());
}

}  // namespace hand_tracking
