// The MPF observation functions (thesis 5.1.3, 6.3) on integral volumes, O(1) per particle:
//   head(x) = mean skin probability in the head box centred at x
//             x mean non-occupancy of a slab over the box (the crown; not in the thesis);
//   hand(x) = mean skin probability in the palm box centred at x
//             x mean non-occupancy (1 - P(F), body volume) of the box's frontal plane.
// Box means count the outside of a volume's grid as probability 0 in smooth mode (a box that
// leaves the workspace fades out) and clip to the grid in voxel-centre mode (as boxMean).
#pragma once

#include <Eigen/Core>

#include "hand_tracking/integral_volume.h"
#include "hand_tracking/mpf_params.h"
#include "hand_tracking/target.h"

namespace hand_tracking {

class BoxObservation {
 public:
  explicit BoxObservation(const MpfParams& params);

  // skin: integral volume of P(skin-coloured foreground); body: of P(foreground). Both must be
  // built; they may use different grids.
  double head(const IntegralVolume& skin, const IntegralVolume& body,
              const Eigen::Vector3d& x) const;
  double hand(const IntegralVolume& skin, const IntegralVolume& body,
              const Eigen::Vector3d& x) const;
  double operator()(Target::Type type, const IntegralVolume& skin, const IntegralVolume& body,
                    const Eigen::Vector3d& x) const {
    return type == Target::kHead ? head(skin, body, x) : hand(skin, body, x);
  }

  // The box of the hand observation's frontal plane for a palm box centred at x (for tests and
  // visualisation): [*min, *max].
  void frontalPlane(const Eigen::Vector3d& x, Eigen::Vector3d* min, Eigen::Vector3d* max) const;
  // The slab over a head box centred at x (MpfParams::head_crown_*): [*min, *max].
  void crownSlab(const Eigen::Vector3d& x, Eigen::Vector3d* min, Eigen::Vector3d* max) const;

 private:
  double mean(const IntegralVolume& v, const Eigen::Vector3d& min,
              const Eigen::Vector3d& max) const {
    return smooth_ ? v.boxMeanSmooth(min, max) : v.boxMean(min, max);
  }

  Eigen::Vector3d head_half_, hand_half_;
  int axis_ = 1;      // frontal axis
  double sign_ = 1;   // +1 / -1 along it
  double thickness_ = 0, gap_ = 0;
  double crown_thickness_ = 0, crown_gap_ = 0;
  bool smooth_ = true;
};

}  // namespace hand_tracking
