// The device side of GpuPixelStage (pixel_pipeline_device.h): buffers, streams and the kernels
// of the pixel stage. Every kernel is a thread-index wrapper around a per-thread function of
// pixel_arithmetic.h, which the CPU path and the host emulation (pixel_stage_emulation.cpp) run
// too; the only device-specific code here is memory management and the integer reductions
// (classification totals, gain histogram, peak), whose results do not depend on their order.
#include <cuda_runtime.h>

#include <cstdint>
#include <stdexcept>
#include <string>

#include "psfs_reconstruction/cuda_device.h"
#include "../pixel_pipeline_device.h"

namespace psfs {
namespace detail {
namespace {

constexpr int kBlock = 256;

void check(cudaError_t e, const char* what) {
  if (e == cudaSuccess) return;
  cudaGetLastError();  // clear a non-sticky error so later calls report their own
  throw std::runtime_error(std::string("GpuPixelStage: ") + what + ": " + cudaGetErrorString(e));
}
#define PSFS_CUDA(call) check((call), #call)
#define PSFS_LAUNCHED(kernel) check(cudaGetLastError(), "launch of " kernel)

int blocks(long long n) { return int((n + kBlock - 1) / kBlock); }

__device__ __forceinline__ int warpSum(int v) {
  for (int o = 16; o > 0; o >>= 1) v += __shfl_down_sync(0xffffffffu, v, o);
  return v;
}

// One thread per pixel; per block one atomic add of each count.
__global__ void __launch_bounds__(kBlock)
    classifyKernel(const pixel::ClassifyArgs a, unsigned long long* totals) {
  __shared__ int part[4][kBlock / 32];
  const int i = blockIdx.x * kBlock + threadIdx.x;
  pixel::PixelCounts c = {0, 0, 0, 0};
  if (i < a.width * a.height) c = pixel::classifyThread(a, i);
  int v[4] = {c.dark, c.shadow, c.saturated, c.foreground_bytes};
  const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
  for (int j = 0; j < 4; ++j) {
    v[j] = warpSum(v[j]);
    if (lane == 0) part[j][warp] = v[j];
  }
  __syncthreads();
  if (threadIdx.x < 4) {
    int s = 0;
    for (int w = 0; w < kBlock / 32; ++w) s += part[threadIdx.x][w];
    if (s) atomicAdd(totals + threadIdx.x, (unsigned long long)s);
  }
}

// One thread per sample (every 2nd row and column); a block histogram in shared memory.
__global__ void __launch_bounds__(kBlock) gainHistogramKernel(const pixel::GainArgs a, int* hist) {
  __shared__ int h[pixel::kGainBins];
  for (int b = threadIdx.x; b < pixel::kGainBins; b += kBlock) h[b] = 0;
  __syncthreads();
  const int s = blockIdx.x * kBlock + threadIdx.x;
  if (s < a.samplesX() * a.samplesY()) {
    const int bin = pixel::gainSampleThread(a, s);
    if (bin >= 0) atomicAdd(&h[bin], 1);
  }
  __syncthreads();
  for (int b = threadIdx.x; b < pixel::kGainBins; b += kBlock)
    if (h[b]) atomicAdd(&hist[b], h[b]);
}

// One block, one thread per bin: windows, their maximum, the sample count and the brightest
// candidate, then one thread walks to the top of its peak.
__global__ void __launch_bounds__(pixel::kGainBins)
    gainPeakKernel(const int* hist, pixel::GainPeak* peak) {
  __shared__ int window[pixel::kGainBins];
  __shared__ int max_window, samples, candidate;
  const int b = threadIdx.x;
  if (b == 0) {
    max_window = 0;
    samples = 0;
    candidate = -1;
  }
  __syncthreads();
  window[b] = pixel::gainWindow(hist, b);
  atomicMax(&max_window, window[b]);
  atomicAdd(&samples, hist[b]);
  __syncthreads();
  if (pixel::gainCandidate(window[b], max_window)) atomicMax(&candidate, b);
  __syncthreads();
  if (b == 0) *peak = pixel::gainPeakOf(window, candidate, samples);
}

__global__ void __launch_bounds__(kBlock) evidenceTermKernel(const pixel::EvidenceArgs a) {
  const int i = blockIdx.x * kBlock + threadIdx.x;
  if (i < a.pixels() + pixel::kTermGuard) pixel::evidenceTermThread(a, i);
}

__global__ void __launch_bounds__(kBlock) evidencePairKernel(const pixel::EvidenceArgs a) {
  const int i = blockIdx.x * kBlock + threadIdx.x;
  if (i < a.pairCount()) pixel::evidencePairThread(a, i);
}

__global__ void __launch_bounds__(kBlock) updateKernel(const pixel::UpdateArgs a) {
  const int i = blockIdx.x * kBlock + threadIdx.x;
  if (i < a.pixels) pixel::updateThread(a, i);
}

// Sub-allocation of one block: 256-byte aligned pieces (base 0 measures the size).
class Carver {
 public:
  explicit Carver(void* base) : at_(reinterpret_cast<std::uintptr_t>(base)), base_(at_) {}
  template <typename T>
  T* take(std::size_t count) {
    at_ = (at_ + 255) & ~std::uintptr_t(255);
    T* p = reinterpret_cast<T*>(at_);
    at_ += count * sizeof(T);
    return p;
  }
  std::size_t size() const { return at_ - base_ + 256; }

