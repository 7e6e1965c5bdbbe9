#include "psfs_reconstruction/gpu_psfs_fusion.h"

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "empty_space_bound.h"
#include "fusion_common.h"
#include "psfs_reconstruction/cuda_device.h"
#include "volume_fusion.h"

namespace psfs {
namespace {

const char* const kWho = "psfs::GpuPsfsFusion::fuse";

bool sameCamera(const tabletop_capture::CameraModel& a, const tabletop_capture::CameraModel& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx &&
         a.cy == b.cy && a.distortion == b.distortion && a.world_T_camera.matrix() == b.world_T_camera.matrix();
}

// Evidence entries the volume kernel can read (view_evidence.h's layout): the terms up to the
// last level's guard pixel, the pair images plus the entry past their end.
size_t termsCount(const ViewEvidence& e, int v) {
  const size_t W = e.width(v), H = e.height(v);
  const size_t levels = e.footprint().levels > 1 ? e.footprint().levels : 1;
  return W * (H + 1) * (levels - 1) + W * H + 1;
}
size_t pairsCount(const ViewEvidence& e, int v) {
  return size_t(e.quadStride(v)) * (e.height(v) + 2 * ViewEvidence::kQuadPad) + 1;
}

// The evidence arrays as the device backend copies them.
std::vector<detail::HostEvidenceView> hostViews(const ViewEvidence& evidence, bool pairs) {
  std::vector<detail::HostEvidenceView> views(evidence.numViews());
  for (int c = 0; c < evidence.numViews(); ++c) {
    detail::HostEvidenceView& v = views[c];
    v.terms = evidence.terms(c);
    v.terms_count = termsCount(evidence, c);
    if (pairs) {
      v.pairs = evidence.pairs(c);
      v.pairs_count = pairsCount(evidence, c);
    }
    v.width = evidence.width(c), v.height = evidence.height(c), v.quad_stride = evidence.quadStride(c);
    v.has_mask = evidence.hasInactivePixels(c);
  }
  return views;
}

}  // namespace

// The device backend (created with the first frame) and what the device's table was made from.
struct GpuPsfsFusion::Impl {
  std::unique_ptr<detail::CudaVolumeFusion> backend;
  detail::EmptySkipCache skip;  // PsfsOptions::skip_empty_below: what PsfsFusion skips
  bool table_valid = false;
  VoxelGrid grid;
  bool multi = false, precomputed = false;
  int levels = 0;
  double scale = 0.0;
  std::vector<tabletop_capture::CameraModel> cameras;

