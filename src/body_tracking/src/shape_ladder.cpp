#include "body_tracking/shape_ladder.h"

#include <cmath>
#include <stdexcept>

namespace body_tracking {

void LadderParams::validate(const std::string& frames_key, const std::string& prefix) const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("papf: shape/" + what); };
  if (frames < 0) fail(frames_key + " must be >= 0");
  if (!(min > 0.3 && min <= 1.0)) fail(prefix + "_min must be in (0.3, 1]");
  if (!(max >= 1.0 && max < 3.0)) fail(prefix + "_max must be in [1, 3)");
  if (!(step > 0.005 && step <= max - min + 1e-9) && max > min)
    fail(prefix + "_step must be in (0.005, " + prefix + "_max - " + prefix + "_min]");
}

ShapeLadder::ShapeLadder(const LadderParams& params) : frames_limit_(params.frames) {
  // 1 on the ladder exactly (the profile as given), so that ties keep the profile.
  const bool ladder = params.max > params.min && params.step > 0;
  const int below = ladder ? static_cast<int>(std::floor((1.0 - params.min) / params.step + 1e-9)) : 0;
  const int above = ladder ? static_cast<int>(std::floor((params.max - 1.0) / params.step + 1e-9)) : 0;
  for (int k = -below; k <= above; ++k) factors_.push_back(1.0 + k * params.step);
  reset();
}

void ShapeLadder::reset() {
  sums_.assign(factors_.size(), 0.0);
  frames_ = 0;
  factor_ = 1.0;
}

void ShapeLadder::endFrame() {
  ++frames_;
  size_t best = 0;
  for (size_t k = 1; k < factors_.size(); ++k)
    if (sums_[k] > sums_[best] ||
        (sums_[k] == sums_[best] && std::abs(factors_[k] - 1.0) < std::abs(factors_[best] - 1.0)))
      best = k;
  factor_ = factors_[best];
}

}  // namespace body_tracking
