// Mixture particle filter (MPF) tracking of the head and both hands on integral volumes
// (thesis 5.1, 6.3; Vermaak et al. 2003), ROS-free.
//
// Up to three mixture components (slot 0: the head, slots 1 and 2: hands), state = 3-D
// position, one SIR filter per component. Per frame (thesis algorithm 1):
//  1. integral volumes of the skin volume (P(skin-coloured foreground), the likelihoods) and of
//     the body volume (P(foreground), the hands' frontal-plane non-occupancy);
//  2. prediction: each active component is resampled (systematic) and propagated (head: random
//     walk; hands: thirds with AR(1), AR(2), AR(3)); inactive components scatter their
//     particles over the workspace to search for a target;
//  3. update: box-mean observations (BoxObservation); a searching component whose best
//     particle reaches the initialisation weight far enough from every tracked target is born
//     there (its particles spread around the find); mixture weights
//     pi_m,t ~ pi_m,t-1 x (mean particle weight of m);
//  4. reconfiguration: cluster means from the components' modes (head first; a hand only above
//     the tracking weight and apart from the means before it: else it is lost or merged; extra
//     hand means from far, strong particles: split), typed k-means (<= 50 iterations),
//     particles on a mean of foreign type deactivated, weights renormalised (eq. 5.4) and
//     corrected for the reclustering (pi'_k = sum of pi_c w_i over the cluster, w'_i =
//     pi_c w_i / pi'_k);
//  5. estimates: weighted particle means (hands optionally refined to the skin centroid, see
//     MpfParams::refine_hand_centroid).
// Identities: a track keeps its id for its life. A hand that splits off a merged pair, or is
// re-found while the other hand stayed tracked, gets its former id back (within
// identity_memory); after a merge the side it returns on (relative to its partner, as it was
// when the two were last at least split_distance apart) decides which of the pair gets which id.
//
// Deterministic: all random numbers come from one seeded std::mt19937_64 and are drawn
// serially; the parallel part (OpenMP over particles) only evaluates observations, so the
// results do not depend on the thread count.
#pragma once

#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "hand_tracking/box_observation.h"
#include "hand_tracking/integral_volume.h"
#include "hand_tracking/motion_model.h"
#include "hand_tracking/mpf_params.h"
#include "hand_tracking/reclustering.h"
#include "hand_tracking/target.h"
#include "psfs_reconstruction/probability_volume.h"

namespace hand_tracking {

class MpfTracker {
 public:
  static constexpr int kHeadSlot = 0;
  static constexpr int kNumSlots = 3;  // head, hand, hand

  // Throws std::invalid_argument (naming the field) on bad params.
  MpfTracker(const MpfParams& params, uint64_t seed);

  // One frame. dt in seconds (> 0). Throws std::invalid_argument for empty/inconsistent
  // volumes or a bad dt; the tracker state is then unchanged.
  const std::vector<Target>& update(const psfs::ProbabilityVolume& skin,
                                    const psfs::ProbabilityVolume& body, double dt);

  // Always 3 entries: [0] head, [1] and [2] hands (inactive ones have active=false, weight 0
  // and their last position).
  const std::vector<Target>& targets() const { return targets_; }

  struct Particle {
    Eigen::Vector3f position;
    float weight;    // absolute mixture weight pi_m * normalised particle weight (0: inactive)
    int component;   // slot 0..2, or -1 for a searching or deactivated particle
  };
  std::vector<Particle> particles() const;  // for visualisation

  struct Times {
    double integral_ms = 0, weights_ms = 0, reconfigure_ms = 0, total_ms = 0;
  };
  const Times& lastTimes() const { return times_; }

  // What the last update did (diagnostics, tests).
  struct Stats {
    int kmeans_iterations = 0;
    bool kmeans_converged = true;
    int births = 0, splits = 0, merges = 0, losses = 0;
    int active_particles = 0;
  };
  const Stats& lastStats() const { return stats_; }

  // Back to the state after construction (same seed: the same input gives the same output).
  void reset();
  const MpfParams& params() const { return params_; }
  // Live tuning: the process noise of the dynamics (MpfParams::head_noise, hand_noise_ar*) from
  // the next update on. Throws std::invalid_argument (nothing changed) for values validate()
  // rejects.
  void setProcessNoise(double head, double ar1, double ar2, double ar3);
  double time() const { return time_; }      // sum of the dt so far (s)
  uint64_t frames() const { return frames_; }  // updates since construction / reset()

  // The observation the tracker uses, on the volumes of the last update (tests, tools).
  double observe(Target::Type type, const Eigen::Vector3d& x) const {
    return observation_(type, skin_iv_, body_iv_, x);
  }

