#include "hand_tracking/mpf_tracker.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "hand_tracking/arm_geodesic.h"
#include "hand_tracking/body_top.h"
#include "hand_tracking/distal_centroid.h"
#include "hand_tracking/resampling.h"
#include "hand_tracking/skin_path.h"

namespace hand_tracking {

namespace {

using Clock = std::chrono::steady_clock;
// Half edge (m) of the box in which the distal cut weighs the body that is not skin around an
// arm's end: a sleeve within 5 cm of the elbow counts (the hull smears a limb by ~3 voxels).
constexpr double kForeignProbeHalf = 0.05;
// The arm walk's min_arm_length is hand_distal_length plus this: 0.27 m, a 21 cm hand with the
// hull's 3 cm of smear at each end (arm_geodesic.h).
constexpr double kHandAloneSmear = 0.10;
constexpr double kRootwardRamp = 0.05;  // m
// The limb test's cube around each point of the line (skin_path.h): 5 cm, and a quarter of it
// skin. A point 4 cm from the axis of a 7 cm forearm still counts; a point in the air more
// than ~2 cm from any skin does not.
constexpr double kLimbProbeHalf = 0.025;
constexpr double kLimbProbeSkin = 0.25;
double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

void checkVolume(const psfs::ProbabilityVolume& v, const char* name) {
  try {
    v.grid.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("hand_tracking::MpfTracker: ") + name +
                                " volume has an invalid grid: " + e.what());
  }
  if (v.data.size() != v.grid.numVoxels())
    throw std::invalid_argument(std::string("hand_tracking::MpfTracker: ") + name +
                                " volume has " + std::to_string(v.data.size()) +
                                " bytes but its grid " + v.grid.describe() + " needs " +
                                std::to_string(v.grid.numVoxels()));
}

}  // namespace

MpfTracker::MpfTracker(const MpfParams& params, uint64_t seed)
    : params_((params.validate(), params)), seed_(seed), observation_(params_) {
  const int n = params_.head_particles + 2 * params_.hand_particles;
  parts_.resize(n);
  next_.resize(n);
  reset();
}

void MpfTracker::setProcessNoise(double head, double ar1, double ar2, double ar3) {
  MpfParams p = params_;
  p.head_noise = head;
  p.hand_noise_ar1 = ar1;
  p.hand_noise_ar2 = ar2;
  p.hand_noise_ar3 = ar3;
  p.validate();
  params_ = p;
}

void MpfTracker::reset() {
  rng_.seed(seed_);
  int begin = 0;
  for (int s = 0; s < kNumSlots; ++s) {
    Component& c = comps_[s];
    c = Component();
    c.type = s == kHeadSlot ? Target::kHead : Target::kHand;
    c.begin = begin;
    c.count = s == kHeadSlot ? params_.head_particles : params_.hand_particles;
    begin += c.count;
  }
  for (P& p : parts_) p = P();
  next_id_ = 1;
  time_ = 0;
  prev_dt_ = 0;
  frames_ = 0;
  times_ = Times();
  stats_ = Stats();
  targets_.assign(kNumSlots, Target());
  for (int s = 0; s < kNumSlots; ++s) targets_[s].type = comps_[s].type;
}

void MpfTracker::validateInput(const psfs::ProbabilityVolume& skin,
                               const psfs::ProbabilityVolume& body, double dt) const {
  if (!std::isfinite(dt) || !(dt > 0.0))
    throw std::invalid_argument("hand_tracking::MpfTracker: dt must be finite and > 0 (got " +
                                std::to_string(dt) + ")");
  checkVolume(skin, "skin");
  checkVolume(body, "body");
}

Eigen::Vector3f MpfTracker::clampToWorkspace(const Eigen::Vector3f& x) const {
  const Eigen::Vector3f lo = params_.workspace_min.cast<float>();
  const Eigen::Vector3f hi = (params_.workspace_min + params_.workspace_size).cast<float>();
  return x.cwiseMax(lo).cwiseMin(hi);
}

