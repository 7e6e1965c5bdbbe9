// Device probe of the CUDA backend (cuda_device.h).
#include <cuda_runtime.h>

#include <string>

#include "../cuda_device_common.h"

namespace psfs {
namespace cuda {

bool compiledIn() { return true; }

namespace {
DeviceInfo probe() {
  DeviceInfo d;
  cudaRuntimeGetVersion(&d.runtime_version);
  cudaDriverGetVersion(&d.driver_version);  // 0 when no driver is installed
  const int want = detail::requestedDeviceIndex();
  if (want < 0) {
    d.reason = "disabled by TABLETOP_CUDA_DEVICE=" + std::to_string(want);
    return d;
  }
  int n = 0;
  const cudaError_t e = cudaGetDeviceCount(&n);
  if (e != cudaSuccess) {
    d.reason = std::string("cudaGetDeviceCount: ") + cudaGetErrorString(e);
    cudaGetLastError();  // clear the sticky error for later calls
    return d;
  }
  if (want >= n) {
    d.reason = "TABLETOP_CUDA_DEVICE=" + std::to_string(want) + " but " + std::to_string(n) +
               " device(s) found";
    return d;
  }
  cudaDeviceProp p{};
  if (cudaGetDeviceProperties(&p, want) != cudaSuccess) {
    d.reason = "cudaGetDeviceProperties failed for device " + std::to_string(want);
    cudaGetLastError();
    return d;
  }
  if (p.major < 7 || (p.major == 7 && p.minor < 5)) {
    d.reason = std::string(p.name) + " is compute " + std::to_string(p.major) + "." +
               std::to_string(p.minor) + "; the backend is built for 7.5 and later";
    return d;
  }
  if (cudaSetDevice(want) != cudaSuccess || cudaFree(nullptr) != cudaSuccess) {
    d.reason = std::string("cannot create a context on ") + p.name;
    cudaGetLastError();
    return d;
  }
  d.usable = true;
  d.index = want;
  d.name = p.name;
  d.compute_major = p.major;
  d.compute_minor = p.minor;
  d.memory_bytes = p.totalGlobalMem;
  d.multiprocessors = p.multiProcessorCount;
  int clock_khz = 0, bus_bits = 0;
  cudaDeviceGetAttribute(&clock_khz, cudaDevAttrMemoryClockRate, want);
  cudaDeviceGetAttribute(&bus_bits, cudaDevAttrGlobalMemoryBusWidth, want);
  d.memory_bandwidth_gbs = 2.0 * clock_khz * 1e3 * (bus_bits / 8.0) / 1e9;  // double data rate
  return d;
}
}  // namespace

const DeviceInfo& device() {
  static const DeviceInfo info = probe();  // thread-safe static initialisation
  return info;
}

}  // namespace cuda
}  // namespace psfs
