// Private: the observation's Eigen-side data as the plain structs of part_score.h (g++ only).
#pragma once

#include "body_tracking/truncated_quadric.h"
#include "body_tracking/volume_observation.h"
#include "part_score.h"

namespace body_tracking {

inline part_score::PartQuadric plainPart(const TruncatedQuadric& t, bool skin_part, bool extrapolate) {
  part_score::PartQuadric q;
  for (int i = 0; i < 16; ++i) q.Q[i] = t.Q.data()[i];
  for (int p = 0; p < 2; ++p)  // an ellipsoid's planes are unset: zeros
    for (int i = 0; i < 4; ++i) q.planes[p][i] = p < t.num_planes ? t.planes[p][i] : 0.0;
  for (int i = 0; i < 3; ++i) {
    q.lo[i] = t.bounds.min()[i];
    q.hi[i] = t.bounds.max()[i];
  }
  q.num_planes = t.num_planes;
  q.skin = skin_part ? 1 : 0;
  q.extrapolate = extrapolate ? 1 : 0;
  q.pad_ = 0;
  return q;
}

inline part_score::ObservationGrid plainGrid(const psfs::VoxelGrid& g, double unknown) {
  part_score::ObservationGrid p;
  for (int i = 0; i < 3; ++i) {
    p.origin[i] = g.origin[i];
    p.dims[i] = g.dims[i];
  }
  p.voxel_size = g.voxel_size;
  p.unknown = unknown;
  return p;
}

inline part_score::RowSumsView rowSumsView(const VolumeObservation::RowSums& s) {
  return {s.s0.data(), s.s1.data(), s.s2.data()};
}

}  // namespace body_tracking
