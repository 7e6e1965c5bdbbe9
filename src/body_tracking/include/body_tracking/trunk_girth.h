// Online body shape (issue 16, the thesis' future work), the part the trunk's shell needs: the
// trunk's girth. The shell (volume_observation.h) holds a trunk cylinder to the person's trunk
// boundary, so a model trunk narrower than the person's has its shell inside the person and is
// pushed about (generated people of girth 1.24: head 28 -> 50 mm). Over the first frames of a
// track each frame scores the estimate's abdomen and chest, shells included, at a ladder of girth
// factors (half width and half depth of both scaled alike) and sums the scores per factor; the
// tracker uses the factor with the best sum so far and keeps it once `frames` frames are in.
// The pose is the one tracked with the girth of the frame before, so the two settle together.
// Off by default (PapfParams::shape.frames = 0). Measured on generated people (2026-12-05,
// docs/benchmarks.md, with the shell then counted inside the grid only): the factor follows
// the person's trunk width (true size x girth 0.90 /
// 0.92 / 1.10 / 1.19 / 1.20 / 1.25 -> 0.90 / 0.95 / 1.05 / 1.10 / 1.15 / 1.10, the widest
// under-read), but tracking did not gain (10 scenarios x 2 seeds: hands median 73 -> 55 and
// 47 -> 65 mm, head 35 -> 36 and 23 -> 30): the wide people's trunks still sink, and the
// lengths (size) cannot be read this way (the pose was fitted with the old lengths, and the
// old lengths always win; arm_length.h re-poses the arm for each length instead).
#pragma once

#include "body_tracking/body_profile.h"
#include "body_tracking/body_state.h"
#include "body_tracking/shape_ladder.h"
#include "body_tracking/volume_observation.h"

namespace body_tracking {

struct TrunkGirthParams : LadderParams {  // keys shape/frames, shape/girth_min, _max, _step
  TrunkGirthParams() : LadderParams{0, 0.8, 1.4, 0.05} {}
  void validate() const { LadderParams::validate("frames", "girth"); }
};

class TrunkGirth {
 public:
  explicit TrunkGirth(const TrunkGirthParams& params = TrunkGirthParams());
  const TrunkGirthParams& params() const { return params_; }

  void reset() { ladder_.reset(); }  // a new track (perhaps a new person): back to factor 1
  // One frame of the track: the trunk of `state` with `base` scaled by each factor, scored.
  void add(const VolumeObservation& obs, const BodyProfile& base, const BodyState& state);
  bool refining() const { return ladder_.refining(); }
  int frames() const { return ladder_.frames(); }
  double factor() const { return ladder_.factor(); }  // the best so far (1 before any frame)

  // base with the trunk's half widths and depths (abdomen, chest) times `factor`.
  static BodyProfile scaled(const BodyProfile& base, double factor);

 private:
  TrunkGirthParams params_;
  ShapeLadder ladder_;
};

}  // namespace body_tracking
