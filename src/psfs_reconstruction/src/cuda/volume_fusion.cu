// The CUDA backend of GpuPsfsFusion (volume_fusion.h): buffers, stream, staging, and two thin
// kernels around the per-thread functions of volume_fusion.h / voxel_arithmetic.h, which the
// host tests run through hostEmulateFusion. Nothing here computes anything of its own.
#include <cuda_runtime.h>

#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "../volume_fusion.h"
#include "psfs_reconstruction/cuda_device.h"

namespace psfs {
namespace detail {
namespace {

void check(cudaError_t e, const char* what) {
  if (e == cudaSuccess) return;
  cudaGetLastError();  // clear a non-sticky error so a later call can start afresh
  throw std::runtime_error(std::string("psfs::GpuPsfsFusion: ") + what + ": " + cudaGetErrorString(e));
}
#define PSFS_CUDA(call) check((call), #call)

// ---- kernels --------------------------------------------------------------------------------
// One block per (row, camera): thread 0 derives the row's constants, every thread projects its
// share of the row's centres and chunk offsets (the table build's code, projectTableRow).
__global__ void projectKernel(const ProjectionCamera* cameras, int num_cameras,
                              const __grid_constant__ ProjectionGrid g, bool multi, uint32_t* centres,
                              uint32_t* offsets) {
  const size_t slice = blockIdx.x;  // row * C + camera
  const int c = static_cast<int>(slice % num_cameras);
  const size_t row = slice / num_cameras;
  const int y = static_cast<int>(row % g.ny), z = static_cast<int>(row / g.ny);
  __shared__ ProjectionRow r;
  if (threadIdx.x == 0) r = projectionRow(cameras[c], g, y, z);
  __syncthreads();
  projectTableRow(cameras[c], g, r, y, z, multi, threadIdx.x, blockDim.x, centres + slice * g.nxp,
                  multi ? offsets + slice * g.chunks * 3 : nullptr);
}

// The views travel as a kernel parameter (no per-frame upload); p.views points at them.
struct FuseArgs {
  PsfsRowParams p;
  KernelView views[kMaxGpuCameras];
  TableView t;
  bool multi;
  uint8_t* out;
};

// One thread per voxel: x and y from the block grid, z = blockIdx.z.
template <int K>
__global__ void fuseKernel(const __grid_constant__ FuseArgs a) {
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int z = blockIdx.z;
  if (x >= a.t.nx || y >= a.t.ny) return;
  PsfsRowParams p = a.p;
  p.views = a.views;
  a.out[(static_cast<size_t>(z) * a.t.ny + y) * a.t.nx + x] = fuseVoxel<K>(p, a.t, a.multi, x, y, z);
}

constexpr int kBlockX = 32, kBlockY = 4;  // 128 threads: a warp per x-run of 32 voxels
constexpr int kProjectThreads = 64;
constexpr size_t kAlign = 256;
size_t aligned(size_t bytes) { return (bytes + kAlign - 1) / kAlign * kAlign; }

// Grow-only device and pinned buffers, counted.
struct Buffer {
  void* p = nullptr;
  size_t bytes = 0;
};
void growDevice(Buffer& b, size_t bytes, size_t* allocations) {
  if (bytes <= b.bytes) return;
  if (b.p) PSFS_CUDA(cudaFree(b.p));
  b.p = nullptr;
  b.bytes = 0;
  PSFS_CUDA(cudaMalloc(&b.p, bytes));
  b.bytes = bytes;
  ++*allocations;
}
void growPinned(Buffer& b, size_t bytes, size_t* allocations) {
  if (bytes <= b.bytes) return;
  if (b.p) PSFS_CUDA(cudaFreeHost(b.p));
  b.p = nullptr;
  b.bytes = 0;
  PSFS_CUDA(cudaMallocHost(&b.p, bytes));
  b.bytes = bytes;
  ++*allocations;
}
void freeDevice(Buffer& b) {
  if (b.p) cudaFree(b.p);
  b = Buffer();
}
void freePinned(Buffer& b) {
  if (b.p) cudaFreeHost(b.p);
  b = Buffer();
}

int usableDevice() {
  const cuda::DeviceInfo& d = cuda::device();
  if (!d.usable) throw std::runtime_error("psfs::GpuPsfsFusion: " + d.describe());
  PSFS_CUDA(cudaSetDevice(d.index));
  return d.index;
}

}  // namespace

struct CudaEvidence::Impl {
  int device = 0;
  Buffer staging, evidence;
  size_t allocations = 0;
  ~Impl() {
    cudaSetDevice(device);
    freeDevice(evidence);
    freePinned(staging);
    cudaGetLastError();
  }
};

CudaEvidence::CudaEvidence() {
  std::unique_ptr<Impl> m(new Impl);
  m->device = usableDevice();
  impl_ = m.release();
}
CudaEvidence::~CudaEvidence() { delete impl_; }
size_t CudaEvidence::allocations() const { return impl_->allocations; }

void CudaEvidence::upload(const HostEvidenceView* views, int n, KernelView* device_views, void* stream_ptr) {
  Impl& m = *impl_;
  PSFS_CUDA(cudaSetDevice(m.device));
  cudaStream_t stream = static_cast<cudaStream_t>(stream_ptr);
  size_t total = 0;
  for (int c = 0; c < n; ++c)
    total += aligned(views[c].terms_count * sizeof(int16_t)) + aligned(views[c].pairs_count * sizeof(uint16_t));
  growPinned(m.staging, total, &m.allocations);
  growDevice(m.evidence, total, &m.allocations);
  // The staging buffer is free: every upload before this one finished (synchronised by its
  // caller, or here).
  char* host = static_cast<char*>(m.staging.p);
  char* dev = static_cast<char*>(m.evidence.p);
  size_t at = 0;
  for (int c = 0; c < n; ++c) {
    const HostEvidenceView& h = views[c];
    KernelView& v = device_views[c];
    std::memcpy(host + at, h.terms, h.terms_count * sizeof(int16_t));
    v.terms = reinterpret_cast<const int16_t*>(dev + at);
    at += aligned(h.terms_count * sizeof(int16_t));
    v.pairs = nullptr;
    if (h.pairs) {
      std::memcpy(host + at, h.pairs, h.pairs_count * sizeof(uint16_t));
      v.pairs = reinterpret_cast<const uint16_t*>(dev + at);
      at += aligned(h.pairs_count * sizeof(uint16_t));
    }
    v.width = h.width;
    v.quad_stride = h.quad_stride;
    v.has_mask = h.has_mask;
    v.not_observed = static_cast<uint32_t>(16 * h.height) << 16;  // PackedUV::notObserved
  }
  if (stream) {
    PSFS_CUDA(cudaMemcpyAsync(m.evidence.p, m.staging.p, at, cudaMemcpyHostToDevice, stream));
  } else {
    PSFS_CUDA(cudaMemcpyAsync(m.evidence.p, m.staging.p, at, cudaMemcpyHostToDevice, cudaStreamPerThread));
    PSFS_CUDA(cudaStreamSynchronize(cudaStreamPerThread));
  }
}

struct CudaVolumeFusion::Impl {
  int device = 0;
  cudaStream_t stream = nullptr;
  cudaEvent_t ev[8] = {};  // 0-1 table upload, 2-3 projection, 4 frame start, 5 evidence, 6 fuse, 7 readback
  bool table_uploaded = false, table_projected = false;
  Buffer centres, offsets, cameras, out, exp_table;
  Buffer pinned_out, pinned_cameras;
  size_t allocations = 0;
  std::unique_ptr<CudaEvidence> evidence;  // host evidence, per frame
  TableView table;  // device pointers and dims of the current table
  bool has_table = false, table_multi = false;
  int table_cameras = 0;
  StageTimes times;

