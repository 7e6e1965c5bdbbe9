#include "psfs_reconstruction/voxel_grid.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace psfs {

Eigen::Vector3i VoxelGrid::coords(size_t index) const {
  const size_t nx = static_cast<size_t>(dims.x()), ny = static_cast<size_t>(dims.y());
  const size_t x = index % nx;
  const size_t r = index / nx;
  return Eigen::Vector3i(static_cast<int>(x), static_cast<int>(r % ny), static_cast<int>(r / ny));
}

bool VoxelGrid::voxelOf(const Eigen::Vector3d& p, Eigen::Vector3i* voxel) const {
  const Eigen::Vector3d q = (p - origin) / voxel_size;
  for (int i = 0; i < 3; ++i)
    if (!(q[i] >= 0.0 && q[i] < dims[i])) return false;
  *voxel = Eigen::Vector3i(static_cast<int>(q.x()), static_cast<int>(q.y()),
                           static_cast<int>(q.z()));
  return true;
}

bool VoxelGrid::voxelRange(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                           Eigen::Vector3i* lo, Eigen::Vector3i* hi) const {
  Eigen::Vector3i a, b;
  for (int i = 0; i < 3; ++i) {
    const double l = std::floor((min[i] - origin[i]) / voxel_size);
    const double h = std::floor((max[i] - origin[i]) / voxel_size);
    if (!(l <= h) || h < 0 || l >= dims[i]) return false;  // also NaN
    a[i] = l < 0 ? 0 : static_cast<int>(l);
    b[i] = h >= dims[i] ? dims[i] - 1 : static_cast<int>(h);
  }
  *lo = a;
  *hi = b;
  return true;
}

void VoxelGrid::validate() const {
  if (!origin.allFinite())
    throw std::invalid_argument("psfs::VoxelGrid: field 'origin' is not finite");
  if (!std::isfinite(voxel_size) || !(voxel_size > 0.0))
    throw std::invalid_argument("psfs::VoxelGrid: field 'voxel_size' must be finite and > 0");
  for (int i = 0; i < 3; ++i)
    if (dims[i] < 1)
      throw std::invalid_argument("psfs::VoxelGrid: field 'dims' must be >= 1 along every axis (got " +
                                  std::to_string(dims.x()) + "x" + std::to_string(dims.y()) + "x" +
                                  std::to_string(dims.z()) + ")");
  if (numVoxels() > static_cast<size_t>(std::numeric_limits<int>::max()))
    throw std::invalid_argument("psfs::VoxelGrid: more than 2^31 voxels");
}

std::string VoxelGrid::describe() const {
  std::ostringstream s;
  s.precision(4);
  s << dims.x() << "x" << dims.y() << "x" << dims.z() << " @ " << voxel_size * 1000.0
    << " mm, min (" << origin.x() << ", " << origin.y() << ", " << origin.z() << ")";
  return s.str();
}

Eigen::Vector3i referenceDims(Resolution r) {
  switch (r) {
    case Resolution::k16mm: return {64, 64, 48};
    case Resolution::k8mm: return {128, 128, 96};
    case Resolution::k4mm: return {256, 256, 192};
  }
  throw std::invalid_argument("psfs::referenceDims: unknown resolution");
}

VoxelGrid workspaceGrid(const Workspace& ws, const Eigen::Vector3i& dims) {
  if (!ws.min_corner.allFinite() || !ws.size.allFinite() || (ws.size.array() <= 0.0).any())
    throw std::invalid_argument("psfs::workspaceGrid: workspace must be finite with size > 0");
  if ((dims.array() < 1).any())
    throw std::invalid_argument("psfs::workspaceGrid: dims must be >= 1");
  VoxelGrid g;
  g.dims = dims;
  g.voxel_size = (ws.size.array() / dims.cast<double>().array()).minCoeff();
  // Centre the grid in the box along axes where size/dims is larger than the voxel.
  g.origin = ws.min_corner + 0.5 * (ws.size - g.voxel_size * dims.cast<double>());
  g.validate();
  return g;
}

VoxelGrid referenceGrid(Resolution r, const Workspace& ws) {
  return workspaceGrid(ws, referenceDims(r));
}

VoxelGrid cubeGrid(const Eigen::Vector3d& centre, double edge, int n) {
  if (!centre.allFinite() || !std::isfinite(edge) || !(edge > 0.0) || n < 1)
    throw std::invalid_argument("psfs::cubeGrid: centre and edge must be finite, edge > 0, n >= 1");
  VoxelGrid g;
  g.voxel_size = edge / n;
  g.dims = Eigen::Vector3i(n, n, n);
  g.origin = centre - Eigen::Vector3d::Constant(0.5 * edge);
  g.validate();
  return g;
}

VoxelGrid snappedCubeGrid(const Eigen::Vector3d& centre, double edge, int n) {
  VoxelGrid g = cubeGrid(centre, edge, n);
  for (int i = 0; i < 3; ++i) g.origin[i] = std::round(g.origin[i] / g.voxel_size) * g.voxel_size;
  return g;
}

}  // namespace psfs
