#include "body_tracking/part_collision.h"

#include <algorithm>

namespace body_tracking {

using Eigen::Vector3d;

namespace {

// Distance between segments [a0, a1] and [b0, b1] (clamped closest points).
double segmentDistance(const Vector3d& a0, const Vector3d& a1, const Vector3d& b0,
                       const Vector3d& b1) {
  const Vector3d u = a1 - a0, v = b1 - b0, w = a0 - b0;
  const double a = u.dot(u), b = u.dot(v), c = v.dot(v), d = u.dot(w), e = v.dot(w);
  const double den = a * c - b * b;
  double s = den > 1e-12 ? std::clamp((b * e - c * d) / den, 0.0, 1.0) : 0.0;
  double t = c > 1e-12 ? std::clamp((b * s + e) / c, 0.0, 1.0) : 0.0;
  s = a > 1e-12 ? std::clamp((b * t - d) / a, 0.0, 1.0) : 0.0;
  return (a0 + s * u - (b0 + t * v)).norm();
}

}  // namespace

bool bodyCollides(const BodyProfile& profile, const BodyFrames& f, const BodyParts& parts) {
  const TruncatedQuadric& chest = parts[static_cast<int>(Part::CHEST)];
  const TruncatedQuadric& abdomen = parts[static_cast<int>(Part::ABDOMEN)];
  const TruncatedQuadric& head = parts[static_cast<int>(Part::HEAD)];
  // The head grown by half a hand's width: a hand whose centre comes that close lies on the
  // face. The face is skin, so the skin-weighted hand part scores as well there as on the real
  // hand, and a hand that waved past the head stayed locked on the face for seconds (generated
  // scenarios, wave and reach_targets). A hand held against the face is given up for it.
  const Eigen::Vector3d head_reach = head.semi + Eigen::Vector3d::Constant(profile.hand_half_width);
  const Eigen::Isometry3d head_inverse = head.frame.inverse();
  for (int i = 0; i < 2; ++i) {
    // The bone's axis inside the trunk means the limb is inside it (its surface merely touching
    // the trunk leaves the axis a limb radius outside).
    const Vector3d pts[] = {0.5 * (f.shoulder[i] + f.elbow[i]), f.elbow[i],
                            0.5 * (f.elbow[i] + f.wrist[i]), f.wrist[i], f.hand[i]};
    for (const Vector3d& p : pts)
      if (chest.contains(p) || abdomen.contains(p) || head.contains(p)) return true;
    if ((head_inverse * f.hand[i]).cwiseQuotient(head_reach).squaredNorm() < 1.0) return true;
  }
  // Forearms through each other (not merely touching).
  return segmentDistance(f.elbow[0], f.wrist[0], f.elbow[1], f.wrist[1]) <
         1.4 * profile.forearm_radius;
}

}  // namespace body_tracking
