#include "body_tracking/papf_config.h"

#include <cmath>
#include <stdexcept>

namespace body_tracking {

void addPapfKeys(PapfConfig* c, tabletop_common::ConfigSchema* s) {
  PapfParams& p = c->params;
  s->add("particles", &p.particles)
      .add("layers", &p.layers)
      .add("survival_rate", &p.survival_rate)
      .add("weight_scale", &p.weight_scale)
      .add("diffusion", &p.diffusion)
      .add("reseed_arms", &p.reseed_arms)
      .add("velocity_damping", &p.velocity_damping)
      .add("noise_translation", &p.noise_translation)
      .add("noise_torso_rotation", &p.noise_torso_rotation)
      .add("noise_spine", &p.noise_spine)
      .add("noise_head", &p.noise_head)
      .add("noise_shoulder_shift", &p.noise_shoulder_shift)
      .add("noise_upper_arm", &p.noise_upper_arm)
      .add("noise_forearm", &p.noise_forearm)
      .add("proposal_fraction", &p.proposal_fraction)
      .add("proposal_head_clearance", &p.proposal_head_clearance)
      .add("observation/downsample", &p.observation.downsample)
      .add("observation/skin_weight", &p.observation.skin_weight)
      .add("observation/unknown_likelihood", &p.observation.unknown_likelihood)
      .add("observation/trunk_shell_width", &p.observation.trunk_shell_width)
      .add("observation/trunk_shell_weight", &p.observation.trunk_shell_weight)
      .add("shape/frames", &p.shape.frames)
      .add("shape/girth_min", &p.shape.min)
      .add("shape/girth_max", &p.shape.max)
      .add("shape/girth_step", &p.shape.step)
      .add("shape/arm_frames", &p.arm_length.frames)
      .add("shape/arm_min", &p.arm_length.min)
      .add("shape/arm_max", &p.arm_length.max)
      .add("shape/arm_step", &p.arm_length.step)
      .add("hands/enabled", &p.hands.enabled)
      .add("hands/radius", &p.hands.radius)
      .add("hands/wrist_offset", &p.hands.wrist_offset)
      .add("hands/min_probability", &p.hands.min_probability)
      .add("hands/min_volume", &p.hands.min_volume)
      .add("hands/iterations", &p.hands.iterations)
      .add("min_person_voxels", &p.min_person_voxels)
      .add("init_runs", &p.init_runs)
      .add("lost_score", &p.lost_score)
      .add("lost_frames", &p.lost_frames)
      .add("seed", &p.seed)
      .add("threads", &p.threads)
      .add("gpu_weights", &p.gpu_weights);
  s->add("world_frame", &c->nodelet.world_frame)
      .add("tf_prefix", &c->nodelet.tf_prefix)
      .add("body_profile_file", &c->nodelet.body_profile_file)
      .add("publish_masks", &c->nodelet.publish_masks)
      .add("mask_margin_px", &c->nodelet.mask_margin_px)
      .add("use_skin_volume", &c->nodelet.use_skin_volume)
      .add("publish_volume", &c->nodelet.publish_volume)
      .add("volume_prior/offset", &c->nodelet.volume_prior.offset)
      .add("volume_prior/falloff", &c->nodelet.volume_prior.falloff)
      .add("volume_prior/neck_radius", &c->nodelet.volume_prior.neck_radius)
      .add("volume_prior/hand_reach", &c->nodelet.volume_prior.hand_reach)
      .add("queue_size", &c->nodelet.queue_size);
}

void finishPapfConfig(const std::string& where, PapfConfig* c) {
  try {
    c->params.validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(where + e.what());
  }
  if (c->nodelet.world_frame.empty()) throw std::runtime_error(where + "world_frame: must not be empty");
  if (c->nodelet.queue_size < 1) throw std::runtime_error(where + "queue_size: must be >= 1");
  if (!(std::abs(c->nodelet.volume_prior.offset) <= 0.1))
    throw std::runtime_error(where + "volume_prior/offset: must be in [-0.1, 0.1] m");
  if (!(c->nodelet.volume_prior.falloff > 0 && c->nodelet.volume_prior.falloff <= 0.1))
    throw std::runtime_error(where + "volume_prior/falloff: must be in (0, 0.1] m");
  if (!(c->nodelet.volume_prior.neck_radius >= 0 && c->nodelet.volume_prior.neck_radius <= 0.15))
    throw std::runtime_error(where + "volume_prior/neck_radius: must be in [0, 0.15] m");
  if (!(c->nodelet.volume_prior.hand_reach >= 0 && c->nodelet.volume_prior.hand_reach <= 0.15))
    throw std::runtime_error(where + "volume_prior/hand_reach: must be in [0, 0.15] m");
  if (!(c->nodelet.mask_margin_px >= 0 && c->nodelet.mask_margin_px <= 50))
    throw std::runtime_error(where + "mask_margin_px: must be in [0, 50]");
}

PapfConfig loadPapfConfig(const std::string& path) {
  PapfConfig c;
  tabletop_common::ConfigSchema schema;
  addPapfKeys(&c, &schema);
  schema.loadFile(path);
  finishPapfConfig(path + ": ", &c);
  return c;
}

}  // namespace body_tracking
