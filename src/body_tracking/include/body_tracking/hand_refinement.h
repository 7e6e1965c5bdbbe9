// The body model's hands, read from the skin volume. The 18-DOF model has no wrist, so its hand
// ellipsoid sits on the forearm's axis while a real hand bends at the wrist (a flat hand on the
// desk under a raised forearm is 3-6 cm off that axis). The reported hand is therefore the
// centroid of the skin evidence around the model's hand and beyond its wrist: skin voxels
// within `radius` of the model hand (re-centred twice on the centroid), on the distal side of
// the plane through the wrist across the forearm, and nearer to this hand than to the other
// (folded hands). Falls back to the model's hand when too little skin is found.
#pragma once

#include <array>

#include <Eigen/Core>

#include "body_tracking/kinematics.h"
#include "psfs_reconstruction/probability_volume.h"

namespace body_tracking {

struct HandRefinementParams {
  bool enabled = true;
  double radius = 0.09;             // m, search sphere around the hand
  double wrist_offset = 0.01;       // m, the cut plane sits this far beyond the wrist
  double min_probability = 0.5;     // skin voxels counted: p above this, weighted by p - it
  double min_volume = 3e-5;         // m^3 of skin (weighted) needed, else the model's hand
  int iterations = 2;
};

struct RefinedHands {
  std::array<Eigen::Vector3d, 2> position;  // by Side
  std::array<bool, 2> from_skin{{false, false}};
};

RefinedHands refineHands(const psfs::ProbabilityVolume& skin, const BodyFrames& frames,
                         const HandRefinementParams& params);

}  // namespace body_tracking
