// Swing-twist decomposition of joint rotations (Baerlocher and Boulic 2001, thesis 5.2.2) and
// the hard joint limits built on it: a rotation q about a joint is split as q = swing * twist,
// where twist turns about the bone axis and swing tilts the axis. Limits are an elliptic cone
// on the swing and an interval on the twist, so they hold whatever Euler order the angles came
// from, and clamping never leaves a gimbal-locked remainder.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace body_tracking {

// Rotation vector (angle in [0, pi] times the unit axis) of a unit quaternion, and back.
Eigen::Vector3d rotationLog(const Eigen::Quaterniond& q);
Eigen::Quaterniond rotationExp(const Eigen::Vector3d& r);

// q = swing * twist; twist about `axis` (unit), swing about an axis perpendicular to it. Both
// returned with w >= 0. For a half-turn swing (axis flipped), twist is the identity.
void swingTwist(const Eigen::Quaterniond& q, const Eigen::Vector3d& axis,
                Eigen::Quaterniond* swing, Eigen::Quaterniond* twist);

// Limits of one joint in its parent frame. The bone axis is `axis`; the swing's rotation
// vector (angle * unit axis, perpendicular to the bone) is limited to the ellipse with
// semi-axes max_swing_u and max_swing_v along `u` and axis x u; the twist angle to
// [min_twist, max_twist] (radians, right-handed about the bone axis).
struct SwingTwistLimit {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitY();
  Eigen::Vector3d u = Eigen::Vector3d::UnitX();
  double max_swing_u = M_PI, max_swing_v = M_PI;
  double min_twist = -M_PI, max_twist = M_PI;

  bool satisfied(const Eigen::Quaterniond& q, double tolerance = 1e-9) const;
  // The rotation inside the limits closest to q in the decomposition's terms: the swing vector
  // scaled onto the ellipse along its own direction, the twist clamped to its interval.
  Eigen::Quaterniond clamp(const Eigen::Quaterniond& q) const;
};

}  // namespace body_tracking
