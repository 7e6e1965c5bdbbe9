// Articulated seated person for the simulated rig: the 18-DOF state of tabletop_msgs/BodyPose
// plus per-hand shape and wrist pose, forward kinematics to solid primitives, and a 2-bone arm
// IK so motion scripts can be written as hand positions.
//
// Frames (all right-handed, metres/radians):
// - torso (pelvis) frame: origin = state[0..2], R = Rz(yaw) Ry(pitch) Rx(roll) of state[3..5].
//   At zero rotation its axes are the world's: x = the person's right, y = forward (towards
//   the screen), z = up. So leaning forward is a NEGATIVE roll.
// - chest frame: the torso frame moved up the spine by kSpineHeight and rotated about its x
//   axis by -state[6], so a positive upper-spine bend leans the chest forward.
// - head: turns by state[7] about the chest z axis at the neck (positive = to the left).
// - arms, in the chest frame: shoulder joint at (-/+ (kShoulderHalfWidth + shift), 0,
//   kShoulderHeight) for the left/right arm (shift = state[10]/[15], + = outwards). The
//   upper-arm rotation is U = R_chest Rx(swing1) Rz(swing2) with its rest direction along +y
//   (pointing forward): direction = (-sin s2, cos s2 cos s1, cos s2 sin s1), so swing1 raises
//   it (-pi/2 = hanging down) and swing2 turns it to the left. The forearm frame is
//   F = U Ry(twist) Rx(flex) (origin at the elbow, y along the forearm, x = the elbow hinge);
//   flex = 0 is a straight arm, flex > 0 bends the forearm towards U's +z. Both arms use the
//   same formulas (no mirroring), so a mirror-symmetric pose has swing2 and twist negated.
// - palm frame: P = F T(0, kForearm, 0) Ry(roll) Rx(-flex_w) Rz(deviation) T(0, kWristToPalm, 0)
//   with the HandPose's wrist angles: origin = palm centre, y = towards the fingers,
//   z = back of the hand (dorsal), thumb on -x for the right hand and +x for the left.
//
// Ground-truth definitions (what ground_truth/* publish and what trackers are scored against):
// - hand centroid = volume-weighted mean of the centroids of the hand's SKIN primitives (palm
//   and finger segments; overlaps are counted twice, which moves it about 2 mm), see handCentroid.
// - visible hand skin centroid = the same solid minus what sleeves and cuffs cover, counted
//   once where primitives overlap (the MPF's target), see visibleSkinCentroid.
// - head centroid = centre of the head (skin) ellipsoid, see headCentre.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tabletop_sim/primitives.h"

namespace tabletop_sim {

enum class Side { LEFT = 0, RIGHT = 1 };
enum class HandShape { OPEN, FIST, POINT };
const char* handShapeName(HandShape s);

// Indices into BodyPose::state (the order of tabletop_msgs/BodyPose.state).
namespace dof {
enum : int {
  TORSO_X = 0,
  TORSO_Y,
  TORSO_Z,
  TORSO_ROLL,
  TORSO_PITCH,
  TORSO_YAW,
  SPINE_BEND,
  HEAD_YAW,
  L_SWING_1,
  L_SWING_2,
  L_SHIFT,
  L_FLEX,
  L_TWIST,
  R_SWING_1,
  R_SWING_2,
  R_SHIFT,
  R_FLEX,
  R_TWIST,
  COUNT
};
// Arm joint k (0 swing1, 1 swing2, 2 shift, 3 elbow flex, 4 elbow twist) of one side.
inline int arm(Side s, int k) { return (s == Side::LEFT ? L_SWING_1 : R_SWING_1) + k; }
}  // namespace dof

struct HandPose {
  HandShape shape = HandShape::OPEN;  // nominal shape (label); the curls below are the truth
  // Finger curl, thumb first then index, middle, ring, little: 0 = straight, 1 = fully curled.
  std::array<double, 5> curl{{0.0, 0.1, 0.05, 0.1, 0.15}};
  double roll = 0.0;       // forearm pronation: rotation about the forearm axis
  double flex = 0.0;       // wrist palmar flexion (+ bends the hand towards the palm side)
  double deviation = 0.0;  // wrist side bend about the palm normal

