// Parameters of the body volume's model prior (model_prior.h), on their own so that the
// tracker's configuration (papf_config.h) needs no volume or body-part types.
#pragma once

namespace body_tracking {

struct ModelPriorParams {
  // m from the model's surface (negative: inside it) where the prior starts to fall. The model
  // is fitted to the hull, which holds a voxel's worth of halo, so its parts run a little wide.
  double offset = -0.005;
  // m per unit of log-odds beyond the offset (> 0). Byte 255 (taken as p = 254.5/255, logit
  // 6.2) is zeroed (below 0.5/255) 2 ln(509) = 12.5 falloffs beyond the offset.
  double falloff = 0.005;
  // The model has no neck and its hands end short of the finger tips (no finger or wrist
  // DOF): both are skin the hull sees well, and the prior would cut them (10-50 % of the neck's
  // and 30-50 % of the hands' voxels on generated scenarios). The prior measures its distances
  // to these as well (priorSolids in model_prior.h); 0 turns either off.
  // Radius (m) of a neck cylinder from the shoulders' height up into the head along the head's
  // axis; a neck is 4.5-6 cm in radius (the simulator's 5 cm x girth 0.86-1.24).
  double neck_radius = 0.055;
  // m by which each hand's ellipsoid reaches further along the forearm's axis, with a round
  // cross-section of its half width (the hand's roll about the forearm is not tracked): open
  // fingers end 18-20 cm past the wrist, the model's hand 12 cm.
  double hand_reach = 0.06;
};

}  // namespace body_tracking
