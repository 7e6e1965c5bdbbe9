// A fused volume as the pipeline passes it on: the grid plus one byte per voxel, p = value/255,
// x fastest then y then z (the VoxelVolume message contract, DESIGN.md section 3).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "psfs_reconstruction/voxel_grid.h"

namespace psfs {

struct ProbabilityVolume {
  VoxelGrid grid;
  std::vector<uint8_t> data;

  uint8_t at(int x, int y, int z) const { return data[grid.index(x, y, z)]; }
};

// The byte level that separates "in the hull" from "not in the hull" for threshold t: a voxel is
// in the hull iff value > thresholdByte(t). Fusion stores its bytes so that this is exactly the
// decision it made in floating point (t = 0.6 gives 153: the iso value 153.5 of the meshing stage).
inline uint8_t thresholdByte(double t) {
  const double b = std::floor(255.0 * t);
  return static_cast<uint8_t>(b < 0 ? 0 : (b > 255 ? 255 : b));
}

// Number of voxels with value > threshold_byte.
size_t countAbove(const ProbabilityVolume& v, uint8_t threshold_byte);

// Number of z layers of the grid whose centre lies below height z (world).
int layersBelow(const VoxelGrid& g, double z);

// Sets every voxel whose centre lies below height z (world) to 0; returns the number of z
// layers cleared. Throws std::invalid_argument if the data does not match the grid.
int clearBelow(double z, ProbabilityVolume* v);

// Intersection over union of {a > ta} and {b > tb} (same grid; throws std::invalid_argument
// otherwise). Returns 1 when both sets are empty.
double volumeIoU(const ProbabilityVolume& a, uint8_t ta, const ProbabilityVolume& b, uint8_t tb);

}  // namespace psfs
