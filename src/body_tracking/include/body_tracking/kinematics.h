// Forward kinematics of the 18-DOF body: the three chains (trunk-head, left arm, right arm)
// rooted at the pelvis, with exactly the formulas of tabletop_msgs/BodyPose and the simulated
// rig (tabletop_sim/body_model.h), so a state means the same pose to both. Frames:
// - pelvis: origin = TORSO_X..Z, R = Rz(yaw) Ry(pitch) Rx(roll); x = the person's right,
//   y = forward, z = up;
// - chest: pelvis moved up by spine_height, rotated by -SPINE_BEND about x;
// - head: chest moved up by neck_height, turned by HEAD_YAW about z;
// - upper arm (origin at the shoulder, y along the bone): chest * T(-/+(half width + shift), 0,
//   shoulder_height) * Rx(swing1) Rz(swing2), left arm on -x;
// - forearm (origin at the elbow, y along the bone, x the hinge): upper arm's rotation *
//   Ry(twist) Rx(flex).
#pragma once

#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "body_tracking/body_profile.h"
#include "body_tracking/body_state.h"

namespace body_tracking {

struct BodyFrames {
  Eigen::Isometry3d pelvis, chest, head;
  std::array<Eigen::Isometry3d, 2> upper_arm, forearm;  // indexed by Side
  std::array<Eigen::Vector3d, 2> shoulder, elbow, wrist, hand;
  Eigen::Vector3d head_centre;

  const Eigen::Vector3d& handOf(Side s) const { return hand[static_cast<int>(s)]; }
};

BodyFrames forwardKinematics(const BodyProfile& profile, const BodyState& state);

// Joint rotations as quaternions in their parent frames (what the limits act on) and back.
// The shoulder is the swing Rx(swing1) Rz(swing2) of the rest direction +y; the elbow
// Ry(twist) Rx(flex). toState keeps only what the 2-DOF joints can hold: the bone direction
// for the shoulder, the bend and its plane for the elbow (the twist is kept where the arm is
// straight and the plane undefined).
Eigen::Quaterniond shoulderRotation(double swing1, double swing2);
void shoulderAngles(const Eigen::Quaterniond& q, double* swing1, double* swing2);
Eigen::Quaterniond elbowRotation(double flex, double twist);
void elbowAngles(const Eigen::Quaterniond& q, double* flex, double* twist);
Eigen::Quaterniond torsoRotation(double roll, double pitch, double yaw);
void torsoAngles(const Eigen::Quaterniond& q, double* roll, double* pitch, double* yaw);

}  // namespace body_tracking
