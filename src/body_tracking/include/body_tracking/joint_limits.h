// Hard joint limits of the 18-DOF body (thesis 5.2.2, figure 5.5): the rotational joints are
// limited in swing-twist terms (swing_twist.h) on their quaternions, the scalar joints by
// intervals. The PAPF enforces them on every particle it creates.
#pragma once

#include "body_tracking/body_state.h"
#include "body_tracking/swing_twist.h"

namespace body_tracking {

struct BodyLimits {
  // Torso: the tilt of its up axis (swing about x = leaning forward/back, about y = sideways)
  // and its turn about the vertical (twist = yaw), relative to sitting upright facing +y.
  SwingTwistLimit torso;
  // Upper arm: swing of the bone from its rest direction (+y, forward) in the chest frame:
  // about x raises/lowers it (2.4 rad reaches down and somewhat back), about z turns it
  // sideways. The twist is not a DOF of the model (the elbow's plane stands in for it).
  SwingTwistLimit shoulder;
  // Forearm: bend from the upper arm's axis, in any plane (the plane is the elbow twist).
  SwingTwistLimit elbow;
  double min_spine_bend = -0.3, max_spine_bend = 0.8;  // rad
  double max_head_yaw = 1.3;                           // rad, either way
  // Shoulder blades: reaching pushes the shoulder out a few cm, pulling it in moves it less.
  double min_shoulder_shift = -0.02, max_shoulder_shift = 0.05;  // m

  BodyLimits();
  bool satisfied(const BodyState& s, double tolerance = 1e-6) const;
  // Moves the state onto the nearest allowed one, joint by joint.
  void enforce(BodyState* s) const;
  // The same for the joints of state coordinates [first, first + count) only (a PAPF partition:
  // the others are left as they are).
  void enforce(BodyState* s, int first, int count) const;
};

}  // namespace body_tracking