  static HandPose preset(HandShape s);
};
// Finger curls and wrist angles blended linearly; the label switches at s = 0.5.
HandPose blend(const HandPose& a, const HandPose& b, double s);

struct BodyPose {
  std::array<double, dof::COUNT> state{};
  std::array<HandPose, 2> hands;  // indexed by Side
  HandPose& hand(Side s) { return hands[static_cast<int>(s)]; }
  const HandPose& hand(Side s) const { return hands[static_cast<int>(s)]; }
};

// Sleeves: LONG ends ~1 cm before the wrist (a bare wrist shows); ROLLED up to mid-forearm;
// SHORT leaves the forearm and the lower upper arm bare; CUFF reaches past the wrist over part
// of the palm (cuff_cover of its length), so the visible skin is the fingers and the rest.
enum class Sleeves : uint8_t { LONG, ROLLED, SHORT, CUFF };
// Hair: SHORT covers the back and top of the scalp; LONG also falls to the shoulders; NONE
// leaves the whole head skin.
enum class Hair : uint8_t { SHORT, LONG, NONE };
const char* sleevesName(Sleeves s);
const char* hairName(Hair h);

struct BodyOptions {
  bool short_sleeves = false;  // the same as sleeves = SHORT (kept for the rig's flag)
  Sleeves sleeves = Sleeves::LONG;
  double cuff_cover = 0.35;  // CUFF: fraction of the palm's length covered, from the wrist (0..0.8)
  Hair hair = Hair::SHORT;
  // Shape, relative to the medium-sized adult of the constants below. size scales the trunk,
  // head (by half as much), shoulders and arm lengths (0.8..1.2); arm_length the arms again
  // (0.85..1.15); girth the radii of trunk and arms (0.8..1.4); hand_size palm and fingers
  // (0.75..1.25).
  double size = 1.0, arm_length = 1.0, girth = 1.0, hand_size = 1.0;

  Sleeves effectiveSleeves() const { return short_sleeves ? Sleeves::SHORT : sleeves; }
};

struct BodyFrames {
  Eigen::Isometry3d pelvis, chest, head;  // head: neck pivot, turned by HEAD_YAW
  std::array<Eigen::Isometry3d, 2> upper_arm, forearm, palm;  // indexed by Side
  std::array<Eigen::Vector3d, 2> shoulder, elbow, wrist;
};

struct ArmSolution {
  double swing1 = 0, swing2 = 0, flex = 0, twist = 0;
  bool reachable = true;  // false: target beyond reach (or too close); the arm points at it
  double residual = 0;    // |palm centre - target| after solving (m)
};

class BodyModel {
 public:
  // Body dimensions (m) of the default, medium-sized adult; a model's own are scaled by its
  // BodyOptions (the accessors below).
  static constexpr double kSpineHeight = 0.25;        // pelvis origin -> upper-spine joint
  static constexpr double kShoulderHalfWidth = 0.17;  // chest centre line -> shoulder joint
  static constexpr double kShoulderHeight = 0.29;     // above the spine joint
  static constexpr double kNeckHeight = 0.34;         // neck pivot above the spine joint
  static constexpr double kUpperArm = 0.29;           // shoulder -> elbow
  static constexpr double kForearm = 0.26;            // elbow -> wrist
  static constexpr double kWristToPalm = 0.05;        // wrist -> palm centre
  static constexpr double kMaxElbowFlex = 2.6;