  bool sameTable(const ProjectionTable& t) const {
    if (!table_valid || t.grid() != grid || t.multiProjection() != multi || t.precomputed() != precomputed ||
        t.footprintLevels() != levels || t.options().footprint_scale != scale ||
        t.numCameras() != static_cast<int>(cameras.size()))
      return false;
    for (int c = 0; c < t.numCameras(); ++c)
      if (!sameCamera(t.camera(c), cameras[c])) return false;
    return true;
  }
  void remember(const ProjectionTable& t) {
    grid = t.grid();
    multi = t.multiProjection();
    precomputed = t.precomputed();
    levels = t.footprintLevels();
    scale = t.options().footprint_scale;
    cameras.clear();
    for (int c = 0; c < t.numCameras(); ++c) cameras.push_back(t.camera(c));
    table_valid = true;
  }
};

GpuPsfsFusion::GpuPsfsFusion(const PsfsOptions& options) : options_(options), impl_(new Impl) {
  const PsfsFusion validated(options);  // same checks and messages
}
GpuPsfsFusion::~GpuPsfsFusion() = default;
GpuPsfsFusion::GpuPsfsFusion(GpuPsfsFusion&&) noexcept = default;
GpuPsfsFusion& GpuPsfsFusion::operator=(GpuPsfsFusion&&) noexcept = default;

bool GpuPsfsFusion::usable() const { return cuda::device().usable; }

std::string GpuPsfsFusion::reason() const { return cuda::device().usable ? "" : cuda::device().describe(); }

size_t GpuPsfsFusion::deviceAllocations() const {
  return impl_ && impl_->backend ? impl_->backend->allocations() : 0;
}

void GpuPsfsFusion::prepare(const ProjectionTable& table) {
  if (!usable()) throw std::runtime_error(std::string(kWho) + ": " + reason());
  if (table.numCameras() > detail::kMaxGpuCameras)
    throw std::runtime_error(std::string(kWho) + ": " + std::to_string(table.numCameras()) +
                             " cameras, the GPU path takes at most " + std::to_string(detail::kMaxGpuCameras));
  if (!impl_) impl_ = std::make_unique<Impl>();  // moved from
  Impl& m = *impl_;
  if (!m.backend) m.backend = std::make_unique<detail::CudaVolumeFusion>();
  if (m.sameTable(table)) return;
  m.table_valid = false;
  const int C = table.numCameras();
  if (table.precomputed()) {
    detail::TableView host;
    host.centres = table.rowCentres(0, nullptr);  // the stored table is one array, row by row
    host.offsets = table.multiProjection() ? table.rowOffsets(0, nullptr) : nullptr;
    host.nx = table.grid().dims.x(), host.ny = table.grid().dims.y(), host.nz = table.grid().dims.z();
    host.nxp = table.paddedRowLength(), host.chunks = table.chunksPerRow();
    m.backend->uploadTable(host, C, table.multiProjection());
  } else {
    std::vector<ProjectionCamera> cams;
    for (int c = 0; c < C; ++c) cams.push_back(table.projectionCamera(c));
    m.backend->projectTable(cams.data(), C, table.projectionGrid(), table.multiProjection());
  }
  m.remember(table);
}

void GpuPsfsFusion::run(const ProjectionTable& table, const void* host_views, const void* device_views,
                        ProbabilityVolume* out) {
  try {
    prepare(table);
    detail::PsfsRowParams p = detail::psfsRowParams(options_, table);
    p.exp_table = detail::psfsExpTable();  // host copy: the backend uploads it once
    out->grid = table.grid();
    out->data.resize(table.grid().numVoxels());
    impl_->backend->fuse(p, options_.occluded_views, options_.multi_projection,
                         static_cast<const detail::HostEvidenceView*>(host_views),
                         static_cast<const detail::KernelView*>(device_views), out->data.data(),
                         out->data.size());
    const detail::StageTimes& t = impl_->backend->times();
    timings_ = GpuFusionTimings{t.upload, t.project, t.fuse, t.readback};
  } catch (const std::runtime_error&) {
    impl_->table_valid = false;  // the device's state is unknown: upload again next time
    throw;
  }
}

void GpuPsfsFusion::fuse(const ProjectionTable& table, const ViewEvidence& evidence, ProbabilityVolume* out) {
  if (!out) throw std::invalid_argument(std::string(kWho) + ": null output");
  detail::checkInputs(table, evidence, options_.multi_projection, kWho);
  detail::checkFootprint(table, evidence, options_.footprint, kWho);
  const std::vector<detail::HostEvidenceView> views = hostViews(evidence, options_.multi_projection);
  run(table, views.data(), nullptr, out);
  if (detail::skipsEmptySpace(options_)) {  // the device fused every voxel: fill PsfsFusion's skipped chunks
    detail::tileMaxImages(evidence, options_.threads, &impl_->skip.tiles);
    detail::fillSkipped(options_, table, &impl_->skip, out);
  }
  if (detail::skipsCentreSpace(options_)) {  // ... or zero the single projection's
    std::vector<uint8_t> flags;
    impl_->skip.centre.skippableChunks(table, evidence, detail::psfsRowParams(options_, table), options_.occluded_views,
                                       options_.skip_empty_below, options_.threads, &flags);
    detail::zeroChunks(table, flags, out);
  }
}

void GpuPsfsFusion::fuse(const ProjectionTable& table, const GpuEvidence& evidence, ProbabilityVolume* out) {
  if (!out) throw std::invalid_argument(std::string(kWho) + ": null output");
  const int C = table.numCameras();
  if (C == 0) throw std::invalid_argument(std::string(kWho) + ": empty projection table");
  if (static_cast<int>(evidence.size()) != C)
    throw std::invalid_argument(std::string(kWho) + ": " + std::to_string(evidence.size()) + " views for " +
                                std::to_string(C) + " cameras");
  if (options_.multi_projection && !table.multiProjection())
    throw std::invalid_argument(std::string(kWho) + ": multi-projection needs a table built with multi_projection");
  if (options_.footprint != (table.footprintLevels() > 0))
    throw std::invalid_argument(std::string(kWho) + ": PsfsOptions::footprint and the table's footprint levels disagree");
  std::vector<detail::KernelView> views(C);
  for (int c = 0; c < C; ++c) {
    const GpuViewEvidence& e = evidence[c];
    const std::string view = std::string(kWho) + ": view " + std::to_string(c);
    if (e.width != table.camera(c).width || e.height != table.camera(c).height)
      throw std::invalid_argument(view + " is " + std::to_string(e.width) + "x" + std::to_string(e.height) +
                                  " but camera '" + table.camera(c).name + "' is " +
                                  std::to_string(table.camera(c).width) + "x" +
                                  std::to_string(table.camera(c).height));
    if (!e.terms) throw std::invalid_argument(view + ": no terms");
    if (options_.multi_projection && (!e.pairs || e.quad_stride != e.width + 2 * ViewEvidence::kQuadPad))
      throw std::invalid_argument(view + ": multi-projection needs the pair images (quad_stride = width + " +
                                  std::to_string(2 * ViewEvidence::kQuadPad) + ")");
    views[c] = detail::KernelView{e.terms, e.pairs, e.width, e.quad_stride, e.has_inactive_pixels,
                                  PackedUV::notObserved(e.height)};
  }
  run(table, nullptr, views.data(), out);
}

// ---- GpuEvidenceBuffer ---------------------------------------------------------------------
struct GpuEvidenceBuffer::Impl {
  std::unique_ptr<detail::CudaEvidence> backend;
};

GpuEvidenceBuffer::GpuEvidenceBuffer() : impl_(new Impl) {}
GpuEvidenceBuffer::~GpuEvidenceBuffer() = default;
GpuEvidenceBuffer::GpuEvidenceBuffer(GpuEvidenceBuffer&&) noexcept = default;
GpuEvidenceBuffer& GpuEvidenceBuffer::operator=(GpuEvidenceBuffer&&) noexcept = default;

size_t GpuEvidenceBuffer::deviceAllocations() const {
  return impl_ && impl_->backend ? impl_->backend->allocations() : 0;
}

void GpuEvidenceBuffer::upload(const ViewEvidence& evidence) {
  if (!cuda::device().usable)
    throw std::runtime_error("psfs::GpuEvidenceBuffer::upload: " + cuda::device().describe());
  if (evidence.numViews() > detail::kMaxGpuCameras)
    throw std::runtime_error("psfs::GpuEvidenceBuffer::upload: more than " +
                             std::to_string(detail::kMaxGpuCameras) + " views");
  if (!impl_) impl_ = std::make_unique<Impl>();
  if (!impl_->backend) impl_->backend = std::make_unique<detail::CudaEvidence>();
  const std::vector<detail::HostEvidenceView> host = hostViews(evidence, evidence.bilinear());
  std::vector<detail::KernelView> dev(host.size());
  views_.clear();
  impl_->backend->upload(host.data(), static_cast<int>(host.size()), dev.data(), nullptr);
  for (size_t c = 0; c < host.size(); ++c)
    views_.push_back(GpuViewEvidence{dev[c].terms, dev[c].pairs, host[c].width, host[c].height,
                                     host[c].quad_stride, host[c].has_mask});
}

}  // namespace psfs
