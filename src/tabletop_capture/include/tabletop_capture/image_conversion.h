// Converts a raw camera image (the fields of a sensor_msgs/Image) to rgb8 (CV_8UC3, R,G,B).
// ROS-free, so the nodelet, bag tools and tests share one validated path. Never throws and
// never reads outside the buffer: every invalid input gives ok = false and a message.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace tabletop_capture {

// A view of a raw image buffer; nothing is owned.
struct RawImageView {
  std::string encoding;  // ROS name: rgb8, bgr8, mono8, bayer_rggb8, bayer_bggr8, ...
  int width = 0;
  int height = 0;
  std::size_t step = 0;  // bytes per row (>= width * bytes per pixel)
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;  // bytes available at data (>= step * height)
};

struct ImageConversionResult {
  bool ok = false;
  std::string error;  // set when !ok, e.g. "cam3: unsupported encoding 'mono16' ..."
  cv::Mat rgb;        // CV_8UC3, R,G,B order; empty when !ok
  // True when rgb wraps the input buffer (rgb8 input, no copy): the buffer must outlive rgb
  // and rgb must be treated as read-only. Clone it if either cannot be guaranteed.
  bool wraps_input = false;
};

// Bytes per pixel of a supported encoding, or 0 if the encoding is not supported.
int bytesPerPixel(const std::string& encoding);

// Converts `image` to rgb8. Bayer encodings are demosaiced (OpenCV bilinear). If
// expected_width/expected_height are > 0 (the camera_info size), a different image size is
// an error. `source` (e.g. "cam3") prefixes error messages. With allow_wrap = false an rgb8
// input is copied too.
ImageConversionResult convertToRgb8(const RawImageView& image, int expected_width = 0,
                                    int expected_height = 0, const std::string& source = "",
                                    bool allow_wrap = true);

}  // namespace tabletop_capture
