// Intrinsic calibration of one camera from views of a checkerboard (issue 18 step 1, thesis
// 3.2): corner detection with sub-pixel refinement, OpenCV's calibrateCamera (Zhang's method,
// plumb_bob distortion), and the figures a user needs to judge the result: the reprojection
// error overall and per view, and how much of the image the corners covered (a calibration
// from corners in the middle only extrapolates its distortion to the edges). ROS-free.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "tabletop_capture/calibration/checkerboard.h"
#include "tabletop_capture/camera_model.h"

namespace tabletop_capture {

// The inner corners of `board` in an image (rgb8, bgr8 or mono8 Mat), refined to sub-pixel
// accuracy, in the board's order (CheckerboardSpec::boardPoints). False if the whole board is
// not found.
bool detectCheckerboard(const cv::Mat& image, const CheckerboardSpec& board,
                        std::vector<Eigen::Vector2d>* corners);

struct IntrinsicCalibrationOptions {
  bool estimate_k3 = false;  // the 6th-order radial term (wide-angle lenses); off: k3 = 0
  bool tangential = true;    // estimate p1, p2 (they trade off against the principal point:
                             // views that fill the image at varied tilts keep them apart)
  int coverage_grid = 4;     // the image is cut into grid x grid cells for the coverage figure
};

struct IntrinsicCalibration {
  CameraModel camera;                 // width, height, fx, fy, cx, cy, distortion (no pose)
  double rms_px = 0;                  // reprojection error over all corners (px, RMS)
  std::vector<double> view_rms_px;    // per view
  double coverage = 0;                // fraction of the coverage grid's cells with a corner
  int views = 0;
  std::vector<std::string> warnings;  // too few views, poor coverage, a bad view
};

// At least 3 views with the whole board (`views[v]` = its corners). Throws
// std::invalid_argument for fewer views, a view with the wrong corner count, or a bad spec.
IntrinsicCalibration calibrateIntrinsics(const std::vector<std::vector<Eigen::Vector2d>>& views,
                                         const CheckerboardSpec& board, int width, int height,
                                         const IntrinsicCalibrationOptions& options = {});

// The whole job of the calibrate_intrinsics tool: reads the image files in order, detects the
// board in each (progress(i, file, found) after each), keeps at most max_views of the views
// with a board, evenly spread over the sequence (calibrateCamera's cost grows with the cube of
// the view count; a waved board gives hundreds of near-duplicates), and calibrates. Throws
// std::runtime_error for an unreadable image, images of different sizes, or fewer than 3
// views with the board.
struct ImageCalibration {
  IntrinsicCalibration calibration;
  int images = 0, boards_found = 0;
  std::vector<std::string> used;  // the files of the views calibrated from
};
ImageCalibration calibrateIntrinsicsFromImages(
    const std::vector<std::string>& files, const CheckerboardSpec& board, int max_views,
    const IntrinsicCalibrationOptions& options = {},
    const std::function<void(int, const std::string&, bool)>& progress = {});

}  // namespace tabletop_capture
