#include "body_tracking/kinematics.h"

#include <algorithm>
#include <cmath>

namespace body_tracking {

using Eigen::AngleAxisd;
using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

namespace {

Isometry3d make(const Matrix3d& r, const Vector3d& t) {
  Isometry3d T = Isometry3d::Identity();
  T.linear() = r;
  T.translation() = t;
  return T;
}
Isometry3d trans(double x, double y, double z) { return make(Matrix3d::Identity(), {x, y, z}); }
Isometry3d rot(const Quaterniond& q) { return make(q.toRotationMatrix(), Vector3d::Zero()); }

}  // namespace

Quaterniond shoulderRotation(double swing1, double swing2) {
  return AngleAxisd(swing1, Vector3d::UnitX()) * AngleAxisd(swing2, Vector3d::UnitZ());
}

void shoulderAngles(const Quaterniond& q, double* swing1, double* swing2) {
  // The bone direction d = (-sin s2, cos s2 cos s1, cos s2 sin s1).
  const Vector3d d = q * Vector3d::UnitY();
  *swing2 = std::asin(std::clamp(-d.x(), -1.0, 1.0));
  *swing1 = std::atan2(d.z(), d.y());
}

Quaterniond elbowRotation(double flex, double twist) {
  return AngleAxisd(twist, Vector3d::UnitY()) * AngleAxisd(flex, Vector3d::UnitX());
}

void elbowAngles(const Quaterniond& q, double* flex, double* twist) {
  // The forearm direction in the upper arm's frame: (sin f sin t, cos f, sin f cos t).
  const Vector3d e = q * Vector3d::UnitY();
  *flex = std::acos(std::clamp(e.y(), -1.0, 1.0));
  if (std::hypot(e.x(), e.z()) > 1e-6) *twist = std::atan2(e.x(), e.z());
}

Quaterniond torsoRotation(double roll, double pitch, double yaw) {
  return AngleAxisd(yaw, Vector3d::UnitZ()) * AngleAxisd(pitch, Vector3d::UnitY()) *
         AngleAxisd(roll, Vector3d::UnitX());
}

void torsoAngles(const Quaterniond& q, double* roll, double* pitch, double* yaw) {
  const Matrix3d R = q.toRotationMatrix();
  // R = Rz(yaw) Ry(pitch) Rx(roll): R(2,0) = -sin(pitch).
  *pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  *roll = std::atan2(R(2, 1), R(2, 2));
  *yaw = std::atan2(R(1, 0), R(0, 0));
}

BodyFrames forwardKinematics(const BodyProfile& p, const BodyState& s) {
  BodyFrames f;
  f.pelvis = make(torsoRotation(s[dof::TORSO_ROLL], s[dof::TORSO_PITCH], s[dof::TORSO_YAW])
                      .toRotationMatrix(),
                  Vector3d(s[dof::TORSO_X], s[dof::TORSO_Y], s[dof::TORSO_Z]));
  f.chest = f.pelvis * trans(0, 0, p.spine_height) *
            rot(Quaterniond(AngleAxisd(-s[dof::SPINE_BEND], Vector3d::UnitX())));
  f.head = f.chest * trans(0, 0, p.neck_height) *
           rot(Quaterniond(AngleAxisd(s[dof::HEAD_YAW], Vector3d::UnitZ())));
  f.head_centre = f.head * Vector3d(0, p.head_centre_forward, p.head_centre_height);
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    const int i = static_cast<int>(side);
    const double sx = side == Side::LEFT ? -1.0 : 1.0;
    f.upper_arm[i] = f.chest *
                     trans(sx * (p.shoulder_half_width + s[armDof(side, 2)]), 0, p.shoulder_height) *
                     rot(shoulderRotation(s[armDof(side, 0)], s[armDof(side, 1)]));
    f.shoulder[i] = f.upper_arm[i].translation();
    f.elbow[i] = f.upper_arm[i] * Vector3d(0, p.upper_arm, 0);
    f.forearm[i] = make(f.upper_arm[i].linear() *
                            elbowRotation(s[armDof(side, 3)], s[armDof(side, 4)]).toRotationMatrix(),
                        f.elbow[i]);
    f.wrist[i] = f.forearm[i] * Vector3d(0, p.forearm, 0);
    f.hand[i] = f.forearm[i] * Vector3d(0, p.forearm + p.wrist_to_hand, 0);
  }
  return f;
}

}  // namespace body_tracking
