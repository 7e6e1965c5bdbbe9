#include "body_tracking/joint_limits.h"

#include <algorithm>

#include "body_tracking/kinematics.h"

namespace body_tracking {

using Eigen::Quaterniond;
using Eigen::Vector3d;

BodyLimits::BodyLimits() {
  torso.axis = Vector3d::UnitZ();
  torso.u = Vector3d::UnitX();
  torso.max_swing_u = 0.7;  // lean forward / back
  torso.max_swing_v = 0.4;  // lean sideways
  torso.min_twist = -0.9;
  torso.max_twist = 0.9;
  shoulder.axis = Vector3d::UnitY();
  shoulder.u = Vector3d::UnitX();
  shoulder.max_swing_u = 2.4;
  shoulder.max_swing_v = 1.7;
  elbow.axis = Vector3d::UnitY();
  elbow.u = Vector3d::UnitX();
  elbow.max_swing_u = elbow.max_swing_v = 2.6;
}

bool BodyLimits::satisfied(const BodyState& s, double tol) const {
  if (!torso.satisfied(torsoRotation(s[dof::TORSO_ROLL], s[dof::TORSO_PITCH], s[dof::TORSO_YAW]),
                       tol))
    return false;
  if (s[dof::SPINE_BEND] < min_spine_bend - tol || s[dof::SPINE_BEND] > max_spine_bend + tol)
    return false;
  if (std::abs(s[dof::HEAD_YAW]) > max_head_yaw + tol) return false;
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    if (!shoulder.satisfied(shoulderRotation(s[armDof(side, 0)], s[armDof(side, 1)]), tol))
      return false;
    const double shift = s[armDof(side, 2)];
    if (shift < min_shoulder_shift - tol || shift > max_shoulder_shift + tol) return false;
    if (!elbow.satisfied(elbowRotation(s[armDof(side, 3)], s[armDof(side, 4)]), tol))
      return false;
  }
  return true;
}

void BodyLimits::enforce(BodyState* sp) const { enforce(sp, 0, dof::COUNT); }

void BodyLimits::enforce(BodyState* sp, int first, int count) const {
  BodyState& s = *sp;
  const int last = first + count;
  const auto touches = [&](int b, int n) { return b < last && first < b + n; };
  if (touches(dof::TORSO_ROLL, 3)) {
    const Quaterniond t = torsoRotation(s[dof::TORSO_ROLL], s[dof::TORSO_PITCH], s[dof::TORSO_YAW]);
    if (!torso.satisfied(t))
      torsoAngles(torso.clamp(t), &s[dof::TORSO_ROLL], &s[dof::TORSO_PITCH], &s[dof::TORSO_YAW]);
  }
  if (touches(dof::SPINE_BEND, 1)) s[dof::SPINE_BEND] = std::clamp(s[dof::SPINE_BEND], min_spine_bend, max_spine_bend);
  if (touches(dof::HEAD_YAW, 1)) s[dof::HEAD_YAW] = std::clamp(s[dof::HEAD_YAW], -max_head_yaw, max_head_yaw);
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    if (!touches(armDof(side, 0), 5)) continue;
    double& s1 = s[armDof(side, 0)];
    double& s2 = s[armDof(side, 1)];
    const Quaterniond q = shoulderRotation(s1, s2);
    if (!shoulder.satisfied(q)) shoulderAngles(shoulder.clamp(q), &s1, &s2);
    double& shift = s[armDof(side, 2)];
    shift = std::clamp(shift, min_shoulder_shift, max_shoulder_shift);
    double& flex = s[armDof(side, 3)];
    double& twist = s[armDof(side, 4)];
    // The elbow's (flex, twist) are polar coordinates of the bend: keep flex >= 0 so that one
    // bend has one representation, then limit the bend.
    if (flex < 0) {
      flex = -flex;
      twist += M_PI;
    }
    const Quaterniond e = elbowRotation(flex, twist);
    if (!elbow.satisfied(e)) elbowAngles(elbow.clamp(e), &flex, &twist);
    twist = std::remainder(twist, 2 * M_PI);
  }
}

}  // namespace body_tracking
