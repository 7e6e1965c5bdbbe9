// Synthetic rgb8 frames for the background/classifier tests and the benchmark: a static scene
// of flat colour bands plus Gaussian sensor noise, rounded and clipped like a uint8 sensor.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <opencv2/core.hpp>

namespace psfs_test {

using Rgb = std::array<double, 3>;

// Vertical bands of equal width, left to right.
inline cv::Mat bandScene(int width, int height, const std::vector<Rgb>& bands) {
  cv::Mat img(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const Rgb& c = bands[std::size_t(x) * bands.size() / std::size_t(width)];
      auto* p = img.ptr<std::uint8_t>(y) + 3 * x;
      for (int k = 0; k < 3; ++k) p[k] = std::uint8_t(std::lround(std::clamp(c[k], 0.0, 255.0)));
    }
  return img;
}

// The noise-free band colours as doubles (for exact expectations), one value per pixel column.
inline Rgb bandColour(int x, int width, const std::vector<Rgb>& bands) {
  return bands[std::size_t(x) * bands.size() / std::size_t(width)];
}

// Frame = round(clip(colour + N(0, sigma^2))) per channel; colour is given in double so that
// tests can reason about the exact generating values.
inline cv::Mat noisyBandScene(int width, int height, const std::vector<Rgb>& bands, double sigma,
                              std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, sigma);
  cv::Mat img(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const Rgb& c = bandColour(x, width, bands);
      auto* p = img.ptr<std::uint8_t>(y) + 3 * x;
      for (int k = 0; k < 3; ++k)
        p[k] = std::uint8_t(std::lround(std::clamp(c[k] + n(rng), 0.0, 255.0)));
    }
  return img;
}

// A textured "office" background: smooth colour gradients and blocks, so every pixel has its
// own background colour (no two neighbouring pixels share parameters by accident).
inline cv::Mat officeBackground(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(40.0, 220.0);
  cv::Mat img(height, width, CV_8UC3);
  const int bw = 40, bh = 30;
  std::vector<Rgb> blocks(std::size_t((width / bw + 1) * (height / bh + 1)));
  for (auto& b : blocks) b = {u(rng), u(rng), u(rng)};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const Rgb& b = blocks[std::size_t((y / bh) * (width / bw + 1) + x / bw)];
      auto* p = img.ptr<std::uint8_t>(y) + 3 * x;
      const double shade = 0.85 + 0.15 * std::sin(0.05 * x + 0.07 * y);
      for (int k = 0; k < 3; ++k)
        p[k] = std::uint8_t(std::lround(std::clamp(b[k] * shade, 0.0, 255.0)));
    }
  return img;
}

inline cv::Mat addNoise(const cv::Mat& clean, double sigma, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, sigma);
  cv::Mat img = clean.clone();
  for (int y = 0; y < img.rows; ++y) {
    auto* p = img.ptr<std::uint8_t>(y);
    for (int i = 0; i < 3 * img.cols; ++i)
      p[i] = std::uint8_t(std::lround(std::clamp(double(p[i]) + n(rng), 0.0, 255.0)));
  }
  return img;
}

}  // namespace psfs_test
