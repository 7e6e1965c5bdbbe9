#include "body_tracking/papf.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include <Eigen/Cholesky>

#include "body_tracking/arm_ik.h"
#include "body_tracking/state_tangent.h"
#include "scored_parts.h"

namespace body_tracking {

using Eigen::Vector3d;

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Survival rate d(beta) / N of weights exp(beta * x_i) (thesis 5.2.1), computed stably.
double survivalRate(const std::vector<double>& x, double beta) {
  const double mx = *std::max_element(x.begin(), x.end());
  double s1 = 0, s2 = 0;
  for (double v : x) {
    const double e = std::exp(beta * (v - mx));
    s1 += e;
    s2 += e * e;
  }
  return s1 * s1 / (s2 * static_cast<double>(x.size()));
}

}  // namespace

Papf::Papf(const BodyProfile& profile, const PapfParams& params)
    : base_profile_(profile),
      profile_(profile),
      params_(params),
      girth_(params.shape),
      arms_(params.arm_length),
      observation_(params.observation),
      rng_(params.seed) {
  profile_.validate();
  params_.validate();
  beta_.fill(1.0);
  if (params_.gpu_weights) {
    gpu_ = std::make_unique<GpuParticleWeights>();
    if (!gpu_->usable()) dropGpu(gpu_->reason());
  }
}

void Papf::dropGpu(const std::string& why) {
  gpu_warning_ = "gpu_weights: " + why + "; the particle weights run on the CPU";  // `why` may be gpu_'s
  gpu_.reset();
}

void Papf::reset() {
  estimate_ = BodyEstimate();
  velocity_.setZero();
  particles_.clear();
  weights_.clear();
  bad_frames_ = 0;
  beta_.fill(1.0);
  restartShape();
}

void Papf::restartShape() {  // a new track, perhaps a new person: the profile as given
  girth_.reset();
  arms_.reset();
  profile_ = base_profile_;
}

void Papf::refineShape() {
  if (!girth_.refining() && !arms_.refining()) return;
  // This frame's pose, tracked with the shape so far, votes; the next frame uses the best.
  const double arm_factor = arms_.factor();
  girth_.add(observation_, base_profile_, estimate_.state);
  const BodyProfile girthed = TrunkGirth::scaled(base_profile_, girth_.factor());
  arms_.add(observation_, girthed, estimate_.state, estimate_.hands);
  profile_ = ArmLength::scaled(girthed, arms_.factor());
  // The reported joints follow the profile in use, so that the frames and profile() drawn
  // together (markers, masks) agree; only the arms' length moves a joint.
  if (arms_.factor() != arm_factor) {
    estimate_.frames = forwardKinematics(profile_, estimate_.state);
    for (int i = 0; i < 2; ++i)  // a hand the skin did not place is the model's
      if (!estimate_.hands.from_skin[i]) estimate_.hands.position[i] = estimate_.frames.hand[i];
  }
}

static_assert(Papf::kPartitions == kPapfPartitions, "scored_parts.h lists the partitions");

double Papf::scoreState(const BodyState& s, int partition) const {
  return scorePartition(observation_, profile_, s, partition);
}

void Papf::scoreAll(int partition) {
  if (gpu_) {
    try {
      gpu_->score(profile_, particles_, partition, params_.threads, &scores_);
      return;
    } catch (const std::runtime_error& e) {
      dropGpu(e.what());
    }
  }
  const int n = static_cast<int>(particles_.size());
  scores_.resize(n);
#pragma omp parallel for num_threads(std::max(1, params_.threads)) schedule(dynamic, 8)
  for (int i = 0; i < n; ++i) scores_[i] = scoreState(particles_[i], partition);
}

void Papf::resampleUniform() {
  const int n = static_cast<int>(particles_.size());
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double u0 = uni(rng_) / n;
  scratch_.resize(n);
  for (int i = 0; i < n; ++i) scratch_[i] = particles_[drawIndex(u0 + static_cast<double>(i) / n)];
  particles_.swap(scratch_);
  weights_.assign(n, 1.0 / n);
  for (int i = 0; i < n; ++i) cumulative_[i] = (i + 1.0) / n;
}

