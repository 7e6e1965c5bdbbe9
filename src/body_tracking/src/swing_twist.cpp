#include "body_tracking/swing_twist.h"

#include <algorithm>
#include <cmath>

namespace body_tracking {

using Eigen::AngleAxisd;
using Eigen::Quaterniond;
using Eigen::Vector3d;

namespace {

Quaterniond positive(const Quaterniond& q) {
  return q.w() < 0 ? Quaterniond(-q.w(), -q.x(), -q.y(), -q.z()) : q;
}

struct Parts {
  Vector3d swing_vector;  // perpendicular to the axis
  double twist_angle;     // (-pi, pi]
};

Parts decompose(const SwingTwistLimit& l, const Quaterniond& q) {
  Quaterniond swing, twist;
  swingTwist(q, l.axis, &swing, &twist);
  Parts p;
  p.swing_vector = rotationLog(swing);
  p.twist_angle = 2.0 * std::atan2(twist.vec().dot(l.axis), twist.w());
  if (p.twist_angle > M_PI) p.twist_angle -= 2 * M_PI;
  return p;
}

double ellipseRadius(const SwingTwistLimit& l, const Vector3d& r) {
  const Vector3d v = l.axis.cross(l.u);
  const double a = r.dot(l.u) / l.max_swing_u, b = r.dot(v) / l.max_swing_v;
  return std::sqrt(a * a + b * b);
}

}  // namespace

Vector3d rotationLog(const Quaterniond& q_in) {
  const Quaterniond q = positive(q_in);
  const double s = q.vec().norm();
  if (s < 1e-12) return 2.0 * q.vec();
  return 2.0 * std::atan2(s, q.w()) / s * q.vec();
}

Quaterniond rotationExp(const Vector3d& r) {
  const double a = r.norm();
  if (a < 1e-12) return Quaterniond(1, 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z()).normalized();
  return Quaterniond(AngleAxisd(a, r / a));
}

void swingTwist(const Quaterniond& q_in, const Vector3d& axis, Quaterniond* swing,
                Quaterniond* twist) {
  const Quaterniond q = positive(q_in.normalized());
  const Vector3d p = q.vec().dot(axis) * axis;
  Quaterniond t(q.w(), p.x(), p.y(), p.z());
  const double n = t.norm();
  // A half-turn swing leaves no twist component at all (w = 0 and vec perpendicular).
  t = n < 1e-12 ? Quaterniond::Identity() : Quaterniond(t.coeffs() / n);
  *twist = positive(t);
  *swing = positive(q * twist->conjugate());
}

bool SwingTwistLimit::satisfied(const Quaterniond& q, double tolerance) const {
  const Parts p = decompose(*this, q);
  return ellipseRadius(*this, p.swing_vector) <= 1.0 + tolerance &&
         p.twist_angle >= min_twist - tolerance && p.twist_angle <= max_twist + tolerance;
}

Quaterniond SwingTwistLimit::clamp(const Quaterniond& q) const {
  Parts p = decompose(*this, q);
  const double r = ellipseRadius(*this, p.swing_vector);
  if (r > 1.0) p.swing_vector /= r;
  p.twist_angle = std::clamp(p.twist_angle, min_twist, max_twist);
  return rotationExp(p.swing_vector) * Quaterniond(AngleAxisd(p.twist_angle, axis));
}

}  // namespace body_tracking
