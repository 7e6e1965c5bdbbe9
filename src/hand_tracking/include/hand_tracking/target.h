// One tracked target of the mixture particle filter: what the tracker reports per frame and
// what tabletop_msgs/TrackedTarget carries (DESIGN.md section 3, hands/targets).
#pragma once

#include <cstdint>

#include <Eigen/Core>

namespace hand_tracking {

struct Target {
  enum Type : uint8_t { kHand = 0, kHead = 1 };  // same values as tabletop_msgs/TrackedTarget
  uint32_t id = 0;  // identity, stable over a track's life (0 = never tracked)
  Type type = kHand;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, metres (weighted particle mean)
  double weight = 0.0;                                 // mixture weight pi_m (0 when inactive)
  bool active = false;
};

inline const char* typeName(Target::Type t) { return t == Target::kHead ? "head" : "hand"; }

}  // namespace hand_tracking
