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
// old lengths always win).
#pragma once

#include <vector>

#include "body_tracking/body_profile.h"
#include "body_tracking/body_state.h"
#include "body_tracking/volume_observation.h"

namespace body_tracking {

struct TrunkGirthParams {
  int frames = 0;       // frames of a track that refine the girth (e.g. 50: 2 s at 25 fps); 0 = off
  double min = 0.8;     // the ladder of factors: min, min + step, ... <= max (the profile's = 1)
  double max = 1.4;
  double step = 0.05;
  // Throws std::invalid_argument naming the parameter.
  void validate() const;
};

class TrunkGirth {
 public:
  explicit TrunkGirth(const TrunkGirthParams& params = TrunkGirthParams());
  const TrunkGirthParams& params() const { return params_; }

  void reset();  // a new track (perhaps a new person): back to factor 1
  // One frame of the track: the trunk of `state` with `base` scaled by each factor, scored.
  void add(const VolumeObservation& obs, const BodyProfile& base, const BodyState& state);
  bool refining() const { return params_.frames > 0 && frames_ < params_.frames; }
  int frames() const { return frames_; }
  double factor() const { return factor_; }  // the best so far (1 before any frame)

  // base with the trunk's half widths and depths (abdomen, chest) times `factor`.
  static BodyProfile scaled(const BodyProfile& base, double factor);

 private:
  TrunkGirthParams params_;
  std::vector<double> factors_, sums_;
  int frames_ = 0;
  double factor_ = 1.0;
};

}  // namespace body_tracking
