#include "psfs_reconstruction/clothing_colour.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace psfs {
namespace {

// The upper body reaches this far below its highest voxel (m): head, trunk and arms, not the
// legs under the desk (the workspace ends at the desk top anyway).
constexpr double kUpperBodyDepth = 0.55;
// At most this many band voxels are projected (every k-th of them): 400 voxels in 4-8 cameras
// give thousands of samples, and a full 16 mm band (~2000) cost ~4 ms per set.
constexpr size_t kMaxBandVoxels = 400;

double median(std::vector<double> v) {
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + m, v.end());
  return v[m];
}

}  // namespace

void ClothingColourParams::validate() const {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("clothing colour: " + what);
  };
  if (!(weight >= 0.0 && std::isfinite(weight))) fail("weight must be finite and >= 0");
  if (!(band_top >= 0.0 && band_bottom > band_top && std::isfinite(band_bottom)))
    fail("need 0 <= band_top < band_bottom (m)");
  if (!(core_radius > 0.0 && std::isfinite(core_radius))) fail("core_radius must be > 0 (m)");
  if (!(hand_exclusion_radius >= 0.0 && std::isfinite(hand_exclusion_radius)))
    fail("hand_exclusion_radius must be >= 0 (m)");
  if (!(trim_radius > 0.0 && trim_radius < 1.0)) fail("trim_radius must be in (0, 1)");
  if (!(min_inlier_fraction >= 0.0 && min_inlier_fraction <= 1.0))
    fail("min_inlier_fraction must be in [0, 1]");
  if (min_samples < 3) fail("min_samples must be >= 3");
  if (!(min_sd > 0.0 && min_sd < 1.0)) fail("min_sd must be in (0, 1)");
  if (!(update_rate > 0.0 && update_rate <= 1.0)) fail("update_rate must be in (0, 1]");
}

TrunkColourSample measureTrunkColour(const ProbabilityVolume& body, uint8_t occupied_byte,
                                     const std::vector<cv::Mat>& rgb,
                                     const std::vector<tabletop_capture::CameraModel>& cameras,
                                     const std::vector<bool>& active,
                                     const std::vector<Eigen::Vector3d>& hands,
                                     float min_intensity, const ClothingColourParams& params) {
  TrunkColourSample out;
  const VoxelGrid& g = body.grid;
  if (body.data.size() != g.numVoxels() || body.data.empty()) return out;
  std::vector<Eigen::Vector3d> occupied;
  double top = -1e9;
  for (size_t i = 0; i < body.data.size(); ++i) {
    if (body.data[i] <= occupied_byte) continue;
    occupied.push_back(g.centre(i));
    top = std::max(top, occupied.back().z());
  }
  if (occupied.empty()) return out;
  // 1. the upper body's axis
  std::vector<double> xs, ys;
  for (const Eigen::Vector3d& p : occupied)
    if (p.z() >= top - kUpperBodyDepth) xs.push_back(p.x()), ys.push_back(p.y());
  const Eigen::Vector2d axis(median(xs), median(ys));
  const double r2 = params.core_radius * params.core_radius;
  auto inCore = [&](const Eigen::Vector3d& p) { return (p.head<2>() - axis).squaredNorm() <= r2; };
  // 2. the top of its column
  double column_top = -1e9;
  for (const Eigen::Vector3d& p : occupied)
    if (inCore(p)) column_top = std::max(column_top, p.z());
  // 3. the chest band, less what lies near a hand
  const double h2 = params.hand_exclusion_radius * params.hand_exclusion_radius;
  auto nearHand = [&](const Eigen::Vector3d& p) {
    for (const Eigen::Vector3d& h : hands)
      if ((p - h).squaredNorm() < h2) return true;
    return false;
  };
  std::vector<Eigen::Vector3d> band;
  for (const Eigen::Vector3d& p : occupied)
    if (inCore(p) && p.z() <= column_top - params.band_top &&
        p.z() >= column_top - params.band_bottom && !nearHand(p))
      band.push_back(p);
  out.band_voxels = static_cast<int>(band.size());
  if (band.empty()) return out;

  const size_t stride = (band.size() + kMaxBandVoxels - 1) / kMaxBandVoxels;
  std::vector<Eigen::Vector3d> sampled;
  for (size_t i = 0; i < band.size(); i += stride) sampled.push_back(band[i]);
  std::vector<double> rs, gs;
  const float dark_sum = 3.0f * min_intensity;
  for (size_t c = 0; c < cameras.size() && c < rgb.size(); ++c) {
    if ((c < active.size() && !active[c]) || rgb[c].empty() || rgb[c].type() != CV_8UC3) continue;
    const cv::Mat& img = rgb[c];
    for (const Eigen::Vector3d& p : sampled) {
      Eigen::Vector2d px;
      if (!cameras[c].projectWorld(p, &px)) continue;
      const int u = static_cast<int>(std::lround(px.x()));
      const int v = static_cast<int>(std::lround(px.y()));
      if (u < 0 || v < 0 || u >= img.cols || v >= img.rows) continue;
      const uint8_t* q = img.ptr<uint8_t>(v) + 3 * u;
      if (q[0] == 255 || q[1] == 255 || q[2] == 255) continue;  // clipped: chroma unreliable
      const float s = float(q[0]) + float(q[1]) + float(q[2]);
      if (s < dark_sum || s <= 0.0f) continue;
      rs.push_back(q[0] / double(s));
      gs.push_back(q[1] / double(s));
    }
  }
  out.samples = static_cast<int>(rs.size());
  if (out.samples < params.min_samples) return out;
  const Eigen::Vector2d m(median(rs), median(gs));
  const double t2 = params.trim_radius * params.trim_radius;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  Eigen::Matrix2d sum2 = Eigen::Matrix2d::Zero();
  int n = 0;
  for (size_t i = 0; i < rs.size(); ++i) {
    const Eigen::Vector2d c(rs[i], gs[i]);
    if ((c - m).squaredNorm() > t2) continue;
    sum += c;
    sum2 += c * c.transpose();
    ++n;
  }
  out.inlier_fraction = double(n) / out.samples;
  if (n < 3 || out.inlier_fraction < params.min_inlier_fraction) return out;
  out.colour.mean = sum / n;
  out.colour.covariance = sum2 / n - out.colour.mean * out.colour.mean.transpose();
  out.colour.covariance.diagonal().array() += params.min_sd * params.min_sd;
  out.valid = true;
  return out;
}

ClothingColourModel::ClothingColourModel(const ClothingColourParams& params) : params_(params) {
  params_.validate();
}

void ClothingColourModel::update(const TrunkColourSample& sample) {
  if (!sample.valid) return;
  if (!valid_) {
    colour_ = sample.colour;
    valid_ = true;
    return;
  }
  const double a = params_.update_rate;
  const Eigen::Vector2d d = sample.colour.mean - colour_.mean;
  colour_.mean += a * d;
  colour_.covariance = (1.0 - a) * colour_.covariance + a * sample.colour.covariance +
                       a * (1.0 - a) * d * d.transpose();
}

}  // namespace psfs