Eigen::Vector3f MpfTracker::searchPosition() {
  std::uniform_real_distribution<float> u01(0.f, 1.f);
  const float pick = u01(rng_);
  const Eigen::Vector3f j(u01(rng_), u01(rng_), u01(rng_));
  if (!search_voxels_.empty() && pick < params_.search_skin_fraction) {
    const size_t k = std::min(search_voxels_.size() - 1,
                              static_cast<size_t>(u01(rng_) * search_voxels_.size()));
    const psfs::VoxelGrid& g = skin_->grid;
    const Eigen::Vector3i v = g.coords(search_voxels_[k]);
    const Eigen::Vector3d p =
        g.origin + g.voxel_size * (v.cast<double>() + j.cast<double>());
    return clampToWorkspace(p.cast<float>());
  }
  return (params_.workspace_min.cast<float>() +
          params_.workspace_size.cast<float>().cwiseProduct(j));
}

void MpfTracker::predict(double dt) {
  const float r = prev_dt_ > 0.0 ? static_cast<float>(dt / prev_dt_) : 1.f;
  const float scale = static_cast<float>(dt / params_.reference_dt);
  const float max_step = static_cast<float>(params_.max_speed * dt);
  std::normal_distribution<float> normal(0.f, 1.f);
  std::uniform_real_distribution<double> u01(0.0, 1.0);

  bool searching = false;
  for (const Component& c : comps_) searching |= !c.active;
  search_voxels_.clear();
  if (searching) {
    const uint8_t thr = static_cast<uint8_t>(std::floor(255.0 * params_.search_skin_threshold));
    const std::vector<uint8_t>& d = skin_->data;
    for (size_t i = 0; i < d.size(); ++i)
      if (d[i] > thr) search_voxels_.push_back(static_cast<uint32_t>(i));
  }

  for (int s = 0; s < kNumSlots; ++s) {
    Component& c = comps_[s];
    if (c.active) {
      // Gather the component's particles (after last frame's reclustering they may sit in any
      // pool) and resample its own pool from them.
      gather_.clear();
      gather_w_.clear();
      for (size_t i = 0; i < parts_.size(); ++i)
        if (parts_[i].active && parts_[i].comp == s) {
          gather_.push_back(static_cast<int>(i));
          gather_w_.push_back(parts_[i].wn);
        }
      double total = 0.0;
      for (double w : gather_w_) total += w;
      if (gather_.empty() || !(total > 0.0)) {
        // Cannot happen after reconfigure() (an active component keeps weight); be safe.
        endTrack(s, -1, Eigen::Vector3d::Zero());
      }
    }
    if (c.active) {
      systematicResample(gather_w_.data(), gather_w_.size(), c.count, u01(rng_), &picks_);
      for (int k = 0; k < c.count; ++k) {
        const P& a = parts_[gather_[picks_[k]]];
        P& q = next_[c.begin + k];
        q = P();
        q.h.x = a.x;
        q.h.x1 = a.h.x;
        q.h.x2 = a.h.x1;
        q.comp = s;
        q.active = true;
        Eigen::Vector3f noise(normal(rng_), normal(rng_), normal(rng_));
        Eigen::Vector3f x;
        if (c.type == Target::kHead) {
          x = q.h.x + static_cast<float>(params_.head_noise) * scale * noise;
        } else {
          const MotionModel m = handModelOf(k);
          const double sigma = m == MotionModel::kAR1   ? params_.hand_noise_ar1
                               : m == MotionModel::kAR2 ? params_.hand_noise_ar2
                                                        : params_.hand_noise_ar3;
          x = extrapolate(m, q.h, r) + static_cast<float>(sigma) * scale * noise;
        }
        q.x = clampToWorkspace(limitStep(q.h.x, x, max_step));
      }
    } else {  // searching: scatter over the workspace
      for (int k = 0; k < c.count; ++k) {
        P& q = next_[c.begin + k];
        q = P();
        q.x = searchPosition();
        q.h.x = q.h.x1 = q.h.x2 = q.x;
        q.comp = s;
        q.active = false;  // searching
      }
    }
  }
  parts_.swap(next_);
  prev_dt_ = dt;
}

