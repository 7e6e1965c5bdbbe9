// Background model: learning matches the statistics of the generating sensor model, the
// selective update touches only unmasked pixels and converges at rate alpha, persistence
// round-trips bit-exactly, and bad input is rejected with a clear error.
#include <cmath>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "expect_throw.h"

#include "psfs_reconstruction/background_model.h"
#include "synthetic_scene.h"

namespace {

using psfs::BackgroundModel;
using psfs::BackgroundModelParams;
using psfs_test::Rgb;

constexpr int W = 320, H = 240;

std::string tempPath(const std::string& name) {
  return (::testing::TempDir().empty() ? std::string("/tmp/") : ::testing::TempDir()) + name;
}

std::string readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

void writeFile(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), std::streamsize(bytes.size()));
}

BackgroundModel learnNoisy(const std::vector<Rgb>& bands, double sigma, std::uint64_t seed,
                           const BackgroundModelParams& params = {}) {
  BackgroundModel m(W, H, params);
  std::mt19937_64 rng(seed);
  for (int i = 0; i < params.learning_frames; ++i)
    m.addLearningFrame(psfs_test::noisyBandScene(W, H, bands, sigma, rng));
  return m;
}

bool samePlanes(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

using psfs_test::expectThrowContaining;

}  // namespace

TEST(BackgroundModel, LearnsStatisticsOfNoisyStaticScene) {
  // Sensor model: each channel = round(colour + N(0, sigma^2)). Rounding adds 1/12 level^2.
  // r = R/S propagates to var_r = s^2 ((G+B)^2 + 2 R^2) / S^4 (delta method), with a
  // second-order mean shift s^2 (2R - G - B) / S^3; I = S/3 has var_I = s^2 / 3.
  const std::vector<Rgb> bands = {{180, 150, 110}, {120, 120, 120}, {60, 80, 160}, {200, 140, 110}};
  const double sigma = 2.0;
  const double s2 = sigma * sigma + 1.0 / 12.0;
  BackgroundModelParams params;
  params.min_sigma_rg = 1e-5f;  // far below the noise: measure the learned values themselves
  params.min_sigma_intensity = 1e-3f;
  const BackgroundModel m = learnNoisy(bands, sigma, 1, params);
  ASSERT_TRUE(m.ready());
  EXPECT_EQ(m.learnedFrames(), 25);

  const cv::Mat mr = m.meanR(), mg = m.meanG(), mi = m.meanIntensity();
  const cv::Mat vr = m.varianceR(), vg = m.varianceG(), vi = m.varianceIntensity();
  const int N = params.learning_frames;
  for (std::size_t b = 0; b < bands.size(); ++b) {
    const double R = bands[b][0], G = bands[b][1], B = bands[b][2], S = R + G + B;
    const double exp_r = R / S + s2 * (2 * R - G - B) / (S * S * S);
    const double exp_g = G / S + s2 * (2 * G - R - B) / (S * S * S);
    const double exp_vr = s2 * ((G + B) * (G + B) + 2 * R * R) / (S * S * S * S);
    const double exp_vg = s2 * ((R + B) * (R + B) + 2 * G * G) / (S * S * S * S);
    const double exp_vi = s2 / 3.0;
    const int x0 = int(b) * W / int(bands.size()), x1 = int(b + 1) * W / int(bands.size());
    const cv::Rect roi(x0, 0, x1 - x0, H);
    const double npx = double(roi.area());
    const double mean_r = cv::mean(mr(roi))[0], mean_g = cv::mean(mg(roi))[0];
    const double mean_i = cv::mean(mi(roi))[0];
    const double avg_vr = cv::mean(vr(roi))[0], avg_vg = cv::mean(vg(roi))[0];
    const double avg_vi = cv::mean(vi(roi))[0];
    // Standard errors of band averages: means sqrt(var / (N npx)); variances sqrt(2/(N-1)/npx).
    const double se_r = std::sqrt(exp_vr / (N * npx)), se_g = std::sqrt(exp_vg / (N * npx));
    const double rel_se_var = std::sqrt(2.0 / (N - 1) / npx);
    std::printf(
        "band %zu (%g,%g,%g): r %.6f (exp %.6f)  g %.6f (exp %.6f)  sd_r %.5f (exp %.5f)"
        "  sd_g %.5f (exp %.5f)  I %.3f (exp %.3f)  sd_I %.3f (exp %.3f)\n",
        b, R, G, B, mean_r, exp_r, mean_g, exp_g, std::sqrt(avg_vr), std::sqrt(exp_vr),
        std::sqrt(avg_vg), std::sqrt(exp_vg), mean_i, S / 3, std::sqrt(avg_vi), std::sqrt(exp_vi));
    // 5 standard errors plus 2e-6 for the neglected higher orders of the delta method.
    EXPECT_NEAR(mean_r, exp_r, 5 * se_r + 2e-6);
    EXPECT_NEAR(mean_g, exp_g, 5 * se_g + 2e-6);
    EXPECT_NEAR(mean_i, S / 3, 5 * std::sqrt(exp_vi / (N * npx)));
    // Variances: 5 standard errors (~1 %) plus 1 % for the delta method and the rounding model.
    EXPECT_NEAR(avg_vr / exp_vr, 1.0, 5 * rel_se_var + 0.01);
    EXPECT_NEAR(avg_vg / exp_vg, 1.0, 5 * rel_se_var + 0.01);
    EXPECT_NEAR(avg_vi / exp_vi, 1.0, 5 * rel_se_var + 0.01);
    // Per pixel: the learned mean is within 4 standard errors of the truth almost everywhere
    // (Gaussian: 6e-5 of the pixels outside).
    int outside = 0;
    for (int y = 0; y < H; ++y)
      for (int x = x0; x < x1; ++x)
        outside += std::abs(mr.at<float>(y, x) - exp_r) > 4 * std::sqrt(exp_vr / N);
    EXPECT_LT(outside / npx, 1e-3) << outside << " pixels";
  }
}

