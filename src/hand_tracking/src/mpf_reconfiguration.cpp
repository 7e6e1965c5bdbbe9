// The MPF's reconfiguration step (thesis 5.1, 6.3; algorithm 1: kMeanAnalysis,
// renormaliseMixWeights, recomputeMixWeights): once per frame, after the mixture weights,
// the components' modes seed a typed k-means over the particles; what the seeds found decides
// which tracks continue, merge, split or are lost, and the weights are corrected for the
// particles that changed cluster or left the mixture. No random numbers are drawn here.
#include "hand_tracking/mpf_tracker.h"

#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "hand_tracking/reclustering.h"
#include "hand_tracking/target.h"

namespace hand_tracking {

// The working state of one reconfigure() pass, handed from step to step.
struct MpfTracker::Reclustering {
  struct Mean {
    Eigen::Vector3d position;
    Target::Type type;
    int slot;  // component the mean continues, or -1 (split)
  };
  std::vector<Mean> means;  // the k-means seeds, head first
  int hand_order[2] = {1, 2};  // the hand slots, older track first
  int hand_means = 0;  // seeds of type hand so far
  // A tracked hand that got no seed but is still a good hand: the index of the hand mean it
  // merges into (else -1).
  int merged_into_mean[kNumSlots] = {-1, -1, -1};
  std::vector<ClusterMean> cm;  // the k-means means: the seeds, then where k-means left them
  std::vector<int> slot_of;  // component slot of each cluster, or -1
  double new_pi[kNumSlots] = {0, 0, 0};  // sum of W_i = pi_c w_i per new slot
  double total = 0.0;  // sum of new_pi
};

void MpfTracker::reconfigure() {
  // The components' modes after the mixture weights: what rules 1 and 2 seed from.
  for (int s = 0; s < kNumSlots; ++s)
    if (comps_[s].active) updateEstimate(s, true);
  Reclustering r;
  seedHeadMean(&r);
  seedHandMeans(&r);
  seedSplitMeans(&r);
  clusterParticles(&r);
  assignClusterSlots(&r);
  reweightClusteredParticles(&r);
  endMergedAndLostTracks(r);
  startSplitTracks(r);
  renormaliseMixture(r);
  updateReportedEstimates();
}

// Where a hand mean may go: at least hand_distance from the hand means chosen so far and
// head_hand_distance from the head's (closer, it is taken for the head: neck, chin, face).
bool MpfTracker::handPlaceOk(const Reclustering& r, const Eigen::Vector3d& x,
                             double hand_distance) const {
  for (const Reclustering::Mean& m : r.means) {
    const double d = (m.position - x).norm();
    if (d < (m.type == Target::kHead ? params_.head_hand_distance : hand_distance)) return false;
  }
  return true;
}

// The strongest particle of a component at min_obs or above (and, for a hand, at a place
// handPlaceOk(x, hand_distance) accepts and, with off_limb, off the tracked hands' limbs).
bool MpfTracker::bestParticle(const Reclustering& r, int s, double min_obs, double hand_distance,
                              Eigen::Vector3d* at, bool off_limb) const {
  double best_w = -1.0;
  for (const P& p : parts_) {
    if (!p.active || p.comp != s || p.obs < min_obs || p.w <= best_w) continue;
    const Eigen::Vector3d x = p.x.cast<double>();
    if (comps_[s].type == Target::kHand && !handPlaceOk(r, x, hand_distance)) continue;
    if (off_limb && onTrackedLimb(x)) continue;
    best_w = p.w;
    *at = x;
  }
  return best_w >= 0.0;
}

// Rule 1: the head first (largest target, highest priority): its estimate at the tracking
// weight or above, else its strongest particle that is; else the head is lost.
void MpfTracker::seedHeadMean(Reclustering* r) const {
  const Component& h = comps_[kHeadSlot];
  Eigen::Vector3d at;
  if (h.active) {
    if (h.estimate_obs >= params_.head_track_weight)
      r->means.push_back({h.estimate, Target::kHead, kHeadSlot});
    else if (bestParticle(*r, kHeadSlot, params_.head_track_weight, 0.0, &at))
      r->means.push_back({at, Target::kHead, kHeadSlot});
  }
}

// Rule 2: one mean per tracked hand, older tracks first (they keep their identity when two
// merge). The estimate qualifies at the tracking weight or above at a place handPlaceOk
// accepts (merge_distance); else the strongest particle at the initialisation weight at
// least split_distance from the means (the thesis' alternative: the hand still has a mode
// of its own; the split distance keeps the fringe of a merged blob from passing for one);
// else the hand gets no mean: merged into the nearby hand mean if its estimate is still a
// good hand, lost otherwise (so is a hand that ran into the head).
void MpfTracker::seedHandMeans(Reclustering* r) const {
  if (comps_[2].active && (!comps_[1].active || comps_[2].active_since < comps_[1].active_since))
    std::swap(r->hand_order[0], r->hand_order[1]);
  for (int s : r->hand_order) {
    const Component& c = comps_[s];
    if (!c.active) continue;
    Eigen::Vector3d at;
    if (c.estimate_obs >= params_.hand_track_weight &&
        handPlaceOk(*r, c.estimate, params_.merge_distance)) {
      r->means.push_back({c.estimate, Target::kHand, s});
      ++r->hand_means;
    } else if (bestParticle(*r, s, params_.hand_init_weight, params_.split_distance, &at)) {
      r->means.push_back({at, Target::kHand, s});
      ++r->hand_means;
    } else if (c.estimate_obs >= params_.hand_track_weight) {
      for (size_t k = 0; k < r->means.size(); ++k)
        if (r->means[k].type == Target::kHand &&
            (r->means[k].position - c.estimate).norm() < params_.merge_distance)
          r->merged_into_mean[s] = static_cast<int>(k);
    }
  }
}

// Rule 3: split: fewer than two hands found, a strong particle far from every mean.
void MpfTracker::seedSplitMeans(Reclustering* r) const {
  for (int s : r->hand_order) {
    if (r->hand_means >= 2) break;
    if (!comps_[s].active) continue;
    Eigen::Vector3d at;
    // Not on the limb of a tracked hand (MpfParams::birth_limb_fraction): a hand's particles
    // that spread up a bare forearm would split off a track at the elbow.
    if (bestParticle(*r, s, params_.hand_init_weight, params_.split_distance, &at, true)) {
      r->means.push_back({at, Target::kHand, -1});
      ++r->hand_means;
    }
  }
}

// Typed k-means over the particles of the active components, seeded with the means. A
// component that got no mean and merged into none is lost: its particles leave the mixture
// (else k-means hands them to the nearest cluster, and a vanished hand's cloud would drag the
// other hand's estimate towards where it was lost).
void MpfTracker::clusterParticles(Reclustering* r) {
  bool has_mean[kNumSlots] = {false, false, false};
  for (const Reclustering::Mean& m : r->means)
    if (m.slot >= 0) has_mean[m.slot] = true;
  bool pruned[kNumSlots] = {false, false, false};
  for (int s = 0; s < kNumSlots; ++s)
    pruned[s] = comps_[s].active && !has_mean[s] && r->merged_into_mean[s] < 0;

  cluster_points_.resize(parts_.size());
  for (size_t i = 0; i < parts_.size(); ++i) {
    const P& p = parts_[i];
    ClusterPoint& q = cluster_points_[i];
    q.position = p.x;
    q.active = p.active && comps_[p.comp].active && !pruned[p.comp];
    q.type = comps_[p.comp].type;
    q.weight = q.active ? static_cast<float>(comps_[p.comp].pi * p.wn) : 0.f;
  }
  r->cm.resize(r->means.size());
  for (size_t k = 0; k < r->means.size(); ++k) r->cm[k] = {r->means[k].position, r->means[k].type};
  const KMeansResult km =
      typedKMeans(cluster_points_, &r->cm, params_.kmeans_max_iterations, &assignment_);
  stats_.kmeans_iterations = km.iterations;
  stats_.kmeans_converged = km.converged;
}

// Slots for the clusters: a continued component keeps its slot (and so its identity); a
// split takes a hand slot that no cluster continues.
void MpfTracker::assignClusterSlots(Reclustering* r) const {
  r->slot_of.assign(r->means.size(), -1);
  bool claimed[kNumSlots] = {false, false, false};
  for (size_t k = 0; k < r->means.size(); ++k)
    if (r->means[k].slot >= 0) {
      r->slot_of[k] = r->means[k].slot;
      claimed[r->means[k].slot] = true;
    }
  for (size_t k = 0; k < r->means.size(); ++k)
    if (r->means[k].slot < 0)
      for (int s = 1; s < kNumSlots; ++s)
        if (!claimed[s]) {
          r->slot_of[k] = s;
          claimed[s] = true;
          break;
        }
}

// Every surviving particle moves to its cluster's slot with its absolute weight
// W_i = pi_c w_i (the reclustering correction needs the old mixture weights); particles that
// settled on a mean of foreign type are deactivated (they measure another observation
// function; eq. 5.4 renormalises without them).
void MpfTracker::reweightClusteredParticles(Reclustering* r) {
  for (size_t i = 0; i < parts_.size(); ++i) {
    P& p = parts_[i];
    if (!cluster_points_[i].active) {
      p.active = false;
      continue;
    }
    const int k = assignment_[i];
    const int old = p.comp;
    if (k < 0 || r->slot_of[k] < 0 || r->cm[k].type != comps_[old].type) {
      p.active = false;
      continue;
    }
    const double W = comps_[old].pi * p.wn;
    p.wn = W;  // absolute for now
    p.comp = r->slot_of[k];
    r->new_pi[p.comp] += W;
    r->total += W;
  }
}

// A tracked component whose mean kept no weight ends: merged (its mean gave way to a nearby
// hand that continues; the offset to it decides the identities when they split again) or
// lost. Its particles keep the slots k-means gave them (a split may reuse this slot).
void MpfTracker::endMergedAndLostTracks(const Reclustering& r) {
  // Old estimates are still in comps_ (used for merge offsets).
  Eigen::Vector3d old_estimate[kNumSlots];
  for (int s = 0; s < kNumSlots; ++s) old_estimate[s] = comps_[s].estimate;
  bool continues[kNumSlots] = {false, false, false};
  for (size_t k = 0; k < r.means.size(); ++k)
    if (r.means[k].slot >= 0 && r.new_pi[r.means[k].slot] > 0.0) continues[r.means[k].slot] = true;
  for (int s = 0; s < kNumSlots; ++s) {
    Component& c = comps_[s];
    if (!c.active || continues[s]) continue;
    int into = r.merged_into_mean[s] >= 0 ? r.slot_of[r.merged_into_mean[s]] : -1;
    if (into >= 0 && !continues[into]) into = -1;
    Eigen::Vector3d side = Eigen::Vector3d::Zero();
    if (into >= 0) side = c.apart_offset.isZero() ? old_estimate[s] - old_estimate[into] : c.apart_offset;
    endTrack(s, into, side);
  }
}

// Splits: a split cluster that kept weight becomes a new component in its slot, with an
// identity (a hand that splits off a merged pair gets its former id back).
void MpfTracker::startSplitTracks(const Reclustering& r) {
  for (size_t k = 0; k < r.means.size(); ++k) {
    if (r.means[k].slot >= 0 || r.slot_of[k] < 0 || !(r.new_pi[r.slot_of[k]] > 0.0)) continue;
    Component& c = comps_[r.slot_of[k]];
    c.active = true;
    assignIdentity(r.slot_of[k], r.cm[k].position);
    ++stats_.splits;
  }
}

// Particles of slots that ended stay deactivated; then the reclustering correction (eq. 5.4):
// pi'_k = sum of W over the cluster (normalised over all), w'_i = W_i / pi'_k, so the mixture
// approximates the same (pruned) distribution as before the reclustering.
void MpfTracker::renormaliseMixture(const Reclustering& r) {
  for (P& p : parts_)
    if (p.active && !comps_[p.comp].active) p.active = false;

  if (r.total > 0.0) {
    for (int s = 0; s < kNumSlots; ++s)
      comps_[s].pi = comps_[s].active ? r.new_pi[s] / r.total : 0.0;
    for (P& p : parts_)
      if (p.active) p.wn = p.wn / r.new_pi[p.comp];
  } else {  // nothing survived
    for (int s = 0; s < kNumSlots; ++s)
      if (comps_[s].active) endTrack(s, -1, Eigen::Vector3d::Zero());
    for (P& p : parts_) p.active = false;
  }
}

// The estimates of the new mixture (weighted particle means), and the positions to report
// (optionally refined to the skin centroid).
void MpfTracker::updateReportedEstimates() {
  stats_.active_particles = 0;
  for (const P& p : parts_) stats_.active_particles += p.active;
  for (int s = 0; s < kNumSlots; ++s) {
    Component& c = comps_[s];
    if (!c.active) continue;
    updateEstimate(s, true);
    const bool refine = c.type == Target::kHand ? params_.refine_hand_centroid
                                                : params_.refine_head_centroid;
    Eigen::Vector3d end = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    c.reported = refine ? refineCentroid(s, &end) : c.estimate;
    if (end.allFinite()) c.hand_end = end, c.hand_end_frame = frames_;
    if (c.type == Target::kHead && params_.head_model && body_) {
      const HeadFit fit = fitHeadCentre(*body_, c.reported, params_.head_fit);
      if (fit.ok) c.reported = fit.centre;
    }
  }
  recordHandSides();
}

// Each hand's side of the other while the two are clearly apart (Component::apart_offset).
void MpfTracker::recordHandSides() {
  Component &a = comps_[1], &b = comps_[2];
  if (!a.active || !b.active || a.type != Target::kHand || b.type != Target::kHand) return;
  const Eigen::Vector3d d = a.estimate - b.estimate;
  if (d.norm() < params_.split_distance) return;
  a.apart_offset = d;
  b.apart_offset = -d;
}

}  // namespace hand_tracking
