// Private: the device half of GpuParticleWeights (gpu_particle_weights.h): its buffers and
// kernels are in particle_weights.cu, or, in a build without nvcc, in
// ../particle_weights_unavailable.cpp, whose constructor throws. Plain types only (part_score.h),
// so the C++ compiler builds the caller and nvcc only this half.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "../part_score.h"

namespace body_tracking {
namespace gpu {

// Threads per part block: each computes one voxel row's terms; thread 0 then adds a chunk of
// this many rows' terms in row order (the host emulation walks the same chunks).
constexpr int kRowThreads = 64;

// True if this build contains the kernels.
bool compiledIn();

class ParticleWeightsDevice {
 public:
  // Selects `device_index` and creates the stream; throws std::runtime_error on CUDA errors.
  explicit ParticleWeightsDevice(int device_index);
  ~ParticleWeightsDevice();
  ParticleWeightsDevice(const ParticleWeightsDevice&) = delete;
  ParticleWeightsDevice& operator=(const ParticleWeightsDevice&) = delete;

  // The frame's row sums (`count` doubles in each of the six arrays) through pinned staging to
  // the device; the copy overlaps with the host's part poses for the first score().
  void uploadRowSums(const part_score::RowSumsView& body, const part_score::RowSumsView& blended,
                     size_t count, const part_score::ObservationGrid& grid);
  // Pinned staging for the next score(): particles x parts_per_particle parts (particle-major)
  // and one collision flag per particle, valid until the next reserve().
  void reserve(int particles, int parts_per_particle);
  part_score::PartQuadric* stagedParts();
  uint8_t* stagedCollides();
  // Uploads the staged particles, runs the part and the particle kernels, and returns the
  // particles' scores (pinned, valid until the next call). Throws std::runtime_error.
  const double* score(int particles, int parts_per_particle);
  // Device and pinned host allocations so far (buffers grow only when sizes grow).
  size_t allocations() const;

 private:
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace gpu
}  // namespace body_tracking
