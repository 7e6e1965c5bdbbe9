// Private: the device side of GpuPixelStage (gpu_pixel_stage.h), behind a plain interface so the
// stage itself (validation, cv::Mat staging, statistics) is ordinary C++ in every build, and
// nvcc compiles only memory management, streams and the kernels: cuda/pixel_pipeline.cu. A build
// without nvcc has no implementation (cuda_unavailable.cpp returns none).
//
// Per camera the device holds its rgb image, likelihood image, mask, the eight background planes,
// the gain histogram and peak, the classification totals and both classes' evidence (terms and
// pairs); the host side holds pinned staging buffers for what travels each frame. Everything is
// allocated by resize() and only when the camera count or a size changes (two allocations per
// camera: one device block, one pinned block), counted by allocations(). Work is queued on the
// camera's own stream; synchronize() waits for all of them. Every failure throws
// std::runtime_error with the CUDA error string.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "pixel_arithmetic.h"

namespace psfs {
namespace detail {

struct PixelCameraBuffers {
  int width = 0, height = 0;
  // device
  std::uint8_t* rgb = nullptr;         // 3 * width * height
  std::uint8_t* likelihood = nullptr;  // 2 * width * height (CV_8UC2 layout)
  std::uint8_t* mask = nullptr;        // width * height (update mask or active mask)
  MutableBackgroundPlanes background;  // width * height floats each
  int* gain_histogram = nullptr;       // pixel::kGainBins
  pixel::GainPeak* gain_peak = nullptr;
  pixel::ClassifyTotals* totals = nullptr;
  std::int16_t* terms[2] = {nullptr, nullptr};    // body, skin: width * height + kTermGuard
  std::uint16_t* pairs[2] = {nullptr, nullptr};   // body, skin: pixel::EvidenceArgs::pairCount()
  // pinned host staging
  std::uint8_t* host_rgb = nullptr;
  std::uint8_t* host_mask = nullptr;
  std::uint8_t* host_likelihood = nullptr;
  pixel::ClassifyTotals* host_totals = nullptr;
  pixel::GainPeak* host_gain_peak = nullptr;
};

struct ImageSize {
  int width = 0, height = 0;
  bool operator==(const ImageSize& o) const { return width == o.width && height == o.height; }
};

class PixelPipelineDevice {
 public:
  virtual ~PixelPipelineDevice() = default;
  // Buffers for these cameras; reallocates only if the sizes differ from the current ones.
  virtual void resize(const std::vector<ImageSize>& sizes) = 0;
  virtual const PixelCameraBuffers& buffers(int camera) const = 0;
  virtual std::size_t allocations() const = 0;

  // Synchronous copies of the eight planes (pageable host memory; not per frame).
  virtual void uploadPlanes(int camera, const BackgroundPlanes& host) = 0;
  virtual void downloadPlanes(int camera, const MutableBackgroundPlanes& host) = 0;
  // Synchronous copy of any device range (diagnostics, tests).
  virtual void copyToHost(void* host, const void* device, std::size_t bytes) = 0;

  // Queued on the camera's stream. classify: host_rgb -> rgb, then the gain histogram and peak
  // (if gain is set), the classification (its totals reset first), and the totals, the gain
  // peak and (read_likelihood) the likelihood back to the pinned buffers.
  virtual void classify(int camera, const pixel::ClassifyArgs& args, const pixel::GainArgs* gain,
                        bool read_likelihood) = 0;
  // A camera without an image: its likelihood is set to 0.
  virtual void clearLikelihood(int camera) = 0;
  // upload_mask: host_mask -> mask first. pairs: also the pair image.
  virtual void evidence(int camera, const pixel::EvidenceArgs& args, bool upload_mask,
                        bool pairs) = 0;
  virtual void update(int camera, const pixel::UpdateArgs& args, bool upload_mask) = 0;
  virtual void synchronize() = 0;
};

// The CUDA implementation on psfs::cuda::device(); nullptr in a build without the backend.
// Throws std::runtime_error when the device cannot be set up.
std::unique_ptr<PixelPipelineDevice> makePixelPipelineDevice();

}  // namespace detail
}  // namespace psfs
