// The quadric body model: nine truncated quadrics placed by the forward kinematics (thesis
// figure 5.6). Trunk and limbs are elliptic cylinders along their bones, the head and the hands
// ellipsoids. The hands carry no wrist DOF: each hand sits on the forearm's axis, wrist_to_hand
// beyond the wrist.
#pragma once

#include <array>

#include "body_tracking/body_profile.h"
#include "body_tracking/kinematics.h"
#include "body_tracking/truncated_quadric.h"

namespace body_tracking {

enum class Part : int {
  ABDOMEN = 0,
  CHEST,
  HEAD,
  LEFT_UPPER_ARM,
  LEFT_FOREARM,
  LEFT_HAND,
  RIGHT_UPPER_ARM,
  RIGHT_FOREARM,
  RIGHT_HAND,
  COUNT
};
constexpr int kNumParts = static_cast<int>(Part::COUNT);
const char* partName(Part p);
inline Part upperArmPart(Side s) { return s == Side::LEFT ? Part::LEFT_UPPER_ARM : Part::RIGHT_UPPER_ARM; }
inline Part forearmPart(Side s) { return s == Side::LEFT ? Part::LEFT_FOREARM : Part::RIGHT_FOREARM; }
inline Part handPart(Side s) { return s == Side::LEFT ? Part::LEFT_HAND : Part::RIGHT_HAND; }
// Head and hands are mostly skin: the observation weights their skin evidence.
inline bool isSkinPart(Part p) {
  return p == Part::HEAD || p == Part::LEFT_HAND || p == Part::RIGHT_HAND;
}

inline bool isTrunkPart(Part p) { return p == Part::ABDOMEN || p == Part::CHEST; }

using BodyParts = std::array<TruncatedQuadric, kNumParts>;

TruncatedQuadric buildPart(const BodyProfile& profile, const BodyFrames& frames, Part part);
BodyParts buildParts(const BodyProfile& profile, const BodyFrames& frames);
inline BodyParts buildParts(const BodyProfile& profile, const BodyState& state) {
  return buildParts(profile, forwardKinematics(profile, state));
}

}  // namespace body_tracking
