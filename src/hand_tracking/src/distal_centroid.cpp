#include "hand_tracking/distal_centroid.h"

#include <algorithm>

#include <Eigen/Eigenvalues>

namespace hand_tracking {
namespace {
constexpr double kHullSmear = 0.05;  // m
constexpr double kRamp = 0.05;       // m of extent over which a blob becomes fully an arm
constexpr double kEndSlice = 0.03;   // m: the voxels this near an end locate it
}  // namespace

Eigen::Vector3d distalCentroid(const std::vector<WeightedPoint>& voxels,
                               const Eigen::Vector3d& centroid, const Eigen::Vector3d& head,
                               double length, double* arm_weight,
                               const ForeignBodyProbe& foreign) {
  if (arm_weight) *arm_weight = 0.0;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double mass = 0.0;
  for (const auto& [p, w] : voxels) {
    const Eigen::Vector3d d = p - centroid;
    cov += w * d * d.transpose();
    mass += w;
  }
  if (!(mass > 0.0)) return centroid;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov / mass);
  const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
  // Elongated: the long axis' spread at least 1.5x the next one's (a flat open hand is about
  // 19 x 9 cm; its 2.1:1 in extent is 1.4:1 in standard deviation at 16 mm voxels), fully an
  // arm from 1.7x (variance ratio 3).
  if (!(ev[2] > 2.25 * ev[1])) return centroid;
  const double elongation = std::min(1.0, (ev[2] / ev[1] - 2.25) / 0.75);
  Eigen::Vector3d axis = eig.eigenvectors().col(2);
  if (axis.dot(centroid - head) < 0.0) axis = -axis;  // pointing away from the head
  double t_max = -1e9, t_min = 1e9;
  for (const auto& [p, w] : voxels) {
    const double t = (p - centroid).dot(axis);
    t_max = std::max(t_max, t);
    t_min = std::min(t_min, t);
  }
  // No more than a hand: the hull smears a hand by about 3 voxels along its axis (5 cm at
  // 16 mm), so a blob is an arm only when longer than length + that.
  if (t_max - t_min <= length + kHullSmear) return centroid;
  if (foreign) {
    // Each end: the mean of the voxels within kEndSlice of it.
    Eigen::Vector3d far_sum = Eigen::Vector3d::Zero(), near_sum = Eigen::Vector3d::Zero();
    double far_w = 0.0, near_w = 0.0;
    for (const auto& [p, w] : voxels) {
      const double t = (p - centroid).dot(axis);
      if (t >= t_max - kEndSlice) far_sum += w * p, far_w += w;
      if (t <= t_min + kEndSlice) near_sum += w * p, near_w += w;
    }
    if (far_w > 0.0 && near_w > 0.0 &&
        foreign(far_sum / far_w) > foreign(near_sum / near_w) + kForeignMargin) {
      axis = -axis;
      std::swap(t_min, t_max);
      t_min = -t_min;
      t_max = -t_max;
    }
  }
  const double longer = std::min(1.0, (t_max - t_min - length - kHullSmear) / kRamp);
  if (arm_weight) *arm_weight = elongation * longer;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double kept = 0.0;
  for (const auto& [p, w] : voxels)
    if ((p - centroid).dot(axis) >= t_max - length) sum += w * p, kept += w;
  return kept > 0.0 ? Eigen::Vector3d(sum / kept) : centroid;
}

}  // namespace hand_tracking
