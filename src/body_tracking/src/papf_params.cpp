#include "body_tracking/papf_params.h"

#include <cmath>
#include <stdexcept>
#include <string>


namespace body_tracking {

namespace {

[[noreturn]] void bad(const std::string& name, const std::string& rule) {
  throw std::invalid_argument("papf: " + name + " " + rule);
}

void positive(double v, const char* name) {
  if (!(std::isfinite(v) && v > 0)) bad(name, "must be a finite value > 0");
}

}  // namespace

void PapfParams::validate() const {
  if (particles < 2 || particles > 100000) bad("particles", "must be in 2..100000");
  if (layers < 1 || layers > 8) bad("layers", "must be in 1..8");
  if (!(survival_rate > 0 && survival_rate < 1)) bad("survival_rate", "must be in (0, 1)");
  positive(weight_scale, "weight_scale");
  if (!(diffusion >= 0 && diffusion <= 1)) bad("diffusion", "must be in [0, 1]");
  if (!(velocity_damping >= 0 && velocity_damping <= 1)) bad("velocity_damping", "must be in [0, 1]");
  positive(noise_translation, "noise_translation");
  positive(noise_torso_rotation, "noise_torso_rotation");
  positive(noise_spine, "noise_spine");
  positive(noise_head, "noise_head");
  positive(noise_shoulder_shift, "noise_shoulder_shift");
  positive(noise_upper_arm, "noise_upper_arm");
  positive(noise_forearm, "noise_forearm");
  if (!(proposal_fraction >= 0 && proposal_fraction <= 1)) bad("proposal_fraction", "must be in [0, 1]");
  if (!(proposal_head_clearance >= 0)) bad("proposal_head_clearance", "must be >= 0");
  shape.validate();
  arm_length.validate();
  if (min_person_voxels < 1) bad("min_person_voxels", "must be >= 1");
  if (init_runs < 1 || init_runs > 100) bad("init_runs", "must be in 1..100");
  if (!(lost_score >= 0 && lost_score <= 1)) bad("lost_score", "must be in [0, 1]");
  if (lost_frames < 1) bad("lost_frames", "must be >= 1");
  if (threads < 1 || threads > 256) bad("threads", "must be in 1..256");
  VolumeObservation check(observation);  // throws for bad observation parameters
  (void)check;
}

}  // namespace body_tracking
