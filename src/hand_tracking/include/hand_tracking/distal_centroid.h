// The hand at the far end of a skin blob. With short or rolled sleeves the forearm is skin as
// well, and the skin centroid around a hand slides down the arm (9-18 cm on generated
// scenarios). The hand is the end of the arm away from the body: when the skin voxels are
// elongated (their long axis' variance > 2.25x the next one's, i.e. 1.5x the spread: a flat
// open hand alone is about 19 x 9 cm, 1.4:1 in spread at 16 mm voxels) and longer than
// `length` + 5 cm along that axis (the hull smears a hand by about 3 voxels at 16 mm: a hand
// alone in long sleeves must not be cut), only the voxels within `length` of the hand's end
// count (the end away from `head`, or the one the body around the ends tells: `foreign`
// below), and their weighted centroid is returned; otherwise `centroid` unchanged.
#pragma once

#include <functional>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace hand_tracking {

using WeightedPoint = std::pair<Eigen::Vector3d, double>;  // position (m), weight >= 0

// centroid: the weighted centroid of `voxels`; head: a point on the body side (the head).
// arm_weight (may be null): how surely the blob is an arm, 0 (returned `centroid` unchanged)
// to 1, rising over the first 5 cm of extent past the threshold and from a variance ratio of
// 2.25 to 3, so that a caller can blend and a blob near the threshold does not flip between
// the two answers from frame to frame.
// foreign (may be empty): how much body that is not skin lies around a point (0..1). When
// given, the end with more of it around than the other end by kForeignMargin is taken for the
// elbow (a rolled or short sleeve goes on from there; a hand ends in free space or on the
// desk), whatever the head says: a forearm raised to wave or bent towards the body has its
// hand nearer the head than its elbow, and the head alone picked the elbow. Where the ends
// differ less (a bare upper arm is skin too; a hand on a shirt), the head decides.
using ForeignBodyProbe = std::function<double(const Eigen::Vector3d&)>;
constexpr double kForeignMargin = 0.1;
Eigen::Vector3d distalCentroid(const std::vector<WeightedPoint>& voxels,
                               const Eigen::Vector3d& centroid, const Eigen::Vector3d& head,
                               double length, double* arm_weight = nullptr,
                               const ForeignBodyProbe& foreign = {});

}  // namespace hand_tracking
