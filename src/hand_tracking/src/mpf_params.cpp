#include "hand_tracking/mpf_params.h"

#include <cmath>
#include <stdexcept>

namespace hand_tracking {

namespace {

void fail(const std::string& field, const std::string& what) {
  throw std::invalid_argument("hand_tracking::MpfParams: field '" + field + "' " + what);
}
void positive(double v, const char* field) {
  if (!std::isfinite(v) || !(v > 0.0)) fail(field, "must be finite and > 0");
}
void nonNegative(double v, const char* field) {
  if (!std::isfinite(v) || !(v >= 0.0)) fail(field, "must be finite and >= 0");
}
void unit(double v, const char* field) {
  if (!std::isfinite(v) || v < 0.0 || v > 1.0) fail(field, "must lie in [0, 1]");
}
void positiveBox(const Eigen::Vector3d& v, const char* field) {
  if (!v.allFinite() || !(v.array() > 0.0).all()) fail(field, "must be finite and > 0 per axis");
}

}  // namespace

void MpfParams::validate() const {
  if (hand_particles < 3) fail("hand_particles", "must be >= 3 (one per AR model)");
  if (head_particles < 1) fail("head_particles", "must be >= 1");
  if (static_cast<long long>(hand_particles) * 2 + head_particles > 10000000LL)
    fail("hand_particles", "gives more than 10^7 particles in all");
  positiveBox(head_box, "head_box");
  positiveBox(hand_box, "hand_box");
  {
    const Eigen::Vector3d a = frontal_direction.cwiseAbs();
    int axis = 0;
    if (!frontal_direction.allFinite() || std::abs(a.maxCoeff(&axis) - 1.0) > 1e-9 ||
        a.sum() - a[axis] > 1e-9)
      fail("frontal_direction", "must be a unit vector along +-x, +-y or +-z");
  }
  nonNegative(frontal_plane_thickness, "frontal_plane_thickness");
  nonNegative(frontal_plane_gap, "frontal_plane_gap");
  nonNegative(head_crown_thickness, "head_crown_thickness");
  nonNegative(head_crown_gap, "head_crown_gap");
  nonNegative(head_birth_depth, "head_birth_depth");
  positive(head_birth_top_area, "head_birth_top_area");
  positive(likelihood_exponent, "likelihood_exponent");
  positive(reference_dt, "reference_dt");
  nonNegative(head_noise, "head_noise");
  nonNegative(hand_noise_ar1, "hand_noise_ar1");
  nonNegative(hand_noise_ar2, "hand_noise_ar2");
  nonNegative(hand_noise_ar3, "hand_noise_ar3");
  positive(max_speed, "max_speed");
  unit(head_init_weight, "head_init_weight");
  unit(hand_init_weight, "hand_init_weight");
  unit(head_track_weight, "head_track_weight");
  unit(hand_track_weight, "hand_track_weight");
  if (head_track_weight > head_init_weight)
    fail("head_track_weight", "must not exceed head_init_weight (hysteresis)");
  if (hand_track_weight > hand_init_weight)
    fail("hand_track_weight", "must not exceed hand_init_weight (hysteresis)");
  nonNegative(birth_min_distance, "birth_min_distance");
  nonNegative(birth_spread, "birth_spread");
  unit(birth_limb_fraction, "birth_limb_fraction");
  unit(search_skin_threshold, "search_skin_threshold");
  unit(search_skin_fraction, "search_skin_fraction");
  if (kmeans_max_iterations < 1) fail("kmeans_max_iterations", "must be >= 1");
  nonNegative(merge_distance, "merge_distance");
  nonNegative(split_distance, "split_distance");
  nonNegative(head_hand_distance, "head_hand_distance");
  if (split_distance < merge_distance)
    fail("split_distance", "must be >= merge_distance (hysteresis)");
  if (!std::isfinite(min_mixture_weight) || min_mixture_weight < 0.0 ||
      min_mixture_weight * 3.0 > 1.0)
    fail("min_mixture_weight", "must lie in [0, 1/3]");
  nonNegative(identity_memory, "identity_memory");
  if (!workspace_min.allFinite()) fail("workspace_min", "must be finite");
  positiveBox(workspace_size, "workspace_size");
  positiveBox(hand_centroid_box, "hand_centroid_box");
  positiveBox(head_centroid_box, "head_centroid_box");
  unit(hand_centroid_threshold, "hand_centroid_threshold");
  nonNegative(hand_distal_length, "hand_distal_length");
  nonNegative(hand_arm_box, "hand_arm_box");
  nonNegative(hand_arm_walk, "hand_arm_walk");
  unit(head_centroid_threshold, "head_centroid_threshold");
  if (centroid_iterations < 1) fail("centroid_iterations", "must be >= 1");
  head_fit.validate();
  if (threads < 0) fail("threads", "must be >= 0");
}

}  // namespace hand_tracking
