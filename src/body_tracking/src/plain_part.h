// Private: the observation's Eigen-side data as the plain structs of part_score.h (g++ only).
#pragma once

#include "body_tracking/truncated_quadric.h"
#include "body_tracking/volume_observation.h"
#include "part_score.h"

namespace body_tracking {

// A trunk part (extrapolate, a cylinder) carries its shell when op.trunk_shell_weight > 0: the
// cylinder grown sideways by op.trunk_shell_width (part_score.h).
inline part_score::PartQuadric plainPart(const TruncatedQuadric& t, bool skin_part, bool extrapolate,
                                         const ObservationParams& op) {
  part_score::PartQuadric q;
  for (int i = 0; i < 16; ++i) q.Q[i] = t.Q.data()[i];
  const double shell_width = op.trunk_shell_width, shell_weight = op.trunk_shell_weight;
  const bool shell = extrapolate && shell_weight > 0 && t.shape == TruncatedQuadric::Shape::CYLINDER;
  Eigen::AlignedBox3d bounds = t.bounds;
  if (shell) {
    const TruncatedQuadric grown =
        TruncatedQuadric::cylinder(t.frame, t.length, t.semi.x() + shell_width, t.semi.z() + shell_width);
    for (int i = 0; i < 16; ++i) q.shell_Q[i] = grown.Q.data()[i];
    bounds = grown.bounds;
  } else {
    for (int i = 0; i < 16; ++i) q.shell_Q[i] = 0.0;
  }
  q.shell_weight = shell ? shell_weight : 0.0;
  for (int p = 0; p < 2; ++p)  // an ellipsoid's planes are unset: zeros
    for (int i = 0; i < 4; ++i) q.planes[p][i] = p < t.num_planes ? t.planes[p][i] : 0.0;
  for (int i = 0; i < 3; ++i) {
    q.lo[i] = bounds.min()[i];
    q.hi[i] = bounds.max()[i];
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
