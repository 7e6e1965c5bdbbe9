// Foreground-class pSfS on a CUDA device (issue 20): the bytes of PsfsFusion (psfs_fusion.h),
// one thread per voxel. The per-voxel arithmetic is the CPU reference's own code
// (src/voxel_arithmetic.h, __host__ __device__), so the two agree to the byte; the host tests
// run it over all voxels on the host (src/volume_fusion.h: hostEmulateFusion) in every build.
//
// Per frame: the evidence is uploaded through pinned staging on the object's stream (or is
// already on the device: GpuEvidence, the GPU pixel stage's output), the volume kernel runs,
// and the bytes come back through pinned staging. The table reaches the device once per
// change: a stored table is uploaded, a table projected on the fly (hand sub-volumes, the
// 256x256x192 grid) is projected on the device by the table build's own code. Device buffers
// are reused across frames and grow only; deviceAllocations() counts every allocation, so a
// caller (and test_gpu_fusion) can check that steady frames allocate nothing.
//
// Without a usable device (no nvcc at build time, no GPU, TABLETOP_CUDA_DEVICE=-1) usable()
// is false and fuse() throws std::runtime_error; so does any CUDA failure, with the CUDA error
// string. The caller then runs PsfsFusion, which gives the same bytes:
//   GpuPsfsFusion gpu(o);  PsfsFusion cpu(o);
//   try { if (gpu.usable()) { gpu.fuse(table, evidence, &vol); return; } }
//   catch (const std::runtime_error& e) { log(e.what()); }
//   cpu.fuse(table, evidence, &vol);
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "psfs_reconstruction/gpu_evidence.h"
#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/view_evidence.h"

namespace psfs {

// Milliseconds of the stages of the last fuse() (CUDA events on the object's stream).
struct GpuFusionTimings {
  double upload_ms = 0.0;    // evidence, and the table when it changed, host -> device
  double project_ms = 0.0;   // on-device projection of a changed on-the-fly table (else 0)
  double fuse_ms = 0.0;      // the volume kernel
  double readback_ms = 0.0;  // the volume, device -> host
};

// One object per volume kind and thread: it owns a stream, the device's copy of its table and
// its buffers (fuse is not const, unlike PsfsFusion::fuse).
class GpuPsfsFusion {
 public:
  // Same options and checks as PsfsFusion (std::invalid_argument); `threads` is ignored.
  // Touches no device: construction works everywhere.
  explicit GpuPsfsFusion(const PsfsOptions& options = PsfsOptions());
  ~GpuPsfsFusion();
  GpuPsfsFusion(GpuPsfsFusion&&) noexcept;
  GpuPsfsFusion& operator=(GpuPsfsFusion&&) noexcept;

  const PsfsOptions& options() const { return options_; }
  // True if the CUDA backend is compiled in and a device is usable (psfs::cuda::device()).
  bool usable() const;
  // Why not usable ("" when usable).
  std::string reason() const;

  // PsfsFusion::fuse on the device: same inputs, checks (std::invalid_argument) and bytes.
  // Throws std::runtime_error when no device is usable or on a CUDA error (then fall back).
  void fuse(const ProjectionTable& table, const ViewEvidence& evidence, ProbabilityVolume* out);
  // The same with the evidence already in device memory (gpu_evidence.h), one view per camera;
  // its writer must have finished (its stream synchronised). With PsfsOptions::skip_empty_below
  // this fuses every voxel (the device has no host copy of the likelihoods to bound them): the
  // caller sets the chunks PsfsFusion skips to its fill from its host views (GpuFramePath
  // does), so the bytes agree. Multi-projection needs the pair images, footprint tables
  // evidence with their levels (not checkable here: the caller's).
  void fuse(const ProjectionTable& table, const GpuEvidence& evidence, ProbabilityVolume* out);

  // Device and pinned host allocations made so far (buffers grow only, so steady frames of
  // unchanged sizes add none).
  size_t deviceAllocations() const;
  const GpuFusionTimings& lastTimings() const { return timings_; }

 private:
  struct Impl;
  void prepare(const ProjectionTable& table);
  void run(const ProjectionTable& table, const void* host_views, const void* device_views,
           ProbabilityVolume* out);
  PsfsOptions options_;
  std::unique_ptr<Impl> impl_;
  GpuFusionTimings timings_;
};

// A frame's evidence of one class copied to the device once, for several fusions of that
// frame (the tracking volume and the hand sub-volumes): gpu.fuse(table, buffer.views(), &out).
// Buffers grow only. upload() throws std::runtime_error without a usable device or on a CUDA
// error; the views are complete when it returns.
class GpuEvidenceBuffer {
 public:
  GpuEvidenceBuffer();
  ~GpuEvidenceBuffer();
  GpuEvidenceBuffer(GpuEvidenceBuffer&&) noexcept;
  GpuEvidenceBuffer& operator=(GpuEvidenceBuffer&&) noexcept;

  void upload(const ViewEvidence& evidence);  // pair images too where evidence.bilinear()
  const GpuEvidence& views() const { return views_; }
  size_t deviceAllocations() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  GpuEvidence views_;
};

}  // namespace psfs