TEST(BackgroundModel, VarianceFloorForNoiselessScene) {
  BackgroundModelParams params;
  BackgroundModel m(W, H, params);
  const cv::Mat frame = psfs_test::bandScene(W, H, {{180, 150, 110}, {0, 0, 0}});
  for (int i = 0; i < params.learning_frames; ++i) m.addLearningFrame(frame);
  const float floor_rg = params.min_sigma_rg * params.min_sigma_rg;
  double lo, hi;
  cv::minMaxLoc(m.varianceR(), &lo, &hi);
  EXPECT_EQ(float(lo), floor_rg);
  EXPECT_EQ(float(hi), floor_rg);
  cv::minMaxLoc(m.varianceIntensity(), &lo, &hi);
  EXPECT_EQ(float(hi), params.min_sigma_intensity * params.min_sigma_intensity);
  EXPECT_NEAR(m.meanR().at<float>(0, 0), 180.0 / 440.0, 1e-6);
  // Black pixels learn the grey point, not NaN.
  EXPECT_NEAR(m.meanR().at<float>(0, W - 1), 1.0 / 3.0, 1e-7);
  EXPECT_EQ(m.meanIntensity().at<float>(0, W - 1), 0.0f);
}

TEST(BackgroundModel, SelectiveUpdateOnlyWhereMaskIsZeroAndConvergesAtRateAlpha) {
  BackgroundModelParams params;
  params.learning_rate = 0.1f;
  BackgroundModel m(W, H, params);
  const cv::Mat desk = psfs_test::bandScene(W, H, {{180, 150, 110}});
  for (int i = 0; i < params.learning_frames; ++i) m.addLearningFrame(desk);
  const cv::Mat moved = psfs_test::bandScene(W, H, {{60, 80, 160}});  // e.g. a folder put down
  cv::Mat mask(H, W, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(0, 0, W / 2, H)).setTo(255);  // left half: the tracked person

  const cv::Mat mr0 = m.meanR(), vr0 = m.varianceR(), mi0 = m.meanIntensity();
  m.update(moved, mask);
  const cv::Rect left(0, 0, W / 2, H), right(W / 2, 0, W - W / 2, H);
  EXPECT_TRUE(samePlanes(m.meanR()(left).clone(), mr0(left).clone())) << "masked pixels changed";
  EXPECT_TRUE(samePlanes(m.varianceR()(left).clone(), vr0(left).clone()));
  EXPECT_TRUE(samePlanes(m.meanIntensity()(left).clone(), mi0(left).clone()));

  const double a = params.learning_rate;
  const double c_r = 60.0 / 300.0, mu0 = mr0.at<float>(0, W - 1), var0 = vr0.at<float>(0, W - 1);
  const double d = c_r - mu0;
  EXPECT_NEAR(m.meanR().at<float>(0, W - 1), mu0 + a * d, 1e-6);
  EXPECT_NEAR(m.varianceR().at<float>(0, W - 1), (1 - a) * var0 + a * d * d, 1e-7);
  EXPECT_NEAR(m.meanIntensity().at<float>(5, W - 3), 440.0 / 3 + a * (300.0 - 440.0) / 3, 1e-3);

  // n updates: mu_n - c = (1 - alpha)^n (mu_0 - c).
  for (int n = 2; n <= 40; ++n) m.update(moved, mask);
  const double err = m.meanR().at<float>(H - 1, W - 1) - c_r;
  const double expect = std::pow(1 - a, 40) * (mu0 - c_r);
  std::printf("after 40 updates: mean_r error %.3e, (1-alpha)^40 (mu0 - c) = %.3e\n", err, expect);
  EXPECT_NEAR(err, expect, 1e-5);
  EXPECT_TRUE(samePlanes(m.meanR()(left).clone(), mr0(left).clone()));

  // An empty mask updates every pixel.
  m.update(moved, cv::Mat());
  EXPECT_NEAR(m.meanR().at<float>(0, 0), mu0 + a * d, 1e-6);
}

