#include "tabletop_capture/half_resolution_debayer.h"

#include <cstdint>

namespace tabletop_capture {

bool parseBayerPattern(const std::string& text, BayerPattern* pattern) {
  std::string t = text;
  if (t.rfind("bayer_", 0) == 0 && t.size() == 11 && t.back() == '8') t = t.substr(6, 4);
  if (t == "none") *pattern = BayerPattern::kNone;
  else if (t == "rggb") *pattern = BayerPattern::kRGGB;
  else if (t == "bggr") *pattern = BayerPattern::kBGGR;
  else if (t == "gbrg") *pattern = BayerPattern::kGBRG;
  else if (t == "grbg") *pattern = BayerPattern::kGRBG;
  else return false;
  return true;
}

std::string bayerPatternName(BayerPattern pattern) {
  switch (pattern) {
    case BayerPattern::kRGGB: return "rggb";
    case BayerPattern::kBGGR: return "bggr";
    case BayerPattern::kGBRG: return "gbrg";
    case BayerPattern::kGRBG: return "grbg";
    default: return "none";
  }
}

std::string bayerEncoding(BayerPattern pattern) {
  return pattern == BayerPattern::kNone ? "" : "bayer_" + bayerPatternName(pattern) + "8";
}

// Why a loop and not OpenCV: cv::cvtColor's Bayer codes (bilinear, VNG, edge-aware) all
// demosaic at full resolution, interpolating every output pixel from neighbouring quads, and
// OpenCV 4.6 has no half-resolution Bayer conversion; resizing their output mixes quads. A
// strided-view + cv::split/addWeighted version would avoid the loop but rounds the G mean half
// to even (cvRound), i.e. differently for different quads. The loop is one pass over the
// 640x480 image (about 0.3 ms).
bool debayerHalfResolution(const cv::Mat& bayer, BayerPattern pattern, cv::Mat* rgb,
                           std::string* error) {
  auto fail = [error](const std::string& why) {
    if (error) *error = "half-resolution debayer: " + why;
    return false;
  };
  if (pattern == BayerPattern::kNone) return fail("no Bayer pattern given (bayer: none)");
  if (bayer.empty()) return fail("empty image");
  if (bayer.type() != CV_8UC1)
    return fail("expected a one-channel 8-bit Bayer image, got " + std::to_string(bayer.channels()) +
                " channel(s) of depth " + std::to_string(bayer.depth()));
  if (bayer.cols % 2 != 0 || bayer.rows % 2 != 0)
    return fail("image size " + std::to_string(bayer.cols) + "x" + std::to_string(bayer.rows) +
                " is odd: every 2x2 quad must be complete (width and height must be even)");
  // Offsets within the quad (row, column) of R and B; the two G are the other two.
  int ry = 0, rx = 0;
  switch (pattern) {
    case BayerPattern::kRGGB: ry = 0; rx = 0; break;
    case BayerPattern::kBGGR: ry = 1; rx = 1; break;
    case BayerPattern::kGBRG: ry = 1; rx = 0; break;
    case BayerPattern::kGRBG: ry = 0; rx = 1; break;
    default: break;
  }
  const int by = 1 - ry, bx = 1 - rx;
  const int w = bayer.cols / 2, h = bayer.rows / 2;
  cv::Mat out(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* row[2] = {bayer.ptr<std::uint8_t>(2 * y), bayer.ptr<std::uint8_t>(2 * y + 1)};
    std::uint8_t* o = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < w; ++x, o += 3) {
      const int c = 2 * x;
      o[0] = row[ry][c + rx];
      o[1] = static_cast<std::uint8_t>((row[ry][c + bx] + row[by][c + rx] + 1) >> 1);
      o[2] = row[by][c + bx];
    }
  }
  *rgb = out;
  return true;
}

}  // namespace tabletop_capture