  // Throws std::invalid_argument for shape factors outside their ranges.
  explicit BodyModel(const BodyOptions& options = BodyOptions());
  const BodyOptions& options() const { return options_; }
  double upperArm() const { return kUpperArm * options_.size * options_.arm_length; }
  double forearm() const { return kForearm * options_.size * options_.arm_length; }
  double wristToPalm() const { return kWristToPalm * options_.hand_size; }

  // Seated upright, hands resting palm-down on the desk near the body, head about
  // (0, -0.42, 0.57) (the figures in the header of DESIGN.md's world description).
  static BodyPose restPose();
  // The resting hands: relaxed (fingers slightly curled, thumb straight), lying on the desk top
  // with the palm centre kRestPalmHeight above it and nothing below the desk (motion scripts'
  // desk contact leaves this pose unchanged).
  static HandPose relaxedHand();
  static constexpr double kRestPalmHeight = 0.0325;

  BodyFrames forward(const BodyPose& pose) const;
  // The person as solid primitives (about 50), in world coordinates.
  std::vector<Primitive> build(const BodyPose& pose) const;
  void build(const BodyPose& pose, std::vector<Primitive>* out) const;

  // A hand's primitives in build() order, counted from its palm ellipsoid: two capsules per
  // finger (index .. little), then two for the thumb. Digit d as in HandPose::curl (0 = thumb),
  // segment 0 = proximal, 1 = distal.
  static constexpr int kHandPrimitives = 11;
  static constexpr int digitPrimitive(int digit, int segment) {
    return digit == 0 ? 9 + segment : 1 + 2 * (digit - 1) + segment;
  }

  Eigen::Vector3d palmCentre(const BodyPose& pose, Side side) const;
  Eigen::Vector3d headCentre(const BodyPose& pose) const;
  Eigen::Vector3d shoulder(const BodyPose& pose, Side side) const;

  // 2-bone IK: arm angles that put the palm centre at `palm_target` (world) with the elbow
  // bent towards `elbow_pole` (a world point). Uses the pose's torso, spine, shoulder shift
  // and hand (wrist) pose; the wrist offset is handled by a few fixed-point refinements.
  ArmSolution solveArm(const BodyPose& pose, Side side, const Eigen::Vector3d& palm_target,
                       const Eigen::Vector3d& elbow_pole) const;
  static void applyArm(BodyPose* pose, Side side, const ArmSolution& s);
  // Forearm roll (HandPose::roll) that turns the back of the hand as close as possible to
  // `dorsal` (world), given the current arm angles and wrist flexion.
  double rollForDorsal(const BodyPose& pose, Side side, const Eigen::Vector3d& dorsal) const;
  // Whole arm + wrist in one call (what motion scripts use): IK to `palm_target`, forearm roll
  // towards `dorsal`, and, unless `finger_elevation` is NaN, wrist flexion so the hand's
  // finger axis rises `finger_elevation` rad above horizontal (0 = hand flat). Alternates IK
  // and wrist a few times because the wrist moves the palm centre. Returns the final IK result.
  ArmSolution poseArm(BodyPose* pose, Side side, const Eigen::Vector3d& palm_target,
                      const Eigen::Vector3d& elbow_pole, const Eigen::Vector3d& dorsal,
                      double finger_elevation) const;

 private:
  BodyOptions options_;
};

// Ground-truth hand centroid (see the header comment) from built primitives; NaN if absent.
Eigen::Vector3d handCentroid(const std::vector<Primitive>& primitives, Side side);
// The MPF's hand target: centroid of the hand's visible skin, the union of its skin
// primitives minus whatever any non-skin primitive (a sleeve, a cuff) covers, sampled on a
// grid of `spacing` (m; the centroid is good to a small fraction of it). NaN if none.
Eigen::Vector3d visibleSkinCentroid(const std::vector<Primitive>& primitives, Side side,
                                    double spacing = 0.002);
inline BodyPart handPart(Side s) {
  return s == Side::LEFT ? BodyPart::LEFT_HAND : BodyPart::RIGHT_HAND;
}

}  // namespace tabletop_sim
