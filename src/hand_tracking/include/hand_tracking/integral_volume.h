// Summed-volume table ("integral volume", thesis 6.3) of a ProbabilityVolume's bytes: the sum of
// any axis-aligned voxel box in O(1) (8 table reads), which makes the MPF's box-mean
// observations independent of the box size.
//
// Layout: a (dims + 1)^3 table T with T(x, y, z) = sum of the bytes of the voxels [0,x) x [0,y) x
// [0,z), x fastest. Entries are 32-bit (unsigned wrap-around keeps the 8-corner differences
// exact while a box sum fits, i.e. up to 2^32 / 255 = 16.8 M voxels) and 64-bit above that.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/voxel_grid.h"

namespace hand_tracking {

class IntegralVolume {
 public:
  IntegralVolume() = default;
  explicit IntegralVolume(const psfs::ProbabilityVolume& v) { build(v); }

  // O(voxels); reuses its buffer. Throws std::invalid_argument for an invalid grid or a data
  // size that does not match it.
  void build(const psfs::ProbabilityVolume& v);
  bool empty() const { return grid_.numVoxels() == 0 || (t32_.empty() && t64_.empty()); }
  const psfs::VoxelGrid& grid() const { return grid_; }

  // Sum of bytes over voxel index box [lo, hi) (half-open), clipped to the grid; 0 if empty.
  uint64_t boxSum(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi) const;

  // Mean probability (0..1) over the voxels whose centres lie in the world box [min, max]
  // (metres), clipped to the grid; the count of those voxels via *voxels (may be null).
  // A box entirely outside the grid has mean 0 and 0 voxels.
  double boxMean(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                 int* voxels = nullptr) const;

  // The exact integral, in byte x voxel units, of the piecewise-constant field (each voxel's
  // byte over its cube, 0 outside the grid) over the world box [min, max]: boundary voxels
  // count with the fraction of them the box covers. It is continuous in the box position,
  // which is what a particle filter wants from its likelihood (boxMean jumps whenever a
  // voxel centre crosses a face). Costs 64 table reads (trilinear reads of the table at the
  // 8 corners). Returns 0 for an empty or non-finite box.
  double boxIntegral(const Eigen::Vector3d& min, const Eigen::Vector3d& max) const;

  // boxIntegral divided by 255 x the box volume in voxels: the mean probability over the whole
  // box with the outside of the grid counting as 0 (a box that leaves the workspace loses
  // likelihood gradually instead of averaging over a thin remainder). 0 for an empty box.
  double boxMeanSmooth(const Eigen::Vector3d& min, const Eigen::Vector3d& max) const;

 private:
  uint64_t at(size_t i) const { return wide_ ? t64_[i] : t32_[i]; }
  // Table value at integer table coordinates (already clamped to [0, dims]).
  uint64_t corner(int x, int y, int z) const {
    return at(static_cast<size_t>(x) + sy_ * static_cast<size_t>(y) +
              sz_ * static_cast<size_t>(z));
  }
  template <typename T>
  void buildTable(const psfs::ProbabilityVolume& v, std::vector<T>* table);
  template <typename T>
  double boxIntegralImpl(const std::vector<T>& table, const Eigen::Vector3d& min,
                         const Eigen::Vector3d& max) const;

  psfs::VoxelGrid grid_;
  size_t sy_ = 0, sz_ = 0;  // table strides (x stride is 1)
  bool wide_ = false;
  std::vector<uint32_t> t32_;
  std::vector<uint64_t> t64_;
};

}  // namespace hand_tracking
