#include <stdexcept>
#include <string>

#include "tabletop_sim/renderer.h"

namespace tabletop_sim {

cv::Mat mosaicBayer(const cv::Mat& rgb, const std::string& encoding) {
  if (rgb.type() != CV_8UC3) throw std::invalid_argument("mosaicBayer: input must be CV_8UC3 rgb8");
  static const char* names[4] = {"bayer_rggb8", "bayer_bggr8", "bayer_gbrg8", "bayer_grbg8"};
  int pattern = -1;
  for (int i = 0; i < 4; ++i)
    if (encoding == names[i]) pattern = i;
  if (pattern < 0)
    throw std::invalid_argument("mosaicBayer: unknown encoding '" + encoding +
                                "' (valid: bayer_rggb8, bayer_bggr8, bayer_gbrg8, bayer_grbg8)");
  // Channel kept at (row & 1, col & 1), from the letters of the encoding name.
  int ch[4];
  const std::string letters = std::string(names[pattern]).substr(6, 4);
  for (int i = 0; i < 4; ++i) ch[i] = letters[i] == 'r' ? 0 : (letters[i] == 'g' ? 1 : 2);
  cv::Mat out(rgb.rows, rgb.cols, CV_8UC1);
  for (int y = 0; y < rgb.rows; ++y) {
    const uint8_t* s = rgb.ptr<uint8_t>(y);
    uint8_t* d = out.ptr<uint8_t>(y);
    const int* row = ch + 2 * (y & 1);
    for (int x = 0; x < rgb.cols; ++x) d[x] = s[3 * x + row[x & 1]];
  }
  return out;
}

}  // namespace tabletop_sim
