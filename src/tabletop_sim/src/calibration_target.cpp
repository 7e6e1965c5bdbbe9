#include "tabletop_sim/calibration_target.h"

#include <cmath>
#include <stdexcept>

namespace tabletop_sim {

CheckerboardRenderer::CheckerboardRenderer(const tabletop_capture::CameraModel& camera,
                                           const tabletop_capture::CheckerboardSpec& board,
                                           const TargetImageOptions& options)
    : camera_(camera), board_(board), options_(options) {
  board_.validate();
  if (options_.supersample < 1) throw std::invalid_argument("checkerboard renderer: supersample < 1");
  const int S = options_.supersample;
  rays_.reserve(size_t(camera_.width) * camera_.height * S * S);
  // Pixel centres at integer coordinates (OpenCV's convention, the camera model's too).
  for (int v = 0; v < camera_.height; ++v)
    for (int u = 0; u < camera_.width; ++u)
      for (int j = 0; j < S; ++j)
        for (int i = 0; i < S; ++i)
          rays_.push_back(camera_.rayCamera(
              Eigen::Vector2d(u + (i + 0.5) / S - 0.5, v + (j + 0.5) / S - 0.5)));
}

cv::Mat CheckerboardRenderer::render(const Eigen::Isometry3d& camera_T_board, std::uint64_t seed) const {
  const int S = options_.supersample, W = camera_.width, H = camera_.height;
  const Eigen::Matrix3d R = camera_T_board.linear();
  const Eigen::Vector3d o = camera_T_board.translation(), n = R.col(2);
  const double s = board_.square;
  // The squares span [-s, cols * s] x [-s, rows * s] around the inner corners, the white
  // border one more square around them.
  const double x0 = -s, x1 = board_.cols * s, y0 = -s, y1 = board_.rows * s;
  cv::Mat grey(H, W, CV_64FC1);
  const double no = n.dot(o);
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      double sum = 0;
      const Eigen::Vector3d* r = &rays_[(size_t(v) * W + u) * S * S];
      for (int k = 0; k < S * S; ++k) {
        const double nd = n.dot(r[k]);
        double level = options_.background;
        if (std::abs(nd) > 1e-12 && no / nd > 0) {
          const Eigen::Vector3d b = R.transpose() * (r[k] * (no / nd) - o);
          if (b.x() >= x0 && b.x() < x1 && b.y() >= y0 && b.y() < y1) {
            const long cx = static_cast<long>(std::floor(b.x() / s)), cy = static_cast<long>(std::floor(b.y() / s));
            level = ((cx + cy) & 1) ? options_.light : options_.dark;
          } else if (b.x() >= x0 - s && b.x() < x1 + s && b.y() >= y0 - s && b.y() < y1 + s) {
            level = options_.light;
          }
        }
        sum += level;
      }
      grey.at<double>(v, u) = sum / (S * S);
    }
  cv::Mat noise(H, W, CV_64FC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, options_.noise_sigma);
  grey += noise;
  cv::Mat grey8, rgb;
  grey.convertTo(grey8, CV_8UC1);  // rounds and saturates
  cv::Mat channels[] = {grey8, grey8, grey8};
  cv::merge(channels, 3, rgb);
  return rgb;
}

}  // namespace tabletop_sim
