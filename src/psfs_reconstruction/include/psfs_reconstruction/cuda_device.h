// Whether the CUDA backend (issue 20) can run here. The backend is compiled only where nvcc
// was found at build time (TABLETOP_CUDA, tabletop_common-extras.cmake); at run time it needs a
// device and a driver new enough for the CUDA runtime it was built with. Everything else runs
// on the CPU path, which gives the same results.
#pragma once

#include <cstddef>
#include <string>

namespace psfs {
namespace cuda {

struct DeviceInfo {
  bool usable = false;
  std::string reason;         // why not usable ("" when usable)
  int index = -1;             // CUDA device index in use
  std::string name;           // e.g. "NVIDIA H200"
  int compute_major = 0, compute_minor = 0;
  size_t memory_bytes = 0;
  int multiprocessors = 0;
  double memory_bandwidth_gbs = 0.0;  // theoretical peak (bus width x memory clock)
  int driver_version = 0, runtime_version = 0;  // 13000 = 13.0
  std::string describe() const;  // one line for logs and reports
};

// True if this build contains the CUDA kernels.
bool compiledIn();
// Probes the device once (thread safe, never throws) and remembers the answer. Device index:
// the environment variable TABLETOP_CUDA_DEVICE (default 0). TABLETOP_CUDA_DEVICE=-1 makes the
// device unusable on purpose, to run the fallback on a GPU machine.
const DeviceInfo& device();

}  // namespace cuda
}  // namespace psfs