double Papf::solveBeta(double previous) {
  // x_i = s * w'_i with w' the min-shifted, normalised scores (thesis 5.2.3). The survival
  // rate falls monotonically with beta, so the root in log(beta) is unique.
  const int n = static_cast<int>(scores_.size());
  const double mn = *std::min_element(scores_.begin(), scores_.end());
  double sum = 0;
  for (double s : scores_) sum += s - mn;
  // weights_ holds x until layerWeights turns it into the layer's weights.
  std::vector<double>& x = weights_;
  x.resize(n);
  for (int i = 0; i < n; ++i) x[i] = sum > 0 ? params_.weight_scale * (scores_[i] - mn) / sum : 0;
  const double target = params_.survival_rate;
  // f(log beta) = survival rate - target falls with beta: bracket the root from last frame's
  // exponent, then the Illinois method (regula falsi that halves a stale end's value), which
  // needs ~8 evaluations where bisection needed ~32 for the same 1e-9.
  const auto f = [&](double lb) { return survivalRate(x, std::exp(lb)) - target; };
  double lo = std::log(std::max(previous, 1e-6)) - 2, hi = lo + 4;
  double flo = f(lo), fhi = f(hi);
  for (int k = 0; k < 30 && flo < 0; ++k) flo = f(lo -= 2);
  for (int k = 0; k < 30 && fhi > 0; ++k) fhi = f(hi += 2);
  if (flo <= 0) return std::exp(lo);  // no sign change (e.g. all scores equal)
  if (fhi >= 0) return std::exp(hi);
  double mid = 0.5 * (lo + hi);
  int side = 0;
  for (int it = 0; it < 100 && hi - lo > 1e-9; ++it) {
    mid = (lo * fhi - hi * flo) / (fhi - flo);
    const double fm = f(mid);
    if (fm == 0) break;
    if (fm > 0) {
      lo = mid, flo = fm;
      if (side > 0) fhi *= 0.5;
      side = 1;
    } else {
      hi = mid, fhi = fm;
      if (side < 0) flo *= 0.5;
      side = -1;
    }
    if (std::abs(fm) < 1e-12) break;
  }
  return std::exp(mid);
}

void Papf::layerWeights(double beta) {
  // weights_ holds x_i = s * w'_i (solveBeta); turn it into normalised exp(beta x_i).
  const double mx = *std::max_element(weights_.begin(), weights_.end());
  double sum = 0;
  for (double& w : weights_) sum += (w = std::exp(beta * (w - mx)));
  cumulative_.resize(weights_.size());
  double c = 0;
  for (size_t i = 0; i < weights_.size(); ++i) {
    weights_[i] /= sum;
    cumulative_[i] = (c += weights_[i]);
  }
  cumulative_.back() = 1.0;
}

int Papf::drawIndex(double u) const {
  const auto it = std::lower_bound(cumulative_.begin(), cumulative_.end(), u);
  return static_cast<int>(std::min<ptrdiff_t>(it - cumulative_.begin(), cumulative_.size() - 1));
}

void Papf::crossoverAndDiffuse(int partition) {
  const PartitionSpec& ps = kPartitionSpecs[partition];
  const int n = static_cast<int>(particles_.size());
  // The diffusion covariance, over the partition's coordinates only (the other chains were
  // settled by their own layers), in the tangent space at the best particle: the spread does
  // not depend on the centre to first order, so this saves the weighted mean's own pass of
  // tangents (a third of the non-observation time, measured).
  const int best = static_cast<int>(std::max_element(weights_.begin(), weights_.end()) - weights_.begin());
  const BodyState& centre = particles_[best];
  const int threads = std::max(1, params_.threads);
  using Sub = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxPartitionDims, 1>;
  struct Draw {
    int a, b, g, d;
    Sub z;
  };
  std::vector<Sub> t(n);
  std::vector<Draw> draws(n);
  // Every random number is drawn by one thread, in a fixed order, so the result does not depend
  // on the thread count; the draws need only the weights, so they run beside the tangents.
#pragma omp parallel num_threads(threads)
  {
#pragma omp single nowait
    {
      std::uniform_real_distribution<double> uni(0.0, 1.0);
      std::normal_distribution<double> normal(0.0, 1.0);
      std::uniform_int_distribution<int> cut(0, ps.count);
      for (Draw& dr : draws) {
        dr.a = drawIndex(uni(rng_));
        dr.b = drawIndex(uni(rng_));
        dr.g = cut(rng_);
        dr.d = cut(rng_);
        if (dr.g > dr.d) std::swap(dr.g, dr.d);
        dr.z.resize(ps.count);
        for (int j = 0; j < ps.count; ++j) dr.z[j] = normal(rng_);
      }
    }
#pragma omp for schedule(dynamic, 16)
    for (int i = 0; i < n; ++i)
      t[i] = weights_[i] > 0 ? Sub(toTangent(centre, particles_[i], ps.first, ps.count).segment(ps.first, ps.count))
                             : Sub(Sub::Zero(ps.count));
  }
  Sub tm = Sub::Zero(ps.count);
  for (int i = 0; i < n; ++i) tm += weights_[i] * t[i];
  using SubCov = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxPartitionDims, kMaxPartitionDims>;
  SubCov cov = SubCov::Zero(ps.count, ps.count);
  for (int i = 0; i < n; ++i) {
    const Sub dlt = t[i] - tm;
    cov += weights_[i] * dlt * dlt.transpose();
  }
  cov = params_.diffusion * cov;
  cov.diagonal().array() += 1e-10;
  const SubCov L = Eigen::LLT<SubCov>(cov).matrixL();
  scratch_.resize(n);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int i = 0; i < n; ++i) {
    const Draw& dr = draws[i];
    BodyState child = particles_[dr.a];
    for (int j = dr.g; j < dr.d; ++j) child[ps.first + j] = particles_[dr.b][ps.first + j];
    Tangent step = Tangent::Zero();
    step.segment(ps.first, ps.count) = L * dr.z;
    child = fromTangent(child, step, ps.first, ps.count);
    limits_.enforce(&child, ps.first, ps.count);
    scratch_[i] = child;
  }
  particles_.swap(scratch_);
}

