#include "hand_tracking/box_observation.h"

#include <algorithm>
#include <cmath>

namespace hand_tracking {

BoxObservation::BoxObservation(const MpfParams& p)
    : head_half_(0.5 * p.head_box),
      hand_half_(0.5 * p.hand_box),
      thickness_(p.frontal_plane_thickness),
      gap_(p.frontal_plane_gap),
      smooth_(p.smooth_boxes) {
  p.frontal_direction.cwiseAbs().maxCoeff(&axis_);
  sign_ = p.frontal_direction[axis_] >= 0.0 ? 1.0 : -1.0;
}

double BoxObservation::head(const IntegralVolume& skin, const IntegralVolume& body,
                            const Eigen::Vector3d& x) const {
  (void)body;  // the head observation is skin only (thesis 5.1.3)
  return mean(skin, x - head_half_, x + head_half_);
}

void BoxObservation::frontalPlane(const Eigen::Vector3d& x, Eigen::Vector3d* min,
                                  Eigen::Vector3d* max) const {
  *min = x - hand_half_;
  *max = x + hand_half_;
  const double face = x[axis_] + sign_ * (hand_half_[axis_] + gap_);
  const double far = face + sign_ * thickness_;
  (*min)[axis_] = std::min(face, far);
  (*max)[axis_] = std::max(face, far);
}

double BoxObservation::hand(const IntegralVolume& skin, const IntegralVolume& body,
                            const Eigen::Vector3d& x) const {
  const double s = mean(skin, x - hand_half_, x + hand_half_);
  if (s <= 0.0 || thickness_ <= 0.0) return s;
  Eigen::Vector3d pmin, pmax;
  frontalPlane(x, &pmin, &pmax);
  const double occupied = std::clamp(mean(body, pmin, pmax), 0.0, 1.0);
  return s * (1.0 - occupied);
}

}  // namespace hand_tracking