// A version-2 file: the 40-byte header, the image filter's 16 bytes, then the planes.
constexpr size_t kHeaderBytes = 56;

TEST(BackgroundModel, SaveLoadRoundTripAndFileChecks) {
  const BackgroundModel m = learnNoisy({{180, 150, 110}, {60, 80, 160}}, 2.0, 3);
  const std::string path = tempPath("psfs_bg_roundtrip.bin");
  m.save(path);
  const BackgroundModel back = BackgroundModel::load(path, W, H);
  EXPECT_TRUE(back.ready());
  EXPECT_EQ(back.learnedFrames(), m.learnedFrames());
  EXPECT_EQ(back.params().learning_rate, m.params().learning_rate);
  EXPECT_TRUE(samePlanes(back.meanR(), m.meanR()));
  EXPECT_TRUE(samePlanes(back.meanG(), m.meanG()));
  EXPECT_TRUE(samePlanes(back.meanIntensity(), m.meanIntensity()));
  EXPECT_TRUE(samePlanes(back.varianceR(), m.varianceR()));
  EXPECT_TRUE(samePlanes(back.varianceG(), m.varianceG()));
  EXPECT_TRUE(samePlanes(back.varianceIntensity(), m.varianceIntensity()));
  EXPECT_EQ(back.density(7, 9, 0.4, 0.33), m.density(7, 9, 0.4, 0.33));

  expectThrowContaining([&] { BackgroundModel::load(path, 640, 480); }, "does not match");

  const std::string bytes = readFile(path);
  const std::string bad = tempPath("psfs_bg_bad.bin");
  auto write = [&](const std::string& b) { writeFile(bad, b); };
  write(bytes.substr(0, bytes.size() - 100));
  expectThrowContaining([&] { BackgroundModel::load(bad); }, "truncated");
  write("NOTAMODEL" + bytes.substr(9));
  expectThrowContaining([&] { BackgroundModel::load(bad); }, "bad magic");
  std::string nan_bytes = bytes;
  const float nan = std::nanf("");
  std::memcpy(&nan_bytes[kHeaderBytes + 3 * 4 * W * H + 4 * 17], &nan, 4);  // a var_r entry
  write(nan_bytes);
  expectThrowContaining([&] { BackgroundModel::load(bad); }, "non-finite");
  write(bytes + "x");
  expectThrowContaining([&] { BackgroundModel::load(bad); }, "trailing");
  expectThrowContaining([&] { BackgroundModel::load("/nonexistent/bg.bin"); }, "cannot open");
  std::remove(path.c_str());
  std::remove(bad.c_str());
}

// The filter the images passed before the model saw them travels with the file, so that the
// Reconstructor can refuse a model learned from other pixels; files written before the field
// existed (version 1) were learned from raw images.
TEST(BackgroundModel, SavedFileRecordsTheImageFilter) {
  BackgroundModelParams p;
  p.learning_frames = 3;
  p.image_filter = "median 3x3";
  BackgroundModel m(W, H, p);
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(120, 100, 80));
  for (int i = 0; i < 3; ++i) m.addLearningFrame(img);
  ASSERT_TRUE(m.ready());
  const std::string path = tempPath("psfs_bg_filter.bin");
  m.save(path);
  const BackgroundModel back = BackgroundModel::load(path);
  EXPECT_EQ(back.params().image_filter, "median 3x3");
  EXPECT_TRUE(samePlanes(back.varianceIntensity(), m.varianceIntensity()));

  const std::string bytes = readFile(path);
  const std::string old = tempPath("psfs_bg_v1.bin");
  auto write = [&](const std::string& b) { writeFile(old, b); };
  // Version 1: the same header without the filter's 16 bytes.
  std::string v1 = bytes.substr(0, 40) + bytes.substr(kHeaderBytes);
  const uint32_t one = 1;
  std::memcpy(&v1[8], &one, 4);
  write(v1);
  const BackgroundModel legacy = BackgroundModel::load(old);
  EXPECT_EQ(legacy.params().image_filter, psfs::kUnrecordedImageFilter);
  EXPECT_TRUE(samePlanes(legacy.meanR(), m.meanR()));
  // A filter field without its terminating NUL is corrupt.
  std::string unterminated = bytes;
  unterminated[kHeaderBytes - 1] = 'x';
  write(unterminated);
  expectThrowContaining([&] { BackgroundModel::load(old); }, "corrupt image filter");
  std::string garbage = bytes;  // "median 3x3", NUL, then something after it
  garbage[kHeaderBytes - 2] = 'x';
  write(garbage);
  expectThrowContaining([&] { BackgroundModel::load(old); }, "corrupt image filter");
  const uint32_t three = 3;
  std::string v3 = bytes;
  std::memcpy(&v3[8], &three, 4);
  write(v3);
  expectThrowContaining([&] { BackgroundModel::load(old); }, "unsupported format version 3");

  for (const std::string& name : std::vector<std::string>{"", std::string(16, 'a'), "tab\there"}) {
    BackgroundModelParams q;
    q.image_filter = name;
    EXPECT_THROW(BackgroundModel(W, H, q), std::invalid_argument) << "'" << name << "'";
  }
  BackgroundModelParams longest;
  longest.image_filter = std::string(15, 'a');  // the field's 16 bytes with its NUL
  EXPECT_NO_THROW(BackgroundModel(W, H, longest));
  std::remove(path.c_str());
  std::remove(old.c_str());
}