void MpfTracker::evaluate(int begin, int end) {
  const double kappa = params_.likelihood_exponent;
  const int threads = params_.threads > 0 ? params_.threads : omp_get_max_threads();
  const Target::Type types[kNumSlots] = {comps_[0].type, comps_[1].type, comps_[2].type};
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && end - begin > 128)
  for (int i = begin; i < end; ++i) {
    P& p = parts_[i];
    const double o = observation_(types[p.comp], skin_iv_, body_iv_, p.x.cast<double>());
    p.obs = o;
    p.w = kappa == 1.0 ? o : std::pow(o, kappa);
  }
}

void MpfTracker::updateEstimate(int s, bool normalised) {
  Component& c = comps_[s];
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double mass = 0.0;
  for (const P& p : parts_)
    if (p.active && p.comp == s) {
      const double w = normalised ? p.wn : p.w;
      sum += w * p.x.cast<double>();
      mass += w;
    }
  if (mass > 0.0) c.estimate = sum / mass;
  c.estimate_obs = observation_(c.type, skin_iv_, body_iv_, c.estimate);
}

void MpfTracker::assignIdentity(int s, const Eigen::Vector3d& at) {
  Component& c = comps_[s];
  const bool remembered =
      c.last_id != 0 && time_ - c.inactive_since <= params_.identity_memory;
  if (c.type == Target::kHead) {
    c.id = c.last_id != 0 ? c.last_id : next_id_++;  // there is only one head
  } else {
    const int o = s == 1 ? 2 : 1;
    Component& other = comps_[o];
    const bool other_continuous = other.active && other.active_since <= c.inactive_since;
    if (remembered && other_continuous) {
      if (c.merged_into == o && (at - other.estimate).dot(c.merge_offset) < 0.0) {
        // The partner took this hand's side: swap the pair's identities back.
        c.id = other.id;
        other.id = c.last_id;
      } else {
        c.id = c.last_id;
      }
    } else {
      c.id = next_id_++;
    }
  }
  c.active_since = time_;
  c.merged_into = -1;
  // A new pairing: its sides are read afresh, from here if the two are already clearly apart
  // (a split happens only then).
  c.apart_offset.setZero();
  if (c.type == Target::kHand) {
    Component& other = comps_[s == 1 ? 2 : 1];
    other.apart_offset.setZero();
    const Eigen::Vector3d d = at - other.estimate;
    if (other.active && d.norm() >= params_.split_distance) {
      c.apart_offset = d;
      other.apart_offset = -d;
    }
  }
}

void MpfTracker::activate(int s, const Eigen::Vector3d& at) {
  Component& c = comps_[s];
  std::normal_distribution<float> normal(0.f, 1.f);
  const float spread = static_cast<float>(params_.birth_spread);
  const Eigen::Vector3f centre = at.cast<float>();
  for (int k = 0; k < c.count; ++k) {
    P& q = parts_[c.begin + k];
    q = P();
    Eigen::Vector3f n(normal(rng_), normal(rng_), normal(rng_));
    q.x = clampToWorkspace(centre + spread * n);
    q.h.x = q.h.x1 = q.h.x2 = q.x;  // at rest
    q.comp = s;
    q.active = true;
  }
  evaluate(c.begin, c.begin + c.count);
  int active = 0;
  double pi_sum = 0.0;
  for (const Component& o : comps_)
    if (o.active) {
      ++active;
      pi_sum += o.pi;
    }
  // Prior mixture weight of a newcomer: an equal share (the thesis leaves it open).
  c.pi = active > 0 ? pi_sum / active : 1.0;
  c.active = true;
  assignIdentity(s, at);
  c.estimate = at;
}

bool MpfTracker::onTrackedLimb(const Eigen::Vector3d& x) const {
  if (!(params_.birth_limb_fraction > 0.0)) return false;
  for (const Component& o : comps_)
    if (o.active && o.type == Target::kHand &&
        skinPathFraction(skin_iv_, x, o.estimate, kLimbProbeHalf, kLimbProbeSkin) >=
            params_.birth_limb_fraction)
      return true;
  return false;
}

