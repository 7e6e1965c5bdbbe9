// The partitioned annealed particle filter for the upper body (thesis 5.2.1, Deutscher and
// Reid 2005). Each frame: particles drawn from the last frame's final weighted set plus uniform
// process noise, then L annealing layers for each partition of the state in turn: the trunk
// chain (torso, spine, head: scored on abdomen, chest and head), then each arm (scored on its
// three parts). The observation is a sum over parts and the arms are independent given the
// trunk, so each partition's search runs in 8 or 5 dimensions instead of 18; without it the
// search, on volumes that see the trunk only in part, settles with the arms explaining the
// chest. In each layer: weights w^beta with beta solved so that the survival diagnostic is
// alpha_d * N, then new particles from two-point crossover of weight-drawn parents plus
// Gaussian diffusion with 10 % of the particle covariance, over the partition's coordinates in
// the tangent space of state_tangent.h; between partitions the set is resampled. The estimate
// is the weighted mean of the last layer.
// Self-colliding particles are rejected (weight zero). The tracker starts by itself on the
// first volume with a person (head from the top of the body volume, torso below it), and
// restarts when the fit stays bad or the person leaves. Seeded: the same volumes and seed give
// the same estimates, whatever the thread count.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "body_tracking/arm_length.h"
#include "body_tracking/body_parts.h"
#include "body_tracking/gpu_particle_weights.h"
#include "body_tracking/hand_refinement.h"
#include "body_tracking/joint_limits.h"
#include "body_tracking/papf_params.h"
#include "body_tracking/state_tangent.h"
#include "body_tracking/trunk_girth.h"
#include "body_tracking/volume_observation.h"

namespace body_tracking {

struct BodyEstimate {
  bool tracking = false;     // a pose is being reported
  bool started = false;      // this frame (re)started the track
  BodyState state{};
  BodyFrames frames;
  // The hands to report: from the skin volume around the model's hands (hand_refinement.h),
  // or the model's own where no skin volume was given or too little skin was found.
  RefinedHands hands;
  std::array<double, kNumParts> part_scores{};  // the estimate's mean likelihood per part
  double score = 0;          // mean over parts, at most 1 (the trunk's shells take off)
  // How much of the abdomen, chest and head the volume fills (their mean likelihood without the
  // trunk's shell, VolumeObservation::partMean, averaged): what judges a loss.
  double trunk_score = 0;
  double trunk_girth = 1.0;  // the trunk's girth factor in use (trunk_girth.h)
  double arm_length = 1.0;   // the arms' length factor in use (arm_length.h)
  int frames_tracked = 0;
  // Solved exponents (diagnostics), per partition (trunk, left, right), layer L first.
  std::array<double, 24> layer_beta{};
};

struct PapfTimes {
  double total_ms = 0, observation_ms = 0;
};

class Papf {
 public:
  Papf(const BodyProfile& profile, const PapfParams& params);

  // One frame: the body volume and, optionally, the skin volume on the same grid.
  const BodyEstimate& update(const psfs::ProbabilityVolume& body,
                             const psfs::ProbabilityVolume* skin);
  void reset();
  // Starts (or restarts) the track at a known pose, e.g. from a calibration pose or a test's
  // ground truth: every particle at `state`, spread by one frame's process noise.
  void startAt(const BodyState& state);

  const BodyEstimate& estimate() const { return estimate_; }
  // The profile in use: the given one, its trunk's girth and arms' length refined over a track's
  // first frames (trunk_girth.h, arm_length.h; PapfParams::shape, arm_length).
  const BodyProfile& profile() const { return profile_; }
  const PapfParams& params() const { return params_; }
  const BodyLimits& limits() const { return limits_; }
  const std::vector<BodyState>& particles() const { return particles_; }
  const std::vector<double>& weights() const { return weights_; }
  const PapfTimes& lastTimes() const { return times_; }
  const VolumeObservation& observation() const { return observation_; }
  // Whether the particle weights run on the GPU (params().gpu_weights and a usable device), and
  // why not where they were asked for ("" otherwise): for the caller to log once.
  bool gpuWeightsActive() const { return gpu_ != nullptr; }
  const std::string& gpuWarning() const { return gpu_warning_; }

  // The scoring of one state as the filter sees it (0 for a self-colliding pose): all parts
  // (partition < 0), or one partition's (0 trunk, 1 left arm, 2 right arm).
  double scoreState(const BodyState& s, int partition = -1) const;
  static constexpr int kPartitions = 3;

 private:
  bool initialise();  // false: no person in the volume
  void anneal(bool from_previous);
  void scoreAll(int partition);
  void dropGpu(const std::string& why);  // back to the CPU for good, saying why
  void resampleUniform();
  double solveBeta(double previous);
  void layerWeights(double beta);
  void propagate();                 // resample + process noise
  void crossoverAndDiffuse(int partition);
  int drawIndex(double u) const;    // by the cumulative weights
  void finishEstimate();
  void restartShape();
  void refineShape();  // this frame's estimate votes on the girth and arm length
  // Hand candidates for the arm proposals: skin voxels, those near the head left out.
  void collectSkinTargets(const Eigen::Vector3d* head);
  bool proposeArm(Side side, BodyState* s, std::uniform_real_distribution<double>* uni);

  BodyProfile base_profile_, profile_;
  PapfParams params_;
  TrunkGirth girth_;
  ArmLength arms_;
  BodyLimits limits_;
  VolumeObservation observation_;
  std::mt19937_64 rng_;
  std::vector<BodyState> particles_, scratch_;
  std::vector<BodyState> seed_;  // the frame's propagated particles (reseed_arms)
  std::vector<double> scores_, weights_, cumulative_;
  std::array<double, 8 * kPartitions> beta_{};
  Tangent velocity_ = Tangent::Zero();  // the estimate's last step
  BodyState previous_state_{};
  std::vector<Eigen::Vector3d> skin_targets_;
  std::vector<double> skin_cumulative_;
  BodyEstimate estimate_;
  int bad_frames_ = 0;
  PapfTimes times_;
  std::unique_ptr<GpuParticleWeights> gpu_;
  std::string gpu_warning_;
};

}  // namespace body_tracking
