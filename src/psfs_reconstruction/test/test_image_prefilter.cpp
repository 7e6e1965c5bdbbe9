// The images' noise filter (image_prefilter.h): what it does to noise and to edges, and its
// parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#include "psfs_reconstruction/image_prefilter.h"

namespace psfs {
namespace {

constexpr int kW = 160, kH = 120, kEdge = 80;  // columns < kEdge: kDark, the rest kLight
constexpr double kDark = 60, kLight = 120, kNoise = 3.0;  // levels; sensor noise sd

// A vertical step edge with Gaussian noise in every channel (seeded).
cv::Mat noisyStep() {
  cv::Mat img(kH, kW, CV_8UC3);
  cv::RNG rng(7);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (int c = 0; c < 3; ++c)
        img.at<cv::Vec3b>(y, x)[c] =
            cv::saturate_cast<uchar>((x < kEdge ? kDark : kLight) + rng.gaussian(kNoise));
  return img;
}

// Mean and standard deviation of channel 0 over columns [x0, x1), rows away from the border.
void columnStats(const cv::Mat& img, int x0, int x1, double* mean, double* sd) {
  double s = 0, s2 = 0;
  int n = 0;
  for (int y = 2; y < kH - 2; ++y)
    for (int x = x0; x < x1; ++x) {
      const double v = img.at<cv::Vec3b>(y, x)[0];
      s += v;
      s2 += v * v;
      ++n;
    }
  *mean = s / n;
  *sd = std::sqrt(std::max(0.0, s2 / n - *mean * *mean));
}

cv::Mat filtered(const cv::Mat& img, ImagePrefilter type, int size = 3) {
  std::vector<cv::Mat> out;
  prefilterImages({img}, ImagePrefilterParams{type, size}, &out, 1);
  return out[0];
}

TEST(ImagePrefilter, MedianCutsNoiseAndKeepsTheEdge) {
  const cv::Mat raw = noisyStep();
  const cv::Mat med = filtered(raw, ImagePrefilter::kMedian);
  const cv::Mat box = filtered(raw, ImagePrefilter::kBox);
  double m_raw, sd_raw, m_med, sd_med, m_box, sd_box;
  columnStats(raw, 10, 60, &m_raw, &sd_raw);
  columnStats(med, 10, 60, &m_med, &sd_med);
  columnStats(box, 10, 60, &m_box, &sd_box);
  std::printf("[ figures  ] noise sd %.2f raw, %.2f median 3x3, %.2f box 3x3 (levels)\n", sd_raw,
              sd_med, sd_box);
  // The median of 9 normal samples has sd ~ sigma sqrt(pi / 2 / 9) = 0.42 sigma; a mean of 9,
  // sigma / 3 (0.34 with the output's rounding to whole levels).
  EXPECT_NEAR(sd_raw, kNoise, 0.3);
  EXPECT_LT(sd_med, 0.50 * sd_raw);
  EXPECT_LT(sd_box, 0.40 * sd_raw);
  EXPECT_NEAR(m_med, kDark, 0.5);  // flat areas keep their level
  EXPECT_NEAR(m_box, kDark, 0.5);
  // The last dark column: the median keeps it dark (6 of its 9 window pixels are; the 5th
  // smallest of 9 is the 5th of the 6 dark ones, ~0.64 sd above their mean), the mean moves it
  // a third of the step towards the light side: a pixel of smeared edge.
  double e_med, e_box, sd;
  columnStats(med, kEdge - 1, kEdge, &e_med, &sd);
  columnStats(box, kEdge - 1, kEdge, &e_box, &sd);
  std::printf("[ figures  ] last dark column: %.1f median, %.1f box (step %.0f -> %.0f)\n", e_med,
              e_box, kDark, kLight);
  EXPECT_NEAR(e_med, kDark + 0.64 * kNoise, 1.0);
  EXPECT_NEAR(e_box, kDark + (kLight - kDark) / 3.0, 2.0);
}

TEST(ImagePrefilter, NoneSharesThePixelsAndEmptyImagesStayEmpty) {
  const cv::Mat raw = noisyStep();
  std::vector<cv::Mat> out;
  prefilterImages({raw, cv::Mat()}, ImagePrefilterParams{ImagePrefilter::kNone, 3}, &out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].data, raw.data);
  EXPECT_TRUE(out[1].empty());
  prefilterImages({cv::Mat(), raw}, ImagePrefilterParams{ImagePrefilter::kMedian, 3}, &out);
  EXPECT_TRUE(out[0].empty());
  EXPECT_EQ(out[1].size(), raw.size());
  EXPECT_EQ(out[1].type(), CV_8UC3);
  EXPECT_NE(out[1].data, raw.data);
}

TEST(ImagePrefilter, NamesAndSizesAreChecked) {
  for (ImagePrefilter t : {ImagePrefilter::kNone, ImagePrefilter::kMedian, ImagePrefilter::kBox})
    EXPECT_EQ(parseImagePrefilter(imagePrefilterName(t)), t);
  EXPECT_THROW(parseImagePrefilter("gaussian"), std::invalid_argument);
  EXPECT_THROW(parseImagePrefilter(""), std::invalid_argument);
  for (int size : {3, 5, 7})
    EXPECT_NO_THROW((ImagePrefilterParams{ImagePrefilter::kMedian, size}.validate()));
  for (int size : {-1, 0, 1, 2, 4, 9})
    EXPECT_THROW((ImagePrefilterParams{ImagePrefilter::kBox, size}.validate()), std::invalid_argument)
        << size;
  EXPECT_NO_THROW((ImagePrefilterParams{ImagePrefilter::kNone, 4}.validate()));  // unused size
  std::vector<cv::Mat> out;
  EXPECT_THROW(prefilterImages({cv::Mat(8, 8, CV_8UC1)}, ImagePrefilterParams{ImagePrefilter::kMedian, 3}, &out),
               std::invalid_argument);
}

// A header kNone left on a caller's image is not filtered into: the caller's pixels stay.
TEST(ImagePrefilter, ACallersImageIsNeverWrittenInto) {
  const cv::Mat raw = noisyStep();
  const cv::Mat copy = raw.clone();
  std::vector<cv::Mat> out;
  prefilterImages({raw}, ImagePrefilterParams{ImagePrefilter::kNone, 3}, &out);
  prefilterImages({noisyStep()}, ImagePrefilterParams{ImagePrefilter::kMedian, 3}, &out);
  EXPECT_EQ(cv::norm(raw, copy, cv::NORM_INF), 0.0);
  EXPECT_NE(out[0].data, raw.data);
}

}  // namespace
}  // namespace psfs
