#include <gtest/gtest.h>

#include <climits>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "tabletop_capture/image_conversion.h"

using namespace tabletop_capture;

namespace {

RawImageView view(const std::string& enc, int w, int h, size_t step,
                  const std::vector<uint8_t>& buf) {
  RawImageView v;
  v.encoding = enc;
  v.width = w;
  v.height = h;
  v.step = step;
  v.data = buf.data();
  v.size = buf.size();
  return v;
}

// Channel-distinct colours (no two share a channel value pattern), so any R/B or pattern
// mix-up changes at least one channel by far more than the tolerance.
const cv::Vec3b kPatch[4] = {{200, 40, 90}, {30, 180, 60}, {90, 60, 220}, {250, 240, 10}};

// Four flat quadrant patches, RGB order.
cv::Mat quadrants(int w, int h) {
  cv::Mat rgb(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) rgb.at<cv::Vec3b>(y, x) = kPatch[(y >= h / 2) * 2 + (x >= w / 2)];
  return rgb;
}

// Mosaics an RGB image with a ROS Bayer pattern: pattern[i] is the colour of pixel
// (i / 2, i % 2) of each 2x2 block (row, column).
std::vector<uint8_t> mosaic(const cv::Mat& rgb, const std::string& pattern, size_t step) {
  std::vector<uint8_t> buf(step * rgb.rows, 0xAB);  // padding bytes must be ignored
  for (int y = 0; y < rgb.rows; ++y) {
    for (int x = 0; x < rgb.cols; ++x) {
      const char colour = pattern[(y % 2) * 2 + (x % 2)];
      const int ch = colour == 'r' ? 0 : colour == 'g' ? 1 : 2;
      buf[y * step + x] = rgb.at<cv::Vec3b>(y, x)[ch];
    }
  }
  return buf;
}

std::string errorOf(const RawImageView& v, int ew = 0, int eh = 0) {
  const auto r = convertToRgb8(v, ew, eh, "cam3");
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(r.rgb.empty());
  return r.error;
}

}  // namespace

TEST(ImageConversion, Rgb8WrapsWithoutCopy) {
  const int w = 5, h = 3;
  const size_t step = w * 3 + 4;  // row padding
  std::vector<uint8_t> buf(step * h);
  for (size_t i = 0; i < buf.size(); ++i) buf[i] = static_cast<uint8_t>(i);
  const auto r = convertToRgb8(view("rgb8", w, h, step, buf));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_TRUE(r.wraps_input);
  EXPECT_EQ(r.rgb.type(), CV_8UC3);
  EXPECT_EQ(r.rgb.data, buf.data());
  EXPECT_EQ(r.rgb.step[0], step);
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(2, 4), cv::Vec3b(2 * step + 12, 2 * step + 13, 2 * step + 14));

  const auto copy = convertToRgb8(view("rgb8", w, h, step, buf), 0, 0, "", false);
  ASSERT_TRUE(copy.ok);
  EXPECT_FALSE(copy.wraps_input);
  EXPECT_NE(copy.rgb.data, buf.data());
  EXPECT_EQ(copy.rgb.at<cv::Vec3b>(2, 4), r.rgb.at<cv::Vec3b>(2, 4));
}

TEST(ImageConversion, Bgr8SwapsChannels) {
  const int w = 4, h = 2;
  std::vector<uint8_t> buf(w * 3 * h);
  for (int p = 0; p < w * h; ++p) {
    buf[p * 3 + 0] = 10 + p;   // B
    buf[p * 3 + 1] = 100 + p;  // G
    buf[p * 3 + 2] = 200 + p;  // R
  }
  const auto r = convertToRgb8(view("bgr8", w, h, w * 3, buf));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_FALSE(r.wraps_input);
  EXPECT_EQ(r.rgb.type(), CV_8UC3);
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(1, 3), cv::Vec3b(207, 107, 17));
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(0, 0), cv::Vec3b(200, 100, 10));
}

TEST(ImageConversion, Mono8ReplicatesGrey) {
  const int w = 3, h = 2;
  const size_t step = 8;
  std::vector<uint8_t> buf(step * h, 0);
  buf[0] = 7;
  buf[step + 2] = 250;
  const auto r = convertToRgb8(view("mono8", w, h, step, buf));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.rgb.size(), cv::Size(w, h));
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(0, 0), cv::Vec3b(7, 7, 7));
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(1, 2), cv::Vec3b(250, 250, 250));
  EXPECT_EQ(r.rgb.at<cv::Vec3b>(1, 1), cv::Vec3b(0, 0, 0));
}

class BayerRoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(BayerRoundTrip, FlatPatchesComeBackWithRightChannels) {
  const std::string enc = GetParam();  // e.g. bayer_rggb8
  const std::string pattern = enc.substr(6, 4);
  for (const cv::Size size : {cv::Size(64, 48), cv::Size(63, 47)}) {  // even and odd
    const int w = size.width, h = size.height;
    const cv::Mat truth = quadrants(w, h);
    const size_t step = w + 3;
    const auto buf = mosaic(truth, pattern, step);
    const auto r = convertToRgb8(view(enc, w, h, step, buf), w, h);
    ASSERT_TRUE(r.ok) << r.error;
    ASSERT_EQ(r.rgb.type(), CV_8UC3);
    ASSERT_EQ(r.rgb.size(), size);
    // Interior of each patch (3 px away from patch and image borders, where interpolation
    // mixes neighbours).
    int checked = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const int dy = std::min({y, h - 1 - y, std::abs(y - h / 2), std::abs(y - (h / 2 - 1))});
        const int dx = std::min({x, w - 1 - x, std::abs(x - w / 2), std::abs(x - (w / 2 - 1))});
        if (dy < 3 || dx < 3) continue;
        const cv::Vec3b got = r.rgb.at<cv::Vec3b>(y, x);
        const cv::Vec3b want = truth.at<cv::Vec3b>(y, x);
        for (int ch = 0; ch < 3; ++ch) {
          ASSERT_NEAR(got[ch], want[ch], 3)
              << enc << " " << w << "x" << h << " at (" << x << "," << y << ") channel " << ch;
        }
        ++checked;
      }
    }
    EXPECT_GT(checked, w * h / 3);
  }
}

INSTANTIATE_TEST_SUITE_P(AllPatterns, BayerRoundTrip,
                         ::testing::Values("bayer_rggb8", "bayer_bggr8", "bayer_gbrg8",
                                           "bayer_grbg8"));

TEST(ImageConversion, BytesPerPixel) {
  EXPECT_EQ(bytesPerPixel("rgb8"), 3);
  EXPECT_EQ(bytesPerPixel("bgr8"), 3);
  EXPECT_EQ(bytesPerPixel("mono8"), 1);
  EXPECT_EQ(bytesPerPixel("bayer_grbg8"), 1);
  EXPECT_EQ(bytesPerPixel("mono16"), 0);
  EXPECT_EQ(bytesPerPixel("RGB8"), 0);  // names are case-sensitive, as in ROS
}

TEST(ImageConversion, UnsupportedEncodings) {
  std::vector<uint8_t> buf(64 * 64 * 8, 0);
  const std::string unknown = errorOf(view("yuv422", 4, 4, 8, buf));
  EXPECT_NE(unknown.find("cam3: unsupported encoding 'yuv422'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("bayer_grbg8"), std::string::npos) << unknown;  // lists supported
  for (const char* enc : {"mono16", "rgb16", "bgr16", "bayer_rggb16", "16UC1", "32FC1"}) {
    const std::string e = errorOf(view(enc, 4, 4, 32, buf));
    EXPECT_NE(e.find(std::string("unsupported encoding '") + enc + "'"), std::string::npos) << e;
    EXPECT_NE(e.find("only 8-bit"), std::string::npos) << e;
  }
  EXPECT_NE(errorOf(view("", 4, 4, 12, buf)).find("unsupported encoding ''"), std::string::npos);
}

TEST(ImageConversion, BadGeometry) {
  std::vector<uint8_t> buf(10 * 3 * 4, 0);
  // Step too small for rgb8.
  std::string e = errorOf(view("rgb8", 10, 4, 29, buf));
  EXPECT_NE(e.find("step 29 < width * 3 = 30"), std::string::npos) << e;
  // Buffer shorter than step * height.
  e = errorOf(view("rgb8", 10, 5, 30, buf));
  EXPECT_NE(e.find("data size 120 < step * height = 150"), std::string::npos) << e;
  // Null data.
  RawImageView v = view("mono8", 2, 2, 2, buf);
  v.data = nullptr;
  e = errorOf(v);
  EXPECT_NE(e.find("data size 0"), std::string::npos) << e;
  // Zero and negative sizes.
  EXPECT_NE(errorOf(view("mono8", 0, 4, 0, buf)).find("invalid image size 0x4"),
            std::string::npos);
  EXPECT_NE(errorOf(view("mono8", 4, -1, 4, buf)).find("invalid image size 4x-1"),
            std::string::npos);
  // Size disagrees with camera_info.
  e = errorOf(view("mono8", 10, 4, 10, buf), 640, 480);
  EXPECT_NE(e.find("image size 10x4 does not match camera_info 640x480"), std::string::npos)
      << e;
  EXPECT_TRUE(convertToRgb8(view("mono8", 10, 4, 10, buf), 10, 4).ok);
  // Hostile sizes: no overflow, no read past the buffer.
  e = errorOf(view("rgb8", INT_MAX, INT_MAX, static_cast<size_t>(INT_MAX) * 3, buf));
  EXPECT_NE(e.find("data size"), std::string::npos) << e;
  e = errorOf(view("mono8", 2, INT_MAX, SIZE_MAX, buf));
  EXPECT_NE(e.find("overflows"), std::string::npos) << e;
  // Bayer needs a full 2x2 block.
  e = errorOf(view("bayer_rggb8", 1, 8, 1, buf));
  EXPECT_NE(e.find("smaller than 2x2"), std::string::npos) << e;
}
