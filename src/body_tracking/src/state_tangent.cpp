#include "body_tracking/state_tangent.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "body_tracking/kinematics.h"
#include "body_tracking/swing_twist.h"

namespace body_tracking {

using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

// Orthonormal basis of the tangent plane at unit m, a function of m alone.
void tangentBasis(const Vector3d& m, Vector3d* e1, Vector3d* e2) {
  const Vector3d ref = std::abs(m.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitZ();
  *e1 = (ref - m * m.dot(ref)).normalized();
  *e2 = m.cross(*e1);
}

Vector2d sphereLog(const Vector3d& m, const Vector3d& d) {
  Vector3d e1, e2;
  tangentBasis(m, &e1, &e2);
  const Vector3d perp = d - m * m.dot(d);
  const double s = perp.norm();
  if (s < 1e-12) return Vector2d::Zero();  // the same direction (or exactly opposite)
  const double angle = std::atan2(s, m.dot(d));
  const Vector3d v = perp * (angle / s);
  return Vector2d(v.dot(e1), v.dot(e2));
}

Vector3d sphereExp(const Vector3d& m, const Vector2d& t) {
  Vector3d e1, e2;
  tangentBasis(m, &e1, &e2);
  const Vector3d v = t.x() * e1 + t.y() * e2;
  const double a = v.norm();
  if (a < 1e-12) return m;
  return (std::cos(a) * m + std::sin(a) * (v / a)).normalized();
}

Vector3d shoulderDir(const BodyState& s, Side side) {
  return shoulderRotation(s[armDof(side, 0)], s[armDof(side, 1)]) * Vector3d::UnitY();
}
Vector3d forearmDir(const BodyState& s, Side side) {
  return elbowRotation(s[armDof(side, 3)], s[armDof(side, 4)]) * Vector3d::UnitY();
}
Quaterniond torsoQ(const BodyState& s) {
  return torsoRotation(s[dof::TORSO_ROLL], s[dof::TORSO_PITCH], s[dof::TORSO_YAW]);
}

}  // namespace

Tangent toTangent(const BodyState& at, const BodyState& s) { return toTangent(at, s, 0, kTangentDim); }

Tangent toTangent(const BodyState& at, const BodyState& s, int first, int count) {
  const int last = first + count;
  const auto touches = [&](int b, int n) { return b < last && first < b + n; };
  Tangent t = Tangent::Zero();
  for (int i = 0; i < 3; ++i)
    if (touches(i, 1)) t[i] = s[i] - at[i];
  if (touches(3, 3)) t.segment<3>(3) = rotationLog(torsoQ(at).conjugate() * torsoQ(s));
  if (touches(6, 1)) t[6] = s[dof::SPINE_BEND] - at[dof::SPINE_BEND];
  if (touches(7, 1)) t[7] = std::remainder(s[dof::HEAD_YAW] - at[dof::HEAD_YAW], 2 * M_PI);
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    const int b = armDof(side, 0);
    if (touches(b, 2)) t.segment<2>(b) = sphereLog(shoulderDir(at, side), shoulderDir(s, side));
    if (touches(b + 2, 1)) t[b + 2] = s[b + 2] - at[b + 2];
    if (touches(b + 3, 2)) t.segment<2>(b + 3) = sphereLog(forearmDir(at, side), forearmDir(s, side));
  }
  return t;
}

BodyState fromTangent(const BodyState& at, const Tangent& t) { return fromTangent(at, t, 0, kTangentDim); }

BodyState fromTangent(const BodyState& at, const Tangent& t, int first, int count) {
  // Block by block (a rotation's coordinates only make sense together): a block the range does
  // not touch is copied, not sent through its log / exp round trip.
  const int last = first + count;
  const auto touches = [&](int b, int n) { return b < last && first < b + n; };
  BodyState s = at;
  for (int i = 0; i < 3; ++i)
    if (touches(i, 1)) s[i] = at[i] + t[i];
  if (touches(3, 3))
    torsoAngles(torsoQ(at) * rotationExp(t.segment<3>(3)), &s[dof::TORSO_ROLL],
                &s[dof::TORSO_PITCH], &s[dof::TORSO_YAW]);
  if (touches(6, 1)) s[dof::SPINE_BEND] = at[dof::SPINE_BEND] + t[6];
  if (touches(7, 1)) s[dof::HEAD_YAW] = std::remainder(at[dof::HEAD_YAW] + t[7], 2 * M_PI);
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    const int b = armDof(side, 0);
    if (touches(b, 2)) {
      const Vector3d d = sphereExp(shoulderDir(at, side), t.segment<2>(b));
      s[b + 1] = std::asin(std::max(-1.0, std::min(1.0, -d.x())));
      s[b] = std::atan2(d.z(), d.y());
    }
    if (touches(b + 2, 1)) s[b + 2] = at[b + 2] + t[b + 2];
    if (touches(b + 3, 2)) {
      const Vector3d e = sphereExp(forearmDir(at, side), t.segment<2>(b + 3));
      s[b + 3] = std::acos(std::max(-1.0, std::min(1.0, e.y())));
      if (std::hypot(e.x(), e.z()) > 1e-6) s[b + 4] = std::atan2(e.x(), e.z());
    }
  }
  return s;
}

BodyState weightedMean(const BodyState* states, const double* weights, int n,
                       const BodyState& start, int iterations, int threads) {
  // The tangents (quaternion logs, swing-twist) are most of the cost and independent: computed
  // in parallel, summed in order.
  std::vector<Tangent> t(std::max(0, n));
  BodyState centre = start;
  for (int it = 0; it < std::max(1, iterations); ++it) {
#pragma omp parallel for num_threads(std::max(1, threads)) schedule(static)
    for (int i = 0; i < n; ++i)
      if (weights[i] > 0) t[i] = toTangent(centre, states[i]);
    Tangent sum = Tangent::Zero();
    double wsum = 0;
    for (int i = 0; i < n; ++i) {
      if (weights[i] <= 0) continue;
      sum += weights[i] * t[i];
      wsum += weights[i];
    }
    if (wsum <= 0) return centre;
    centre = fromTangent(centre, sum / wsum);
  }
  return centre;
}

}  // namespace body_tracking
