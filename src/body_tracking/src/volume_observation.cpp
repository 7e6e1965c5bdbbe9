#include "body_tracking/volume_observation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "part_spans.h"
#include "plain_part.h"

namespace body_tracking {

namespace {

// Block mean of a uint8 volume (p = value / 255) over f^3 blocks; partial blocks at the far
// edges average what they have. Integer block sums (exact, so the same floats as summing the
// bytes as floats), output layers in parallel.
void downsample(const psfs::ProbabilityVolume& in, int f, int threads, psfs::VoxelGrid* grid,
                std::vector<float>* out) {
  const Eigen::Vector3i& d = in.grid.dims;
  grid->origin = in.grid.origin;
  grid->voxel_size = in.grid.voxel_size * f;
  grid->dims = Eigen::Vector3i((d.x() + f - 1) / f, (d.y() + f - 1) / f, (d.z() + f - 1) / f);
  out->resize(grid->numVoxels());
  const int nxo = grid->dims.x(), nyo = grid->dims.y(), nzo = grid->dims.z();
  const auto extent = [f](int o, int n) { return std::min(n, o * f + f) - o * f; };  // inputs in block o
#pragma omp parallel for num_threads(std::max(1, threads)) schedule(static)
  for (int zo = 0; zo < nzo; ++zo) {
    std::vector<int32_t> sum(size_t(nxo) * nyo, 0);
    const int cz = extent(zo, d.z());
    for (int z = zo * f; z < zo * f + cz; ++z)
      for (int y = 0; y < d.y(); ++y) {
        const uint8_t* row = &in.data[in.grid.index(0, y, z)];
        int32_t* acc = &sum[size_t(y / f) * nxo];
        for (int xo = 0, x = 0; xo < nxo; ++xo)
          for (const int x1 = std::min(d.x(), x + f); x < x1; ++x) acc[xo] += row[x];
      }
    float* o = out->data() + size_t(nxo) * nyo * zo;
    for (int yo = 0; yo < nyo; ++yo)
      for (int xo = 0; xo < nxo; ++xo) {
        const int count = cz * extent(yo, d.y()) * extent(xo, d.x());
        o[size_t(yo) * nxo + xo] = static_cast<float>(sum[size_t(yo) * nxo + xo]) / (255.0f * count);
      }
  }
}

}  // namespace

VolumeObservation::VolumeObservation(const ObservationParams& params) : params_(params) {
  if (params_.downsample < 1 || params_.downsample > 8)
    throw std::invalid_argument("observation downsample must be in 1..8");
  if (!(params_.skin_weight >= 0 && params_.skin_weight <= 1))
    throw std::invalid_argument("observation skin_weight must be in [0, 1]");
  if (!(params_.unknown_likelihood >= 0 && params_.unknown_likelihood <= 1))
    throw std::invalid_argument("observation unknown_likelihood must be in [0, 1]");
  if (!(params_.trunk_shell_width > 0 && params_.trunk_shell_width <= 0.2))
    throw std::invalid_argument("observation trunk_shell_width must be in (0, 0.2] m");
  if (!(params_.trunk_shell_weight >= 0 && params_.trunk_shell_weight <= 5))
    throw std::invalid_argument("observation trunk_shell_weight must be in [0, 5]");

}

void VolumeObservation::setVolumes(const psfs::ProbabilityVolume& body,
                                   const psfs::ProbabilityVolume* skin, int threads) {
  body.grid.validate();
  if (body.data.size() != body.grid.numVoxels())
    throw std::invalid_argument("body volume: data size does not match its grid");
  if (skin && (skin->grid != body.grid || skin->data.size() != body.data.size()))
    throw std::invalid_argument("skin volume: grid differs from the body volume's");
  downsample(body, params_.downsample, threads, &grid_, &body_);
  if (skin) {
    psfs::VoxelGrid g;
    downsample(*skin, params_.downsample, threads, &g, &skin_);
  } else {
    skin_.assign(body_.size(), 0.0f);
  }
  const float k = static_cast<float>(skin ? params_.skin_weight : 0.0);
  blended_.resize(body_.size());
  occupied_ = 0;
  for (size_t i = 0; i < body_.size(); ++i) {
    blended_[i] = (1.0f - k) * body_[i] + k * skin_[i];
    if (body_[i] > 0.5f) ++occupied_;
  }
  buildRowSums(grid_, body_, threads, &body_sums_);
  buildRowSums(grid_, blended_, threads, &blended_sums_);
}

void VolumeObservation::buildRowSums(const psfs::VoxelGrid& g, const std::vector<float>& y,
                                     int threads, RowSums* out) {
  const int nx = g.dims.x();
  const long rows = static_cast<long>(g.numRows());
  out->s0.resize(rows * (nx + 1));
  out->s1.resize(rows * (nx + 1));
  out->s2.resize(rows * (nx + 1));
#pragma omp parallel for num_threads(std::max(1, threads)) schedule(static)
  for (long r = 0; r < rows; ++r) {
    const float* row = &y[r * nx];
    double* a = &out->s0[r * (nx + 1)];
    double* b = &out->s1[r * (nx + 1)];
    double* c = &out->s2[r * (nx + 1)];
    a[0] = b[0] = c[0] = 0.0;
    for (int x = 0; x < nx; ++x) {
      a[x + 1] = a[x] + row[x];
      b[x + 1] = b[x] + static_cast<double>(x) * row[x];
      c[x + 1] = c[x] + static_cast<double>(x) * x * row[x];
    }
  }
}

namespace {
// part_score.h's arithmetic, as the GPU particle weights do it, with the rows' intervals a SIMD
// vector at a time (part_spans.h: the same bytes as part_score::scorePart).
double scoreWith(const TruncatedQuadric& part, bool skin_part, bool extrapolate,
                 const ObservationParams& op, const psfs::VoxelGrid& grid,
                 const VolumeObservation::RowSums& sums) {
  thread_local part_spans::SpanRows rows;
  return part_spans::scorePart(plainPart(part, skin_part, extrapolate, op),
                               plainGrid(grid, op.unknown_likelihood), rowSumsView(sums),
                               part_spans::activeSpans(), &rows);
}
}  // namespace

double VolumeObservation::partScore(const TruncatedQuadric& part, bool skin_part,
                                     bool extrapolate) const {
  return scoreWith(part, skin_part, extrapolate, params_, grid_, rowSums(skin_part));
}

double VolumeObservation::partMean(const TruncatedQuadric& part, bool skin_part,
                                   bool extrapolate) const {
  ObservationParams no_shell = params_;
  no_shell.trunk_shell_weight = 0.0;
  return scoreWith(part, skin_part, extrapolate, no_shell, grid_, rowSums(skin_part));
}

double VolumeObservation::score(const BodyParts& parts,
                                std::array<double, kNumParts>* per_part) const {
  double total = 0;
  for (int p = 0; p < kNumParts; ++p) {
    const double s = partScore(parts[p], isSkinPart(static_cast<Part>(p)), isTrunkPart(static_cast<Part>(p)));
    if (per_part) (*per_part)[p] = s;
    total += s;
  }
  return total;
}

}  // namespace body_tracking
