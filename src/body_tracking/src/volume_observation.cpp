#include "body_tracking/volume_observation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "plain_part.h"

namespace body_tracking {

namespace {

// Block mean of a uint8 volume (p = value / 255) over f^3 blocks; partial blocks at the far
// edges average what they have.
void downsample(const psfs::ProbabilityVolume& in, int f, psfs::VoxelGrid* grid,
                std::vector<float>* out) {
  const Eigen::Vector3i& d = in.grid.dims;
  grid->origin = in.grid.origin;
  grid->voxel_size = in.grid.voxel_size * f;
  grid->dims = Eigen::Vector3i((d.x() + f - 1) / f, (d.y() + f - 1) / f, (d.z() + f - 1) / f);
  out->assign(grid->numVoxels(), 0.0f);
  std::vector<int> count(grid->numVoxels(), 0);
  for (int z = 0; z < d.z(); ++z)
    for (int y = 0; y < d.y(); ++y) {
      const uint8_t* row = &in.data[in.grid.index(0, y, z)];
      for (int x = 0; x < d.x(); ++x) {
        const size_t o = grid->index(x / f, y / f, z / f);
        (*out)[o] += row[x];
        ++count[o];
      }
    }
  for (size_t i = 0; i < out->size(); ++i) (*out)[i] /= 255.0f * std::max(1, count[i]);
}

}  // namespace

VolumeObservation::VolumeObservation(const ObservationParams& params) : params_(params) {
  if (params_.downsample < 1 || params_.downsample > 8)
    throw std::invalid_argument("observation downsample must be in 1..8");
  if (!(params_.skin_weight >= 0 && params_.skin_weight <= 1))
    throw std::invalid_argument("observation skin_weight must be in [0, 1]");
  if (!(params_.unknown_likelihood >= 0 && params_.unknown_likelihood <= 1))
    throw std::invalid_argument("observation unknown_likelihood must be in [0, 1]");

}

void VolumeObservation::setVolumes(const psfs::ProbabilityVolume& body,
                                   const psfs::ProbabilityVolume* skin) {
  body.grid.validate();
  if (body.data.size() != body.grid.numVoxels())
    throw std::invalid_argument("body volume: data size does not match its grid");
  if (skin && (skin->grid != body.grid || skin->data.size() != body.data.size()))
    throw std::invalid_argument("skin volume: grid differs from the body volume's");
  downsample(body, params_.downsample, &grid_, &body_);
  if (skin) {
    psfs::VoxelGrid g;
    downsample(*skin, params_.downsample, &g, &skin_);
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
  buildRowSums(grid_, body_, &body_sums_);
  buildRowSums(grid_, blended_, &blended_sums_);
}

void VolumeObservation::buildRowSums(const psfs::VoxelGrid& g, const std::vector<float>& y,
                                     RowSums* out) {
  const int nx = g.dims.x();
  const size_t rows = g.numRows();
  out->s0.assign(rows * (nx + 1), 0.0);
  out->s1.assign(rows * (nx + 1), 0.0);
  out->s2.assign(rows * (nx + 1), 0.0);
  for (size_t r = 0; r < rows; ++r) {
    const float* row = &y[r * nx];
    double* a = &out->s0[r * (nx + 1)];
    double* b = &out->s1[r * (nx + 1)];
    double* c = &out->s2[r * (nx + 1)];
    for (int x = 0; x < nx; ++x) {
      a[x + 1] = a[x] + row[x];
      b[x + 1] = b[x] + static_cast<double>(x) * row[x];
      c[x + 1] = c[x] + static_cast<double>(x) * x * row[x];
    }
  }
}

double VolumeObservation::partScore(const TruncatedQuadric& part, bool skin_part,
                                     bool extrapolate) const {
  // part_score.h: the same arithmetic as the GPU particle weights.
  return part_score::scorePart(plainPart(part, skin_part, extrapolate),
                               plainGrid(grid_, params_.unknown_likelihood),
                               rowSumsView(rowSums(skin_part)));
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
