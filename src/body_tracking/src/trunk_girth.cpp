#include "body_tracking/trunk_girth.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "body_tracking/body_parts.h"

namespace body_tracking {

void TrunkGirthParams::validate() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("papf: shape/" + what); };
  if (frames < 0) fail("frames must be >= 0");
  if (!(min > 0.3 && min <= 1.0)) fail("girth_min must be in (0.3, 1]");
  if (!(max >= 1.0 && max < 3.0)) fail("girth_max must be in [1, 3)");
  if (!(step > 0.005 && step <= max - min + 1e-9) && max > min) fail("girth_step must be in (0.005, girth_max - girth_min]");
}

TrunkGirth::TrunkGirth(const TrunkGirthParams& params) : params_(params) {
  params_.validate();
  // The ladder, with 1 on it exactly (the profile as given), so that ties keep the profile.
  const int below = static_cast<int>(std::floor((1.0 - params_.min) / params_.step + 1e-9));
  const int above = static_cast<int>(std::floor((params_.max - 1.0) / params_.step + 1e-9));
  for (int k = -below; k <= above; ++k) factors_.push_back(1.0 + k * params_.step);
  reset();
}

void TrunkGirth::reset() {
  sums_.assign(factors_.size(), 0.0);
  frames_ = 0;
  factor_ = 1.0;
}

BodyProfile TrunkGirth::scaled(const BodyProfile& base, double factor) {
  BodyProfile p = base;
  p.abdomen_half_width *= factor;
  p.abdomen_half_depth *= factor;
  p.chest_half_width *= factor;
  p.chest_half_depth *= factor;
  return p;
}

void TrunkGirth::add(const VolumeObservation& obs, const BodyProfile& base, const BodyState& state) {
  if (!refining()) return;
  const BodyFrames f = forwardKinematics(base, state);  // the trunk's radii do not move a joint
  for (size_t k = 0; k < factors_.size(); ++k) {
    const BodyProfile p = scaled(base, factors_[k]);
    for (Part part : {Part::ABDOMEN, Part::CHEST})
      sums_[k] += obs.partScore(buildPart(p, f, part), false, true);
  }
  ++frames_;
  // The best sum; on a tie the factor nearer 1 (the profile as given).
  size_t best = 0;
  for (size_t k = 1; k < factors_.size(); ++k)
    if (sums_[k] > sums_[best] ||
        (sums_[k] == sums_[best] && std::abs(factors_[k] - 1.0) < std::abs(factors_[best] - 1.0)))
      best = k;
  factor_ = factors_[best];
}

}  // namespace body_tracking
