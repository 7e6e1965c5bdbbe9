#include <sstream>

#include "psfs_reconstruction/cuda_device.h"

namespace psfs {
namespace cuda {

std::string DeviceInfo::describe() const {
  std::ostringstream s;
  if (!usable) {
    s << "no usable CUDA device (" << reason << ")";
    return s.str();
  }
  s << "CUDA device " << index << ": " << name << ", compute " << compute_major << "." << compute_minor
    << ", " << multiprocessors << " SMs, " << (memory_bytes >> 20) << " MiB, peak "
    << memory_bandwidth_gbs << " GB/s, driver " << driver_version / 1000 << "."
    << (driver_version % 1000) / 10 << ", runtime " << runtime_version / 1000 << "."
    << (runtime_version % 1000) / 10;
  return s.str();
}

}  // namespace cuda
}  // namespace psfs
