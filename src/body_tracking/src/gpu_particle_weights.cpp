#include "body_tracking/gpu_particle_weights.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "cuda/particle_weights_device.h"
#include "plain_part.h"
#include "psfs_reconstruction/cuda_device.h"
#include "scored_parts.h"

namespace body_tracking {

using part_score::PartQuadric;

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

int partsPerParticle(int partition) {
  Part scored[kNumParts];
  return scoredParts(partition, scored);
}

// Module 1 of figure 6.4, on the host: each particle's scored parts and its collision flag,
// written at fixed places (particle-major), so the thread count does not change the result.
// The trunk parts carry their shell as VolumeObservation::partScore builds it.
void buildBatch(const BodyProfile& profile, const ObservationParams& op,
                const std::vector<BodyState>& particles, int partition, int threads,
                PartQuadric* parts, uint8_t* collides) {
  Part scored[kNumParts];
  const int k = scoredParts(partition, scored);
  const int n = static_cast<int>(particles.size());
#pragma omp parallel for num_threads(std::max(1, threads)) schedule(static)
  for (int i = 0; i < n; ++i) {
    BodyParts bp;
    collides[i] = buildScoredParts(profile, particles[i], partition, &bp) ? 1 : 0;
    for (int j = 0; j < k; ++j) {
      const Part p = scored[j];
      parts[static_cast<size_t>(i) * k + j] = plainPart(bp[static_cast<int>(p)], isSkinPart(p), isTrunkPart(p), op);
    }
  }
}

}  // namespace

struct GpuParticleWeights::Impl {
  std::unique_ptr<gpu::ParticleWeightsDevice> device;
  std::string reason;
  bool have_observation = false;
  ObservationParams observation;  // of the last setObservation: the trunk shells
  GpuWeightTimes times;

  void requireUsable() const {
    if (!device) throw std::logic_error("GPU particle weights: not usable: " + reason);
  }
};

GpuParticleWeights::GpuParticleWeights() : impl_(new Impl) {
  const psfs::cuda::DeviceInfo& d = psfs::cuda::device();
  if (!gpu::compiledIn()) {
    impl_->reason = "body_tracking has no CUDA backend in this build (nvcc was not found at build "
                    "time, or TABLETOP_CUDA=OFF)";
  } else if (!d.usable) {
    impl_->reason = d.describe();
  } else {
    try {
      impl_->device = std::make_unique<gpu::ParticleWeightsDevice>(d.index);
    } catch (const std::exception& e) {
      impl_->reason = e.what();
    }
  }
}

GpuParticleWeights::~GpuParticleWeights() = default;

bool GpuParticleWeights::usable() const { return impl_->device != nullptr; }
const std::string& GpuParticleWeights::reason() const { return impl_->reason; }
size_t GpuParticleWeights::deviceAllocations() const {
  return impl_->device ? impl_->device->allocations() : 0;
}
const GpuWeightTimes& GpuParticleWeights::lastTimes() const { return impl_->times; }

void GpuParticleWeights::setObservation(const VolumeObservation& obs) {
  impl_->requireUsable();
  if (!obs.ready()) throw std::logic_error("GPU particle weights: the observation has no volumes");
  const VolumeObservation::RowSums& body = obs.rowSums(false);
  impl_->device->uploadRowSums(rowSumsView(body), rowSumsView(obs.rowSums(true)), body.s0.size(),
                               plainGrid(obs.grid(), obs.params().unknown_likelihood));
  impl_->observation = obs.params();
  impl_->have_observation = true;
}

void GpuParticleWeights::score(const BodyProfile& profile, const std::vector<BodyState>& particles,
                               int partition, int threads, std::vector<double>* scores) {
  impl_->requireUsable();
  if (!impl_->have_observation) throw std::logic_error("GPU particle weights: score() before setObservation()");
  const int n = static_cast<int>(particles.size()), k = partsPerParticle(partition);
  gpu::ParticleWeightsDevice& dev = *impl_->device;
  const auto t0 = std::chrono::steady_clock::now();
  dev.reserve(n, k);
  buildBatch(profile, impl_->observation, particles, partition, threads, dev.stagedParts(),
             dev.stagedCollides());
  const auto t1 = std::chrono::steady_clock::now();
  const double* out = dev.score(n, k);
  scores->assign(out, out + n);
  impl_->times.poses_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  impl_->times.device_ms = msSince(t1);
}

void emulateGpuParticleWeights(const VolumeObservation& obs, const BodyProfile& profile,
                               const std::vector<BodyState>& particles, int partition, int threads,
                               std::vector<double>* scores) {
  if (!obs.ready()) throw std::logic_error("emulateGpuParticleWeights: the observation has no volumes");
  const int n = static_cast<int>(particles.size()), k = partsPerParticle(partition);
  const int items = n * k;
  std::vector<PartQuadric> parts(items);
  std::vector<uint8_t> collides(n);
  buildBatch(profile, obs.params(), particles, partition, threads, parts.data(), collides.data());
  const part_score::ObservationGrid g = plainGrid(obs.grid(), obs.params().unknown_likelihood);
  const part_score::RowSumsView body = rowSumsView(obs.rowSums(false));
  const part_score::RowSumsView blended = rowSumsView(obs.rowSums(true));
  // partScoresKernel: a block per part; its threads' row terms, then thread 0's in-order sum,
  // one chunk of kRowThreads rows at a time.
  std::vector<double> part_scores(items, 0.0);
#pragma omp parallel for num_threads(std::max(1, threads)) schedule(dynamic, 16)
  for (int item = 0; item < items; ++item) {
    if (collides[item / k]) continue;
    const PartQuadric& q = parts[item];
    const part_score::PartSetup s = part_score::setupPart(q, g);
    const part_score::RowSumsView& sums = q.skin ? blended : body;
    const int rows = part_score::rowCount(s);
    part_score::RowTerms terms[gpu::kRowThreads];
    part_score::PartSums acc = {0.0, 0.0, 0.0, 0.0};
    for (int first = 0; first < rows; first += gpu::kRowThreads) {
      const int m = std::min(gpu::kRowThreads, rows - first);
      for (int t = 0; t < m; ++t) terms[t] = part_score::rowTermsAt(s, q, g, sums, first + t);
      for (int j = 0; j < m; ++j) part_score::accumulateRow(terms[j], &acc);
    }
    part_scores[item] = part_score::finishPart(acc, g.unknown, q.shell_weight);
  }
  // particleScoresKernel: a thread per particle.
  scores->resize(n);
  for (int i = 0; i < n; ++i)
    (*scores)[i] = part_score::particleScore(&part_scores[static_cast<size_t>(i) * k], k, collides[i] != 0);
}

}  // namespace body_tracking
