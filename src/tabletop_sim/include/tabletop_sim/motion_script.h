// Scripted motions of the simulated person as functions of time. A script is a list of
// keyframes written in hand positions (palm centres, elbow pole directions, back-of-hand
// directions, hand shapes) plus trunk/head angles; between keyframes everything follows a
// minimum-jerk profile (zero velocity and acceleration at each keyframe, peak speed 1.875x the
// mean), and the arm angles come from the body model's IK at every instant. Every script
// starts and ends in BodyModel::restPose(), so scripts concatenate and loop without jumps.
//
// Hands over the desk rest ON it: the keyframes place palm centres by eye, and curled fingers,
// a fist or a pointing finger reach below the palm. At every instant, open digits (curl < 0.5)
// that would sink into the desk top are straightened just enough (fingers pressed flat on a
// table), and if the palm, a closed digit or a straight one still reaches below the desk top
// the whole hand is lifted (the palm target raised, the arm solved again). Without this the
// ground truth would include hand volume inside the desk that no camera can see.
//
// Names: wave, point, fold_hands, reach_targets, leave_reenter, head_turn, static, all
// (all = the others in that order).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tabletop_sim/body_model.h"

namespace tabletop_sim {

struct ArmKey {
  Eigen::Vector3d palm = Eigen::Vector3d::Zero();  // palm centre target (world)
  // Elbow pole: direction from the shoulder, in the chest frame (moves with the torso).
  Eigen::Vector3d pole = Eigen::Vector3d(0, -0.3, -1);
  Eigen::Vector3d dorsal = Eigen::Vector3d::UnitZ();  // back of the hand towards (world)
  double finger_elevation = 0.0;  // finger axis above horizontal (rad); NaN = use hand.flex
  double shoulder_shift = 0.0;    // m, + outwards
  HandPose hand;                  // shape, finger curls, wrist flex/deviation (roll is solved)
};

struct Keyframe {
  double time = 0;  // seconds from the start of the script
  // torso x, y, z, roll, pitch, yaw, spine bend, head yaw (BodyPose::state[0..7]).
  std::array<double, 8> trunk{};
  std::array<ArmKey, 2> arms;  // indexed by Side
};

class MotionScript {
 public:
  // Throws std::invalid_argument (listing the valid names) for an unknown name.
  static MotionScript create(const std::string& name, const BodyModel& model = BodyModel());
  static const std::vector<std::string>& names();
  // The keyframe of BodyModel::restPose() (what every script starts and ends with).
  static Keyframe restKey();

  MotionScript(std::string name, std::vector<Keyframe> keys, const BodyModel& model,
               bool idle_sway = true);

  const std::string& name() const { return name_; }
  double duration() const { return keys_.back().time; }
  const std::vector<Keyframe>& keyframes() const { return keys_; }

  // The interpolated keyframe at time t (clamped to [0, duration]).
  Keyframe keyAt(double t) const;
  // The full body pose at time t (IK applied). Deterministic and thread-safe.
  BodyPose poseAt(double t) const;
  // Where the script wants the palm centre at time t, after the desk lift (to check that IK
  // reaches it).
  Eigen::Vector3d palmTarget(double t, Side side) const;
  // The body pose a (possibly interpolated) keyframe describes at its time (IK and desk
  // contact applied). palm_targets (optional): the palm targets after the desk lift.
  BodyPose poseFromKey(const Keyframe& key, Eigen::Vector3d* palm_targets = nullptr) const;

 private:
  std::string name_;
  std::vector<Keyframe> keys_;
  BodyModel model_;
  bool idle_sway_;
};

// Minimum-jerk position profile s(u) = 10u^3 - 15u^4 + 6u^5 on [0, 1].
double minJerk(double u);

}  // namespace tabletop_sim
