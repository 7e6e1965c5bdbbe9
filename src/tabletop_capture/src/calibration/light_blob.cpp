#include "tabletop_capture/calibration/light_blob.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace tabletop_capture {
namespace {

// The brightest channel per pixel: a red or blue LED stays bright in its own channel, where a
// grey conversion would dim it.
cv::Mat brightestChannel(const cv::Mat& image) {
  if (image.type() == CV_8UC1) return image;
  if (image.type() != CV_8UC3)
    throw std::invalid_argument("detectLightBlob: needs an rgb8, bgr8 or mono8 image");
  cv::Mat channels[3], grey;
  cv::split(image, channels);
  cv::max(channels[0], channels[1], grey);
  cv::max(grey, channels[2], grey);
  return grey;
}

struct Candidate {
  Eigen::Vector2d pixel;
  int area = 0;
  double peak = 0, sum = 0;
};

// Intensity-weighted centroid in the spot's box grown by 3 px. The weights fall to zero at
// 5 % of the spot's height above the local background (the median of the window's border), so
// the dim tails and the sensor noise of the background, which would pull the centroid towards
// the window's centre, do not count, while a symmetric spot keeps its centre exactly.
Candidate centroid(const cv::Mat& grey, const cv::Rect& box) {
  const cv::Rect window = (box + cv::Size(6, 6) - cv::Point(3, 3)) & cv::Rect(0, 0, grey.cols, grey.rows);
  std::vector<int> border;
  for (int x = window.x; x < window.x + window.width; ++x) {
    border.push_back(grey.at<uint8_t>(window.y, x));
    border.push_back(grey.at<uint8_t>(window.y + window.height - 1, x));
  }
  for (int y = window.y; y < window.y + window.height; ++y) {
    border.push_back(grey.at<uint8_t>(y, window.x));
    border.push_back(grey.at<uint8_t>(y, window.x + window.width - 1));
  }
  std::nth_element(border.begin(), border.begin() + border.size() / 2, border.end());
  const double background = border[border.size() / 2];
  double peak = 0;
  for (int y = window.y; y < window.y + window.height; ++y)
    for (int x = window.x; x < window.x + window.width; ++x) peak = std::max<double>(peak, grey.at<uint8_t>(y, x));
  const double floor = background + 0.05 * (peak - background);
  Candidate c;
  c.peak = peak;
  double sx = 0, sy = 0;
  for (int y = window.y; y < window.y + window.height; ++y)
    for (int x = window.x; x < window.x + window.width; ++x) {
      const double w = grey.at<uint8_t>(y, x) - floor;
      if (w <= 0) continue;
      sx += w * x;
      sy += w * y;
      c.sum += w;
    }
  c.pixel = c.sum > 0 ? Eigen::Vector2d(sx / c.sum, sy / c.sum)
                      : Eigen::Vector2d(box.x + 0.5 * (box.width - 1), box.y + 0.5 * (box.height - 1));
  return c;
}

// Minor over major axis of the component's pixels (second moments), 1 for a disc.
double roundness(const cv::Mat& labels, int label, const cv::Rect& box) {
  const cv::Moments m = cv::moments(labels(box) == label, true);
  if (m.m00 <= 0) return 0;
  const double a = m.mu20 / m.m00, b = m.mu11 / m.m00, c = m.mu02 / m.m00;
  const double d = std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  const double major = 0.5 * (a + c) + d, minor = 0.5 * (a + c) - d;
  return major > 0 ? std::sqrt(std::max(0.0, minor) / major) : 1.0;
}

}  // namespace

LightBlob detectLightBlob(const cv::Mat& image, const LightBlobOptions& options) {
  const cv::Mat grey = brightestChannel(image);
  LightBlob blob;
  double max_value = 0;
  cv::minMaxLoc(grey, nullptr, &max_value);
  if (max_value <= options.min_threshold) {
    blob.rejected = "too dark (brightest " + std::to_string(static_cast<int>(max_value)) + ")";
    return blob;
  }
  const double threshold = std::max(options.min_threshold, options.threshold_fraction * max_value);
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(grey > threshold, labels, stats, centroids, 8, CV_32S);
  std::vector<Candidate> accepted;
  for (int label = 1; label < n; ++label) {
    const int area = stats.at<int>(label, cv::CC_STAT_AREA);
    const cv::Rect box(stats.at<int>(label, cv::CC_STAT_LEFT), stats.at<int>(label, cv::CC_STAT_TOP),
                       stats.at<int>(label, cv::CC_STAT_WIDTH), stats.at<int>(label, cv::CC_STAT_HEIGHT));
    if (area < options.min_area) {
      blob.rejected = "too small (" + std::to_string(area) + " px)";
      continue;
    }
    if (area > options.max_area) {
      blob.rejected = "too large (" + std::to_string(area) + " px)";
      continue;
    }
    if (area >= options.min_area_for_shape) {
      const double r = roundness(labels, label, box);
      if (r < options.min_roundness) {
        blob.rejected = "not round (axis ratio " + std::to_string(r).substr(0, 4) + ")";
        continue;
      }
    }
    Candidate c = centroid(grey, box);
    c.area = area;
    accepted.push_back(c);
  }
  if (accepted.empty()) return blob;
  std::sort(accepted.begin(), accepted.end(), [](const Candidate& a, const Candidate& b) { return a.sum > b.sum; });
  if (accepted.size() > 1 && accepted[0].sum < options.dominance * accepted[1].sum) {
    blob.rejected = "ambiguous (" + std::to_string(accepted.size()) + " spots)";
    return blob;
  }
  blob.found = true;
  blob.rejected.clear();
  blob.pixel = accepted[0].pixel;
  blob.area = accepted[0].area;
  blob.peak = accepted[0].peak;
  return blob;
}

}  // namespace tabletop_capture
