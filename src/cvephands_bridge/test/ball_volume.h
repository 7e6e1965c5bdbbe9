// Shared by the nodelet tests: a synthetic hand volume message, a ball with a linear probability
// ramp (p = 0.6 exactly on the sphere, 0.25 per voxel) at the centre of a cube.
#pragma once

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

#include <tabletop_msgs/VoxelVolume.h>

namespace cvephands_test {

inline tabletop_msgs::VoxelVolume ballVolume(const Eigen::Vector3d& origin, double radius,
                                             int n = 83, double edge = 0.30) {
  tabletop_msgs::VoxelVolume v;
  const double voxel = edge / n;
  v.origin.x = origin.x(), v.origin.y = origin.y(), v.origin.z = origin.z();
  v.voxel_size = voxel;
  v.size_x = v.size_y = v.size_z = n;
  v.data.resize(size_t(n) * n * n);
  const Eigen::Vector3d c = origin + Eigen::Vector3d::Constant(0.5 * edge);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const Eigen::Vector3d p = origin + voxel * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
        const double sd = (p - c).norm() - radius;
        const double prob = std::clamp(0.6 - 0.25 * sd / voxel, 0.0, 1.0);
        v.data[x + n * (y + size_t(n) * z)] = uint8_t(std::lround(255.0 * prob));
      }
  return v;
}

}  // namespace cvephands_test
