#include "tabletop_sim/point_light.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace tabletop_sim {
namespace {

double pixelMass(double centre, double x, double sigma) {
  const double k = 1.0 / (sigma * M_SQRT2);
  return 0.5 * (std::erf((x + 0.5 - centre) * k) - std::erf((x - 0.5 - centre) * k));
}

// Adds a Gaussian spot of `peak` grey levels at its centre, integrated over each pixel (so its
// intensity-weighted centroid is the true centre, not the nearest pixel).
void addSpot(cv::Mat& grey, const Eigen::Vector2d& at, double sigma, double peak) {
  const double scale = peak / (pixelMass(0, 0, sigma) * pixelMass(0, 0, sigma));
  const int r = static_cast<int>(std::ceil(4 * sigma)) + 1;
  const int x0 = std::max(0, static_cast<int>(std::floor(at.x())) - r), x1 = std::min(grey.cols - 1, static_cast<int>(std::ceil(at.x())) + r);
  const int y0 = std::max(0, static_cast<int>(std::floor(at.y())) - r), y1 = std::min(grey.rows - 1, static_cast<int>(std::ceil(at.y())) + r);
  for (int y = y0; y <= y1; ++y) {
    const double my = pixelMass(at.y(), y, sigma);
    for (int x = x0; x <= x1; ++x) grey.at<float>(y, x) += static_cast<float>(scale * my * pixelMass(at.x(), x, sigma));
  }
}

// A two-state (visible, hidden) chain per camera whose hidden share is `hidden` and whose hidden
// runs last `mean_run` frames on average.
struct Hider {
  double hidden = 0, p_hide = 0, p_show = 1;
  bool now = false;
  Hider(double hidden_fraction, int mean_run) : hidden(hidden_fraction) {
    if (hidden <= 0) return;
    p_show = 1.0 / std::max(1, mean_run);
    p_hide = hidden >= 1 ? 1.0 : std::min(1.0, hidden * p_show / (1 - hidden));
  }
  bool step(std::mt19937_64& rng, std::uniform_real_distribution<double>& u) {
    if (hidden <= 0) return false;
    now = now ? u(rng) >= p_show : u(rng) < p_hide;
    return now;
  }
};

}  // namespace

std::vector<Eigen::Vector3d> randomLightPath(const Eigen::AlignedBox3d& box, int frames, std::uint64_t seed,
                                             double step, double margin) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const Eigen::Vector3d lo = box.min() + Eigen::Vector3d::Constant(margin);
  const Eigen::Vector3d size = (box.sizes() - Eigen::Vector3d::Constant(2 * margin)).cwiseMax(0);
  const auto waypoint = [&] { return Eigen::Vector3d(lo + size.cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)))); };
  std::vector<Eigen::Vector3d> w = {waypoint(), waypoint(), waypoint(), waypoint()};
  std::vector<Eigen::Vector3d> path;
  while (static_cast<int>(path.size()) < frames) {
    // Catmull-Rom from w[1] to w[2], sampled about `step` apart; then the window moves on. The
    // curve may bulge a little outside the waypoints' box: clamp it into the workspace.
    const int samples = std::max(2, static_cast<int>(std::ceil((w[2] - w[1]).norm() / step)));
    for (int k = 0; k < samples && static_cast<int>(path.size()) < frames; ++k) {
      const double t = static_cast<double>(k) / samples, t2 = t * t, t3 = t2 * t;
      const Eigen::Vector3d p = 0.5 * (2 * w[1] + (w[2] - w[0]) * t + (2 * w[0] - 5 * w[1] + 4 * w[2] - w[3]) * t2 +
                                       (3 * w[1] - w[0] - 3 * w[2] + w[3]) * t3);
      path.push_back(p.cwiseMax(box.min()).cwiseMin(box.max()));
    }
    w.erase(w.begin());
    w.push_back(waypoint());
  }
  return path;
}

std::vector<std::vector<LightView>> planLightSequence(const tabletop_capture::RigDescription& rig,
                                                      const std::vector<Eigen::Vector3d>& path,
                                                      const LightSequenceFaults& faults, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Hider> hiders;
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    double hidden = faults.occlusion;
    if (static_cast<int>(c) == faults.sparse_camera) hidden = 1 - (1 - hidden) * faults.sparse_fraction;
    hiders.emplace_back(hidden, faults.mean_hidden_frames);
  }
  // The LED's axis: a smooth random walk of directions (a path in a cube around 0, normalised).
  const Eigen::AlignedBox3d around_zero(Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1));
  const auto axes = randomLightPath(around_zero, static_cast<int>(path.size()), seed + 7, 0.05, 0.0);
  const double cos_half_angle = std::cos(faults.emission_half_angle_deg * M_PI / 180);
  std::vector<std::vector<LightView>> views(path.size(), std::vector<LightView>(rig.cameras.size()));
  for (size_t f = 0; f < path.size(); ++f)
    for (size_t c = 0; c < rig.cameras.size(); ++c) {
      const auto& cam = rig.cameras[c];
      LightView& v = views[f][c];
      const bool hidden = hiders[c].step(rng, u);
      Eigen::Vector2d pixel;
      const bool in_view = cam.projectWorld(path[f], &pixel) && pixel.x() >= 3 && pixel.y() >= 3 &&
                           pixel.x() <= cam.width - 4 && pixel.y() <= cam.height - 4;
      const Eigen::Vector3d to_camera = (cam.center() - path[f]).normalized();
      const bool shines = faults.emission_half_angle_deg >= 180 ||
                          to_camera.dot(axes[f].normalized()) >= cos_half_angle;
      if (!in_view || hidden || !shines) continue;
      if (u(rng) < faults.outliers) {
        // A reflection (on the desk, a screen) somewhere else: the light itself is hidden.
        v.reflection = true;
        do {
          v.reflection_pixel = Eigen::Vector2d(5 + u(rng) * (cam.width - 10), 5 + u(rng) * (cam.height - 10));
        } while ((v.reflection_pixel - pixel).norm() < 20);
        continue;
      }
      v.light = true;
      v.pixel = pixel;
    }
  return views;
}

cv::Mat renderLightView(const tabletop_capture::CameraModel& camera, const LightView& view,
                        const LightImageOptions& options, std::uint64_t seed) {
  cv::Mat grey(camera.height, camera.width, CV_32FC1, cv::Scalar(options.background));
  if (view.light) addSpot(grey, view.pixel, options.spot_sigma, options.peak);
  if (view.reflection) addSpot(grey, view.reflection_pixel, options.spot_sigma, 0.9 * options.peak);
  cv::Mat noise(grey.size(), CV_32FC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, options.noise_sigma);
  grey += noise;
  cv::Mat grey8, rgb;
  grey.convertTo(grey8, CV_8U);  // rounds and saturates, as a sensor does
  cv::Mat channels[3] = {grey8, grey8, grey8};
  cv::merge(channels, 3, rgb);
  return rgb;
}

}  // namespace tabletop_sim