void Papf::propagate() {
  // Systematic resampling of the last frame's final weighted set, then uniform process noise
  // in the tangent coordinates.
  const int n = params_.particles;
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  scratch_.resize(n);
  const double u0 = uni(rng_) / n;
  Tangent b;
  b << params_.noise_translation, params_.noise_translation, params_.noise_translation,
      params_.noise_torso_rotation, params_.noise_torso_rotation, params_.noise_torso_rotation,
      params_.noise_spine, params_.noise_head, params_.noise_upper_arm, params_.noise_upper_arm,
      params_.noise_shoulder_shift, params_.noise_forearm, params_.noise_forearm,
      params_.noise_upper_arm, params_.noise_upper_arm, params_.noise_shoulder_shift,
      params_.noise_forearm, params_.noise_forearm;
  const Tangent drift = params_.velocity_damping * velocity_;
  // Draws first, in a fixed order; the conversions in parallel; the arm proposals (which draw
  // too) in order; the limits in parallel.
  std::vector<int> from(n), propose(n, -1);
  std::vector<Tangent> z(n);
  for (int i = 0; i < n; ++i) {
    from[i] = drawIndex(u0 + static_cast<double>(i) / n);
    for (int j = 0; j < kTangentDim; ++j) z[i][j] = drift[j] + b[j] * (2.0 * uni(rng_) - 1.0);
    if (uni(rng_) < params_.proposal_fraction) propose[i] = uni(rng_) < 0.5 ? 0 : 1;
  }
  const int threads = std::max(1, params_.threads);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int i = 0; i < n; ++i) scratch_[i] = fromTangent(particles_[from[i]], z[i]);
  for (int i = 0; i < n; ++i)
    if (propose[i] >= 0) proposeArm(static_cast<Side>(propose[i]), &scratch_[i], &uni);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int i = 0; i < n; ++i) limits_.enforce(&scratch_[i]);
  particles_.swap(scratch_);
}

void Papf::collectSkinTargets(const Vector3d* head) {
  skin_targets_.clear();
  skin_cumulative_.clear();
  const psfs::VoxelGrid& g = observation_.grid();
  const std::vector<float>& skin = observation_.skinLikelihood();
  const bool have_head = head != nullptr;
  const double clear2 = params_.proposal_head_clearance * params_.proposal_head_clearance;
  double c = 0;
  for (size_t i = 0; i < skin.size(); ++i) {
    if (skin[i] <= 0.5f) continue;
    const Vector3d p = g.centre(i);
    if (have_head && (p - *head).squaredNorm() < clear2) continue;
    skin_targets_.push_back(p);
    skin_cumulative_.push_back(c += skin[i] - 0.5);
  }
}

