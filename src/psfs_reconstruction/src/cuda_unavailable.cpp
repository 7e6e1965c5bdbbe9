// The CUDA backend's entry points in a build without nvcc: nothing is compiled in, and every
// caller falls back to the CPU path.
#include <stdexcept>

#include "psfs_reconstruction/cuda_device.h"
#include "pixel_pipeline_device.h"
#include "volume_fusion.h"

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

// GpuPsfsFusion's and GpuEvidenceBuffer's backends: never constructed (usable() is false), so
// the rest is unreachable.
struct CudaEvidence::Impl {};
CudaEvidence::CudaEvidence() : impl_(nullptr) {
  throw std::runtime_error("psfs::GpuEvidenceBuffer: " + cuda::device().describe());
}
CudaEvidence::~CudaEvidence() { delete impl_; }
void CudaEvidence::upload(const HostEvidenceView*, int, KernelView*, void*) {}
size_t CudaEvidence::allocations() const { return 0; }

struct CudaVolumeFusion::Impl {
  StageTimes times;
};

CudaVolumeFusion::CudaVolumeFusion() : impl_(nullptr) {
  throw std::runtime_error("psfs::GpuPsfsFusion: " + cuda::device().describe());
}
CudaVolumeFusion::~CudaVolumeFusion() { delete impl_; }
void CudaVolumeFusion::uploadTable(const TableView&, int, bool) {}
void CudaVolumeFusion::projectTable(const ProjectionCamera*, int, const ProjectionGrid&, bool) {}
void CudaVolumeFusion::fuse(const PsfsRowParams&, int, bool, const HostEvidenceView*, const KernelView*,
                            uint8_t*, size_t) {}
size_t CudaVolumeFusion::allocations() const { return 0; }
const StageTimes& CudaVolumeFusion::times() const {
  static const StageTimes none;
  return none;
}

}  // namespace detail
}  // namespace psfs
