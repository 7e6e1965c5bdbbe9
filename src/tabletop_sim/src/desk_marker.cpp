#include "tabletop_sim/desk_marker.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "tabletop_capture/calibration/marker_detection.h"

namespace tabletop_sim {

DeskMarkerRenderer::DeskMarkerRenderer(const tabletop_capture::CameraModel& camera,
                                       const tabletop_capture::MarkerLayout& layout,
                                       const DeskMarkerImageOptions& options)
    : options_(options) {
  layout.validate();
  if (options_.supersample < 1) throw std::invalid_argument("desk marker renderer: supersample < 1");
  std::vector<cv::Mat> cells;
  for (const auto& m : layout.markers) cells.push_back(tabletop_capture::markerCells(layout.dictionary, m.id));
  const int S = options_.supersample, W = camera.width, H = camera.height;
  const Eigen::Matrix3d R = camera.world_T_camera.linear();
  const Eigen::Vector3d o = camera.center();
  clean_.create(H, W, CV_64FC1);
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      double sum = 0;
      for (int j = 0; j < S; ++j)
        for (int i = 0; i < S; ++i) {
          // Pixel centres at integer coordinates (OpenCV's convention, the camera model's too).
          const Eigen::Vector3d d =
              R * camera.rayCamera(Eigen::Vector2d(u + (i + 0.5) / S - 0.5, v + (j + 0.5) / S - 0.5));
          double level = options_.room;
          if (d.z() < -1e-12 && o.z() > 0) {
            const Eigen::Vector3d p = o + d * (-o.z() / d.z());
            if (std::abs(p.x()) <= options_.desk_half_x && std::abs(p.y()) <= options_.desk_half_y)
              level = options_.desk;
            for (size_t m = 0; m < layout.markers.size(); ++m) {
              const auto& mk = layout.markers[m];
              // Marker frame: origin at the top-left corner seen from above (world y up),
              // a = along x, b = down (-y), in cells.
              const double h = mk.size / 2;
              const double a = p.x() - (mk.centre.x() - h), b = (mk.centre.y() + h) - p.y();
              const double margin = options_.paper_margin_cells * mk.size / cells[m].rows;
              if (a < -margin || b < -margin || a >= mk.size + margin || b >= mk.size + margin) continue;
              level = options_.paper;
              if (a >= 0 && b >= 0 && a < mk.size && b < mk.size) {
                const int n = cells[m].rows;
                const int ca = std::min(n - 1, static_cast<int>(a / mk.size * n));
                const int cb = std::min(n - 1, static_cast<int>(b / mk.size * n));
                level = cells[m].at<std::uint8_t>(cb, ca) ? options_.paper : options_.black;
              }
              break;
            }
          }
          sum += level;
        }
      clean_.at<double>(v, u) = sum / (S * S);
    }
}

cv::Mat DeskMarkerRenderer::render(std::uint64_t seed) const {
  cv::Mat noise(clean_.size(), CV_64FC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, options_.noise_sigma);
  cv::Mat grey8, rgb;
  cv::Mat(clean_ + noise).convertTo(grey8, CV_8UC1);  // rounds and saturates
  cv::Mat channels[] = {grey8, grey8, grey8};
  cv::merge(channels, 3, rgb);
  return rgb;
}

}  // namespace tabletop_sim
