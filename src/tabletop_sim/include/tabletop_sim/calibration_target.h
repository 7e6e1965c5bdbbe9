// Renders a checkerboard calibration target as one camera of the simulated rig sees it (issue
// 18 step 4: simulated calibration sequences): the board's plane is hit by each pixel's ray
// through the camera's own distortion model, with supersampling for the anti-aliased edges a
// real lens gives, a white border of one square (OpenCV's detector needs it) and sensor noise.
// The ground truth is the camera model and the pose given. ROS-free.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "tabletop_capture/calibration/checkerboard.h"
#include "tabletop_capture/camera_model.h"

namespace tabletop_sim {

struct TargetImageOptions {
  int supersample = 4;       // samples per pixel along each axis
  double noise_sigma = 2.0;  // sensor noise (grey levels), as the rig's default
  std::uint8_t dark = 30, light = 220, background = 110;  // square, border and room levels
};

class CheckerboardRenderer {
 public:
  // Precomputes the camera's sample rays (undistorted) once. Throws std::invalid_argument for a
  // bad board spec or supersample < 1.
  CheckerboardRenderer(const tabletop_capture::CameraModel& camera,
                       const tabletop_capture::CheckerboardSpec& board,
                       const TargetImageOptions& options = {});
  // rgb8 image of the board at camera_T_board (board frame as CheckerboardSpec::boardPoints).
  // `seed` makes the noise reproducible.
  cv::Mat render(const Eigen::Isometry3d& camera_T_board, std::uint64_t seed) const;

 private:
  tabletop_capture::CameraModel camera_;
  tabletop_capture::CheckerboardSpec board_;
  TargetImageOptions options_;
  std::vector<Eigen::Vector3d> rays_;  // per sample, camera frame, row-major by pixel
};

}  // namespace tabletop_sim
