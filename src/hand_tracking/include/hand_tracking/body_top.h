// The top of the body in the body volume: the highest z level whose occupied area reaches a
// minimum. A seated person's highest part is the head (DESIGN.md section 3: the user sits at
// the desk, the workspace holds the upper body), so the MPF starts its head track only near
// it (MpfParams::head_birth_depth): a shirt in a skin tone makes the chest the largest skin
// blob, and the skin alone cannot tell it from a head. The area minimum keeps a hand raised
// above the head (a few 16 mm voxels per level) from counting as the top.
#pragma once

#include "psfs_reconstruction/probability_volume.h"

namespace hand_tracking {

// z (m, world) of the upper face of the highest level of `body` with at least `min_area` (m^2)
// of voxels above `threshold` (probability); NaN when no level has, or when the volume is
// malformed (data size not the grid's, voxel size <= 0).
double bodyTop(const psfs::ProbabilityVolume& body, double min_area, double threshold = 0.5);

}  // namespace hand_tracking