 private:
  struct P {
    ParticleHistory h;  // positions of the previous frames
    Eigen::Vector3f x = Eigen::Vector3f::Zero();
    double obs = 0;  // observation (0..1)
    double w = 0;    // unnormalised weight obs^exponent
    double wn = 0;   // normalised within its component
    int comp = -1;   // slot
    bool active = false;
  };
  struct Component {
    Target::Type type = Target::kHand;
    int begin = 0, count = 0;  // particle pool
    bool active = false;
    uint32_t id = 0;
    double pi = 0;
    double active_since = 0;  // time the current identity started
    Eigen::Vector3d estimate = Eigen::Vector3d::Zero();  // weighted particle mean
    double estimate_obs = 0;
    Eigen::Vector3d reported = Eigen::Vector3d::Zero();
    // A hand's end of its bare arm (arm_geodesic.h) and the frame (frames_) it was found in:
    // the next frame's walk keeps to that end where the other rules cannot tell.
    Eigen::Vector3d hand_end = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    uint64_t hand_end_frame = 0;  // 0: none (frames_ counts from 1 during an update)
    // Memory of the last track (identity recovery).
    uint32_t last_id = 0;
    double inactive_since = 0;
    int merged_into = -1;
    Eigen::Vector3d merge_offset = Eigen::Vector3d::Zero();  // this - partner, at the merge
    // this - the other hand, the last frame both were tracked at least split_distance apart
    // (zero: not yet since this track started). What the merge remembers as this hand's side:
    // at the merge itself the two estimates are a few cm apart in any direction (clasped hands
    // lie one above the other), and a side read there swapped the identities at the split.
    Eigen::Vector3d apart_offset = Eigen::Vector3d::Zero();
  };

  void validateInput(const psfs::ProbabilityVolume& skin, const psfs::ProbabilityVolume& body,
                     double dt) const;
  void predict(double dt);
  Eigen::Vector3f searchPosition();
  void evaluate(int begin, int end);
  // Weighted particle mean and its observation; weights w (before normalisation) or wn.
  void updateEstimate(int slot, bool normalised);
  void births();
  // Whether skin joins x to a tracked hand (MpfParams::birth_limb_fraction).
  bool onTrackedLimb(const Eigen::Vector3d& x) const;
  void activate(int slot, const Eigen::Vector3d& at);
  void assignIdentity(int slot, const Eigen::Vector3d& at);
  // Marks a track ended (lost, or merged into another slot) and remembers its identity;
  // leaves its particles alone.
  void endTrack(int slot, int merged_into, const Eigen::Vector3d& merge_offset);
  void mixWeights();
  // Reconfiguration (step 4 above; mpf_reconfiguration.cpp): reconfigure() runs the steps
  // from seedHeadMean() to updateReportedEstimates() in this order, passing their working
  // state (the k-means seeds and what became of them) in a Reclustering; handPlaceOk() and
  // bestParticle() are the seeding rules' tests.
  struct Reclustering;
  void reconfigure();
  bool handPlaceOk(const Reclustering& r, const Eigen::Vector3d& x, double hand_distance) const;
  // off_limb: only where onTrackedLimb() is false (a split's seed).
  bool bestParticle(const Reclustering& r, int slot, double min_obs, double hand_distance,
                    Eigen::Vector3d* at, bool off_limb = false) const;
  void seedHeadMean(Reclustering* r) const;
  void seedHandMeans(Reclustering* r) const;
  void seedSplitMeans(Reclustering* r) const;
  void clusterParticles(Reclustering* r);
  void assignClusterSlots(Reclustering* r) const;
  void reweightClusteredParticles(Reclustering* r);
  void endMergedAndLostTracks(const Reclustering& r);
  void startSplitTracks(const Reclustering& r);
  void recordHandSides();
  void renormaliseMixture(const Reclustering& r);
  void updateReportedEstimates();
  // hand_end (may be null): set to the arm's hand end when the arm walk found one.
  Eigen::Vector3d refineCentroid(int slot, Eigen::Vector3d* hand_end = nullptr) const;
  void publish();
  Eigen::Vector3f clampToWorkspace(const Eigen::Vector3f& x) const;

  MpfParams params_;
  uint64_t seed_;
  BoxObservation observation_;
  std::mt19937_64 rng_;
  IntegralVolume skin_iv_, body_iv_;
  const psfs::ProbabilityVolume* skin_ = nullptr;  // valid during update() only
  const psfs::ProbabilityVolume* body_ = nullptr;  // valid during update() only
  std::vector<P> parts_, next_;
  Component comps_[kNumSlots];
  std::vector<Target> targets_;
  std::vector<uint32_t> search_voxels_;  // skin voxels above the search threshold
  std::vector<ClusterPoint> cluster_points_;
  std::vector<int> assignment_;
  std::vector<int> gather_;
  std::vector<double> gather_w_;
  std::vector<int> picks_;
  uint32_t next_id_ = 1;
  double time_ = 0, prev_dt_ = 0;
  uint64_t frames_ = 0;
  Times times_;
  Stats stats_;
};

}  // namespace hand_tracking
