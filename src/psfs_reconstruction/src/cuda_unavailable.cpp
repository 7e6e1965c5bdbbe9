// The CUDA backend's entry points in a build without nvcc: nothing is compiled in, and every
// caller falls back to the CPU path.
#include "psfs_reconstruction/cuda_device.h"
#include "pixel_pipeline_device.h"

namespace psfs {
namespace cuda {

bool compiledIn() { return false; }

const DeviceInfo& device() {
  static const DeviceInfo info = [] {
    DeviceInfo d;
    d.reason = "this build has no CUDA backend (nvcc was not found at build time, or TABLETOP_CUDA=OFF)";
    return d;
  }();
  return info;
}

}  // namespace cuda

namespace detail {
// GpuPixelStage: no device side in this build (GpuPixelStage::usable() is false).
std::unique_ptr<PixelPipelineDevice> makePixelPipelineDevice() { return nullptr; }
}  // namespace detail

}  // namespace psfs
