// Where every voxel of a grid lands in every camera: the geometric half of fusion.
//
// Cameras are static, so for a static grid (the full workspace volumes) the projections are
// computed once and stored; fusion then only streams 4 bytes per voxel and camera and gathers
// from small per-camera images. Grids that move every frame (hand sub-volumes) or that are too
// big to store (256x256x192 x 8 cameras would be 400 MB) are projected on the fly, one x-row at
// a time into a per-thread buffer, by the same float code, so both storages give the same bytes.
// That code (src/voxel_projection.h) also projects on-the-fly tables on a GPU
// (gpu_psfs_fusion.h), from the plain constants projectionCamera() / projectionGrid().
//
// Per voxel and camera the table holds the voxel centre's image position, packed (see PackedUV).
// For the multi-projection test it also holds, per camera and per chunk of 8 voxels along x
// (one SIMD vector), the image displacement of half a voxel along x, y and z: the 6 samples of
// a voxel are its 6 face centres, centre +- these. Over 8 voxels the local Jacobian of the
// projection changes by a few percent of a pixel-sized offset, so one set per chunk costs
// nothing in accuracy and 1.5 bytes per voxel and camera instead of 24.
//
// Face samples are shared: the face between voxels A (lower) and B (upper) along an axis is
// sampled once, at A's centre + A's offset when A's centre projects into camera c's image, else
// at B's centre - B's offset (see psfs_kernels.h). So a voxel costs 3 bilinear lookups per
// camera, not 6.
//
// Footprint levels (ReconstructorParams body/skin.footprint): instead of sampling the voxel's
// footprint per voxel, the evidence images are filtered to footprints of a few sizes once per
// frame (ViewEvidence, FootprintFilter), stacked one above the other, and each voxel's packed
// centre points into the level that matches its projected width. Then fusion is the
// single-projection kernel: one lookup per voxel and camera. See footprintLevelOf().
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "psfs_reconstruction/projection_constants.h"
#include "psfs_reconstruction/voxel_grid.h"
#include "tabletop_capture/camera_model.h"

namespace psfs {

// Sub-pixel image position in 32 bits, 1/16 pixel resolution. Pixel centres sit at integer
// coordinates, so a camera's image covers u in [-0.5, width - 0.5), v in [-0.5, height - 0.5).
// Low 16 bits: (u + 0.5) * 16, high 16 bits: (v + 0.5) * 16; the nearest pixel is then simply
// (low >> 4, high >> 4). A point the camera does not observe (behind it, outside the image, or
// beyond the range where the lens model is valid) is packed as u = 0, v = 16 * height, which
// decodes to pixel index width * height: the guard pixel after each evidence image that always
// says "no evidence". So the inner loops need no branch for unobserved voxels.
struct PackedUV {
  static constexpr int kFracBits = 4;
  static constexpr int kOne = 1 << kFracBits;
  // 16 * side plus the pair images' pad and the largest sample offset (8 + 7 px) must fit 16
  // bits: the multi-projection kernels add them in 16-bit lanes.
  static constexpr int kMaxImageSide = 4080;
  static uint32_t notObserved(int height) { return static_cast<uint32_t>(kOne * height) << 16; }
  static int pixelIndex(uint32_t p, int width) {
    return static_cast<int>(p >> (16 + kFracBits)) * width + static_cast<int>((p & 0xFFFFu) >> kFracBits);
  }
  static double u(uint32_t p) { return (p & 0xFFFFu) / double(kOne) - 0.5; }
  static double v(uint32_t p) { return (p >> 16) / double(kOne) - 0.5; }
};

namespace detail {
// Leaves resized elements uninitialised: a table is written in parallel right after it is
// sized, so zero-filling 50 MB first (single-threaded) would only cost time.
template <class T>
struct UninitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitAllocator<U>;
  };
  UninitAllocator() = default;
  template <class U>
  UninitAllocator(const UninitAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
}  // namespace detail

enum class TableStorage {
  kAuto,         // precompute when the table fits Options::auto_max_bytes, else on the fly
  kPrecomputed,  // static grids: compute once, stream from memory every frame
  kOnTheFly,     // moving or huge grids: project each row when it is fused
};

struct ProjectionTableOptions {
  bool multi_projection = false;   // also provide the 6 sample offsets per voxel
  // Footprint levels (prototype, see the file comment): 0 = off (plain centres). L in
  // [2, kMaxFootprintLevels]: voxel centres point into level l of L stacked evidence images, l =
  // the voxel's footprint radius round(footprint_scale * w) clamped to L - 1, w = f s / Z the
  // voxel's projected width in pixels (f = sqrt(fx fy), s the voxel edge, Z its depth in the
  // camera; lens distortion and obliqueness are ignored). Level l is read from an image filtered
  // over (2l + 1)^2 pixels. Exclusive with multi_projection; only PsfsFusion with
  // PsfsOptions::footprint reads such a table. Needs (height + 1) * L <= 4095 per camera.
  int footprint_levels = 0;
  double footprint_scale = 0.7;
  TableStorage storage = TableStorage::kAuto;
  size_t auto_max_bytes = size_t(128) << 20;
  int threads = 0;                 // OpenMP threads for building (0 = OpenMP default)
};

class ProjectionTable {
 public:
  // Largest sample offset the multi-projection test uses (pixels): half a voxel, clamped to
  // this. A memory bound too: samples must stay inside the evidence images' 8 px border
  // (static_assert in psfs_kernels.cpp). Voxels wider than ~14 pixels would need more than 6
  // samples anyway (the default rig's 16 mm voxels are at most 4.5 px wide).
  static constexpr int kMaxSampleOffsetPx = 7;
  static constexpr int kChunk = 8;  // voxels per chunk along x (one AVX2 vector of int32)
  static constexpr int kMaxFootprintLevels = 3;  // windows 1, 3 and 5 px

