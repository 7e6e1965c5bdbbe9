// The point-light detector (calibration/light_blob.h) on spots drawn here: a Gaussian spot
// integrated over each pixel (as a lens blurs a small LED), a dim noisy background. Its accuracy
// on the simulated rig's rendered images is measured in tabletop_sim/test_point_light_sim.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

#include "tabletop_capture/calibration/light_blob.h"

namespace tabletop_capture {
namespace {

double pixelMass(double centre, double x, double sigma) {
  return 0.5 * (std::erf((x + 0.5 - centre) / (sigma * M_SQRT2)) - std::erf((x - 0.5 - centre) / (sigma * M_SQRT2)));
}

void drawSpot(cv::Mat& grey, const Eigen::Vector2d& at, double sigma, double peak) {
  const double norm = 1.0 / (pixelMass(0, 0, sigma) * pixelMass(0, 0, sigma));
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x) {
      const double v = grey.at<uint8_t>(y, x) + peak * norm * pixelMass(at.x(), x, sigma) * pixelMass(at.y(), y, sigma);
      grey.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(v);
    }
}

cv::Mat background(unsigned seed) {
  cv::Mat grey(240, 320, CV_8UC1);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(20, 2);
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x) grey.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(noise(rng));
  return grey;
}

TEST(LightBlob, SubPixelCentroid) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(10, 300), v(10, 230);
  double err2 = 0;
  const int n = 50;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2d at(u(rng), v(rng));
    cv::Mat grey = background(k);
    drawSpot(grey, at, 1.2, 200);
    const LightBlob blob = detectLightBlob(grey);
    ASSERT_TRUE(blob.found) << blob.rejected;
    err2 += (blob.pixel - at).squaredNorm();
    // Colour images: the brightest channel.
    cv::Mat rgb;
    cv::cvtColor(grey, rgb, cv::COLOR_GRAY2RGB);
    EXPECT_LT((detectLightBlob(rgb).pixel - blob.pixel).norm(), 1e-9);
  }
  const double rms = std::sqrt(err2 / n);
  std::printf("centroid error %.3f px RMS\n", rms);
  EXPECT_LT(rms, 0.05);
}

TEST(LightBlob, NothingWithoutALight) {
  const LightBlob blob = detectLightBlob(background(3));
  EXPECT_FALSE(blob.found);
  EXPECT_EQ(blob.rejected.rfind("too dark", 0), 0u) << blob.rejected;
  cv::Mat hot = background(4);
  hot.at<uint8_t>(100, 100) = 255;  // a hot pixel of the sensor
  EXPECT_FALSE(detectLightBlob(hot).found);
  EXPECT_EQ(detectLightBlob(hot).rejected.rfind("too small", 0), 0u) << detectLightBlob(hot).rejected;
}

TEST(LightBlob, RejectsLargeStreakyAndAmbiguousSpots) {
  cv::Mat lamp = background(4);
  cv::circle(lamp, {100, 100}, 20, 250, -1);  // a lamp, ~1250 px
  EXPECT_FALSE(detectLightBlob(lamp).found);
  EXPECT_EQ(detectLightBlob(lamp).rejected.rfind("too large", 0), 0u) << detectLightBlob(lamp).rejected;

  cv::Mat streak = background(5);
  cv::line(streak, {50, 50}, {80, 52}, 250, 2);  // a specular edge
  EXPECT_FALSE(detectLightBlob(streak).found);

  cv::Mat two = background(6);
  drawSpot(two, {50, 50}, 1.2, 200);
  drawSpot(two, {200, 150}, 1.2, 190);
  EXPECT_FALSE(detectLightBlob(two).found);
  EXPECT_EQ(detectLightBlob(two).rejected.rfind("ambiguous", 0), 0u);

  // A much dimmer second spot (a faint reflection) does not hide the light.
  cv::Mat faint = background(7);
  drawSpot(faint, {50, 50}, 1.2, 220);
  drawSpot(faint, {200, 150}, 0.8, 120);
  const LightBlob blob = detectLightBlob(faint);
  ASSERT_TRUE(blob.found) << blob.rejected;
  EXPECT_LT((blob.pixel - Eigen::Vector2d(50, 50)).norm(), 0.1);

  EXPECT_THROW(detectLightBlob(cv::Mat(10, 10, CV_16UC1)), std::invalid_argument);
}

}  // namespace
}  // namespace tabletop_capture
