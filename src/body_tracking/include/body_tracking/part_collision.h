// Self-collision of the body model, which the PAPF rejects (thesis 5.2): a pose whose arm runs
// through the trunk, or whose forearms pass through each other, scores well on dense volumes
// (every part sits in occupied voxels) but is not a body. Tested on bone points against the
// trunk and head quadrics and on the forearm axes against each other; touching (hands resting on the
// belly, folded hands) is allowed.
#pragma once

#include "body_tracking/body_parts.h"

namespace body_tracking {

bool bodyCollides(const BodyProfile& profile, const BodyFrames& frames, const BodyParts& parts);

}  // namespace body_tracking
