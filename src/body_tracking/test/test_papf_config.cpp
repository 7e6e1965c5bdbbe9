// config/papf.yaml and config/body_profile.yaml through their loaders: the shipped files hold
// the code's defaults (every key present), and a bad file names itself and the key.
#include <string>

#include <gtest/gtest.h>

#include "body_tracking/papf_config.h"
#include "tabletop_common/config_test_support.h"

namespace body_tracking {
namespace {

const std::string kDir = BODY_TRACKING_CONFIG_DIR;

std::string errorOf(const std::string& text) {
  return tabletop_common::config_test::errorOf([](const std::string& p) { loadPapfConfig(p); }, text);
}

TEST(PapfConfig, ShippedFileHoldsTheDefaults) {
  const PapfConfig c = loadPapfConfig(kDir + "/papf.yaml");
  tabletop_common::ConfigSchema schema;
  PapfConfig scratch;
  addPapfKeys(&scratch, &schema);
  EXPECT_TRUE(tabletop_common::config_test::keysMissingFrom(schema, kDir + "/papf.yaml").empty());
  const PapfParams d;
  const PapfNodeletOptions n;
  EXPECT_EQ(c.params.particles, d.particles);
  EXPECT_EQ(c.params.layers, d.layers);
  EXPECT_EQ(c.params.survival_rate, d.survival_rate);
  EXPECT_EQ(c.params.weight_scale, d.weight_scale);
  EXPECT_EQ(c.params.diffusion, d.diffusion);
  EXPECT_EQ(c.params.velocity_damping, d.velocity_damping);
  EXPECT_EQ(c.params.noise_translation, d.noise_translation);
  EXPECT_EQ(c.params.noise_torso_rotation, d.noise_torso_rotation);
  EXPECT_EQ(c.params.noise_spine, d.noise_spine);
  EXPECT_EQ(c.params.noise_head, d.noise_head);
  EXPECT_EQ(c.params.noise_shoulder_shift, d.noise_shoulder_shift);
  EXPECT_EQ(c.params.noise_upper_arm, d.noise_upper_arm);
  EXPECT_EQ(c.params.noise_forearm, d.noise_forearm);
  EXPECT_EQ(c.params.proposal_fraction, d.proposal_fraction);
  EXPECT_EQ(c.params.proposal_head_clearance, d.proposal_head_clearance);
  EXPECT_EQ(c.params.observation.downsample, d.observation.downsample);
  EXPECT_EQ(c.params.observation.skin_weight, d.observation.skin_weight);
  EXPECT_EQ(c.params.observation.unknown_likelihood, d.observation.unknown_likelihood);
  EXPECT_EQ(c.params.hands.enabled, d.hands.enabled);
  EXPECT_EQ(c.params.hands.radius, d.hands.radius);
  EXPECT_EQ(c.params.hands.wrist_offset, d.hands.wrist_offset);
  EXPECT_EQ(c.params.hands.min_probability, d.hands.min_probability);
  EXPECT_EQ(c.params.hands.min_volume, d.hands.min_volume);
  EXPECT_EQ(c.params.hands.iterations, d.hands.iterations);
  EXPECT_EQ(c.params.min_person_voxels, d.min_person_voxels);
  EXPECT_EQ(c.params.init_runs, d.init_runs);
  EXPECT_EQ(c.params.lost_score, d.lost_score);
  EXPECT_EQ(c.params.lost_frames, d.lost_frames);
  EXPECT_EQ(c.params.seed, d.seed);
  EXPECT_EQ(c.params.threads, d.threads);
  EXPECT_EQ(c.params.gpu_weights, d.gpu_weights);
  EXPECT_EQ(c.nodelet.world_frame, n.world_frame);
  EXPECT_EQ(c.nodelet.tf_prefix, n.tf_prefix);
  EXPECT_EQ(c.nodelet.body_profile_file, n.body_profile_file);
  EXPECT_EQ(c.nodelet.publish_masks, n.publish_masks);
  EXPECT_EQ(c.nodelet.mask_margin_px, n.mask_margin_px);
  EXPECT_EQ(c.nodelet.use_skin_volume, n.use_skin_volume);
  EXPECT_EQ(c.nodelet.queue_size, n.queue_size);
}

TEST(PapfConfig, BadFilesNameTheKey) {
  EXPECT_NE(errorOf("particle: 256\n").find("particle"), std::string::npos);
  EXPECT_NE(errorOf("layers: many\n").find("layers"), std::string::npos);
  EXPECT_NE(errorOf("survival_rate: 1.5\n").find("survival_rate"), std::string::npos);
  EXPECT_NE(errorOf("observation:\n  downsample: 0\n").find("downsample"), std::string::npos);
  EXPECT_NE(errorOf("mask_margin_px: -1\n").find("mask_margin_px"), std::string::npos);
  EXPECT_EQ(errorOf("particles: 128\n"), "");
}

TEST(BodyProfileFile, ShippedFileHoldsTheDefaults) {
  const BodyProfile p = BodyProfile::fromYamlFile(kDir + "/body_profile.yaml");
  const BodyProfile d;
  EXPECT_EQ(p.spine_height, d.spine_height);
  EXPECT_EQ(p.shoulder_half_width, d.shoulder_half_width);
  EXPECT_EQ(p.shoulder_height, d.shoulder_height);
  EXPECT_EQ(p.neck_height, d.neck_height);
  EXPECT_EQ(p.upper_arm, d.upper_arm);
  EXPECT_EQ(p.forearm, d.forearm);
  EXPECT_EQ(p.wrist_to_hand, d.wrist_to_hand);
  EXPECT_EQ(p.abdomen_half_width, d.abdomen_half_width);
  EXPECT_EQ(p.abdomen_half_depth, d.abdomen_half_depth);
  EXPECT_EQ(p.chest_half_width, d.chest_half_width);
  EXPECT_EQ(p.chest_half_depth, d.chest_half_depth);
  EXPECT_EQ(p.head_centre_height, d.head_centre_height);
  EXPECT_EQ(p.head_centre_forward, d.head_centre_forward);
  EXPECT_EQ(p.head_half_width, d.head_half_width);
  EXPECT_EQ(p.head_half_depth, d.head_half_depth);
  EXPECT_EQ(p.head_half_height, d.head_half_height);
  EXPECT_EQ(p.upper_arm_radius, d.upper_arm_radius);
  EXPECT_EQ(p.forearm_radius, d.forearm_radius);
  EXPECT_EQ(p.hand_half_length, d.hand_half_length);
  EXPECT_EQ(p.hand_half_width, d.hand_half_width);
  EXPECT_EQ(p.hand_half_thickness, d.hand_half_thickness);
}

}  // namespace
}  // namespace body_tracking
