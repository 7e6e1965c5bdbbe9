#include "tabletop_capture/image_conversion.h"

#include <cstdint>
#include <limits>
#include <string>

#include <opencv2/imgproc.hpp>

namespace tabletop_capture {
namespace {

const char* const kSupported =
    "rgb8, bgr8, mono8, bayer_rggb8, bayer_bggr8, bayer_gbrg8, bayer_grbg8";

// OpenCV names a Bayer pattern by the 2x2 block starting at pixel (1,1), ROS by the block at
// (0,0) (cv_bridge maps bayer_rggb8 -> COLOR_BayerBG2BGR the same way); checked by the
// mosaic/demosaic round trip in test_image_conversion.
int bayerCode(const std::string& encoding) {
  if (encoding == "bayer_rggb8") return cv::COLOR_BayerBG2RGB;
  if (encoding == "bayer_bggr8") return cv::COLOR_BayerRG2RGB;
  if (encoding == "bayer_gbrg8") return cv::COLOR_BayerGR2RGB;
  if (encoding == "bayer_grbg8") return cv::COLOR_BayerGB2RGB;
  return -1;
}

ImageConversionResult fail(const std::string& source, const std::string& message) {
  ImageConversionResult r;
  r.error = (source.empty() ? std::string() : source + ": ") + message;
  return r;
}

}  // namespace

int bytesPerPixel(const std::string& encoding) {
  if (encoding == "rgb8" || encoding == "bgr8") return 3;
  if (encoding == "mono8" || bayerCode(encoding) >= 0) return 1;
  return 0;
}

ImageConversionResult convertToRgb8(const RawImageView& image, int expected_width,
                                    int expected_height, const std::string& source,
                                    bool allow_wrap) {
  const int bpp = bytesPerPixel(image.encoding);
  if (bpp == 0) {
    const bool wide = image.encoding.find("16") != std::string::npos ||
                      image.encoding.find("32") != std::string::npos ||
                      image.encoding.find("64") != std::string::npos;
    return fail(source, "unsupported encoding '" + image.encoding + "'" +
                            (wide ? " (only 8-bit encodings are supported)" : "") +
                            "; supported: " + kSupported);
  }
  if (image.width <= 0 || image.height <= 0) {
    return fail(source, "empty or invalid image size " + std::to_string(image.width) + "x" +
                            std::to_string(image.height));
  }
  if ((expected_width > 0 && image.width != expected_width) ||
      (expected_height > 0 && image.height != expected_height)) {
    return fail(source, "image size " + std::to_string(image.width) + "x" +
                            std::to_string(image.height) + " does not match camera_info " +
                            std::to_string(expected_width) + "x" +
                            std::to_string(expected_height));
  }
  // 64-bit arithmetic: width, height and step come from the wire and may be hostile.
  const std::uint64_t min_step = static_cast<std::uint64_t>(image.width) * bpp;
  if (image.step < min_step) {
    return fail(source, "step " + std::to_string(image.step) + " < width * " +
                            std::to_string(bpp) + " = " + std::to_string(min_step) + " for '" +
                            image.encoding + "'");
  }
  const std::uint64_t rows = static_cast<std::uint64_t>(image.height);
  if (image.step > std::numeric_limits<std::uint64_t>::max() / rows) {
    return fail(source, "step * height overflows");
  }
  const std::uint64_t needed = static_cast<std::uint64_t>(image.step) * rows;
  if (image.data == nullptr || image.size < needed) {
    return fail(source, "data size " + std::to_string(image.data ? image.size : 0) +
                            " < step * height = " + std::to_string(needed));
  }
  const bool is_bayer = bayerCode(image.encoding) >= 0;
  if (is_bayer && (image.width < 2 || image.height < 2)) {
    return fail(source, "Bayer image " + std::to_string(image.width) + "x" +
                            std::to_string(image.height) + " is smaller than 2x2");
  }

  // cv::Mat has no const-data constructor; the input is only read (wraps_input documents it).
  const cv::Mat in(image.height, image.width, bpp == 3 ? CV_8UC3 : CV_8UC1,
                   const_cast<std::uint8_t*>(image.data), image.step);
  ImageConversionResult r;
  try {
    if (image.encoding == "rgb8") {
      r.wraps_input = allow_wrap;
      r.rgb = allow_wrap ? in : in.clone();
    } else if (image.encoding == "bgr8") {
      cv::cvtColor(in, r.rgb, cv::COLOR_BGR2RGB);
    } else if (image.encoding == "mono8") {
      cv::cvtColor(in, r.rgb, cv::COLOR_GRAY2RGB);
    } else {
      cv::cvtColor(in, r.rgb, bayerCode(image.encoding));
    }
  } catch (const cv::Exception& e) {
    return fail(source, "OpenCV conversion from '" + image.encoding + "' failed: " + e.what());
  }
  r.ok = true;
  return r;
}

}  // namespace tabletop_capture
