// Online body shape (issue 16, the thesis' future work) reads one scale factor of the profile at
// a time from the volumes: a ladder of factors around 1 (the profile as given), each frame of a
// track's first `frames` scoring the estimate with every factor, the factor with the best sum so
// far in use. trunk_girth.h scales the trunk's half widths and depths, arm_length.h the bones.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace body_tracking {

struct LadderParams {
  int frames = 0;  // a track's frames that refine the factor (e.g. 50: 2 s at 25 fps); 0 = off
  double min = 0.8;  // the ladder: 1 (the profile) +- k step, within [min, max]
  double max = 1.4;
  double step = 0.05;
  // Throws std::invalid_argument naming the parameter: `frames_key` for frames,
  // `prefix` + "_min" / "_max" / "_step" for the ladder (the keys of config/papf.yaml's shape).
  void validate(const std::string& frames_key, const std::string& prefix) const;
};

class ShapeLadder {
 public:
  explicit ShapeLadder(const LadderParams& params);  // params must be valid
  const std::vector<double>& factors() const { return factors_; }
  void add(size_t k, double score) { sums_[k] += score; }  // factor k's score on this frame
  void endFrame();  // counts the frame and picks the best sum; on a tie the factor nearer 1
  bool refining() const { return frames_limit_ > 0 && frames_ < frames_limit_; }
  int frames() const { return frames_; }
  double factor() const { return factor_; }  // the best so far (1 before any frame)
  void reset();

 private:
  std::vector<double> factors_, sums_;
  int frames_limit_, frames_ = 0;
  double factor_ = 1.0;
};

}  // namespace body_tracking
