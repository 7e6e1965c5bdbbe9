#include "tabletop_sim/camera_effects.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace tabletop_sim {

double CameraEffects::exposureGain(int camera, double t) const {
  if (camera < 0 || camera >= static_cast<int>(exposure_steps.size())) return 1.0;
  double g = 1.0;
  for (const auto& step : exposure_steps[camera]) {
    if (t < step.first) break;
    g = step.second;
  }
  return g;
}

Eigen::Vector3d CameraEffects::whiteBalance(int camera) const {
  if (camera < 0 || camera >= static_cast<int>(white_balance.size())) return Eigen::Vector3d::Ones();
  return white_balance[camera];
}

void applyPostProcessing(const CameraEffects& e, cv::Mat* rgb) {
  if (rgb->type() != CV_8UC3) throw std::invalid_argument("applyPostProcessing: rgb8 image expected");
  if (e.blur_sigma > 0.0) cv::GaussianBlur(*rgb, *rgb, cv::Size(0, 0), e.blur_sigma);
  if (e.bayer) {
    // RGGB mosaic of the R, G, B channels, then OpenCV's bilinear demosaic back to R, G, B.
    // OpenCV names Bayer patterns by the second row's first two pixels: RGGB is its "BG".
    cv::Mat mosaic(rgb->rows, rgb->cols, CV_8UC1);
    for (int y = 0; y < rgb->rows; ++y) {
      const uint8_t* s = rgb->ptr<uint8_t>(y);
      uint8_t* d = mosaic.ptr<uint8_t>(y);
      for (int x = 0; x < rgb->cols; ++x) {
        const int ch = (y % 2 == 0) ? (x % 2 == 0 ? 0 : 1) : (x % 2 == 0 ? 1 : 2);
        d[x] = s[3 * x + ch];
      }
    }
    cv::cvtColor(mosaic, *rgb, cv::COLOR_BayerBG2RGB);
  }
  if (e.jpeg_quality > 0) {
    std::vector<uint8_t> buf;
    cv::Mat bgr;
    cv::cvtColor(*rgb, bgr, cv::COLOR_RGB2BGR);
    cv::imencode(".jpg", bgr, buf, {cv::IMWRITE_JPEG_QUALITY, std::clamp(e.jpeg_quality, 1, 100)});
    cv::cvtColor(cv::imdecode(buf, cv::IMREAD_COLOR), *rgb, cv::COLOR_BGR2RGB);
  }
}

cv::Mat vignettingGain(int width, int height, double vignetting) {
  cv::Mat g(height, width, CV_32FC1);
  const double cx = (width - 1) / 2.0, cy = (height - 1) / 2.0;
  const double r2max = cx * cx + cy * cy;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / r2max;
      g.at<float>(y, x) = static_cast<float>(std::max(0.0, 1.0 - vignetting * r2));
    }
  return g;
}

}  // namespace tabletop_sim
