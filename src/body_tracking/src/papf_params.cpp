#include "body_tracking/papf_params.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <yaml-cpp/yaml.h>

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
  if (min_person_voxels < 1) bad("min_person_voxels", "must be >= 1");
  if (init_runs < 1 || init_runs > 100) bad("init_runs", "must be in 1..100");
  if (!(lost_score >= 0 && lost_score <= 1)) bad("lost_score", "must be in [0, 1]");
  if (lost_frames < 1) bad("lost_frames", "must be >= 1");
  if (threads < 1 || threads > 256) bad("threads", "must be in 1..256");
  VolumeObservation check(observation);  // throws for bad observation parameters
  (void)check;
}

void PapfParams::merge(const YAML::Node& node) {
  if (!node) return;
  if (!node.IsMap()) throw std::invalid_argument("papf: expected a map of parameters");
  for (const auto& kv : node) {
    const std::string k = kv.first.as<std::string>();
    const YAML::Node& v = kv.second;
    if (k == "particles") particles = v.as<int>();
    else if (k == "layers") layers = v.as<int>();
    else if (k == "survival_rate") survival_rate = v.as<double>();
    else if (k == "weight_scale") weight_scale = v.as<double>();
    else if (k == "diffusion") diffusion = v.as<double>();
    else if (k == "velocity_damping") velocity_damping = v.as<double>();
    else if (k == "noise_translation") noise_translation = v.as<double>();
    else if (k == "noise_torso_rotation") noise_torso_rotation = v.as<double>();
    else if (k == "noise_spine") noise_spine = v.as<double>();
    else if (k == "noise_head") noise_head = v.as<double>();
    else if (k == "noise_shoulder_shift") noise_shoulder_shift = v.as<double>();
    else if (k == "noise_upper_arm") noise_upper_arm = v.as<double>();
    else if (k == "noise_forearm") noise_forearm = v.as<double>();
    else if (k == "proposal_fraction") proposal_fraction = v.as<double>();
    else if (k == "proposal_head_clearance") proposal_head_clearance = v.as<double>();
    else if (k == "hand_radius") hands.radius = v.as<double>();
    else if (k == "hand_refinement") hands.enabled = v.as<bool>();
    else if (k == "downsample") observation.downsample = v.as<int>();
    else if (k == "skin_weight") observation.skin_weight = v.as<double>();
    else if (k == "unknown_likelihood") observation.unknown_likelihood = v.as<double>();
    else if (k == "min_person_voxels") min_person_voxels = v.as<int>();
    else if (k == "init_runs") init_runs = v.as<int>();
    else if (k == "lost_score") lost_score = v.as<double>();
    else if (k == "lost_frames") lost_frames = v.as<int>();
    else if (k == "seed") seed = v.as<uint64_t>();
    else if (k == "threads") threads = v.as<int>();
    else throw std::invalid_argument("papf: unknown parameter '" + k + "'");
  }
  validate();
}

PapfParams PapfParams::fromYamlFile(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("papf: cannot read " + path + ": " + e.what());
  }
  PapfParams p;
  p.merge(root["papf"] ? root["papf"] : root);
  return p;
}

}  // namespace body_tracking
