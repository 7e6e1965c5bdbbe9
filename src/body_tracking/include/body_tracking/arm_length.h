// Online body shape (issue 16, the thesis' future work): the arms' length. People differ by
// about +-10 % in arm length; a model arm too short cannot reach the hand of a stretched arm, one
// too long bends its elbow out of the volume. Over a track's first frames each arm whose hand
// the skin volume found (hand_refinement.h) votes: for each factor on the ladder
// (shape_ladder.h) the arm of that length is re-posed by two-bone IK (arm_ik.h), elbow bent
// towards the estimate's elbow, with its hand on the found hand or on the tracked hand slid
// along the forearm by up to 4 cm (the best of these), and scored by how well its upper arm
// and forearm cover the occupied voxels around the arm (an F1 measure, arm_length.cpp says why
// not the filter's own score). Re-posing lets a length win that the tracked pose was not fitted
// with: scored at the tracked pose, the profile's lengths always won (trunk_girth.h). One
// factor scales both arms' upper arm and forearm (people are near symmetric, and two arms
// settle it sooner); the hand's size stays the profile's.
// On by default: 50 voting frames (PapfParams::arm_length.frames; 0 = the profile's lengths).
// Measured (docs/benchmarks.md, 2026-12-05): reach_targets, 5 seeds, hands 13.3 -> 11.2 mm
// median; 10 generated people x 2 seeds, hands median 33.3 -> 27.1 and 35.4 -> 28.6 mm, elbows
// 47.3 -> 40.4 and 47.5 -> 40.6 mm; all ten factors read long, by 0.014-0.126 (mean 0.064,
// as far off as keeping 1: a long arm costs the tracker less than a short one, and the
// shoulders sit 3-4 cm off there). A vote costs 2.8 ms (bench_papf), over a track's first 50
// frames with a hand found (~2 s when the hands are in view).
#pragma once

#include "body_tracking/body_profile.h"
#include "body_tracking/body_state.h"
#include "body_tracking/hand_refinement.h"
#include "body_tracking/joint_limits.h"
#include "body_tracking/shape_ladder.h"
#include "body_tracking/volume_observation.h"

namespace body_tracking {

// Keys shape/arm_frames, shape/arm_min, _max, _step. frames counts the frames with a vote.
struct ArmLengthParams : LadderParams {
  ArmLengthParams() : LadderParams{50, 0.85, 1.15, 0.025} {}
  void validate() const { LadderParams::validate("arm_frames", "arm"); }
};

class ArmLength {
 public:
  explicit ArmLength(const ArmLengthParams& params = ArmLengthParams());
  const ArmLengthParams& params() const { return params_; }

  void reset() { ladder_.reset(); }  // a new track (perhaps a new person): back to factor 1
  // One frame of the track: `state` was tracked with `base` scaled by factor(); the arms whose
  // hands.from_skin is set vote. A frame without a vote does not count.
  void add(const VolumeObservation& obs, const BodyProfile& base, const BodyState& state,
           const RefinedHands& hands);
  bool refining() const { return ladder_.refining(); }
  int frames() const { return ladder_.frames(); }
  double factor() const { return ladder_.factor(); }  // the best so far (1 before any vote)

  // base with both arms' upper arm and forearm times `factor`.
  static BodyProfile scaled(const BodyProfile& base, double factor);

 private:
  ArmLengthParams params_;
  ShapeLadder ladder_;
  BodyLimits limits_;
};

}  // namespace body_tracking
