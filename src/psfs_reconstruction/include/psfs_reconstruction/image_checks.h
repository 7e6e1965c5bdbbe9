// Input validation shared by the background model and the classifier: every public entry point
// that takes an image checks it here and throws std::invalid_argument with a message naming the
// source (e.g. "cam3"), so a bad frame is a clear error and never an out-of-bounds read.
#pragma once

#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

namespace psfs {

// rgb8 = CV_8UC3 in R,G,B order. expected_width/height <= 0 skip the size check.
inline void checkRgb8(const cv::Mat& image, int expected_width, int expected_height,
                      const std::string& source) {
  const std::string who = source.empty() ? std::string("image") : source;
  if (image.empty()) throw std::invalid_argument(who + ": empty image");
  if (image.type() != CV_8UC3)
    throw std::invalid_argument(who + ": expected rgb8 (CV_8UC3), got " +
                                cv::typeToString(image.type()));
  if (image.dims != 2) throw std::invalid_argument(who + ": expected a 2-D image");
  if (expected_width > 0 && expected_height > 0 &&
      (image.cols != expected_width || image.rows != expected_height))
    throw std::invalid_argument(who + ": image is " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + " but the background model is " +
                                std::to_string(expected_width) + "x" +
                                std::to_string(expected_height));
}

// Foreground mask: CV_8UC1, same size, 0 = background, anything else = foreground.
inline void checkMask(const cv::Mat& mask, int expected_width, int expected_height,
                      const std::string& source) {
  const std::string who = source.empty() ? std::string("mask") : source + " mask";
  if (mask.type() != CV_8UC1)
    throw std::invalid_argument(who + ": expected CV_8UC1, got " + cv::typeToString(mask.type()));
  if (mask.cols != expected_width || mask.rows != expected_height)
    throw std::invalid_argument(who + ": mask is " + std::to_string(mask.cols) + "x" +
                                std::to_string(mask.rows) + " but the image is " +
                                std::to_string(expected_width) + "x" +
                                std::to_string(expected_height));
}

}  // namespace psfs
