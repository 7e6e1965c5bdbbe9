#include "body_tracking/body_parts.h"

namespace body_tracking {

using Eigen::Isometry3d;
using Eigen::Vector3d;

const char* partName(Part p) {
  switch (p) {
    case Part::ABDOMEN: return "abdomen";
    case Part::CHEST: return "chest";
    case Part::HEAD: return "head";
    case Part::LEFT_UPPER_ARM: return "left_upper_arm";
    case Part::LEFT_FOREARM: return "left_forearm";
    case Part::LEFT_HAND: return "left_hand";
    case Part::RIGHT_UPPER_ARM: return "right_upper_arm";
    case Part::RIGHT_FOREARM: return "right_forearm";
    case Part::RIGHT_HAND: return "right_hand";
    case Part::COUNT: break;
  }
  return "?";
}

TruncatedQuadric buildPart(const BodyProfile& p, const BodyFrames& f, Part part) {
  // Trunk cylinders run along the frames' z axis; a quarter turn about x puts the cylinder's
  // local y (its axis) there, local x stays the width and local z the depth.
  const Isometry3d up(Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitX()));
  switch (part) {
    case Part::ABDOMEN:
      return TruncatedQuadric::cylinder(f.pelvis * up, p.spine_height, p.abdomen_half_width,
                                        p.abdomen_half_depth);
    case Part::CHEST:  // reaches a little above the shoulder joints (the shoulders' own girth)
      return TruncatedQuadric::cylinder(f.chest * up, p.shoulder_height + 0.5 * p.upper_arm_radius,
                                        p.chest_half_width, p.chest_half_depth);
    case Part::HEAD:
      return TruncatedQuadric::ellipsoid(
          f.head * Eigen::Translation3d(0, p.head_centre_forward, p.head_centre_height),
          Vector3d(p.head_half_width, p.head_half_depth, p.head_half_height));
    default:
      break;
  }
  const bool left = part == Part::LEFT_UPPER_ARM || part == Part::LEFT_FOREARM || part == Part::LEFT_HAND;
  const int i = left ? 0 : 1;
  if (part == Part::LEFT_UPPER_ARM || part == Part::RIGHT_UPPER_ARM)
    return TruncatedQuadric::cylinder(f.upper_arm[i], p.upper_arm, p.upper_arm_radius, p.upper_arm_radius);
  if (part == Part::LEFT_FOREARM || part == Part::RIGHT_FOREARM)
    return TruncatedQuadric::cylinder(f.forearm[i], p.forearm, p.forearm_radius, p.forearm_radius);
  return TruncatedQuadric::ellipsoid(
      f.forearm[i] * Eigen::Translation3d(0, p.forearm + p.wrist_to_hand, 0),
      Vector3d(p.hand_half_width, p.hand_half_length, p.hand_half_thickness));
}

BodyParts buildParts(const BodyProfile& p, const BodyFrames& f) {
  BodyParts parts;
  for (int k = 0; k < kNumParts; ++k) parts[k] = buildPart(p, f, static_cast<Part>(k));
  return parts;
}

}  // namespace body_tracking