  void grow(Buffer& b, size_t bytes) { growDevice(b, bytes, &allocations); }
  void growStaging(Buffer& b, size_t bytes) { growPinned(b, bytes, &allocations); }
  float elapsed(int a, int b) const {
    float ms = 0.0f;
    return cudaEventElapsedTime(&ms, ev[a], ev[b]) == cudaSuccess ? ms : 0.0f;
  }
  ~Impl() {  // also after a constructor that threw half way; errors ignored
    cudaSetDevice(device);
    if (stream) cudaStreamSynchronize(stream);
    evidence.reset();
    for (Buffer* b : {&centres, &offsets, &cameras, &out, &exp_table}) freeDevice(*b);
    for (Buffer* b : {&pinned_out, &pinned_cameras}) freePinned(*b);
    for (cudaEvent_t e : ev)
      if (e) cudaEventDestroy(e);
    if (stream) cudaStreamDestroy(stream);
    cudaGetLastError();
  }
};

CudaVolumeFusion::CudaVolumeFusion() {
  std::unique_ptr<Impl> m(new Impl);
  m->device = usableDevice();
  PSFS_CUDA(cudaStreamCreateWithFlags(&m->stream, cudaStreamNonBlocking));
  for (cudaEvent_t& e : m->ev) PSFS_CUDA(cudaEventCreate(&e));
  impl_ = m.release();
}

CudaVolumeFusion::~CudaVolumeFusion() { delete impl_; }

size_t CudaVolumeFusion::allocations() const {
  return impl_->allocations + (impl_->evidence ? impl_->evidence->allocations() : 0);
}
const StageTimes& CudaVolumeFusion::times() const { return impl_->times; }

void CudaVolumeFusion::uploadTable(const TableView& host, int num_cameras, bool multi) {
  Impl& m = *impl_;
  m.has_table = false;
  PSFS_CUDA(cudaSetDevice(m.device));
  const size_t rows = static_cast<size_t>(host.ny) * host.nz;
  const size_t nc = rows * num_cameras * host.nxp, no = multi ? rows * num_cameras * host.chunks * 3 : 0;
  m.grow(m.centres, nc * sizeof(uint32_t));
  if (multi) m.grow(m.offsets, no * sizeof(uint32_t));
  PSFS_CUDA(cudaEventRecord(m.ev[0], m.stream));
  // Once per table change, from the table's own (pageable) memory.
  PSFS_CUDA(cudaMemcpyAsync(m.centres.p, host.centres, nc * sizeof(uint32_t), cudaMemcpyHostToDevice, m.stream));
  if (multi)
    PSFS_CUDA(cudaMemcpyAsync(m.offsets.p, host.offsets, no * sizeof(uint32_t), cudaMemcpyHostToDevice, m.stream));
  PSFS_CUDA(cudaEventRecord(m.ev[1], m.stream));
  m.table = host;
  m.table.centres = static_cast<const uint32_t*>(m.centres.p);
  m.table.offsets = multi ? static_cast<const uint32_t*>(m.offsets.p) : nullptr;
  m.table_multi = multi;
  m.table_cameras = num_cameras;
  m.table_uploaded = true;
  m.has_table = true;
}

void CudaVolumeFusion::projectTable(const ProjectionCamera* cameras, int num_cameras, const ProjectionGrid& g,
                                    bool multi) {
  Impl& m = *impl_;
  m.has_table = false;
  PSFS_CUDA(cudaSetDevice(m.device));
  const size_t slices = static_cast<size_t>(g.ny) * g.nz * num_cameras;
  m.grow(m.centres, slices * g.nxp * sizeof(uint32_t));
  if (multi) m.grow(m.offsets, slices * g.chunks * 3 * sizeof(uint32_t));
  const size_t cam_bytes = sizeof(ProjectionCamera) * num_cameras;
  m.grow(m.cameras, cam_bytes);
  m.growStaging(m.pinned_cameras, cam_bytes);
  // The previous frame's copy from this staging finished: every fuse ends synchronised.
  std::memcpy(m.pinned_cameras.p, cameras, cam_bytes);
  PSFS_CUDA(cudaEventRecord(m.ev[2], m.stream));
  PSFS_CUDA(cudaMemcpyAsync(m.cameras.p, m.pinned_cameras.p, cam_bytes, cudaMemcpyHostToDevice, m.stream));
  projectKernel<<<static_cast<unsigned>(slices), kProjectThreads, 0, m.stream>>>(
      static_cast<const ProjectionCamera*>(m.cameras.p), num_cameras, g, multi,
      static_cast<uint32_t*>(m.centres.p), multi ? static_cast<uint32_t*>(m.offsets.p) : nullptr);
  PSFS_CUDA(cudaGetLastError());
  PSFS_CUDA(cudaEventRecord(m.ev[3], m.stream));
  m.table.centres = static_cast<const uint32_t*>(m.centres.p);
  m.table.offsets = multi ? static_cast<const uint32_t*>(m.offsets.p) : nullptr;
  m.table.nx = g.nx, m.table.ny = g.ny, m.table.nz = g.nz, m.table.nxp = g.nxp, m.table.chunks = g.chunks;
  m.table_multi = multi;
  m.table_cameras = num_cameras;
  m.table_projected = true;
  m.has_table = true;
}

void CudaVolumeFusion::fuse(const PsfsRowParams& params, int k, bool multi, const HostEvidenceView* views,
                            const KernelView* device_views, uint8_t* out, size_t num_voxels) {
  Impl& m = *impl_;
  const int C = params.num_cameras;
  if (!m.has_table || m.table_cameras != C || (multi && !m.table_multi))
    throw std::logic_error("psfs::CudaVolumeFusion::fuse: no matching table on the device");
  if (C > kMaxGpuCameras)
    throw std::runtime_error("psfs::GpuPsfsFusion: more than " + std::to_string(kMaxGpuCameras) + " cameras");
  PSFS_CUDA(cudaSetDevice(m.device));
  FuseArgs a;
  a.p = params;
  a.t = m.table;
  a.multi = multi;

  // The exp table never changes: uploaded with the first frame.
  if (!m.exp_table.p) {
    m.grow(m.exp_table, sizeof(int32_t) * params.exp_table_size);
    PSFS_CUDA(cudaMemcpy(m.exp_table.p, params.exp_table, sizeof(int32_t) * params.exp_table_size,
                         cudaMemcpyHostToDevice));
  }
  a.p.exp_table = static_cast<const int32_t*>(m.exp_table.p);
  a.p.views = nullptr;  // set in the kernel (the views are a kernel parameter)

  PSFS_CUDA(cudaEventRecord(m.ev[4], m.stream));
  if (device_views) {
    for (int c = 0; c < C; ++c) a.views[c] = device_views[c];
  } else {
    if (!m.evidence) m.evidence = std::make_unique<CudaEvidence>();
    m.evidence->upload(views, C, a.views, m.stream);
  }
  PSFS_CUDA(cudaEventRecord(m.ev[5], m.stream));

  m.grow(m.out, num_voxels);
  m.growStaging(m.pinned_out, num_voxels);
  a.out = static_cast<uint8_t*>(m.out.p);
  const dim3 block(kBlockX, kBlockY, 1);
  const dim3 grid((m.table.nx + kBlockX - 1) / kBlockX, (m.table.ny + kBlockY - 1) / kBlockY, m.table.nz);
  switch (k) {
    case 0: fuseKernel<0><<<grid, block, 0, m.stream>>>(a); break;
    case 1: fuseKernel<1><<<grid, block, 0, m.stream>>>(a); break;
    case 2: fuseKernel<2><<<grid, block, 0, m.stream>>>(a); break;
    case 3: fuseKernel<3><<<grid, block, 0, m.stream>>>(a); break;
    default: fuseKernel<4><<<grid, block, 0, m.stream>>>(a); break;
  }
  PSFS_CUDA(cudaGetLastError());
  PSFS_CUDA(cudaEventRecord(m.ev[6], m.stream));
  PSFS_CUDA(cudaMemcpyAsync(m.pinned_out.p, m.out.p, num_voxels, cudaMemcpyDeviceToHost, m.stream));
  PSFS_CUDA(cudaEventRecord(m.ev[7], m.stream));
  PSFS_CUDA(cudaStreamSynchronize(m.stream));
  std::memcpy(out, m.pinned_out.p, num_voxels);

  m.times.upload = m.elapsed(4, 5) + (m.table_uploaded ? m.elapsed(0, 1) : 0.0f);
  m.times.project = m.table_projected ? m.elapsed(2, 3) : 0.0f;
  m.times.fuse = m.elapsed(5, 6);
  m.times.readback = m.elapsed(6, 7);
  m.table_uploaded = m.table_projected = false;
}

}  // namespace detail
}  // namespace psfs
