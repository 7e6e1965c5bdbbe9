// ArUco marker detection in one image with sub-pixel corners (issue 18 step 3), for the rig's
// small images: at 320x240 a desk marker 2 m away spans 13-30 px, its cells 2-5 px. OpenCV's
// corner refinements (cornerSubPix on an L-shaped corner, contour fitting) were off by
// 0.4-0.8 px RMS there (the code cells next to the corner pull it); so each corner is the
// intersection of two lines fitted to the black border's edges, located to sub-pixel accuracy
// along their whole length (the ARToolKit approach), in undistorted pixels when the camera is
// given (a 25 px edge near the image corner bends by ~0.2 px under the rig's barrel
// distortion). ROS-free.
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "tabletop_capture/camera_model.h"

namespace tabletop_capture {

using MarkerCorners = std::array<Eigen::Vector2d, 4>;  // pixels, ArUco's (clockwise) order

struct DetectedMarker {
  int id = 0;
  MarkerCorners corners;
};

// The markers of `dictionary` (a name MarkerLayout accepts) in an rgb8, bgr8 or mono8 image.
// Throws std::invalid_argument for an unknown dictionary or an empty image. `camera` (optional):
// its intrinsics and distortion straighten the edges before the lines are fitted.
std::vector<DetectedMarker> detectMarkers(const cv::Mat& image, const std::string& dictionary,
                                          const CameraModel* camera = nullptr);

// The marker's cells, black border included, as a (bits+2)^2 mono8 image (0 black, 255 white),
// row 0 at the top: what is printed, one pixel per cell (the simulator's texture).
cv::Mat markerCells(const std::string& dictionary, int id);

// One camera's detections over a sequence of a static scene: the mean corners of each marker
// over the frames it was found in (averaging the detection noise down by sqrt(frames)).
class MarkerSightings {
 public:
  void add(const std::vector<DetectedMarker>& markers);
  // id -> mean corners; id -> frames found.
  std::map<int, MarkerCorners> mean() const;
  const std::map<int, int>& frames() const { return count_; }
  bool empty() const { return count_.empty(); }

 private:
  std::map<int, std::array<Eigen::Vector2d, 4>> sum_;
  std::map<int, int> count_;
};

}  // namespace tabletop_capture
