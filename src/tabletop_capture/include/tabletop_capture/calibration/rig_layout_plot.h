// A picture of a calibrated rig for the calibration reports (issue 18): a top view (world x-y)
// beside a side view (world x-z) with the workspace box, each camera's centre, viewing
// direction and name, the desk markers and optional extra points (e.g. the point light's
// reconstructed path). A user sees at a glance a camera that is mirrored, below the desk or
// looking away. ROS-free (OpenCV drawing only).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "tabletop_capture/rig_description.h"

namespace tabletop_capture {

struct RigLayoutPlotOptions {
  int width = 1200, height = 600;  // the whole image (both views)
  Eigen::AlignedBox3d workspace{Eigen::Vector3d(-0.5, -0.5, 0.0), Eigen::Vector3d(0.5, 0.5, 0.75)};
  std::vector<std::array<Eigen::Vector3d, 4>> markers;  // corners, world
  std::vector<Eigen::Vector3d> points;                  // extra points, world
  double arrow_length = 0.3;                            // m, the viewing direction
  std::string title;
};

// bgr8 image of options.width x options.height; both views share one metric scale, fitted to
// the cameras, the workspace, the markers and the points.
cv::Mat drawRigLayout(const RigDescription& rig, const RigLayoutPlotOptions& options = {});

// The colour camera `index` is drawn in (BGR), for a legend or a test.
cv::Scalar rigLayoutCameraColour(int index);

}  // namespace tabletop_capture
