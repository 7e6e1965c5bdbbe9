// Two-bone inverse kinematics for one arm of the 18-DOF model: the shoulder swing and the elbow
// bend and plane that put the model's hand (on the forearm's axis, wrist_to_hand beyond the
// wrist) at a target, with the elbow bent towards a pole. The PAPF uses it to propose arm
// poses from skin evidence (papf.h), so an arm that lost its hand finds it again.
#pragma once

#include <Eigen/Core>

#include "body_tracking/body_profile.h"
#include "body_tracking/body_state.h"

namespace body_tracking {

// Sets the arm's swing1, swing2, flex and twist of `state` (the torso, spine and shoulder
// shift stay). Returns false when the target is out of reach; the arm then points at it.
bool solveArmIk(const BodyProfile& profile, Side side, const Eigen::Vector3d& hand_target,
                const Eigen::Vector3d& elbow_pole, BodyState* state);

}  // namespace body_tracking