 private:
  std::uintptr_t at_, base_;
};

// Carves one camera's device and pinned blocks into its buffers (either may be null).
PixelCameraBuffers carve(const ImageSize& s, void* device, void* host, std::size_t* device_bytes,
                         std::size_t* host_bytes) {
  PixelCameraBuffers b;
  b.width = s.width;
  b.height = s.height;
  const std::size_t np = std::size_t(s.width) * s.height;
  pixel::EvidenceArgs shape;
  shape.width = s.width;
  shape.height = s.height;
  Carver d(device);
  b.rgb = d.take<std::uint8_t>(3 * np);
  b.likelihood = d.take<std::uint8_t>(2 * np);
  b.mask = d.take<std::uint8_t>(np);
  float** planes[8] = {&b.background.mean_r,   &b.background.mean_g,  &b.background.mean_intensity,
                       &b.background.scale_r,  &b.background.scale_g, &b.background.var_intensity,
                       &b.background.var_r,    &b.background.var_g};
  for (float** p : planes) *p = d.take<float>(np);
  b.gain_histogram = d.take<int>(pixel::kGainBins);
  b.gain_peak = d.take<pixel::GainPeak>(1);
  b.totals = d.take<pixel::ClassifyTotals>(1);
  for (int cls = 0; cls < 2; ++cls) {
    // ViewEvidence's arrays are readable a little past their end (32-bit gathers): so are these.
    b.terms[cls] = d.take<std::int16_t>(np + pixel::kTermGuard + 2);
    b.pairs[cls] = d.take<std::uint16_t>(std::size_t(shape.pairCount()) + 1);
  }
  *device_bytes = d.size();
  Carver h(host);
  b.host_rgb = h.take<std::uint8_t>(3 * np);
  b.host_mask = h.take<std::uint8_t>(np);
  b.host_likelihood = h.take<std::uint8_t>(2 * np);
  b.host_totals = h.take<pixel::ClassifyTotals>(1);
  b.host_gain_peak = h.take<pixel::GainPeak>(1);
  *host_bytes = h.size();
  return b;
}

class CudaPixelPipeline final : public PixelPipelineDevice {
 public:
  CudaPixelPipeline() : device_(cuda::device().index) { setDevice(); }
  ~CudaPixelPipeline() override { release(); }

  void resize(const std::vector<ImageSize>& sizes) override {
    setDevice();
    if (sizes == sizes_) return;
    release();
    for (const ImageSize& s : sizes) {
      Camera cam;
      std::size_t dbytes = 0, hbytes = 0;
      carve(s, nullptr, nullptr, &dbytes, &hbytes);
      PSFS_CUDA(cudaMalloc(&cam.device_block, dbytes));
      ++allocations_;
      cameras_.push_back(cam);  // freed by release() from here on
      PSFS_CUDA(cudaMallocHost(&cameras_.back().host_block, hbytes));
      ++allocations_;
      PSFS_CUDA(cudaStreamCreateWithFlags(&cameras_.back().stream, cudaStreamNonBlocking));
      cameras_.back().buffers =
          carve(s, cameras_.back().device_block, cameras_.back().host_block, &dbytes, &hbytes);
    }
    sizes_ = sizes;
  }

  const PixelCameraBuffers& buffers(int camera) const override {
    return cameras_.at(camera).buffers;
  }
  std::size_t allocations() const override { return allocations_; }

  void uploadPlanes(int camera, const BackgroundPlanes& host) override {
    setDevice();
    const Camera& c = cameras_.at(camera);
    const MutableBackgroundPlanes& d = c.buffers.background;
    const std::size_t bytes = std::size_t(c.buffers.width) * c.buffers.height * sizeof(float);
    const auto src = planeList(host);
    const auto dst = planeList(d);
    for (size_t p = 0; p < src.size(); ++p)
      PSFS_CUDA(cudaMemcpyAsync(dst[p], src[p], bytes, cudaMemcpyHostToDevice, c.stream));
    PSFS_CUDA(cudaStreamSynchronize(c.stream));
  }

  void downloadPlanes(int camera, const MutableBackgroundPlanes& host) override {
    setDevice();
    const Camera& c = cameras_.at(camera);
    const MutableBackgroundPlanes& d = c.buffers.background;
    const std::size_t bytes = std::size_t(c.buffers.width) * c.buffers.height * sizeof(float);
    const auto src = planeList(d);
    const auto dst = planeList(host);
    for (size_t p = 0; p < src.size(); ++p)
      PSFS_CUDA(cudaMemcpyAsync(dst[p], src[p], bytes, cudaMemcpyDeviceToHost, c.stream));
    PSFS_CUDA(cudaStreamSynchronize(c.stream));
  }

