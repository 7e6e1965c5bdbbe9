#include "psfs_reconstruction/psfs_fusion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "cpu_dispatch.h"
#include "empty_space_bound.h"
#include "fusion_common.h"
#include "psfs_kernels.h"
#include "volume_fusion.h"

namespace psfs {
namespace {

constexpr int kExpTableSize = 4096;
constexpr float kExpScale = 512.0f;  // bins per unit of ln p: < 0.2 % steps in p

const std::vector<int32_t>& expTable() {
  static const std::vector<int32_t> t = [] {
    std::vector<int32_t> v(kExpTableSize);
    for (int i = 0; i < kExpTableSize; ++i)
      v[i] = static_cast<int32_t>(std::lround(255.0 * std::exp(-(i + 0.5) / kExpScale)));
    v[0] = 255;  // ln p in (-1/512, 0]: p rounds to 1
    return v;
  }();
  return t;
}

void checkProbability(double p, const char* name, bool allow_zero) {
  if (!std::isfinite(p) || p < 0.0 || p > 1.0 || (!allow_zero && p == 0.0))
    throw std::invalid_argument(std::string("psfs::PsfsOptions: ") + name + " must be in " +
                                (allow_zero ? "[0, 1]" : "(0, 1]"));
}

}  // namespace

namespace detail {

PsfsRowParams psfsRowParams(const PsfsOptions& o, const ProjectionTable& table) {
  const int C = table.numCameras();
  PsfsRowParams p;
  p.nx = table.grid().dims.x();
  p.nxp = table.paddedRowLength();
  p.num_cameras = C;
  p.chunks = table.chunksPerRow();
  const double td = o.drop_threshold > 0.0 ? o.drop_threshold : o.threshold;
  p.drop_below = static_cast<int32_t>(std::lround(ViewEvidence::kLogScale * std::log(td)));
  p.min_views = o.min_views;
  p.offset = (o.hull_prior > 0.0 && o.view_prior > 0.0)
                 ? static_cast<float>(std::log(o.hull_prior) / C - std::log(o.view_prior))
                 : 0.0f;
  p.log_t = static_cast<float>(std::log(o.threshold));
  p.exp_table_size = kExpTableSize;
  p.exp_scale = kExpScale;
  p.t_byte = thresholdByte(o.threshold);
  p.zero_outside = o.zero_outside_hull;
  p.first_layer = layersBelow(table.grid(), o.floor_z);
  return p;
}

const int32_t* psfsExpTable() { return expTable().data(); }

}  // namespace detail

double foregroundViewPrior(double hull_occupancy_foreground, int num_cameras) {
  checkProbability(hull_occupancy_foreground, "hull_occupancy_foreground", false);
  if (num_cameras < 1) throw std::invalid_argument("psfs::foregroundViewPrior: num_cameras < 1");
  return std::pow(hull_occupancy_foreground, 1.0 / num_cameras);
}

double skinViewPrior(double hull_occupancy_skin, double hull_occupancy_foreground, int num_cameras) {
  checkProbability(hull_occupancy_skin, "hull_occupancy_skin", false);
  if (hull_occupancy_skin > hull_occupancy_foreground)
    throw std::invalid_argument("psfs::skinViewPrior: skin hull occupancy exceeds the foreground's");
  return std::pow(hull_occupancy_skin, 1.0 / num_cameras) /
         foregroundViewPrior(hull_occupancy_foreground, num_cameras);
}

PsfsFusion::PsfsFusion(const PsfsOptions& o) : options_(o) {
  if (!std::isfinite(o.threshold) || !(o.threshold > 0.5) || !(o.threshold < 1.0))
    throw std::invalid_argument("psfs::PsfsOptions: threshold must be in (0.5, 1)");
  checkProbability(o.hull_prior, "hull_prior", true);
  checkProbability(o.view_prior, "view_prior", true);
  if (o.occluded_views < 0 || o.occluded_views > detail::kMaxOccludedViews)
    throw std::invalid_argument("psfs::PsfsOptions: occluded_views must be in 0..4");
  if (!std::isfinite(o.drop_threshold) || o.drop_threshold < 0.0 || !(o.drop_threshold < 1.0))
    throw std::invalid_argument("psfs::PsfsOptions: drop_threshold must be in [0, 1)");
  if (o.min_views < 1) throw std::invalid_argument("psfs::PsfsOptions: min_views must be >= 1");
  if (o.threads < 0) throw std::invalid_argument("psfs::PsfsOptions: threads must be >= 0");
  if (o.footprint && o.multi_projection)
    throw std::invalid_argument("psfs::PsfsOptions: footprint and multi_projection are exclusive");
  if (std::isnan(o.floor_z) || o.floor_z == std::numeric_limits<double>::infinity())
    throw std::invalid_argument("psfs::PsfsOptions: floor_z must be a height or -infinity");
  if (!std::isfinite(o.skip_empty_below) || o.skip_empty_below < 0.0 || !(o.skip_empty_below < o.threshold))
    throw std::invalid_argument("psfs::PsfsOptions: skip_empty_below must be in [0, threshold)");
  skip_ = std::make_shared<detail::EmptySkipCache>();
}

double PsfsFusion::lastSkippedFraction() const {
  std::lock_guard<std::mutex> lock(skip_->mutex);
  return skip_->last_fraction;
}

void PsfsFusion::fuse(const ProjectionTable& table, const ViewEvidence& evidence,
                      ProbabilityVolume* out) const {
  if (!out) throw std::invalid_argument("psfs::PsfsFusion::fuse: null output");
  detail::checkInputs(table, evidence, options_.multi_projection, "psfs::PsfsFusion::fuse");
  detail::checkFootprint(table, evidence, options_.footprint, "psfs::PsfsFusion::fuse");
  std::vector<detail::KernelView> views = detail::kernelViews(evidence);
  detail::PsfsRowParams p = detail::psfsRowParams(options_, table);
  p.views = views.data();
  p.exp_table = detail::psfsExpTable();
  out->grid = table.grid();
  out->data.resize(table.grid().numVoxels());
  uint8_t* dst = out->data.data();
  const bool vector = vectorKernelsActive();
  // The layers below the floor are 0. Single projection never projects their rows; the
  // multi-projection kernel carries the faces along z, so it computes them and they are cleared.
  const size_t first_row = size_t(p.first_layer) * size_t(out->grid.dims.y());
  if (options_.multi_projection) {
    const detail::PsfsFaceRowFn face_fn = detail::selectPsfsFaceRow(options_.occluded_views, vector);
    std::vector<uint8_t> skip;
    std::unique_lock<std::mutex> lock;  // held through the fusion: skipped chunks read the bound
    if (detail::skipsEmptySpace(options_)) {
      lock = std::unique_lock<std::mutex>(skip_->mutex);
      detail::tileMaxImages(evidence, options_.threads, &skip_->tiles);
      detail::skippedChunks(options_, table, skip_.get(), &skip);
    }
    detail::forEachFaceRow(
        table, views, options_.threads,
        [&](size_t r, const uint32_t* centres, const uint32_t* offsets, uint16_t* yface, uint16_t* zface,
            const detail::RowSpan& span) { face_fn(p, centres, offsets, yface, zface, dst + r * p.nx, span); },
        skip.empty() ? nullptr : skip.data(), [&](size_t r) {
          skip_->bound.fillChunks(r, &skip[r * size_t(p.chunks)], skip_->fill, p.min_views, skip_->absent,
                                  dst + r * p.nx);
        });
  } else if (detail::skipsCentreSpace(options_)) {
    const detail::PsfsRowFn row_fn = detail::selectPsfsRow(options_.occluded_views, vector);
    std::lock_guard<std::mutex> lock(skip_->mutex);
    std::vector<uint8_t> skip;
    skip_->last_fraction = skip_->centre.skippableChunks(table, evidence, p, options_.occluded_views,
                                                         options_.skip_empty_below, options_.threads, &skip);
    detail::forEachRowSpan(
        table, options_.threads, 8, skip.data(),
        [&](size_t r, const uint32_t* centres, const detail::RowSpan& span) { row_fn(p, centres, dst + r * p.nx, span); },
        [&](size_t r, int begin, int end) {
          std::fill(dst + r * p.nx + begin, dst + r * p.nx + std::min(end, p.nx), uint8_t(0));
        },
        first_row);
  } else {
    const detail::PsfsRowFn row_fn = detail::selectPsfsRow(options_.occluded_views, vector);
    detail::forEachRow(
        table, options_.threads, 8,
        [&](size_t r, const uint32_t* centres) { row_fn(p, centres, dst + r * p.nx, detail::RowSpan{0, p.nxp}); },
        first_row);
  }
  std::fill(dst, dst + first_row * size_t(p.nx), uint8_t(0));
}

}  // namespace psfs
