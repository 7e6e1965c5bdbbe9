// GPU tests skip, saying why, where body_tracking's CUDA backend is not compiled in or no device
// is usable (psfs_reconstruction's test/gpu_test_support.h is private to that package).
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "body_tracking/gpu_particle_weights.h"

namespace body_tracking {

// "" where the GPU particle weights are usable, else why not (probed once).
inline const std::string& gpuSkipReason() {
  static const std::string reason = [] {
    const GpuParticleWeights probe;
    return probe.usable() ? std::string() : probe.reason();
  }();
  return reason;
}

}  // namespace body_tracking

#define BODY_REQUIRE_GPU()                                                              \
  do {                                                                                  \
    if (!body_tracking::gpuSkipReason().empty())                                        \
      GTEST_SKIP() << "GPU test skipped: " << body_tracking::gpuSkipReason();           \
  } while (0)
