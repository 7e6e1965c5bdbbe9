// Renders the desk markers of the world-frame calibration step (issue 18 step 3) as one camera
// of the simulated rig sees them: ArUco markers on white paper lying on the desk plane z = 0 of
// world, a plain desk and room around them, each pixel's rays through the camera's own
// distortion model with supersampling (the anti-aliased edges a real lens gives) and sensor
// noise. The scene is static, so the noiseless image is made once and each frame only draws
// new noise. The ground truth is the camera model given. ROS-free.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

#include "tabletop_capture/calibration/marker_layout.h"
#include "tabletop_capture/camera_model.h"

namespace tabletop_sim {

struct DeskMarkerImageOptions {
  int supersample = 4;          // samples per pixel along each axis
  double noise_sigma = 2.0;     // sensor noise (grey levels), as the rig's default
  // White paper around each marker's black square, in marker cells (one cell: the quiet zone
  // ArUco needs; with less the sheet's own outline can pass for the marker's).
  double paper_margin_cells = 1.0;
  double desk_half_x = 0.8, desk_half_y = 0.6;  // the desk top, centred on the world origin (m)
  std::uint8_t black = 30, paper = 220, desk = 125, room = 70;  // grey levels
};

class DeskMarkerRenderer {
 public:
  // Renders the noiseless image. Throws std::invalid_argument for a bad layout or supersample < 1.
  DeskMarkerRenderer(const tabletop_capture::CameraModel& camera, const tabletop_capture::MarkerLayout& layout,
                     const DeskMarkerImageOptions& options = {});
  // rgb8 image with noise drawn from `seed`.
  cv::Mat render(std::uint64_t seed) const;
  // The noiseless image (grey levels as doubles, CV_64FC1).
  const cv::Mat& clean() const { return clean_; }

 private:
  DeskMarkerImageOptions options_;
  cv::Mat clean_;
};

}  // namespace tabletop_sim
