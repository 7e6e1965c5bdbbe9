// The GPU pSfS path run on the host, thread by thread (volume_fusion.h): what the tests compare
// with PsfsFusion in every build, GPU or not.
#include <vector>

#include "fusion_common.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "volume_fusion.h"

namespace psfs {
namespace detail {

void hostEmulateProjection(const ProjectionTable& table, uint32_t* centres, uint32_t* offsets) {
  const ProjectionGrid g = table.projectionGrid();
  const int C = table.numCameras();
  const bool multi = table.multiProjection();
  const long long slices = static_cast<long long>(table.grid().numRows()) * C;
  // One block per (row, camera) on the device: here one iteration, a single "thread" (first 0,
  // step 1) writing the whole slice.
#pragma omp parallel for schedule(dynamic, 64)
  for (long long i = 0; i < slices; ++i) {
    const size_t row = size_t(i / C);
    const int c = static_cast<int>(i % C);
    const int y = static_cast<int>(row % g.ny), z = static_cast<int>(row / g.ny);
    const ProjectionCamera& cam = table.projectionCamera(c);
    const ProjectionRow r = projectionRow(cam, g, y, z);
    projectTableRow(cam, g, r, y, z, multi, 0, 1, centres + size_t(i) * g.nxp,
                    multi ? offsets + size_t(i) * g.chunks * 3 : nullptr);
  }
}

void hostEmulateFusion(const PsfsOptions& options, const ProjectionTable& table, const ViewEvidence& evidence,
                       ProbabilityVolume* out, bool project) {
  const std::string who = "psfs::detail::hostEmulateFusion";
  if (!out) throw std::invalid_argument(who + ": null output");
  const PsfsFusion validated(options);  // throws for options out of range
  checkInputs(table, evidence, options.multi_projection, who);
  checkFootprint(table, evidence, options.footprint, who);
  const bool multi = options.multi_projection;
  std::vector<KernelView> views = kernelViews(evidence);
  PsfsRowParams p = psfsRowParams(options, table);
  p.views = views.data();
  p.exp_table = psfsExpTable();

  TableView t;
  const VoxelGrid& grid = table.grid();
  t.nx = grid.dims.x(), t.ny = grid.dims.y(), t.nz = grid.dims.z();
  t.nxp = table.paddedRowLength(), t.chunks = table.chunksPerRow();
  std::vector<uint32_t> centres, offsets;
  if (project || !table.precomputed()) {
    centres.resize(grid.numRows() * table.centreScratchSize());
    if (table.multiProjection()) offsets.resize(grid.numRows() * table.offsetScratchSize());
    hostEmulateProjection(table, centres.data(), offsets.data());
    t.centres = centres.data();
    t.offsets = table.multiProjection() ? offsets.data() : nullptr;
  } else {
    t.centres = table.rowCentres(0, nullptr);  // the stored table is one array, row by row
    t.offsets = table.multiProjection() ? table.rowOffsets(0, nullptr) : nullptr;
  }

  out->grid = grid;
  out->data.resize(grid.numVoxels());
  uint8_t* dst = out->data.data();
  const int k = options.occluded_views;
  const long long rows = static_cast<long long>(grid.numRows());
#pragma omp parallel for schedule(dynamic, 8) num_threads(resolveThreads(options.threads))
  for (long long r = 0; r < rows; ++r) {
    const int y = static_cast<int>(r % t.ny), z = static_cast<int>(r / t.ny);
    for (int x = 0; x < t.nx; ++x) dst[size_t(r) * t.nx + x] = fuseVoxelK(k, p, t, multi, x, y, z);
  }
}

}  // namespace detail
}  // namespace psfs
