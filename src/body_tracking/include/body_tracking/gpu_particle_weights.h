// The PAPF's particle weights on the GPU (issue 20; thesis 6.4, figure 6.4): the same scores as
// Papf::scoreState, to the last bit, for a whole particle set at once.
//  1. part poses (host, `threads` OpenMP threads): forward kinematics, the scored parts'
//     quadrics and the self-collision test, exactly as the CPU path builds them. On the host
//     because the collision test needs them there anyway (the thesis ran it on the CPU too),
//     and because the device's sin/cos differ from glibc's in the last bits, which would move
//     every quadric and with it the scores;
//  2.-3. per part (one CUDA block per particle and part): each thread one voxel row's partial
//     weights from the row prefix sums, added in row order;
//  4. per particle (one thread each): the sum over its parts, 0 for a self-colliding pose.
// The frame's row sums are uploaded once per frame; device and pinned buffers grow only when
// sizes grow (deviceAllocations()). Without a usable device (no nvcc at build time, no GPU, or
// TABLETOP_CUDA_DEVICE=-1) usable() is false and reason() says why; Papf then scores on the CPU
// (PapfParams::gpu_weights).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "body_tracking/body_profile.h"
#include "body_tracking/body_state.h"
#include "body_tracking/volume_observation.h"

namespace body_tracking {

struct GpuWeightTimes {
  double poses_ms = 0;   // host: part poses and collision tests into pinned memory
  double device_ms = 0;  // upload, kernels, download
};

class GpuParticleWeights {
 public:
  GpuParticleWeights();  // never throws: see usable()
  ~GpuParticleWeights();
  GpuParticleWeights(const GpuParticleWeights&) = delete;
  GpuParticleWeights& operator=(const GpuParticleWeights&) = delete;

  bool usable() const;
  const std::string& reason() const;  // why not usable ("" when usable)

  // This frame's observation (after its setVolumes): uploads its row sums. Throws
  // std::logic_error when not usable or the observation has no volumes, std::runtime_error on
  // CUDA errors.
  void setObservation(const VolumeObservation& observation);
  // scores[i] = Papf::scoreState(particles[i], partition) for the last observation set:
  // partition 0 trunk, 1 left arm, 2 right arm, < 0 all parts. Throws as setObservation.
  void score(const BodyProfile& profile, const std::vector<BodyState>& particles, int partition,
             int threads, std::vector<double>* scores);

  size_t deviceAllocations() const;  // cudaMalloc + cudaMallocHost calls so far
  const GpuWeightTimes& lastTimes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The GPU computation run on the host in every build: the same part poses, the same per-row
// function, the rows added in the kernel's chunks and order, the same per-particle sum. The
// tests hold it to Papf::scoreState where no device exists.
void emulateGpuParticleWeights(const VolumeObservation& observation, const BodyProfile& profile,
                               const std::vector<BodyState>& particles, int partition, int threads,
                               std::vector<double>* scores);

}  // namespace body_tracking
