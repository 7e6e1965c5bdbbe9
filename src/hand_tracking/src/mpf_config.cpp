#include "hand_tracking/mpf_config.h"

#include <stdexcept>

namespace hand_tracking {

void addMpfKeys(MpfConfig* c, tabletop_common::ConfigSchema* s) {
  MpfParams& p = c->params;
  s->add("hand_particles", &p.hand_particles)
      .add("head_particles", &p.head_particles)
      .add("head_box", &p.head_box)
      .add("hand_box", &p.hand_box)
      .add("head_crown_thickness", &p.head_crown_thickness)
      .add("head_crown_gap", &p.head_crown_gap)
      .add("frontal_direction", &p.frontal_direction)
      .add("frontal_plane_thickness", &p.frontal_plane_thickness)
      .add("frontal_plane_gap", &p.frontal_plane_gap)
      .add("likelihood_exponent", &p.likelihood_exponent)
      .add("smooth_boxes", &p.smooth_boxes)
      .add("reference_dt", &p.reference_dt)
      .add("head_noise", &p.head_noise)
      .add("hand_noise_ar1", &p.hand_noise_ar1)
      .add("hand_noise_ar2", &p.hand_noise_ar2)
      .add("hand_noise_ar3", &p.hand_noise_ar3)
      .add("max_speed", &p.max_speed)
      .add("head_init_weight", &p.head_init_weight)
      .add("head_birth_depth", &p.head_birth_depth)
      .add("head_birth_top_area", &p.head_birth_top_area)
      .add("hand_init_weight", &p.hand_init_weight)
      .add("birth_min_distance", &p.birth_min_distance)
      .add("birth_spread", &p.birth_spread)
      .add("birth_limb_fraction", &p.birth_limb_fraction)
      .add("search_skin_threshold", &p.search_skin_threshold)
      .add("search_skin_fraction", &p.search_skin_fraction)
      .add("kmeans_max_iterations", &p.kmeans_max_iterations)
      .add("head_track_weight", &p.head_track_weight)
      .add("hand_track_weight", &p.hand_track_weight)
      .add("merge_distance", &p.merge_distance)
      .add("split_distance", &p.split_distance)
      .add("min_mixture_weight", &p.min_mixture_weight)
      .add("identity_memory", &p.identity_memory)
      .add("head_hand_distance", &p.head_hand_distance)
      .add("workspace_min", &p.workspace_min)
      .add("workspace_size", &p.workspace_size)
      .add("refine_hand_centroid", &p.refine_hand_centroid)
      .add("hand_centroid_box", &p.hand_centroid_box)
      .add("hand_centroid_threshold", &p.hand_centroid_threshold)
      .add("hand_distal_length", &p.hand_distal_length)
      .add("hand_arm_box", &p.hand_arm_box)
      .add("hand_end_by_body", &p.hand_end_by_body)
      .add("hand_arm_walk", &p.hand_arm_walk)
      .add("refine_head_centroid", &p.refine_head_centroid)
      .add("head_centroid_box", &p.head_centroid_box)
      .add("head_centroid_threshold", &p.head_centroid_threshold)
      .add("centroid_iterations", &p.centroid_iterations)
      .add("head_model", &p.head_model)
      .add("head_fit/radius", &p.head_fit.radius)
      .add("head_fit/max_above", &p.head_fit.max_above)
      .add("head_fit/fit_depth", &p.head_fit.fit_depth)
      .add("head_fit/threshold", &p.head_fit.threshold)
      .add("head_fit/min_top_area", &p.head_fit.min_top_area)
      .add("head_fit/iterations", &p.head_fit.iterations)
      .add("head_fit/top_above_centre", &p.head_fit.top_above_centre)
      .add("head_fit/vertex_weight", &p.head_fit.vertex_weight)
      .add("head_fit/face_weight", &p.head_fit.face_weight)
      .add("threads", &p.threads);
  s->add("seed", &c->nodelet.seed)
      .add("publish_particles", &c->nodelet.publish_particles)
      .add("world_frame", &c->nodelet.world_frame)
      .add("tf_prefix", &c->nodelet.tf_prefix);
}

void finishMpfConfig(const std::string& where, MpfConfig* c) {
  try {
    c->params.validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(where + e.what());
  }
  if (c->nodelet.seed < 0) throw std::runtime_error(where + "seed: must be >= 0");
  if (c->nodelet.world_frame.empty()) throw std::runtime_error(where + "world_frame: must not be empty");
}

MpfConfig loadMpfConfig(const std::string& path) {
  MpfConfig c;
  tabletop_common::ConfigSchema schema;
  addMpfKeys(&c, &schema);
  schema.loadFile(path);
  finishMpfConfig(path + ": ", &c);
  return c;
}

}  // namespace hand_tracking