void MpfTracker::births() {
  for (int s = 0; s < kNumSlots; ++s) {
    Component& c = comps_[s];
    if (c.active) continue;
    const double init =
        c.type == Target::kHead ? params_.head_init_weight : params_.hand_init_weight;
    // The strongest search particle at the initialisation weight or above that lies far
    // enough from every tracked target.
    int best = -1;
    double best_obs = -1.0;
    // The head is the top of the seated body (body_top.h).
    const double lowest = c.type == Target::kHead && params_.head_birth_depth > 0.0
                              ? bodyTop(*body_, params_.head_birth_top_area) - params_.head_birth_depth
                              : -std::numeric_limits<double>::infinity();
    for (int i = c.begin; i < c.begin + c.count; ++i) {
      const P& p = parts_[i];
      if (p.obs < init || p.obs <= best_obs) continue;
      const Eigen::Vector3d x = p.x.cast<double>();
      if (x.z() < lowest) continue;  // false for NaN: no top, no limit
      bool far = true;
      for (const Component& o : comps_) {
        const double min_d = c.type == Target::kHand && o.type == Target::kHead
                                 ? std::max(params_.birth_min_distance, params_.head_hand_distance)
                                 : params_.birth_min_distance;
        if (o.active && (o.estimate - x).norm() < min_d) far = false;
      }
      if (!far) continue;
      if (c.type == Target::kHand && onTrackedLimb(x)) continue;
      best_obs = p.obs;
      best = i;
    }
    if (best < 0) continue;
    const Eigen::Vector3d at = parts_[best].x.cast<double>();
    // Volume-size check (thesis 5.1): while no head is tracked, a hand is not born on a blob
    // that passes as a head (the face fills a palm box as well as a hand does). The crown slab
    // lowers a skin-coloured chest's head observation (its slab holds the neck and head), so
    // such a chest blocks hand births here less often; the birth-depth limit is not applied.
    if (c.type == Target::kHand && !comps_[kHeadSlot].active &&
        observation_.head(skin_iv_, body_iv_, at) >= params_.head_init_weight)
      continue;
    activate(s, at);
    ++stats_.births;
  }
}

void MpfTracker::mixWeights() {
  double total = 0.0;
  for (int s = 0; s < kNumSlots; ++s) {
    Component& c = comps_[s];
    if (!c.active) continue;
    double sum = 0.0;
    for (int i = 0; i < static_cast<int>(parts_.size()); ++i)
      if (parts_[i].active && parts_[i].comp == s) sum += parts_[i].w;
    if (!(sum > 0.0)) {  // nothing left to track
      endTrack(s, -1, Eigen::Vector3d::Zero());
      for (P& p : parts_)
        if (p.comp == s) p.active = false;
      continue;
    }
    for (P& p : parts_)
      if (p.active && p.comp == s) p.wn = p.w / sum;
    c.pi *= sum / c.count;
    total += c.pi;
  }
  if (!(total > 0.0)) return;
  // Normalise, then keep every active component above the floor (see MpfParams).
  for (Component& c : comps_)
    if (c.active) c.pi /= total;
  double sum = 0.0;
  for (Component& c : comps_)
    if (c.active) {
      c.pi = std::max(c.pi, params_.min_mixture_weight);
      sum += c.pi;
    }
  for (Component& c : comps_)
    if (c.active) c.pi /= sum;
}

void MpfTracker::endTrack(int s, int merged_into, const Eigen::Vector3d& merge_offset) {
  Component& c = comps_[s];
  c.active = false;
  c.pi = 0.0;
  c.last_id = c.id;
  c.inactive_since = time_;
  c.merged_into = merged_into;
  c.merge_offset = merged_into >= 0 ? merge_offset : Eigen::Vector3d::Zero();
  c.hand_end_frame = 0;
  c.hand_end = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  ++(merged_into >= 0 ? stats_.merges : stats_.losses);
}