bool Papf::proposeArm(Side side, BodyState* s, std::uniform_real_distribution<double>* uni) {
  if (skin_targets_.empty()) return false;
  const int i = static_cast<int>(side);
  const BodyFrames f = forwardKinematics(profile_, *s);
  const double reach = profile_.upper_arm + profile_.forearm + profile_.wrist_to_hand;
  for (int attempt = 0; attempt < 6; ++attempt) {
    const double u = (*uni)(rng_) * skin_cumulative_.back();
    const size_t k = std::min<size_t>(
        std::lower_bound(skin_cumulative_.begin(), skin_cumulative_.end(), u) - skin_cumulative_.begin(),
        skin_targets_.size() - 1);
    const Vector3d& t = skin_targets_[k];
    if ((t - f.shoulder[i]).norm() > reach) continue;
    // Elbows hang down, a little out and back: the pole is below the shoulder, jittered.
    const double sx = side == Side::LEFT ? -1.0 : 1.0;
    const Vector3d pole_c(sx * (0.1 + 0.3 * (*uni)(rng_)), -0.3 * (*uni)(rng_), -0.5);
    solveArmIk(profile_, side, t, f.shoulder[i] + f.chest.linear() * pole_c, s);
    return true;
  }
  return false;
}

void Papf::anneal(bool from_previous) {
  if (from_previous) propagate();
  if (params_.reseed_arms) seed_ = particles_;  // the arms' own spread (PapfParams::reseed_arms)
  const int layers = params_.layers;
  for (int k = 0; k < kPartitions; ++k) {
    if (k > 0) resampleUniform();
    if (k > 0 && params_.reseed_arms) {
      const PartitionSpec& ps = kPartitionSpecs[k];
      for (size_t i = 0; i < particles_.size(); ++i)
        for (int j = ps.first; j < ps.first + ps.count; ++j) particles_[i][j] = seed_[i][j];
    }
    for (int l = layers - 1; l >= 0; --l) {
      const auto t0 = std::chrono::steady_clock::now();
      scoreAll(k);
      times_.observation_ms += msSince(t0);
      double& beta = beta_[8 * k + l];
      beta = solveBeta(beta);
      layerWeights(beta);
      if (l > 0) crossoverAndDiffuse(k);
    }
  }
  finishEstimate();
}

void Papf::finishEstimate() {
  const int n = static_cast<int>(particles_.size());
  const int best = static_cast<int>(std::max_element(weights_.begin(), weights_.end()) - weights_.begin());
  estimate_.state = weightedMean(particles_.data(), weights_.data(), n, particles_[best], 2,
                                 std::max(1, params_.threads));
  limits_.enforce(&estimate_.state);
  estimate_.frames = forwardKinematics(profile_, estimate_.state);
  const BodyParts parts = buildParts(profile_, estimate_.frames);
  estimate_.score = observation_.score(parts, &estimate_.part_scores) / kNumParts;
  double trunk = 0;
  for (Part p : {Part::ABDOMEN, Part::CHEST, Part::HEAD})
    trunk += observation_.partMean(parts[static_cast<int>(p)], isSkinPart(p), isTrunkPart(p));
  estimate_.trunk_score = trunk / 3.0;
  estimate_.tracking = true;
  const int layers = params_.layers;
  for (int k = 0; k < kPartitions; ++k)
    for (int l = 0; l < 8; ++l)
      estimate_.layer_beta[8 * k + l] = l < layers ? beta_[8 * k + layers - 1 - l] : 0.0;
}

