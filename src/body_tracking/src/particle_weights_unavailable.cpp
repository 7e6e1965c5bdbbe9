// The GPU particle weights' device half in a build without nvcc: nothing is compiled in, the
// constructor throws, and GpuParticleWeights reports itself unusable (Papf stays on the CPU).
#include <stdexcept>

#include "cuda/particle_weights_device.h"

namespace body_tracking {
namespace gpu {

bool compiledIn() { return false; }

struct ParticleWeightsDevice::State {};

namespace {
[[noreturn]] void unavailable() {
  throw std::runtime_error(
      "body_tracking has no CUDA backend in this build (nvcc was not found at build time, or "
      "TABLETOP_CUDA=OFF)");
}
}  // namespace

ParticleWeightsDevice::ParticleWeightsDevice(int) { unavailable(); }
ParticleWeightsDevice::~ParticleWeightsDevice() = default;
void ParticleWeightsDevice::uploadRowSums(const part_score::RowSumsView&, const part_score::RowSumsView&,
                                          size_t, const part_score::ObservationGrid&) {
  unavailable();
}
void ParticleWeightsDevice::reserve(int, int) { unavailable(); }
part_score::PartQuadric* ParticleWeightsDevice::stagedParts() { unavailable(); }
uint8_t* ParticleWeightsDevice::stagedCollides() { unavailable(); }
const double* ParticleWeightsDevice::score(int, int) { unavailable(); }
size_t ParticleWeightsDevice::allocations() const { return 0; }

}  // namespace gpu
}  // namespace body_tracking