  ProjectionTable() = default;
  // Validates grid and cameras (throws std::invalid_argument naming the camera and the field:
  // non-finite or non-positive intrinsics, bad rotation, image side > PackedUV::kMaxImageSide = 4080 px) and builds.
  ProjectionTable(const VoxelGrid& grid, const std::vector<tabletop_capture::CameraModel>& cameras,
                  const ProjectionTableOptions& options = ProjectionTableOptions());

  // Rebuilds only if the grid or any camera parameter changed; returns true if it rebuilt.
  // For an on-the-fly table a rebuild is only the per-camera constants (microseconds), so a
  // hand sub-volume can call this every frame.
  bool update(const VoxelGrid& grid, const std::vector<tabletop_capture::CameraModel>& cameras);

  const VoxelGrid& grid() const { return grid_; }
  const ProjectionTableOptions& options() const { return options_; }
  int numCameras() const { return static_cast<int>(cameras_.size()); }
  const tabletop_capture::CameraModel& camera(int c) const { return cameras_[c].model; }
  bool precomputed() const { return precomputed_; }
  bool multiProjection() const { return options_.multi_projection; }
  int footprintLevels() const { return options_.footprint_levels; }
  // Level of a packed centre of camera c in a footprint table (0 in a plain one). The packed v of
  // level l is offset by l * (height + 1) rows: evidence level l starts at row l * (height + 1).
  int footprintLevelOf(int c, uint32_t packed) const {
    return static_cast<int>(packed >> (16 + PackedUV::kFracBits)) / (cameras_[c].proj.height + 1);
  }
  size_t memoryBytes() const;  // stored projections (0 when on the fly)
  // Changes with every (re)build, unique within the process (0: never built): what a cache of
  // anything derived from the table's projections compares (EmptySpaceBound).
  uint64_t revision() const { return revision_; }
  // What a precomputed table of this grid and these options would take.
  static size_t precomputedBytes(const VoxelGrid& grid, int num_cameras, bool multi_projection);

  // ---- Row access for the fusion kernels ------------------------------------------------
  int paddedRowLength() const { return nxp_; }   // nx rounded up to kChunk
  int chunksPerRow() const { return nxp_ / kChunk; }
  size_t centreScratchSize() const { return size_t(nxp_) * cameras_.size(); }
  size_t offsetScratchSize() const { return size_t(chunksPerRow()) * 3 * cameras_.size(); }
  // Packed centres of grid row `row` (= y + ny * z) for all cameras: [c * paddedRowLength() + x];
  // entries x >= nx are notObserved. Points into the table when precomputed, otherwise fills
  // `scratch` (centreScratchSize() entries) and returns it.
  const uint32_t* rowCentres(size_t row, uint32_t* scratch) const;
  // The same for voxels [begin, end) of the row only (whole chunks: multiples of kChunk, end <=
  // paddedRowLength(); throws std::invalid_argument otherwise): a table projected on the fly
  // projects just those into scratch (the rest of it is left as it was), a stored one returns
  // the whole row. What a fusion that skips parts of rows reads (PsfsOptions::skip_empty_below).
  const uint32_t* rowCentres(size_t row, uint32_t* scratch, int begin, int end) const;
  // Sample offsets (multi-projection tables only): [(c * chunksPerRow() + chunk) * 3 + axis],
  // each int16 du (low) and dv (high) in 1/16 pixel, the displacement of +1/2 voxel along axis
  // (voxel centre to face centre), clamped to kMaxSampleOffsetPx.
  const uint32_t* rowOffsets(size_t row, uint32_t* scratch) const;

  // Scalar access for tests and reference code: packed centre of voxel (x, y, z) in camera c
  // (the image position: without the footprint level, see footprintLevel()).
  uint32_t centre(int c, int x, int y, int z) const;
  // Footprint level of voxel (x, y, z) in camera c (0 in a plain table).
  int footprintLevel(int c, int x, int y, int z) const;
  // A packed centre of camera c as rowCentres gives it, without its footprint level.
  uint32_t withoutLevel(int c, uint32_t packed) const {
    const uint32_t level = static_cast<uint32_t>(footprintLevelOf(c, packed));
    return packed - ((level * static_cast<uint32_t>(PackedUV::kOne * (cameras_[c].proj.height + 1))) << 16);
  }

  // ---- The projection as plain data (projection_constants.h) -----------------------------
  // What the table projects with: a GPU (gpu_psfs_fusion.h) projects an on-the-fly table on
  // the device from these with the table build's own code, to the same packed values.
  const ProjectionCamera& projectionCamera(int c) const { return cameras_[c].proj; }
  ProjectionGrid projectionGrid() const;

 private:
  struct Camera {
    tabletop_capture::CameraModel model;
    ProjectionCamera proj;
  };
  void build();
  void checkFootprintRows(const std::vector<Camera>& cams) const;
  void projectRow(const Camera& cam, int y, int z, uint32_t* out, int begin, int end) const;
  void sampleOffsets(const Camera& cam, int y, int z, uint32_t* out) const;
  static Camera prepareCamera(const tabletop_capture::CameraModel& m, int index);

  VoxelGrid grid_;
  ProjectionTableOptions options_;
  std::vector<Camera> cameras_;
  int nxp_ = 0;
  bool precomputed_ = false;
  uint64_t revision_ = 0;
  std::vector<uint32_t, detail::UninitAllocator<uint32_t>> centres_;  // [row][camera][x]
  std::vector<uint32_t, detail::UninitAllocator<uint32_t>> offsets_;  // [row][camera][chunk][axis]
};

}  // namespace psfs
