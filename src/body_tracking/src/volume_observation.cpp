#include "body_tracking/volume_observation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace body_tracking {

using Eigen::Vector3d;
using Eigen::Vector4d;

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

namespace {

// Sums of 1, x and x^2 over the integers lo..hi (lo <= hi).
inline double sumPow0(long lo, long hi) { return static_cast<double>(hi - lo + 1); }
inline double sumPow1(long lo, long hi) {
  return 0.5 * (static_cast<double>(hi) * (hi + 1) - static_cast<double>(lo - 1) * lo);
}
inline double sumPow2(long lo, long hi) {
  auto f = [](double n) { return n * (n + 1) * (2 * n + 1) / 6.0; };  // sum 0..n of x^2
  // Valid for negative bounds too: sum_{lo..hi} x^2 = F(hi) - F(lo - 1) with F(n) for n < 0
  // defined by the same cubic (it is odd-symmetric about -1/2).
  return f(static_cast<double>(hi)) - f(static_cast<double>(lo - 1));
}

// Tightens [lo, hi] to the integers x with a + b x >= 0.
inline void clipLinear(double a, double b, double* lo, double* hi) {
  if (std::abs(b) < 1e-15) {
    if (a < 0) *hi = *lo - 1;
    return;
  }
  const double r = -a / b;
  if (b > 0) *lo = std::max(*lo, std::ceil(r - 1e-9));
  else *hi = std::min(*hi, std::floor(r + 1e-9));
}

}  // namespace

double VolumeObservation::partScore(const TruncatedQuadric& part, bool skin_part,
                                     bool extrapolate) const {
  const RowSums& sums = skin_part ? blended_sums_ : body_sums_;
  const double h = grid_.voxel_size;
  const double unknown = params_.unknown_likelihood;
  // The voxel lattice over the part's bounds, extended past the grid where the part is.
  const Vector3d lo = (part.bounds.min() - grid_.origin) / h;
  const Vector3d hi = (part.bounds.max() - grid_.origin) / h;
  const double bx0 = std::floor(lo.x()), bx1 = std::floor(hi.x());
  const int y0 = static_cast<int>(std::floor(lo.y())), y1 = static_cast<int>(std::floor(hi.y()));
  const int z0 = static_cast<int>(std::floor(lo.z())), z1 = static_cast<int>(std::floor(hi.z()));
  const Eigen::Vector3i& d = grid_.dims;
  const int nx = d.x();
  // Along a row, v(x) = v0 + x h e_x: v^T Q v = A + B x + C x^2 and each plane P0 + P1 x.
  const double C = h * h * part.Q(0, 0);
  double sw = 0, swy = 0;
  // Q v0 is affine in the row's (y, z): one 4x4 product per part, then additions.
  const Vector4d base(grid_.origin.x() + 0.5 * h, grid_.origin.y() + 0.5 * h,
                      grid_.origin.z() + 0.5 * h, 1.0);
  const Vector4d q_base = part.Q * base, q_dy = h * part.Q.col(1), q_dz = h * part.Q.col(2);
  for (int z = z0; z <= z1; ++z)
    for (int yy = y0; yy <= y1; ++yy) {
      const Vector4d v0 = base + Vector4d(0.0, yy * h, z * h, 0.0);
      const Vector4d qv = q_base + yy * q_dy + z * q_dz;
      const double A = v0.dot(qv), B = 2.0 * h * qv.x();
      double xlo = bx0, xhi = bx1;
      if (C > 1e-15) {
        const double disc = B * B - 4.0 * A * C;
        if (disc < 0) continue;
        const double sq = std::sqrt(disc);
        xlo = std::max(xlo, std::ceil((-B - sq) / (2.0 * C) - 1e-9));
        xhi = std::min(xhi, std::floor((-B + sq) / (2.0 * C) + 1e-9));
      } else {
        clipLinear(-A, -B, &xlo, &xhi);  // A + B x <= 0
      }
      for (int i = 0; i < part.num_planes; ++i)
        clipLinear(part.planes[i].dot(v0), part.planes[i].x() * h, &xlo, &xhi);
      if (xlo > xhi) continue;
      const long a = static_cast<long>(xlo), b = static_cast<long>(xhi);
      auto weights = [&](long lo_x, long hi_x) {
        return (1.0 + A) * sumPow0(lo_x, hi_x) + B * sumPow1(lo_x, hi_x) + C * sumPow2(lo_x, hi_x);
      };
      const double w_all = weights(a, b);
      sw += w_all;
      const bool row_in_grid = yy >= 0 && yy < d.y() && z >= 0 && z < d.z();
      if (!row_in_grid && !extrapolate) {
        swy += unknown * w_all;
        continue;
      }
      // The row's values: its own inside the grid, else the nearest row's (clamp to edge), and
      // beyond its ends the end values (trunk) or the unknown value (the rest).
      const int cy = std::clamp(yy, 0, d.y() - 1), cz = std::clamp(z, 0, d.z() - 1);
      const size_t r = static_cast<size_t>(cy + d.y() * cz) * (nx + 1);
      const long ga = std::max<long>(a, 0), gb = std::min<long>(b, nx - 1);
      if (ga <= gb)
        swy += (1.0 + A) * (sums.s0[r + gb + 1] - sums.s0[r + ga]) +
               B * (sums.s1[r + gb + 1] - sums.s1[r + ga]) +
               C * (sums.s2[r + gb + 1] - sums.s2[r + ga]);
      if (a < 0)
        swy += weights(a, std::min<long>(b, -1)) *
               (extrapolate ? sums.s0[r + 1] - sums.s0[r] : unknown);
      if (b >= nx)
        swy += weights(std::max<long>(a, nx), b) *
               (extrapolate ? sums.s0[r + nx] - sums.s0[r + nx - 1] : unknown);
    }
  // A part thinner than the lattice may catch no voxel centre: its evidence is unknown.
  return sw > 1e-12 ? swy / sw : unknown;
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
