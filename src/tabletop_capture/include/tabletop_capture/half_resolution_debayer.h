// Half-resolution debayering (thesis 4.1): each 2x2 Bayer quad becomes one RGB pixel holding
// the quad's R, the mean of its two G (rounded half up) and its B, so a 640x480 Bayer image
// gives a 320x240 rgb8 image without any interpolation between quads. ROS-free.
#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace tabletop_capture {

enum class BayerPattern { kNone, kRGGB, kBGGR, kGBRG, kGRBG };

// "none", "rggb", "bggr", "gbrg", "grbg" (also the ROS encodings "bayer_rggb8", ...).
// Returns false for anything else.
bool parseBayerPattern(const std::string& text, BayerPattern* pattern);
// "rggb", ... ("none" for kNone).
std::string bayerPatternName(BayerPattern pattern);
// The ROS encoding of a full-resolution image in this pattern ("bayer_rggb8"); "" for kNone.
std::string bayerEncoding(BayerPattern pattern);

// `bayer` (CV_8UC1, W x H, W and H even and > 0) in `pattern` (the colour of its pixel (0,0)
// block, ROS naming: rggb = R at row 0 column 0) -> *rgb (CV_8UC3, R,G,B order, W/2 x H/2).
// Returns false and says why (size, type, pattern) in *error without touching *rgb.
bool debayerHalfResolution(const cv::Mat& bayer, BayerPattern pattern, cv::Mat* rgb,
                           std::string* error);

}  // namespace tabletop_capture
