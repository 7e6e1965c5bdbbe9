#include "body_tracking/arm_ik.h"

#include <algorithm>
#include <cmath>

#include "body_tracking/kinematics.h"

namespace body_tracking {

using Eigen::Matrix3d;
using Eigen::Vector3d;

bool solveArmIk(const BodyProfile& p, Side side, const Vector3d& target, const Vector3d& pole,
                BodyState* state) {
  BodyState& s = *state;
  const int i = static_cast<int>(side);
  const BodyFrames f = forwardKinematics(p, s);
  const Vector3d sh = f.shoulder[i];
  const Matrix3d rc = f.chest.linear();
  const double l1 = p.upper_arm, l2 = p.forearm + p.wrist_to_hand;
  Vector3d v = target - sh;
  double d = v.norm();
  const Vector3d u = d > 1e-9 ? Vector3d(v / d) : Vector3d(rc * Vector3d::UnitY());
  const double dmin = std::abs(l1 - l2) + 1e-4, dmax = l1 + l2 - 1e-4;
  const bool reachable = d >= dmin && d <= dmax;
  d = std::clamp(d, dmin, dmax);
  // The elbow lies on the circle where the two bone spheres meet, on the pole's side.
  const double a = (l1 * l1 - l2 * l2 + d * d) / (2.0 * d);
  const double h = std::sqrt(std::max(0.0, l1 * l1 - a * a));
  Vector3d n = (pole - sh) - u * (pole - sh).dot(u);
  if (n.norm() < 1e-9) n = u.unitOrthogonal();
  n.normalize();
  const Vector3d e = sh + a * u + h * n;
  const Vector3d dc = rc.transpose() * ((e - sh) / l1);
  double& s1 = s[armDof(side, 0)];
  double& s2 = s[armDof(side, 1)];
  s2 = std::asin(std::clamp(-dc.x(), -1.0, 1.0));
  s1 = std::atan2(dc.z(), dc.y());
  const Matrix3d ru = rc * shoulderRotation(s1, s2).toRotationMatrix();
  const Vector3d fu = ru.transpose() * (sh + d * u - e).normalized();
  s[armDof(side, 3)] = std::acos(std::clamp(fu.y(), -1.0, 1.0));
  if (std::hypot(fu.x(), fu.z()) > 1e-9) s[armDof(side, 4)] = std::atan2(fu.x(), fu.z());
  return reachable;
}

}  // namespace body_tracking
