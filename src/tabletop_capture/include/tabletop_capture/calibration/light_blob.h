// Detection of a point light (an LED or a laser pointer with a diffuser, waved through the
// workspace for the extrinsic calibration; thesis 3.2.4) in one camera image: the one small,
// bright, round spot, located to sub-pixel accuracy by its intensity-weighted centroid. The
// room should be dark, so that the light is the only thing near saturation. ROS-free.
#pragma once

#include <string>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace tabletop_capture {

struct LightBlobOptions {
  // A pixel belongs to a spot if it is brighter than max(min_threshold, threshold_fraction x the
  // image's brightest pixel) (grey levels of the brightest channel: a coloured LED is bright in
  // its own channel only).
  double min_threshold = 80;
  double threshold_fraction = 0.5;
  int min_area = 2;    // pixels above the threshold; fewer: a hot pixel of the sensor
  int max_area = 400;  // more: a lamp, a window, a reflection on the desk, not the light
  // Smallest ratio of the spot's minor to its major axis (second moments); a streak or an edge
  // is thinner. Not checked below min_area_for_shape pixels (too few for a shape).
  double min_roundness = 0.4;
  int min_area_for_shape = 6;
  // Of two or more acceptable spots the brightest (summed intensity) is taken only if it is
  // at least this many times the next; otherwise the image is ambiguous and gives no light.
  double dominance = 3.0;
};

struct LightBlob {
  bool found = false;
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // centroid; pixel centres at integers
  int area = 0;                                     // pixels above the threshold
  double peak = 0;                                  // brightest grey level in the spot
  std::string rejected;  // why nothing was found ("too dark", "too large (900 px)", ...)
};

// The light in an rgb8, bgr8 or mono8 image. Throws std::invalid_argument for another type.
LightBlob detectLightBlob(const cv::Mat& image, const LightBlobOptions& options = {});

}  // namespace tabletop_capture
