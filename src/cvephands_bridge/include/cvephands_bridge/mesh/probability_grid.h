// A non-owning view of a probabilistic voxel volume as the VoxelVolume message carries it
// (DESIGN.md section 3): one byte per voxel, p = value / 255, x fastest, then y, then z.
// The meshing code reads the message's data in place through this view (no copy per frame).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

namespace cvephands {

struct ProbabilityGridView {
  const uint8_t* data = nullptr;                   // not owned; dims.prod() bytes
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();  // voxels along x, y, z
  // World position of the MIN CORNER of voxel (0,0,0), as VoxelVolume.origin; the sample of voxel
  // (x,y,z) sits at its centre, origin + (x + 0.5, y + 0.5, z + 0.5) * voxel_size.
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double voxel_size = 1.0;  // edge length of the cubic voxels (m)

  // A grid with a zero dimension holds nothing (it is valid and meshes to nothing).
  bool empty() const { return dims.x() == 0 || dims.y() == 0 || dims.z() == 0; }
  size_t numVoxels() const {
    return static_cast<size_t>(dims.x()) * static_cast<size_t>(dims.y()) *
           static_cast<size_t>(dims.z());
  }
  size_t index(int x, int y, int z) const {
    return static_cast<size_t>(x) +
           static_cast<size_t>(dims.x()) *
               (static_cast<size_t>(y) + static_cast<size_t>(dims.y()) * static_cast<size_t>(z));
  }
  uint8_t at(int x, int y, int z) const { return data[index(x, y, z)]; }
  Eigen::Vector3d centre(int x, int y, int z) const {
    return origin + voxel_size * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
  }
  // The centre of the whole box (a hand sub-volume's: the hand it was cut around).
  Eigen::Vector3d boxCentre() const { return origin + 0.5 * voxel_size * dims.cast<double>(); }

  // Throws std::invalid_argument (the message names the field) for negative dims, a null data
  // pointer with nonzero dims, a non-finite origin or a voxel size that is not finite and > 0.
  void validate() const {
    if ((dims.array() < 0).any())
      throw std::invalid_argument("cvephands::ProbabilityGridView: negative 'dims' (" +
                                  std::to_string(dims.x()) + "x" + std::to_string(dims.y()) +
                                  "x" + std::to_string(dims.z()) + ")");
    if (!empty() && data == nullptr)
      throw std::invalid_argument("cvephands::ProbabilityGridView: 'data' is null for a " +
                                  std::to_string(dims.x()) + "x" + std::to_string(dims.y()) +
                                  "x" + std::to_string(dims.z()) + " grid");
    if (!origin.allFinite())
      throw std::invalid_argument("cvephands::ProbabilityGridView: 'origin' is not finite");
    if (!std::isfinite(voxel_size) || !(voxel_size > 0.0))
      throw std::invalid_argument(
          "cvephands::ProbabilityGridView: 'voxel_size' must be finite and > 0");
  }
};

}  // namespace cvephands
