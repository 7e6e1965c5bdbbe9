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

}  // namespace test
}  // namespace body_tracking
