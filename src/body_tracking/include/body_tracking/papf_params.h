// Parameters of the partitioned annealed particle filter (papf.h); config/papf.yaml documents
// each one for users and papf_config.h reads it. Defaults: the thesis' settings at 25 fps (5.2.1: N = 256, L = 4,
// alpha = 0.5, s = 10, 10 % diffusion, process noise bounds).
#pragma once

#include <cstdint>
#include <string>

#include "body_tracking/arm_length.h"
#include "body_tracking/hand_refinement.h"
#include "body_tracking/trunk_girth.h"
#include "body_tracking/volume_observation.h"

namespace body_tracking {

struct PapfParams {
  int particles = 256;
  int layers = 4;
  double survival_rate = 0.5;   // alpha_d: each layer's exponent is solved for this
  double weight_scale = 10.0;   // s in w = exp(s w') / sum
  double diffusion = 0.1;       // inter-layer diffusion covariance / particle covariance
  // Each arm partition starts from the propagated particles' own values for its coordinates
  // instead of the trunk layers' survivors' values. Resampling in the trunk's layers copies
  // whole particles, so the arms' coordinates collapse to the few that rode on surviving trunks,
  // and the arm layers' diffusion (a share of that collapsed spread) cannot restore them. The
  // arms' coordinates are joint angles relative to the chest, so a propagated arm is a valid arm
  // on any surviving trunk (an arm proposed from a skin voxel, proposal_fraction, was aimed from
  // its own shoulder and misses the voxel by the trunks' difference). false = the thesis
  // (5.2.1). Reach_targets, 5 seeds: hands 20.5 -> 13.3 mm, elbows 33.5 -> 19.0 mm (median),
  // at no cost.
  bool reseed_arms = true;
  // Prediction f_t: each particle moves by this share of the estimate's last step (a damped
  // constant velocity, in the tangent coordinates), so fast reaches do not leave the arm behind.
  // 0 (the default) = the thesis' random walk: at 0.3 and 0.7 the estimate's jitter made the
  // hands worse on reach_targets (20 mm -> 52 and 127 mm mean).
  double velocity_damping = 0.0;
  // Process noise: uniform half-widths per frame (m, rad).
  double noise_translation = 0.01;
  double noise_torso_rotation = 0.0524;  // 3 deg
  double noise_spine = 0.0524;
  double noise_head = 0.1745;
  double noise_shoulder_shift = 0.01;
  double noise_upper_arm = 0.2618;       // 15 deg
  double noise_forearm = 0.3491;         // 20 deg
  // Share of particles whose arm is proposed each frame from the skin volume (arm_ik.h: the
  // hand put on a skin voxel within reach, the elbow bent down and out), so an arm caught in a
  // wrong pose (folded back, out of the volume) is found again; 0 = the thesis' filter.
  double proposal_fraction = 0.15;
  double proposal_head_clearance = 0.15;  // m: skin this close to the head is not a hand
  ObservationParams observation;
  HandRefinementParams hands;
  TrunkGirthParams shape;       // the trunk's girth refined over a track's first frames
  ArmLengthParams arm_length;   // the arms' length refined likewise (arm_length.h)
  // Track start and loss.
  int min_person_voxels = 60;   // occupied voxels (working resolution) that make a person
  int init_runs = 6;            // annealing runs on the first volume of a new track
  // A frame counts as bad when the volume fills less than this of the trunk (the mean
  // likelihood inside the abdomen, chest and head, without the shell's term;
  // BodyEstimate::trunk_score). The arms do not judge: an arm that leaves the workspace reads the
  // unknown likelihood outside the grid, and restarting would not find it. Nor does the shell:
  // on a poor volume its halo term sank a tracked trunk's score below this (generated scenario
  // random-17 restarted every 8 frames).
  double lost_score = 0.35;
  int lost_frames = 8;          // consecutive bad frames (or frames without a person) -> lost
  uint64_t seed = 1;
  int threads = 2;
  // Particle weights on the GPU (gpu_particle_weights.h) where one is usable: the same scores,
  // so the same estimates; without a usable device the CPU scores and Papf::gpuWarning() says
  // why.
  bool gpu_weights = false;

  // Throws std::invalid_argument naming the parameter.
  void validate() const;
};

}  // namespace body_tracking
