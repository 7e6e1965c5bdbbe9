// The tracker's 18-DOF upper-body state: the values of tabletop_msgs/BodyPose.state, in that
// order and with that message's conventions (DESIGN.md section 4; the message file documents
// each angle). Kept as a plain array so particles copy, mix (crossover) and average cheaply.
#pragma once

#include <array>

namespace body_tracking {

namespace dof {
enum : int {
  TORSO_X = 0,
  TORSO_Y,
  TORSO_Z,
  TORSO_ROLL,
  TORSO_PITCH,
  TORSO_YAW,
  SPINE_BEND,
  HEAD_YAW,
  L_SWING_1,
  L_SWING_2,
  L_SHIFT,
  L_FLEX,
  L_TWIST,
  R_SWING_1,
  R_SWING_2,
  R_SHIFT,
  R_FLEX,
  R_TWIST,
  COUNT
};
}  // namespace dof

enum class Side : int { LEFT = 0, RIGHT = 1 };
// Arm joint k (0 swing1, 1 swing2, 2 shift, 3 elbow flex, 4 elbow twist) of one side.
inline int armDof(Side s, int k) { return (s == Side::LEFT ? dof::L_SWING_1 : dof::R_SWING_1) + k; }

using BodyState = std::array<double, dof::COUNT>;

// Joint names as published on body/joint_states (one per state entry).
const char* dofName(int i);

}  // namespace body_tracking
