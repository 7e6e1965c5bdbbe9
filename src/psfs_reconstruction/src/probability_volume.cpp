#include "psfs_reconstruction/probability_volume.h"

#include <algorithm>
#include <stdexcept>

namespace psfs {

size_t countAbove(const ProbabilityVolume& v, uint8_t t) {
  size_t n = 0;
  for (uint8_t b : v.data) n += b > t;
  return n;
}

int layersBelow(const VoxelGrid& g, double z) {
  int layers = 0;
  while (layers < g.dims.z() && g.centre(0, 0, layers).z() < z) ++layers;
  return layers;
}

int clearBelow(double z, ProbabilityVolume* v) {
  const VoxelGrid& g = v->grid;
  if (v->data.size() != g.numVoxels())
    throw std::invalid_argument("psfs::clearBelow: data does not match the grid");
  const size_t layer = size_t(g.dims.x()) * size_t(g.dims.y());
  const int layers = layersBelow(g, z);
  std::fill(v->data.begin(), v->data.begin() + long(layer * size_t(layers)), uint8_t(0));
  return layers;
}

double volumeIoU(const ProbabilityVolume& a, uint8_t ta, const ProbabilityVolume& b, uint8_t tb) {
  if (a.grid != b.grid || a.data.size() != b.data.size())
    throw std::invalid_argument("psfs::volumeIoU: volumes on different grids");
  size_t inter = 0, uni = 0;
  for (size_t i = 0; i < a.data.size(); ++i) {
    const bool x = a.data[i] > ta, y = b.data[i] > tb;
    inter += x && y;
    uni += x || y;
  }
  return uni == 0 ? 1.0 : double(inter) / double(uni);
}

}  // namespace psfs
