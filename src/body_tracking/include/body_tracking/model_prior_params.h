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
};

}  // namespace body_tracking