Eigen::Vector3d MpfTracker::refineCentroid(int s, Eigen::Vector3d* hand_end) const {
  const Component& c = comps_[s];
  const psfs::VoxelGrid& g = skin_->grid;
  const bool hand = c.type == Target::kHand;
  const Eigen::Vector3d half =
      0.5 * (hand ? params_.hand_centroid_box : params_.head_centroid_box);
  // The distal cut looks at the arm in a larger box (it must see more than a hand to tell an
  // arm); the plain centroid stays in the hand-sized one.
  const bool distal = hand && params_.hand_distal_length > 0.0 && comps_[kHeadSlot].active;
  const Eigen::Vector3d gather_half =
      distal ? half.cwiseMax(Eigen::Vector3d::Constant(0.5 * params_.hand_arm_box)) : half;
  const double threshold = hand ? params_.hand_centroid_threshold : params_.head_centroid_threshold;
  const uint8_t thr = static_cast<uint8_t>(std::floor(255.0 * threshold));
  // Body that is not skin in a 10 cm box (the sleeve, the trunk; distal_centroid.h).
  ForeignBodyProbe foreign;
  if (distal && params_.hand_end_by_body)
    foreign = [this](const Eigen::Vector3d& p) {
      const Eigen::Vector3d h = Eigen::Vector3d::Constant(kForeignProbeHalf);
      const double body = body_iv_.boxMean(p - h, p + h), skin = skin_iv_.boxMean(p - h, p + h);
      return std::clamp(body - skin, 0.0, 1.0);
    };
  // The Voronoi cell of this target among the tracked ones.
  const auto ownCell = [this, s](const Eigen::Vector3d& p) {
    const double d = (p - comps_[s].estimate).squaredNorm();
    for (int t = 0; t < kNumSlots; ++t)
      if (t != s && comps_[t].active && (p - comps_[t].estimate).squaredNorm() < d) return false;
    return true;
  };
  Eigen::Vector3d centre = c.estimate;
  double box_arm = 0.0;  // the first box's arm weight: whether the skin there is an arm at all
  for (int it = 0; it < params_.centroid_iterations; ++it) {
    Eigen::Vector3i lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(0, static_cast<int>(std::ceil((centre[a] - gather_half[a] - g.origin[a]) /
                                                     g.voxel_size - 0.5)));
      hi[a] = std::min(g.dims[a], static_cast<int>(std::floor((centre[a] + gather_half[a] -
                                                               g.origin[a]) / g.voxel_size -
                                                              0.5)) + 1);
      if (hi[a] <= lo[a]) return centre;
    }
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), arm_sum = Eigen::Vector3d::Zero();
    double mass = 0.0, arm_mass = 0.0;
    std::vector<WeightedPoint> voxels;  // the larger box's, for the distal cut
    for (int z = lo.z(); z < hi.z(); ++z)
      for (int y = lo.y(); y < hi.y(); ++y) {
        const uint8_t* row = skin_->data.data() + g.index(0, y, z);
        for (int x = lo.x(); x < hi.x(); ++x) {
          const uint8_t v = row[x];
          if (v <= thr) continue;
          const Eigen::Vector3d p = g.centre(x, y, z);
          if (!ownCell(p)) continue;
          if (distal) {
            voxels.emplace_back(p, double(v));
            arm_sum += v * p;
            arm_mass += v;
          }
          if (((p - centre).cwiseAbs() - half).maxCoeff() > 0.0) continue;  // outside the box
          sum += v * p;
          mass += v;
        }
      }
    double arm = 0.0;  // how surely an arm (distal_centroid.h): blend, so nothing flips
    Eigen::Vector3d end = centre;
    if (distal && arm_mass > 0.0)
      end = distalCentroid(voxels, arm_sum / arm_mass, comps_[kHeadSlot].estimate,
                           params_.hand_distal_length, &arm, foreign);
    if (it == 0) box_arm = arm;
    if (!(mass > 0.0) && !(arm > 0.0)) return centre;
    centre = mass > 0.0 ? Eigen::Vector3d((1.0 - arm) * (sum / mass) + arm * end) : end;
  }
  if (!(box_arm > 0.0) || !(params_.hand_arm_walk > 0.0)) return centre;
  // A target the other hand merged into holds both hands (clasped, folded): their blob is no arm.
  const Component& other = comps_[s == 1 ? 2 : 1];
  if (!other.active && other.merged_into == s) return centre;
  // The box sees an arm. Where its answer lies at the arm's root (the particles on the elbow
  // of a stretched or raised bare arm; the box sees neither end), the hand's end along the
  // skin is reported instead (arm_geodesic.h); where it lies at the hand's end already, the
  // box's answer stands.
  ArmWalkParams walk;
  walk.reach = params_.hand_arm_walk;
  walk.hand_length = params_.hand_distal_length;
  walk.min_arm_length = params_.hand_distal_length + kHandAloneSmear;
  walk.frontal = params_.frontal_direction.normalized();
  const bool remembered = c.hand_end_frame != 0 && c.hand_end_frame + 1 == frames_;
  const ArmEnd arm = armHandEnd(*skin_, thr, c.estimate, half.maxCoeff(), ownCell, walk,
                                comps_[kHeadSlot].estimate, foreign,
                                remembered ? &c.hand_end : nullptr);
  if (!(arm.arm_weight > 0.0)) return centre;
  if (hand_end) *hand_end = arm.hand_end;
  // How much nearer the root end the box's answer is, over 5 cm: a blend, so that an answer
  // half-way along the forearm does not flip between the two from frame to frame.
  const double rootward = ((centre - arm.hand_end).norm() - (centre - arm.other_end).norm()) /
                          kRootwardRamp;
  const double w = std::min({arm.arm_weight, box_arm, std::clamp(rootward, 0.0, 1.0)});
  return (1.0 - w) * centre + w * arm.centroid;
}