  void copyToHost(void* host, const void* device, std::size_t bytes) override {
    setDevice();
    PSFS_CUDA(cudaMemcpy(host, device, bytes, cudaMemcpyDeviceToHost));
  }

  void classify(int camera, const pixel::ClassifyArgs& args, const pixel::GainArgs* gain,
                bool read_likelihood) override {
    setDevice();
    const Camera& c = cameras_.at(camera);
    const PixelCameraBuffers& b = c.buffers;
    const std::size_t np = std::size_t(b.width) * b.height;
    PSFS_CUDA(cudaMemcpyAsync(b.rgb, b.host_rgb, 3 * np, cudaMemcpyHostToDevice, c.stream));
    if (gain) {
      PSFS_CUDA(cudaMemsetAsync(b.gain_histogram, 0, pixel::kGainBins * sizeof(int), c.stream));
      gainHistogramKernel<<<blocks((long long)gain->samplesX() * gain->samplesY()), kBlock, 0,
                            c.stream>>>(*gain, b.gain_histogram);
      PSFS_LAUNCHED("gainHistogramKernel");
      gainPeakKernel<<<1, pixel::kGainBins, 0, c.stream>>>(b.gain_histogram, b.gain_peak);
      PSFS_LAUNCHED("gainPeakKernel");
      PSFS_CUDA(cudaMemcpyAsync(b.host_gain_peak, b.gain_peak, sizeof(pixel::GainPeak),
                                cudaMemcpyDeviceToHost, c.stream));
    }
    PSFS_CUDA(cudaMemsetAsync(b.totals, 0, sizeof(pixel::ClassifyTotals), c.stream));
    classifyKernel<<<blocks((long long)np), kBlock, 0, c.stream>>>(
        args, reinterpret_cast<unsigned long long*>(b.totals));
    PSFS_LAUNCHED("classifyKernel");
    PSFS_CUDA(cudaMemcpyAsync(b.host_totals, b.totals, sizeof(pixel::ClassifyTotals),
                              cudaMemcpyDeviceToHost, c.stream));
    if (read_likelihood)
      PSFS_CUDA(cudaMemcpyAsync(b.host_likelihood, b.likelihood, 2 * np, cudaMemcpyDeviceToHost,
                                c.stream));
  }

  void clearLikelihood(int camera) override {
    setDevice();
    const Camera& c = cameras_.at(camera);
    const std::size_t np = std::size_t(c.buffers.width) * c.buffers.height;
    PSFS_CUDA(cudaMemsetAsync(c.buffers.likelihood, 0, 2 * np, c.stream));
  }

  void evidence(int camera, const pixel::EvidenceArgs& args, bool upload_mask,
                bool pairs) override {
    setDevice();
    const Camera& c = cameras_.at(camera);
    if (upload_mask) uploadMask(c);
    evidenceTermKernel<<<blocks(args.pixels() + pixel::kTermGuard), kBlock, 0, c.stream>>>(args);
    PSFS_LAUNCHED("evidenceTermKernel");
    if (pairs) {
      evidencePairKernel<<<blocks(args.pairCount()), kBlock, 0, c.stream>>>(args);
      PSFS_LAUNCHED("evidencePairKernel");
    }
  }

  void update(int camera, const pixel::UpdateArgs& args, bool upload_mask) override {
    setDevice();
    const Camera& c = cameras_.at(camera);
    if (upload_mask) uploadMask(c);
    updateKernel<<<blocks(args.pixels), kBlock, 0, c.stream>>>(args);
    PSFS_LAUNCHED("updateKernel");
  }

  void synchronize() override {
    setDevice();
    for (const Camera& c : cameras_) PSFS_CUDA(cudaStreamSynchronize(c.stream));
  }

 private:
  struct Camera {
    void* device_block = nullptr;
    void* host_block = nullptr;
    cudaStream_t stream = nullptr;
    PixelCameraBuffers buffers;
  };

  void setDevice() { PSFS_CUDA(cudaSetDevice(device_)); }

  void uploadMask(const Camera& c) {
    const std::size_t np = std::size_t(c.buffers.width) * c.buffers.height;
    PSFS_CUDA(cudaMemcpyAsync(c.buffers.mask, c.buffers.host_mask, np, cudaMemcpyHostToDevice,
                              c.stream));
  }

  // Frees everything; errors are ignored (nothing can be done about them here).
  void release() {
    for (Camera& c : cameras_) {
      if (c.stream) {
        cudaStreamSynchronize(c.stream);
        cudaStreamDestroy(c.stream);
      }
      if (c.device_block) cudaFree(c.device_block);
      if (c.host_block) cudaFreeHost(c.host_block);
    }
    cudaGetLastError();
    cameras_.clear();
    sizes_.clear();
  }

  int device_;
  std::vector<ImageSize> sizes_;
  std::vector<Camera> cameras_;
  std::size_t allocations_ = 0;
};

}  // namespace

std::unique_ptr<PixelPipelineDevice> makePixelPipelineDevice() {
  return std::make_unique<CudaPixelPipeline>();
}

}  // namespace detail
}  // namespace psfs
