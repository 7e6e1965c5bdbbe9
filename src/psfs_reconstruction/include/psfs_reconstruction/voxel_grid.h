// A regular voxel grid in the world frame: the geometry shared by every volume of the pipeline
// (full workspace volumes and hand sub-volumes alike), and the layout of the VoxelVolume
// message (DESIGN.md section 3): origin = world position of the min corner, cubic voxels of one
// edge length, dims (x, y, z), linear index x fastest, then y, then z.
#pragma once

#include <cstddef>
#include <string>

#include <Eigen/Core>

namespace psfs {

struct VoxelGrid {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // min corner (m, world frame)
  double voxel_size = 0.0;                            // edge length (m)
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();     // voxels along x, y, z

  size_t numVoxels() const {
    return static_cast<size_t>(dims.x()) * static_cast<size_t>(dims.y()) *
           static_cast<size_t>(dims.z());
  }
  // Rows are the x-lines of the grid (fixed y, z); row = y + dims.y * z. Fusion works row-wise.
  size_t numRows() const { return static_cast<size_t>(dims.y()) * static_cast<size_t>(dims.z()); }
  size_t index(int x, int y, int z) const {
    return static_cast<size_t>(x) +
           static_cast<size_t>(dims.x()) *
               (static_cast<size_t>(y) + static_cast<size_t>(dims.y()) * static_cast<size_t>(z));
  }
  Eigen::Vector3i coords(size_t index) const;
  Eigen::Vector3d centre(int x, int y, int z) const {
    return origin + voxel_size * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
  }
  Eigen::Vector3d centre(size_t index) const {
    const Eigen::Vector3i c = coords(index);
    return centre(c.x(), c.y(), c.z());
  }
  Eigen::Vector3d maxCorner() const { return origin + voxel_size * dims.cast<double>(); }
  // Voxel containing a world point; false when the point lies outside the grid.
  bool voxelOf(const Eigen::Vector3d& p, Eigen::Vector3i* voxel) const;
  // The voxels [lo, hi] (inclusive) that meet the world box [min, max], clipped to the grid:
  // every voxel whose centre lies in the box is among them. False (lo, hi unset) when none is.
  bool voxelRange(const Eigen::Vector3d& min, const Eigen::Vector3d& max, Eigen::Vector3i* lo,
                  Eigen::Vector3i* hi) const;

  // Throws std::invalid_argument (message names the field) for non-finite values, a voxel size
  // <= 0 or a dimension < 1, and for grids above 2^31 voxels (indices are 32-bit in places).
  void validate() const;
  std::string describe() const;  // e.g. "64x64x48 @ 15.6 mm, min (-0.5, -0.5, 0)"

  bool operator==(const VoxelGrid& o) const {
    return origin == o.origin && voxel_size == o.voxel_size && dims == o.dims;
  }
  bool operator!=(const VoxelGrid& o) const { return !(*this == o); }
};

// The user space of DESIGN.md section 3 (world frame, metres).
struct Workspace {
  Eigen::Vector3d min_corner{-0.5, -0.5, 0.0};
  Eigen::Vector3d size{1.0, 1.0, 0.75};
};

// The three reference resolutions of the thesis (Table 7.2) over the default workspace.
enum class Resolution {
  k16mm,  // 64 x 64 x 48 (15.6 mm): tracking volume, needs the multi-projection test
  k8mm,   // 128 x 128 x 96 (7.8 mm)
  k4mm,   // 256 x 256 x 192 (3.9 mm): about the pixel footprint of a 320x240 camera
};

Eigen::Vector3i referenceDims(Resolution r);

// A grid filling a workspace box with `dims` voxels. Voxels are cubic, so the edge length is the
// smallest of size/dims per axis and the grid is centred in the box along the other axes.
// Throws std::invalid_argument for a bad box or dims.
VoxelGrid workspaceGrid(const Workspace& workspace, const Eigen::Vector3i& dims);
VoxelGrid referenceGrid(Resolution r, const Workspace& workspace = Workspace());

// An axis-aligned cube of `edge` metres centred at `centre`, with n voxels per side (hand
// sub-volumes: 0.30 m at n = 83 gives 3.6 mm voxels). Throws std::invalid_argument.
VoxelGrid cubeGrid(const Eigen::Vector3d& centre, double edge, int n);
// Same, with the min corner snapped to multiples of the voxel size, so that a sub-volume that
// follows a hand moves in whole voxels and its voxels stay on one world lattice (no resampling
// shimmer between frames).
VoxelGrid snappedCubeGrid(const Eigen::Vector3d& centre, double edge, int n);

}  // namespace psfs
