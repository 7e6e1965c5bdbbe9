// The hand at the far end of a bare arm, found along the skin rather than in a box. With short
// or rolled sleeves the skin blob runs from the sleeve over the elbow to the finger tips (up to
// 60 cm, bent at the elbow), and the MPF's particles sit on its fullest part (the forearm, the
// elbow: a palm box is fuller there than on a flat hand). A box around them sees neither end
// when the arm is stretched, and a principal axis means nothing for a bent arm: on generated
// scenarios the reported hand stayed at the elbow (10-30 cm off) while the user reached or
// waved. Here the blob's ends are its geodesic extremes (the skin voxel farthest along the skin
// from the start, then the one farthest from that), and the hand is the end
//  1. further along the frontal direction by frontal_margin (a seated user's hands are in front
//     of the elbows, raised or not: a waving hand is nearer the head than its elbow);
//  2. else the one with less body that is not skin just beyond it (the sleeve goes on there);
//  3. else the end nearer last frame's hand end (a forearm held across the body; this keeps a
//     wrong end as well as a right one until rule 1 or 2 decides);
//  4. else the end farther from the head.
// An end where the walk stopped at its reach or at the filter is taken for a real end (the
// skin goes on there; such a blob is usually longer than max_length).
// The voxels within hand_length of that end, along the skin, give the hand's centroid.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>

#include <Eigen/Core>

#include "hand_tracking/distal_centroid.h"
#include "psfs_reconstruction/probability_volume.h"

namespace hand_tracking {

struct ArmWalkParams {
  double reach = 0.6;  // m along the skin from the start (a short sleeve to the tips: <= 0.6)
  // A hand alone, smeared by the hull at both ends, is at most this long along the skin (a 21 cm
  // hand plus 3 cm at each end); longer blobs are arms, fully so 5 cm further.
  double min_arm_length = 0.27;
  // Longer or thicker blobs are not one arm (skin-coloured desk, shirt or clutter joined to it):
  // a short sleeve to the tips with the smear is at most 0.70 m; a forearm's hull at 16 mm has
  // 0.006-0.012 m^2 of cross-section (volume / length), a trunk 0.02 and more.
  double max_length = 0.70;
  double max_cross_section = 0.015;  // m^2
  // The hand's extent from the blob's end, along the skin (the tracker passes
  // hand_distal_length, as for the box's cut).
  double hand_length = 0.17;
  Eigen::Vector3d frontal = Eigen::Vector3d::UnitY();  // unit: towards the screen
  double frontal_margin = 0.08;                        // m between the ends along it
  double continuity_margin = 0.10;  // m nearer last frame's hand end ...
  double continuity_radius = 0.15;  // ... which must lie this near one end (the hand's 3 m/s
                                    // for one 40 ms frame, and the end's 3 cm of jitter)
  double beyond = 0.05;             // m past an end where `foreign` is probed
};

struct ArmEnd {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  Eigen::Vector3d centroid = Eigen::Vector3d::Constant(kNaN);  // the hand's (NaN: no arm)
  double arm_weight = 0.0;     // 0: no arm, 1: surely one (rises over 5 cm of length)
  double length = 0.0;         // m, geodesic length of the blob
  double cross_section = 0.0;  // m^2, the blob's volume / length
  Eigen::Vector3d hand_end = Eigen::Vector3d::Constant(kNaN);  // mean of the end's 3 cm
  Eigen::Vector3d other_end = Eigen::Vector3d::Constant(kNaN);
};

// Whether a voxel centre may be walked (e.g. the target's Voronoi cell); empty: all.
using VoxelFilter = std::function<bool(const Eigen::Vector3d&)>;

// skin: voxels above `threshold` are skin. start: the walk starts at the skin voxel nearest it
// within start_radius. head: a point on the body side. foreign (may be empty): body that is not
// skin around a point (distal_centroid.h). previous_hand_end (may be null): last frame's
// ArmEnd::hand_end for this hand.
ArmEnd armHandEnd(const psfs::ProbabilityVolume& skin, uint8_t threshold,
                  const Eigen::Vector3d& start, double start_radius, const VoxelFilter& filter,
                  const ArmWalkParams& params, const Eigen::Vector3d& head,
                  const ForeignBodyProbe& foreign, const Eigen::Vector3d* previous_hand_end);

}  // namespace hand_tracking