TEST(BackgroundModel, RejectsBadInput) {
  BackgroundModel m(W, H);
  expectThrowContaining([&] { m.addLearningFrame(cv::Mat()); }, "empty image");
  expectThrowContaining([&] { m.addLearningFrame(cv::Mat(H, W, CV_8UC1, cv::Scalar(0))); },
                        "CV_8UC3");
  expectThrowContaining([&] { m.addLearningFrame(cv::Mat(480, 640, CV_8UC3)); },
                        "640x480 but the background model is 320x240");
  const cv::Mat frame = psfs_test::bandScene(W, H, {{100, 100, 100}});
  expectThrowContaining([&] { m.update(frame, cv::Mat()); }, "before learning finished");
  m.addLearningFrame(frame);
  expectThrowContaining([&] { m.finishLearning(); }, ">= 2");
  m.addLearningFrame(frame);
  m.finishLearning();
  EXPECT_TRUE(m.ready());
  expectThrowContaining([&] { m.addLearningFrame(frame); }, "already finished");
  expectThrowContaining([&] { m.update(frame, cv::Mat(H, W, CV_32FC1)); }, "CV_8UC1");
  expectThrowContaining([&] { m.update(frame, cv::Mat(10, 10, CV_8UC1)); }, "10x10");
  EXPECT_THROW(BackgroundModel(0, 240), std::invalid_argument);
  BackgroundModelParams bad;
  bad.learning_rate = 1.5f;
  EXPECT_THROW(BackgroundModel(W, H, bad), std::invalid_argument);
  // Saturated and black frames are valid input and give finite parameters.
  BackgroundModel s(W, H);
  const cv::Mat white = psfs_test::bandScene(W, H, {{255, 255, 255}, {0, 0, 0}});
  for (int i = 0; i < 25; ++i) s.addLearningFrame(white);
  s.update(white, cv::Mat());
  EXPECT_TRUE(cv::checkRange(s.meanR()) && cv::checkRange(s.varianceR()));
}

// Learning only from empty frames: sensor noise (2 levels, dark bands included) changes almost
// no pixel at 5 sigma, while an object covering 12 % of the image shows as ~12 % changed.
TEST(BackgroundModel, ChangedFractionSeesAnObjectNotTheNoise) {
  const std::vector<Rgb> bands = {{180, 150, 110}, {20, 18, 15}, {60, 80, 160}, {200, 140, 110}};
  BackgroundModel m(W, H);
  std::mt19937_64 rng(7);
  expectThrowContaining<std::logic_error>([&] { m.changedFraction(psfs_test::noisyBandScene(W, H, bands, 2.0, rng)); },
                                          "learning");
  for (int i = 0; i < 5; ++i) {
    m.addLearningFrame(psfs_test::noisyBandScene(W, H, bands, 2.0, rng));
    const double noise = m.changedFraction(psfs_test::noisyBandScene(W, H, bands, 2.0, rng));
    EXPECT_LT(noise, 0.001) << "after " << i + 1 << " frames";
  }
  cv::Mat person = psfs_test::noisyBandScene(W, H, bands, 2.0, rng);
  const cv::Rect box(100, 60, 96, 96);  // 12 % of the image, a dark-red sweater
  person(box).setTo(cv::Scalar(90, 30, 40));
  const double f = m.changedFraction(person);
  const double expected = double(box.area()) / (W * H);
  std::printf("[ figures  ] changed fraction %.4f for an object covering %.4f\n", f, expected);
  EXPECT_NEAR(f, expected, 0.01);
}
