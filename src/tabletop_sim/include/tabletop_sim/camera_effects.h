// What a scenario's cameras do to the rendered pictures besides noise: vignetting and
// exposure gains (applied by the renderer before the noise, as in a sensor), and optical blur,
// a Bayer mosaic + demosaic round trip and JPEG compression (applied to the 8-bit image after,
// as the camera's electronics and its driver do).
#pragma once

#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace tabletop_sim {

struct CameraEffects {
  // Relative darkening at the image corners: gain = 1 - vignetting * (r / r_corner)^2.
  double vignetting = 0.0;
  double blur_sigma = 0.0;  // Gaussian blur (pixels; defocus or a soft lens), 0 = off
  bool bayer = false;       // mosaic (RGGB) + OpenCV's bilinear demosaic: colour fringes at edges
  int jpeg_quality = 0;     // JPEG round trip at this quality (1..100), 0 = off
  // Fixed white balance per camera (R, G, B gains; empty = none), set once for the room's light
  // as a real rig is: it cancels the light's tint up to a residual error.
  std::vector<Eigen::Vector3d> white_balance;
  // Auto-exposure steps, per camera: (time s, gain) pairs in time order; from each time on
  // that camera's exposure gain is the pair's gain (1 before the first).
  std::vector<std::vector<std::pair<double, double>>> exposure_steps;

  double exposureGain(int camera, double t) const;
  Eigen::Vector3d whiteBalance(int camera) const;
  bool postProcessing() const { return blur_sigma > 0.0 || bayer || jpeg_quality > 0; }
};

// Blur, Bayer round trip and JPEG, in that order, on an rgb8 (CV_8UC3) image in place.
void applyPostProcessing(const CameraEffects& effects, cv::Mat* rgb);

// Per-pixel vignetting gain of an image (CV_32FC1), for the renderer.
cv::Mat vignettingGain(int width, int height, double vignetting);

}  // namespace tabletop_sim