void MpfTracker::publish() {
  for (int s = 0; s < kNumSlots; ++s) {
    const Component& c = comps_[s];
    Target& t = targets_[s];
    t.type = c.type;
    t.active = c.active;
    if (c.active) {
      t.id = c.id;
      t.position = c.reported;
      t.weight = c.pi;
    } else {
      t.weight = 0.0;
      if (c.last_id != 0) t.id = c.last_id;
    }
  }
}

const std::vector<Target>& MpfTracker::update(const psfs::ProbabilityVolume& skin,
                                              const psfs::ProbabilityVolume& body, double dt) {
  validateInput(skin, body, dt);
  const Clock::time_point t0 = Clock::now();
  stats_ = Stats();
  skin_ = &skin;
  body_ = &body;
  skin_iv_.build(skin);
  body_iv_.build(body);
  times_.integral_ms = msSince(t0);

  const Clock::time_point t1 = Clock::now();
  time_ += dt;
  ++frames_;
  predict(dt);
  evaluate(0, static_cast<int>(parts_.size()));
  for (int s = 0; s < kNumSlots; ++s)
    if (comps_[s].active) updateEstimate(s, false);  // current modes for the birth distances
  births();
  mixWeights();
  times_.weights_ms = msSince(t1);

  const Clock::time_point t2 = Clock::now();
  reconfigure();
  publish();
  skin_ = nullptr;
  body_ = nullptr;
  times_.reconfigure_ms = msSince(t2);
  times_.total_ms = msSince(t0);
  return targets_;
}

std::vector<MpfTracker::Particle> MpfTracker::particles() const {
  std::vector<Particle> out(parts_.size());
  for (size_t i = 0; i < parts_.size(); ++i) {
    const P& p = parts_[i];
    const bool on = p.active && comps_[p.comp].active;
    out[i].position = p.x;
    out[i].weight = on ? static_cast<float>(comps_[p.comp].pi * p.wn) : 0.f;
    out[i].component = on ? p.comp : -1;
  }
  return out;
}

}  // namespace hand_tracking
