// Half-resolution debayer against hand-computed quads for every pattern, and the refusals.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "tabletop_capture/half_resolution_debayer.h"

using namespace tabletop_capture;

namespace {

// A 4x2 Bayer image (two quads side by side), rows written out by hand.
cv::Mat image(std::initializer_list<std::uint8_t> row0, std::initializer_list<std::uint8_t> row1) {
  cv::Mat m(2, static_cast<int>(row0.size()), CV_8UC1);
  int x = 0;
  for (auto v : row0) m.at<std::uint8_t>(0, x++) = v;
  x = 0;
  for (auto v : row1) m.at<std::uint8_t>(1, x++) = v;
  return m;
}

cv::Vec3b px(const cv::Mat& rgb, int x) { return rgb.at<cv::Vec3b>(0, x); }

// Quad 0: R 200, G 10 and 21 (mean 15.5 -> 16, half up), B 90.
// Quad 1: R 7, G 255 and 254 (mean 254.5 -> 255), B 0.
struct Case {
  const char* pattern;
  cv::Mat bayer;
};

TEST(HalfResolutionDebayer, EveryPatternAgainstHandComputedQuads) {
  const Case cases[] = {
      // rggb: R G / G B
      {"rggb", image({200, 10, 7, 255}, {21, 90, 254, 0})},
      // bggr: B G / G R
      {"bggr", image({90, 10, 0, 255}, {21, 200, 254, 7})},
      // gbrg: G B / R G
      {"gbrg", image({10, 90, 255, 0}, {200, 21, 7, 254})},
      // grbg: G R / B G
      {"grbg", image({10, 200, 255, 7}, {90, 21, 0, 254})},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.pattern);
    BayerPattern p;
    ASSERT_TRUE(parseBayerPattern(c.pattern, &p));
    cv::Mat rgb;
    std::string error;
    ASSERT_TRUE(debayerHalfResolution(c.bayer, p, &rgb, &error)) << error;
    ASSERT_EQ(rgb.type(), CV_8UC3);
    ASSERT_EQ(rgb.cols, 2);
    ASSERT_EQ(rgb.rows, 1);
    EXPECT_EQ(px(rgb, 0), cv::Vec3b(200, 16, 90));
    EXPECT_EQ(px(rgb, 1), cv::Vec3b(7, 255, 0));
  }
}

// 640x480 -> 320x240, and a view with padding (step > width) is read row by row.
TEST(HalfResolutionDebayer, FullSizeAndPaddedRows) {
  cv::Mat padded(480, 700, CV_8UC1, cv::Scalar(77));
  cv::Mat bayer = padded(cv::Rect(0, 0, 640, 480));
  for (int y = 0; y < 480; y += 2)
    for (int x = 0; x < 640; x += 2) {
      bayer.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(x / 2);        // R
      bayer.at<std::uint8_t>(y, x + 1) = 100;                                  // G
      bayer.at<std::uint8_t>(y + 1, x) = 102;                                  // G
      bayer.at<std::uint8_t>(y + 1, x + 1) = static_cast<std::uint8_t>(y / 2);  // B
    }
  cv::Mat rgb;
  std::string error;
  ASSERT_TRUE(debayerHalfResolution(bayer, BayerPattern::kRGGB, &rgb, &error)) << error;
  ASSERT_EQ(rgb.size(), cv::Size(320, 240));
  EXPECT_EQ(rgb.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 101, 0));
  EXPECT_EQ(rgb.at<cv::Vec3b>(239, 319), cv::Vec3b(319 & 255, 101, 239));
  EXPECT_EQ(rgb.at<cv::Vec3b>(10, 200), cv::Vec3b(200, 101, 10));
}

TEST(HalfResolutionDebayer, RefusesOddSizesOtherTypesAndNoPattern) {
  cv::Mat rgb(1, 1, CV_8UC3, cv::Scalar(1, 2, 3));
  const cv::Mat before = rgb.clone();
  std::string error;
  EXPECT_FALSE(debayerHalfResolution(cv::Mat(480, 639, CV_8UC1), BayerPattern::kRGGB, &rgb, &error));
  EXPECT_NE(error.find("639x480 is odd"), std::string::npos) << error;
  EXPECT_FALSE(debayerHalfResolution(cv::Mat(3, 4, CV_8UC1), BayerPattern::kBGGR, &rgb, &error));
  EXPECT_NE(error.find("4x3 is odd"), std::string::npos) << error;
  EXPECT_FALSE(debayerHalfResolution(cv::Mat(4, 4, CV_8UC3), BayerPattern::kBGGR, &rgb, &error));
  EXPECT_NE(error.find("one-channel"), std::string::npos) << error;
  EXPECT_FALSE(debayerHalfResolution(cv::Mat(), BayerPattern::kBGGR, &rgb, &error));
  EXPECT_NE(error.find("empty"), std::string::npos) << error;
  EXPECT_FALSE(debayerHalfResolution(cv::Mat(4, 4, CV_8UC1), BayerPattern::kNone, &rgb, &error));
  EXPECT_NE(error.find("no Bayer pattern"), std::string::npos) << error;
  EXPECT_EQ(cv::norm(rgb, before, cv::NORM_INF), 0.0);  // untouched on failure
}

TEST(HalfResolutionDebayer, PatternNames) {
  BayerPattern p;
  EXPECT_TRUE(parseBayerPattern("bayer_grbg8", &p));
  EXPECT_EQ(p, BayerPattern::kGRBG);
  EXPECT_EQ(bayerEncoding(p), "bayer_grbg8");
  EXPECT_TRUE(parseBayerPattern("none", &p));
  EXPECT_EQ(bayerEncoding(p), "");
  EXPECT_FALSE(parseBayerPattern("RGGB", &p));
  EXPECT_FALSE(parseBayerPattern("bayer_rggb16", &p));
}

}  // namespace
