// Private: DeviceInfo::describe and the device-index choice, shared by the CUDA build and the stub.
#pragma once

#include <cstdlib>
#include <sstream>

#include "psfs_reconstruction/cuda_device.h"

namespace psfs {
namespace cuda {
namespace detail {

// TABLETOP_CUDA_DEVICE: the device index (default 0); negative disables the device.
inline int requestedDeviceIndex() {
  const char* e = std::getenv("TABLETOP_CUDA_DEVICE");
  if (!e || !*e) return 0;
  return std::atoi(e);
}

}  // namespace detail
}  // namespace cuda
}  // namespace psfs
