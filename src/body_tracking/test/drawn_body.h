// Test support: a volume drawn from the body model's parts, 255 inside any of them and 0
// elsewhere, on the 16 mm workspace grid (what a perfect pSfS would give a person who is the
// model). `only` picks the parts drawn (all by default), e.g. the hands and head for a skin
// volume.
#pragma once

#include <initializer_list>
#include <vector>

#include "body_tracking/body_parts.h"
#include "psfs_reconstruction/probability_volume.h"

namespace body_tracking {
namespace test {

inline psfs::ProbabilityVolume drawnVolume(const BodyParts& parts, std::initializer_list<Part> only = {}) {
  std::vector<const TruncatedQuadric*> drawn;
  if (only.size() == 0)
    for (const TruncatedQuadric& p : parts) drawn.push_back(&p);
  for (Part p : only) drawn.push_back(&parts[static_cast<int>(p)]);
  psfs::ProbabilityVolume v;
  v.grid = psfs::referenceGrid(psfs::Resolution::k16mm);
  v.data.assign(v.grid.numVoxels(), 0);
  for (size_t i = 0; i < v.data.size(); ++i)
    for (const TruncatedQuadric* p : drawn)
      if (p->contains(v.grid.centre(i))) v.data[i] = 255;
  return v;
}

// A pSfS-like halo: the empty voxels next to a drawn one (6-neighbourhood) set to `value`
// (e.g. 150, p = 0.59: just inside the hull at the default threshold 0.5).
inline void addHalo(psfs::ProbabilityVolume* v, uint8_t value) {
  const psfs::VoxelGrid& g = v->grid;
  const std::vector<uint8_t> in = v->data;
  const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int z = 0; z < g.dims.z(); ++z)
    for (int y = 0; y < g.dims.y(); ++y)
      for (int x = 0; x < g.dims.x(); ++x) {
        if (in[g.index(x, y, z)] != 0) continue;
        for (const auto& o : d) {
          const int a = x + o[0], b = y + o[1], c = z + o[2];
          if (a < 0 || b < 0 || c < 0 || a >= g.dims.x() || b >= g.dims.y() || c >= g.dims.z()) continue;
          if (in[g.index(a, b, c)] == 255) {
            v->data[g.index(x, y, z)] = value;
            break;
          }
        }
      }
}

}  // namespace test
}  // namespace body_tracking