bool Papf::initialise() {
  const psfs::VoxelGrid& g = observation_.grid();
  const std::vector<float>& body = observation_.bodyLikelihood();
  // The head: the highest layer holding a few occupied voxels is its top (hands above the head
  // are rare at a desk, and a restart fixes the exception); its centre is the centroid of the
  // occupied voxels in the 20 cm below.
  int top = -1;
  for (int z = g.dims.z() - 1; z >= 0 && top < 0; --z) {
    int count = 0;
    for (int y = 0; y < g.dims.y(); ++y)
      for (int x = 0; x < g.dims.x(); ++x) count += body[g.index(x, y, z)] > 0.5f;
    if (count >= 3) top = z;
  }
  if (top < 0) return false;
  const double top_z = g.origin.z() + (top + 1) * g.voxel_size;
  Vector3d sum = Vector3d::Zero();
  double wsum = 0;
  for (int z = 0; z <= top; ++z) {
    const Vector3d c0 = g.centre(0, 0, z);
    if (c0.z() < top_z - 0.20) continue;
    for (int y = 0; y < g.dims.y(); ++y)
      for (int x = 0; x < g.dims.x(); ++x) {
        const float p = body[g.index(x, y, z)];
        if (p > 0.5f) {
          sum += p * g.centre(x, y, z);
          wsum += p;
        }
      }
  }
  if (wsum <= 0) return false;
  const Vector3d head = sum / wsum;
  collectSkinTargets(&head);  // the face is not a hand
  // Sitting upright below that head: the pelvis is (spine + neck + head centre height) lower.
  const Vector3d pelvis = head - Vector3d(0, profile_.head_centre_forward,
                                          profile_.spine_height + profile_.neck_height +
                                              profile_.head_centre_height);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  particles_.resize(params_.particles);
  for (BodyState& s : particles_) {
    s.fill(0.0);
    s[dof::TORSO_X] = pelvis.x() + 0.03 * u(rng_);
    s[dof::TORSO_Y] = pelvis.y() - 0.03 + 0.06 * u(rng_);
    s[dof::TORSO_Z] = pelvis.z() + 0.04 * u(rng_);
    s[dof::TORSO_ROLL] = -0.1 + 0.2 * u(rng_);
    s[dof::TORSO_YAW] = 0.2 * u(rng_);
    s[dof::SPINE_BEND] = 0.15 + 0.15 * u(rng_);
    s[dof::HEAD_YAW] = 0.3 * u(rng_);
    for (Side side : {Side::LEFT, Side::RIGHT}) {
      s[armDof(side, 0)] = -0.9 + 1.1 * u(rng_);
      s[armDof(side, 1)] = 0.7 * u(rng_);
      s[armDof(side, 2)] = 0.01 * u(rng_);
      s[armDof(side, 3)] = 1.35 + 1.05 * u(rng_);
      s[armDof(side, 4)] = 1.0 * u(rng_);
    }
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    for (Side side : {Side::LEFT, Side::RIGHT})
      if (uni(rng_) < 0.5) proposeArm(side, &s, &uni);
    limits_.enforce(&s);
  }
  beta_.fill(1.0);
  for (int run = 0; run < std::max(1, params_.init_runs); ++run) anneal(run > 0);
  return true;
}

void Papf::startAt(const BodyState& state) {
  particles_.assign(params_.particles, state);
  weights_.assign(params_.particles, 1.0 / params_.particles);
  cumulative_.resize(params_.particles);
  for (int i = 0; i < params_.particles; ++i) cumulative_[i] = (i + 1.0) / params_.particles;
  estimate_ = BodyEstimate();
  estimate_.tracking = true;
  estimate_.state = state;
  velocity_.setZero();
  bad_frames_ = 0;
  restartShape();
}

const BodyEstimate& Papf::update(const psfs::ProbabilityVolume& body,
                                 const psfs::ProbabilityVolume* skin) {
  const auto t0 = std::chrono::steady_clock::now();
  times_ = PapfTimes();
  observation_.setVolumes(body, skin, params_.threads);
  if (gpu_) {
    try {
      gpu_->setObservation(observation_);
    } catch (const std::runtime_error& e) {
      dropGpu(e.what());
    }
  }
  const bool person = observation_.occupiedVoxels() >= params_.min_person_voxels;
  collectSkinTargets(estimate_.tracking ? &estimate_.frames.head_centre : nullptr);
  estimate_.started = false;
  if (!estimate_.tracking) {
    velocity_.setZero();
    if (person && initialise()) {
      estimate_.started = true;
      estimate_.frames_tracked = 0;
      bad_frames_ = 0;
    }
  } else {
    previous_state_ = estimate_.state;
    anneal(true);
    velocity_ = toTangent(previous_state_, estimate_.state);
  }
  if (estimate_.tracking) {
    if (skin) {
      estimate_.hands = refineHands(*skin, estimate_.frames, params_.hands);
    } else {
      estimate_.hands = RefinedHands();
      estimate_.hands.position = estimate_.frames.hand;
    }
    refineShape();
    ++estimate_.frames_tracked;
    // The trunk judges a loss: an arm that leaves the workspace reads the unknown likelihood
    // outside the grid (and a restart would not find it there either).
    bad_frames_ = (!person || estimate_.trunk_score < params_.lost_score) ? bad_frames_ + 1 : 0;
    if (bad_frames_ >= params_.lost_frames) reset();
  }
  estimate_.trunk_girth = girth_.factor();
  estimate_.arm_length = arms_.factor();
  times_.total_ms = msSince(t0);
  return estimate_;
}

}  // namespace body_tracking
