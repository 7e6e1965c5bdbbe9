// config/mpf.yaml through the strict loader: the shipped file holds the code's defaults, and a
// bad file names itself and the key.
#include <string>

#include <gtest/gtest.h>

#include "hand_tracking/mpf_config.h"
#include "hand_tracking/mpf_tracker.h"
#include "tabletop_common/config_test_support.h"

namespace hand_tracking {
namespace {

std::string errorOf(const std::string& text) {
  return tabletop_common::config_test::errorOf([](const std::string& p) { loadMpfConfig(p); }, text);
}

TEST(MpfConfig, ShippedFileHoldsTheDefaults) {
  const MpfConfig c = loadMpfConfig(std::string(HAND_TRACKING_CONFIG_DIR) + "/mpf.yaml");
  const MpfParams d;
  const MpfNodeletOptions n;
  // Every key of the schema is in the file (a key left out would hide a default that differs).
  tabletop_common::ConfigSchema schema;
  MpfConfig scratch;
  addMpfKeys(&scratch, &schema);
  EXPECT_TRUE(tabletop_common::config_test::keysMissingFrom(schema, std::string(HAND_TRACKING_CONFIG_DIR) + "/mpf.yaml")
                  .empty());
  EXPECT_EQ(c.params.hand_particles, d.hand_particles);
  EXPECT_EQ(c.params.head_particles, d.head_particles);
  EXPECT_EQ(c.params.head_box, d.head_box);
  EXPECT_EQ(c.params.head_crown_thickness, d.head_crown_thickness);
  EXPECT_EQ(c.params.head_crown_gap, d.head_crown_gap);
  EXPECT_EQ(c.params.head_birth_depth, d.head_birth_depth);
  EXPECT_EQ(c.params.head_birth_top_area, d.head_birth_top_area);
  EXPECT_EQ(c.params.hand_box, d.hand_box);
  EXPECT_EQ(c.params.frontal_direction, d.frontal_direction);
  EXPECT_EQ(c.params.frontal_plane_thickness, d.frontal_plane_thickness);
  EXPECT_EQ(c.params.frontal_plane_gap, d.frontal_plane_gap);
  EXPECT_EQ(c.params.likelihood_exponent, d.likelihood_exponent);
  EXPECT_EQ(c.params.smooth_boxes, d.smooth_boxes);
  EXPECT_EQ(c.params.reference_dt, d.reference_dt);
  EXPECT_EQ(c.params.head_noise, d.head_noise);
  EXPECT_EQ(c.params.hand_noise_ar1, d.hand_noise_ar1);
  EXPECT_EQ(c.params.hand_noise_ar2, d.hand_noise_ar2);
  EXPECT_EQ(c.params.hand_noise_ar3, d.hand_noise_ar3);
  EXPECT_EQ(c.params.max_speed, d.max_speed);
  EXPECT_EQ(c.params.head_init_weight, d.head_init_weight);
  EXPECT_EQ(c.params.hand_init_weight, d.hand_init_weight);
  EXPECT_EQ(c.params.birth_min_distance, d.birth_min_distance);
  EXPECT_EQ(c.params.birth_spread, d.birth_spread);
  EXPECT_EQ(c.params.search_skin_threshold, d.search_skin_threshold);
  EXPECT_EQ(c.params.search_skin_fraction, d.search_skin_fraction);
  EXPECT_EQ(c.params.kmeans_max_iterations, d.kmeans_max_iterations);
  EXPECT_EQ(c.params.head_track_weight, d.head_track_weight);
  EXPECT_EQ(c.params.hand_track_weight, d.hand_track_weight);
  EXPECT_EQ(c.params.merge_distance, d.merge_distance);
  EXPECT_EQ(c.params.split_distance, d.split_distance);
  EXPECT_EQ(c.params.min_mixture_weight, d.min_mixture_weight);
  EXPECT_EQ(c.params.identity_memory, d.identity_memory);
  EXPECT_EQ(c.params.head_hand_distance, d.head_hand_distance);
  EXPECT_EQ(c.params.workspace_min, d.workspace_min);
  EXPECT_EQ(c.params.workspace_size, d.workspace_size);
  EXPECT_EQ(c.params.refine_hand_centroid, d.refine_hand_centroid);
  EXPECT_EQ(c.params.hand_centroid_box, d.hand_centroid_box);
  EXPECT_EQ(c.params.hand_centroid_threshold, d.hand_centroid_threshold);
  EXPECT_EQ(c.params.hand_distal_length, d.hand_distal_length);
  EXPECT_EQ(c.params.hand_arm_box, d.hand_arm_box);
  EXPECT_EQ(c.params.hand_end_by_body, d.hand_end_by_body);
  EXPECT_EQ(c.params.hand_arm_walk, d.hand_arm_walk);
  EXPECT_EQ(c.params.refine_head_centroid, d.refine_head_centroid);
  EXPECT_EQ(c.params.head_centroid_box, d.head_centroid_box);
  EXPECT_EQ(c.params.head_centroid_threshold, d.head_centroid_threshold);
  EXPECT_EQ(c.params.centroid_iterations, d.centroid_iterations);
  EXPECT_EQ(c.params.head_model, d.head_model);
  EXPECT_EQ(c.params.head_fit.radius, d.head_fit.radius);
  EXPECT_EQ(c.params.head_fit.max_above, d.head_fit.max_above);
  EXPECT_EQ(c.params.head_fit.fit_depth, d.head_fit.fit_depth);
  EXPECT_EQ(c.params.head_fit.threshold, d.head_fit.threshold);
  EXPECT_EQ(c.params.head_fit.min_top_area, d.head_fit.min_top_area);
  EXPECT_EQ(c.params.head_fit.iterations, d.head_fit.iterations);
  EXPECT_EQ(c.params.head_fit.top_above_centre, d.head_fit.top_above_centre);
  EXPECT_EQ(c.params.head_fit.vertex_weight, d.head_fit.vertex_weight);
  EXPECT_EQ(c.params.head_fit.face_weight, d.head_fit.face_weight);
  EXPECT_EQ(c.params.threads, d.threads);
  EXPECT_EQ(c.nodelet.seed, n.seed);
  EXPECT_EQ(c.nodelet.publish_particles, n.publish_particles);
  EXPECT_EQ(c.nodelet.world_frame, n.world_frame);
  EXPECT_EQ(c.nodelet.tf_prefix, n.tf_prefix);
}

TEST(MpfConfig, BadFilesNameTheFileAndTheKey) {
  // The typo that used to fall back to the default silently.
  EXPECT_NE(errorOf("hand_particels: 800\n").find("hand_particels: unknown key"), std::string::npos);
  EXPECT_NE(errorOf("hand_particles: many\n").find("hand_particles: wrong type"), std::string::npos);
  EXPECT_NE(errorOf("hand_box: [0.1, 0.1]\n").find("hand_box: expected a list of 3 numbers"),
            std::string::npos);
  EXPECT_NE(errorOf("hand_particles: 0\n").find("hand_particles"), std::string::npos);  // validate()
  EXPECT_NE(errorOf("seed: -3\n").find("seed: must be >= 0"), std::string::npos);
  EXPECT_NE(errorOf("[1, 2").find("cannot read"), std::string::npos);
  MpfConfig c;
  EXPECT_EQ(tabletop_common::config_test::errorOf([&](const std::string& p) { c = loadMpfConfig(p); },
                                                  "hand_particles: 800\nhead_box: [0.2, 0.2, 0.25]\n"),
            "");
  EXPECT_EQ(c.params.hand_particles, 800);
  EXPECT_EQ(c.params.head_box, Eigen::Vector3d(0.2, 0.2, 0.25));
  EXPECT_EQ(c.params.head_particles, MpfParams().head_particles);  // missing = default
}

// Live tuning changes the noise only, and refuses what validate() refuses.
TEST(MpfConfig, ProcessNoiseIsTunedLiveAndCheckedFirst) {
  MpfTracker t(MpfParams(), 1);
  t.setProcessNoise(0.01, 0.03, 0.01, 0.004);
  EXPECT_EQ(t.params().head_noise, 0.01);
  EXPECT_EQ(t.params().hand_noise_ar1, 0.03);
  EXPECT_EQ(t.params().hand_noise_ar2, 0.01);
  EXPECT_EQ(t.params().hand_noise_ar3, 0.004);
  EXPECT_THROW(t.setProcessNoise(-0.01, 0.03, 0.01, 0.004), std::invalid_argument);
  EXPECT_EQ(t.params().head_noise, 0.01);  // nothing changed
  EXPECT_EQ(t.params().hand_particles, MpfParams().hand_particles);
}

}  // namespace
}  // namespace hand_tracking
