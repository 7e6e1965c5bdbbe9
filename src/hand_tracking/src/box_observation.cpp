#include "hand_tracking/box_observation.h"

#include <algorithm>
#include <cmath>

namespace hand_tracking {

BoxObservation::BoxObservation(const MpfParams& p)
    : head_half_(0.5 * p.head_box),
      hand_half_(0.5 * p.hand_box),
      thickness_(p.frontal_plane_thickness),
      gap_(p.frontal_plane_gap),
      crown_thickness_(p.head_crown_thickness),
      crown_gap_(p.head_crown_gap),
      smooth_(p.smooth_boxes) {
  p.frontal_direction.cwiseAbs().maxCoeff(&axis_);
  sign_ = p.frontal_direction[axis_] >= 0.0 ? 1.0 : -1.0;
}

double BoxObservation::head(const IntegralVolume& skin, const IntegralVolume& body,
                            const Eigen::Vector3d& x) const {
  // Skin only in the thesis (5.1.3); the crown slab tells the head from a skin-coloured chest.
  const double s = mean(skin, x - head_half_, x + head_half_);
  if (s <= 0.0 || crown_thickness_ <= 0.0) return s;
  Eigen::Vector3d cmin, cmax;
  crownSlab(x, &cmin, &cmax);
  return s * (1.0 - std::clamp(mean(body, cmin, cmax), 0.0, 1.0));
}

void BoxObservation::crownSlab(const Eigen::Vector3d& x, Eigen::Vector3d* min,
                               Eigen::Vector3d* max) const {
  *min = x - head_half_;
  *max = x + head_half_;
  min->z() = x.z() + head_half_.z() + crown_gap_;
  max->z() = min->z() + crown_thickness_;
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
