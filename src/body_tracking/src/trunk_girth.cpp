#include "body_tracking/trunk_girth.h"

#include "body_tracking/body_parts.h"

namespace body_tracking {

TrunkGirth::TrunkGirth(const TrunkGirthParams& params)
    : params_((params.validate(), params)), ladder_(params_) {}

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
  for (size_t k = 0; k < ladder_.factors().size(); ++k) {
    const BodyProfile p = scaled(base, ladder_.factors()[k]);
    for (Part part : {Part::ABDOMEN, Part::CHEST})
      ladder_.add(k, obs.partScore(buildPart(p, f, part), false, true));
  }
  ladder_.endFrame();
}

}  // namespace body_tracking
