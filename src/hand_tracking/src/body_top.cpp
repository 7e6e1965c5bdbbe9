#include "hand_tracking/body_top.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hand_tracking {

double bodyTop(const psfs::ProbabilityVolume& body, double min_area, double threshold) {
  const psfs::VoxelGrid& g = body.grid;
  if (body.data.size() != g.numVoxels() || !(g.voxel_size > 0.0))
    return std::numeric_limits<double>::quiet_NaN();
  const uint8_t thr = psfs::thresholdByte(threshold);
  const size_t layer = size_t(g.dims.x()) * g.dims.y();
  // Voxels a level needs (at least one).
  const double needed = std::max(1.0, std::ceil(min_area / (g.voxel_size * g.voxel_size) - 1e-9));
  for (int z = g.dims.z() - 1; z >= 0; --z) {
    const uint8_t* v = body.data.data() + g.index(0, 0, z);
    size_t n = 0;
    for (size_t i = 0; i < layer; ++i) n += v[i] > thr;
    if (double(n) >= needed) return g.origin.z() + (z + 1) * g.voxel_size;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace hand_tracking
