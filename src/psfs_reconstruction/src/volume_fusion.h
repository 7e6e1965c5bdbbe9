// Private: pSfS on a GPU as plain data and per-thread functions (issue 20). The CUDA kernels
// (cuda/volume_fusion.cu) are thin index wrappers around the functions here, and
// hostEmulateFusion runs the same functions over every thread in plain loops on the host, so
// the host tests check, against PsfsFusion on real scenes, the very code the GPU runs.
//
// Two kernels per frame:
//  * projection (only when an on-the-fly table changed; a stored table is uploaded instead):
//    one block per (row, camera), writing the table in ProjectionTable's stored layout
//    (projectTableRow, the table build's own code);
//  * fusion: one thread per voxel, fuseVoxel (voxel_arithmetic.h). A thread has no carried
//    faces: it reads its lower neighbours' centres and offsets itself (voxelMedianPair).
#pragma once

#include <cstddef>
#include <cstdint>

#include "psfs_reconstruction/projection_constants.h"
#include "voxel_arithmetic.h"
#include "voxel_projection.h"

namespace psfs {
class ProjectionTable;
class ViewEvidence;
struct PsfsOptions;
struct ProbabilityVolume;

namespace detail {

// Views a GPU fusion takes (kernel parameters, not a device array: nothing to upload per frame).
constexpr int kMaxGpuCameras = 32;

// Entry x (< nxp) of the packed centres of one (row, camera) of a table: rowCentres' value.
PSFS_HD uint32_t tableCentre(const ProjectionCamera& cam, const ProjectionGrid& g, const ProjectionRow& r, int x) {
  return x < g.nx ? projectVoxel(cam, r, x) : cam.not_observed;
}

// What one projection thread writes for (row, camera): its share of the entries x = first,
// first + step, ... of the centres and (multi-projection) of the chunks' offsets. `centres`
// and `offsets` point at the (row, camera) slice of the table.
PSFS_HD void projectTableRow(const ProjectionCamera& cam, const ProjectionGrid& g, const ProjectionRow& r,
                             int y, int z, bool multi, int first, int step, uint32_t* centres,
                             uint32_t* offsets) {
  for (int x = first; x < g.nxp; x += step) centres[x] = tableCentre(cam, g, r, x);
  if (multi)
    for (int ch = first; ch < g.chunks; ch += step) chunkOffsets(cam, g, y, z, ch, offsets + ch * 3);
}

// The voxel kernel's dispatch over the occlusion tolerance k (0..4).
PSFS_HD uint8_t fuseVoxelK(int k, const PsfsRowParams& p, const TableView& t, bool multi, int x, int y, int z) {
  switch (k) {
    case 0: return fuseVoxel<0>(p, t, multi, x, y, z);
    case 1: return fuseVoxel<1>(p, t, multi, x, y, z);
    case 2: return fuseVoxel<2>(p, t, multi, x, y, z);
    case 3: return fuseVoxel<3>(p, t, multi, x, y, z);
    default: return fuseVoxel<4>(p, t, multi, x, y, z);
  }
}

// PsfsFusion's parameters for a table (views and exp_table left to the caller, who points
// them at host or device memory). Validates nothing: PsfsFusion's constructor does.
PsfsRowParams psfsRowParams(const PsfsOptions& options, const ProjectionTable& table);
// The byte table exp_table points at (PsfsRowParams::exp_table_size entries).
const int32_t* psfsExpTable();

// The host emulation of the GPU path: the projection kernel's per-thread function over all
// (row, camera) when `project` (else the stored table is read), then fuseVoxel over all voxels,
// into `out`. Same checks and exceptions as PsfsFusion::fuse. Must equal PsfsFusion's bytes.
void hostEmulateFusion(const PsfsOptions& options, const ProjectionTable& table, const ViewEvidence& evidence,
                       ProbabilityVolume* out, bool project);

// The table hostEmulateFusion reads when it projects: the projection kernel's output on the
// host, in ProjectionTable's stored layout (offsets empty without multi-projection).
void hostEmulateProjection(const ProjectionTable& table, uint32_t* centres, uint32_t* offsets);

// ---- The CUDA backend (cuda/volume_fusion.cu; a stub throws where nvcc was missing) --------
// Plain interface: host pointers in, bytes out; device buffers and pinned staging grow only.
struct HostEvidenceView {
  const int16_t* terms = nullptr;
  size_t terms_count = 0;
  const uint16_t* pairs = nullptr;  // nullptr without multi-projection
  size_t pairs_count = 0;
  int width = 0, height = 0, quad_stride = 0;
  bool has_mask = false;
};

struct StageTimes {  // milliseconds of the last fuse, measured with CUDA events
  double upload = 0, project = 0, fuse = 0, readback = 0;
};

// Host evidence copied to the device (GpuEvidenceBuffer, and CudaVolumeFusion per frame):
// all views through one pinned staging buffer, one copy; both buffers grow only.
class CudaEvidence {
 public:
  CudaEvidence();  // throws std::runtime_error when no device is usable
  ~CudaEvidence();
  CudaEvidence(const CudaEvidence&) = delete;
  CudaEvidence& operator=(const CudaEvidence&) = delete;
  // Sets device_views[0..n) to the device copies. stream: a cudaStream_t to copy on (the caller
  // orders and synchronises), or nullptr to copy and synchronise before returning.
  void upload(const HostEvidenceView* views, int n, KernelView* device_views, void* stream);
  size_t allocations() const;

 private:
  struct Impl;
  Impl* impl_;
};

class CudaVolumeFusion {
 public:
  CudaVolumeFusion();  // creates the stream (throws std::runtime_error on CUDA errors)
  ~CudaVolumeFusion();
  CudaVolumeFusion(const CudaVolumeFusion&) = delete;
  CudaVolumeFusion& operator=(const CudaVolumeFusion&) = delete;

  // The table, once per change: a stored one uploaded, or one projected on the device.
  void uploadTable(const TableView& host_table, int num_cameras, bool multi);
  void projectTable(const ProjectionCamera* cameras, int num_cameras, const ProjectionGrid& grid, bool multi);
  // One frame. views: host evidence (uploaded through pinned staging) or, with
  // device_views != nullptr, kernel views already in device memory. params: views and
  // exp_table are set here. out: numVoxels bytes (host).
  void fuse(const PsfsRowParams& params, int k, bool multi, const HostEvidenceView* views,
            const KernelView* device_views, uint8_t* out, size_t num_voxels);

  size_t allocations() const;    // device and pinned allocations so far
  const StageTimes& times() const;

 private:
  struct Impl;
  Impl* impl_;
};

}  // namespace detail
}  // namespace psfs
