// Pixel classifier: shadow cylinder, outlier-model bounds, skin vs. shirt on the skin channel,
// agreement of the fast path with the double-precision reference, and bad input.
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "expect_throw.h"
#include <yaml-cpp/yaml.h>

#include "psfs_reconstruction/background_model.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/pixel_classifier.h"
#include "synthetic_scene.h"
#include "test_data_path.h"

namespace {

using psfs::BackgroundModel;
using psfs::ClassPriors;
using psfs::GaussianMixture2D;
using psfs::PixelClassifier;
using psfs::PixelClassifierParams;
using psfs_test::Rgb;

constexpr int W = 320, H = 240;

// The shipped skin model (the classifier's real configuration); a hand-made model matching
// its shape if the config directory is not known.
GaussianMixture2D skinModel() {
  const std::string dir = psfs_test::configDir();
  if (!dir.empty() && psfs_test::fileExists(dir + "/skin_gmm.yaml"))
    return GaussianMixture2D::load(dir + "/skin_gmm.yaml");
  std::printf("note: config/skin_gmm.yaml not found, using a built-in skin model\n");
  psfs::GaussianComponent2D a, b;
  a.weight = 0.73;
  a.mean = {0.427, 0.313};
  a.covariance << 5.3e-4, -4.5e-5, -4.5e-5, 1.05e-4;
  b.weight = 0.27;
  b.mean = {0.499, 0.321};
  b.covariance << 2.9e-4, 3.5e-5, 3.5e-5, 2.0e-4;
  return GaussianMixture2D({a, b});
}

// Priors of the reference rig: 8 cameras, 10 % of the volume foreground, 1 % skin.
ClassPriors rigPriors() { return ClassPriors::fromOccupancy(0.10, 0.01, 8); }

BackgroundModel learn(const cv::Mat& clean, double sigma, std::uint64_t seed) {
  BackgroundModel m(clean.cols, clean.rows);
  std::mt19937_64 rng(seed);
  while (!m.ready()) m.addLearningFrame(psfs_test::addNoise(clean, sigma, rng));
  return m;
}

cv::Mat uniform(const Rgb& c, int w = W, int h = H) { return psfs_test::bandScene(w, h, {c}); }

// Channel values of the fast classifier at pixel (x, y) as probabilities.
std::pair<double, double> at(const cv::Mat& lik, int x, int y) {
  const auto v = lik.at<cv::Vec2b>(y, x);
  return {v[0] / 255.0, v[1] / 255.0};
}

using psfs_test::expectThrowContaining;

}  // namespace

TEST(ClassPriors, FromOccupancy) {
  const ClassPriors p = ClassPriors::fromOccupancy(0.10, 0.01, 8);
  EXPECT_NEAR(p.foreground, std::pow(0.10, 1.0 / 8), 1e-12);
  EXPECT_NEAR(p.skin, std::pow(0.01, 1.0 / 8) / std::pow(0.10, 1.0 / 8), 1e-12);
  std::printf("P(F) = %.4f, P(S) = %.4f for P(H_F) = 0.10, P(H) = 0.01, C = 8\n", p.foreground,
              p.skin);
  EXPECT_THROW(ClassPriors::fromOccupancy(0.01, 0.10, 8), std::invalid_argument);
  EXPECT_THROW(ClassPriors::fromOccupancy(0.1, 0.01, 0), std::invalid_argument);
  EXPECT_THROW(ClassPriors::fromOccupancy(std::nan(""), 0.01, 8), std::invalid_argument);
}

TEST(PixelClassifier, ShadowOnDeskStaysBackgroundObjectIsForeground) {
  const Rgb desk = {170, 140, 100};
  const BackgroundModel bg = learn(uniform(desk), 1.5, 11);
  PixelClassifier cls(skinModel(), {}, rigPriors());
  const double PF = cls.priors().foreground, eF = cls.params().foreground_outlier;
  const double floor = eF * PF;

  // Same chroma, 40 % darker: (102, 84, 60). Object of the same brightness (sum 246) but
  // a different colour: a grey-green folder (70, 92, 84).
  const Rgb shadow = {desk[0] * 0.6, desk[1] * 0.6, desk[2] * 0.6};
  const Rgb object = {70, 92, 84};
  const cv::Mat img = psfs_test::bandScene(W, H, {shadow, object, desk});
  cv::Mat lik;
  const auto stats = cls.classify(img, bg, lik);
  const auto [f_shadow, fs_shadow] = at(lik, W / 6, H / 2);
  const auto [f_object, fs_object] = at(lik, W / 2, H / 2);
  const auto [f_desk, fs_desk] = at(lik, 5 * W / 6, H / 2);
  std::printf(
      "P'(F|c): desk %.3f, desk in 40%% shadow %.3f, object of equal brightness %.3f "
      "(floor eF P(F) = %.4f); shadow pixels %d of %d; gain %.4f\n",
      f_desk, f_shadow, f_object, floor, stats.shadow_pixels, stats.pixels, stats.gain);
  const double q = 0.5 / 255 + 1e-6;  // output quantisation
  EXPECT_NEAR(f_shadow, floor, q);
  EXPECT_NEAR(f_desk, floor, 0.01);
  EXPECT_GT(f_object, 0.95);
  EXPECT_LT(fs_object, 0.1);  // grey-green is not skin
  EXPECT_LT(fs_shadow, 0.1);  // and no skin in a shadow either
  // The rg model alone (the thesis'): the Gaussian already calls the shadow background, the
  // cylinder did not have to change anything. With the intensity model the shadow's intensity
  // is far from the desk's Gaussian and only the band's uniform share explains it, so there
  // the cylinder is what keeps it background (above).
  PixelClassifierParams rg_only;
  rg_only.intensity_model = false;
  PixelClassifier cls_rg(skinModel(), rg_only, rigPriors());
  const auto stats_rg = cls_rg.classify(img, bg, lik);
  EXPECT_NEAR(at(lik, W / 6, H / 2).first, floor, q);
  EXPECT_EQ(stats_rg.shadow_pixels, 0);
}

TEST(PixelClassifier, ShadowCylinderRemovesTintedShadows) {
  // Real shadows are lit by bluish ambient light: darker and bluer. Shift the chroma by ~0.025
  // (6 background sigmas: far outside what the Gaussian accepts) inside a 0.03 cylinder.
  const Rgb desk = {200, 165, 118};
  const BackgroundModel bg = learn(uniform(desk), 1.5, 12);
  PixelClassifierParams params;
  params.shadow_chroma_radius = 0.03f;
  PixelClassifier cls(skinModel(), params, rigPriors());
  const double floor = params.foreground_outlier * cls.priors().foreground;
  const Rgb tinted = {113, 99, 78};  // I/I_bg = 0.60; r 0.3897 vs 0.4141, g 0.3414 vs 0.3416
  const Rgb deep = {25, 22, 17};     // similar tint, I/I_bg = 0.13 < 0.2: outside the cylinder
  // The lit desk fills half the view (a view all in shadow is a global light change).
  const cv::Mat img = psfs_test::bandScene(W, H, {tinted, deep, desk, desk});
  cv::Mat lik;
  const auto stats = cls.classify(img, bg, lik);
  const double f_tinted = at(lik, W / 8, H / 2).first, f_deep = at(lik, 3 * W / 8, H / 2).first;
  EXPECT_EQ(stats.shadow_pixels, W * H / 4);  // exactly the tinted band was suppressed
  params.shadow_suppression = false;
  cls.setParams(params);
  cls.classify(img, bg, lik);
  const double f_tinted_off = at(lik, W / 8, H / 2).first;
  std::printf(
      "tinted shadow: P'(F|c) %.3f with the cylinder, %.3f without; too deep a shadow "
      "(ratio 0.13): %.3f\n",
      f_tinted, f_tinted_off, f_deep);
  EXPECT_NEAR(f_tinted, floor, 0.5 / 255 + 1e-6);
  EXPECT_GT(f_tinted_off, 0.95);
  EXPECT_GT(f_deep, 0.95);
}

TEST(PixelClassifier, OutlierModelBoundsAndNoNaN) {
  // Random colours against a random textured background, black and saturated included.
  const cv::Mat office = psfs_test::officeBackground(W, H, 5);
  const BackgroundModel bg = learn(office, 2.0, 12);
  std::mt19937_64 rng(99);
  std::uniform_int_distribution<int> u(0, 255);
  cv::Mat img(H, W, CV_8UC3);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      for (int k = 0; k < 3; ++k) img.at<cv::Vec3b>(y, x)[k] = std::uint8_t(u(rng));
  img(cv::Rect(0, 0, 40, 40)).setTo(cv::Scalar(0, 0, 0));
  img(cv::Rect(40, 0, 40, 40)).setTo(cv::Scalar(255, 255, 255));
  office(cv::Rect(80, 0, 40, 40)).copyTo(img(cv::Rect(80, 0, 40, 40)));  // background

  for (const ClassPriors pri : {rigPriors(), ClassPriors{0.5, 0.5}, ClassPriors{0.0, 1.0},
                                ClassPriors{1.0, 0.0}, ClassPriors{0.01, 0.99}}) {
    PixelClassifierParams params;
    params.foreground_outlier = 0.1f;
    params.skin_outlier = 0.2f;
    PixelClassifier cls(skinModel(), params, pri);
    const double eF = params.foreground_outlier, PF = pri.foreground;
    const double lo = eF * PF, hi = eF * PF + 1 - eF;
    cv::Mat lik;
    cls.classify(img, bg, lik);
    double ref_lo = 1, ref_hi = 0;
    int bad = 0, nonfinite = 0;
    for (int y = 0; y < H; y += 3)
      for (int x = 0; x < W; x += 3) {
        const auto c = img.at<cv::Vec3b>(y, x);
        double f, s;
        cls.classifyPixel(c[0], c[1], c[2], bg, x, y, &f, &s);
        nonfinite += !std::isfinite(f) || !std::isfinite(s);
        ref_lo = std::min(ref_lo, f);
        ref_hi = std::max(ref_hi, f);
        bad += f < lo - 1e-12 || f > hi + 1e-12 || s < 0 || s > 1;
        const double fast = lik.at<cv::Vec2b>(y, x)[0] / 255.0;
        // Output quantisation: +-0.5 level; 1e-6 covers float ties (0.9f * 255 = 229.5).
        bad += fast < lo - 0.5 / 255 - 1e-6 || fast > hi + 0.5 / 255 + 1e-6;
      }
    std::printf("P(F) %.3f P(S) %.3f: P'(F|c) in [%.4f, %.4f], bounds [%.4f, %.4f]\n", PF, pri.skin,
                ref_lo, ref_hi, lo, hi);
    EXPECT_EQ(nonfinite, 0);
    EXPECT_EQ(bad, 0);
  }

  // Black has no chroma. With the intensity model, black against the brighter office is
  // foreground and not skin (P'(S|c) = eS P(S)); with rg alone both terms fall back to the
  // priors. Saturated white is a valid grey.
  PixelClassifier cls(skinModel(), {}, rigPriors());
  const ClassPriors p = cls.priors();
  const double eS = cls.params().skin_outlier;
  cv::Mat lik;
  const auto stats = cls.classify(img, bg, lik);
  double f_black, s_black;
  cls.classifyPixel(0, 0, 0, bg, 10, 10, &f_black, &s_black, nullptr, stats.gain);
  EXPECT_GT(f_black, 0.9);
  EXPECT_NEAR(s_black, eS * p.skin, 1e-12);
  EXPECT_NEAR(lik.at<cv::Vec2b>(10, 10)[0] / 255.0, f_black, 0.5 / 255 + 1e-6);
  EXPECT_NEAR(lik.at<cv::Vec2b>(10, 10)[1] / 255.0, f_black * s_black, 0.5 / 255 + 1e-6);
  PixelClassifierParams rg_only;
  rg_only.intensity_model = false;
  PixelClassifier cls_rg(skinModel(), rg_only, rigPriors());
  cv::Mat lik_rg;
  cls_rg.classify(img, bg, lik_rg);
  EXPECT_EQ(lik_rg.at<cv::Vec2b>(10, 10)[0], std::lround(255 * p.foreground));
  EXPECT_EQ(lik_rg.at<cv::Vec2b>(10, 10)[1], std::lround(255 * p.foreground * p.skin));
  double f_white, s_white;
  cls.classifyPixel(255, 255, 255, bg, 50, 10, &f_white, &s_white);
  EXPECT_TRUE(std::isfinite(f_white) && std::isfinite(s_white));
  EXPECT_NEAR(lik.at<cv::Vec2b>(10, 50)[0] / 255.0, f_white, 0.5 / 255 + 1e-6);
  EXPECT_GE(stats.dark_pixels, 40 * 40);
  EXPECT_GE(stats.saturated_pixels, 40 * 40);
}

TEST(PixelClassifier, IntensitySeparatesGreyClothesFromAGreyWall) {
  // Normalised rg cannot tell achromatic clothes from an achromatic wall: a white shirt (1.6x
  // the wall's intensity) and a charcoal one (0.12x) have the wall's chroma. Their intensity,
  // outside the shadow/highlight band [0.2, 1.25], makes them foreground; the wall in a shadow
  // of 0.5 stays background (the cylinder), and so does the lit wall.
  const Rgb wall = {120, 120, 125};
  const BackgroundModel bg = learn(uniform(wall), 1.5, 41);
  const Rgb white = {195, 195, 202}, charcoal = {14, 14, 15}, shade = {60, 60, 62};
  const cv::Mat img = psfs_test::bandScene(W, H, {white, charcoal, shade, wall, wall, wall});
  auto run = [&](bool intensity, double out[4]) {
    PixelClassifierParams params;
    params.intensity_model = intensity;
    PixelClassifier cls(skinModel(), params, rigPriors());
    cv::Mat lik;
    cls.classify(img, bg, lik);
    for (int band = 0; band < 4; ++band) out[band] = at(lik, (2 * band + 1) * W / 12, H / 2).first;
  };
  double with_i[4], rg_only[4];
  run(true, with_i);
  run(false, rg_only);
  std::printf(
      "P'(F|c) intensity model / rg only: white shirt %.3f / %.3f, charcoal %.3f / %.3f, "
      "wall in shadow %.3f / %.3f, wall %.3f / %.3f\n",
      with_i[0], rg_only[0], with_i[1], rg_only[1], with_i[2], rg_only[2], with_i[3], rg_only[3]);
  EXPECT_GT(with_i[0], 0.95);
  EXPECT_GT(with_i[1], 0.95);
  EXPECT_LT(with_i[2], 0.05);
  EXPECT_LT(with_i[3], 0.05);
  EXPECT_LT(rg_only[0], 0.5);  // what the thesis' model misses
  EXPECT_LT(rg_only[1], 0.8);  // near black: the prior at best
}

TEST(PixelClassifier, GlobalLightChangeIsDividedOut) {
  // The light rises by 40 % (a lamp switched on, an exposure step) while a person in a blue
  // shirt fills 30 % of the view. Without the gain the whole wall is brighter than any
  // highlight the band accepts (1.25); with it the wall stays background, the shirt foreground.
  cv::Mat office;  // a dim office (channels <= 132), so that 1.4x saturates nothing
  psfs_test::officeBackground(W, H, 6).convertTo(office, -1, 0.6);
  const BackgroundModel bg = learn(office, 1.5, 42);
  std::mt19937_64 rng(43);
  cv::Mat img;
  office.convertTo(img, -1, 1.4);
  img(cv::Rect(0, 0, W * 3 / 10, H)).setTo(cv::Scalar(40, 60, 150));
  img = psfs_test::addNoise(img, 1.5, rng);
  PixelClassifier cls(skinModel(), {}, rigPriors());
  cv::Mat lik;
  const auto st = cls.classify(img, bg, lik);
  const cv::Mat f = [&] { cv::Mat ch[2]; cv::split(lik, ch); return ch[0]; }();
  const double wall_fg = cv::countNonZero(f(cv::Rect(W / 2, 0, W / 2, H)) > 127) / double(W / 2 * H);
  const double shirt_fg = cv::countNonZero(f(cv::Rect(0, 0, W / 4, H)) > 127) / double(W / 4 * H);
  PixelClassifierParams no_gain;
  no_gain.gain_compensation = false;
  cls.setParams(no_gain);
  cv::Mat lik_ng;
  cls.classify(img, bg, lik_ng);
  const cv::Mat f_ng = [&] { cv::Mat ch[2]; cv::split(lik_ng, ch); return ch[0]; }();
  const double wall_fg_ng =
      cv::countNonZero(f_ng(cv::Rect(W / 2, 0, W / 2, H)) > 127) / double(W / 2 * H);
  std::printf("gain %.4f (true 1.4); wall called foreground: %.4f with the gain, %.4f without; "
              "shirt %.4f\n", st.gain, wall_fg, wall_fg_ng, shirt_fg);
  // The histogram's step is 1/256; the 8-bit rounding of 1.4 x I moves the ratio by < 0.5 %
  EXPECT_NEAR(st.gain, 1.4, 0.01);
  EXPECT_LT(wall_fg, 0.01);
  EXPECT_GT(shirt_fg, 0.99);
  EXPECT_GT(wall_fg_ng, 0.5);
}

TEST(PixelClassifier, DegenerateFramesGiveNeutralOrValidOutput) {
  const BackgroundModel bg = learn(psfs_test::officeBackground(W, H, 5), 2.0, 13);
  // The rg model (thesis): a covered lens / camera off, all black, carries no information
  // anywhere (priors: a neutral view). With the intensity model it is a dark object filling
  // the view; the reconstructor switches such a view off (test_reconstructor, covered lens).
  PixelClassifierParams rg_only;
  rg_only.intensity_model = false;
  PixelClassifier cls(skinModel(), rg_only, rigPriors());
  const ClassPriors p = cls.priors();
  cv::Mat lik;
  auto st = cls.classify(uniform({0, 0, 0}), bg, lik);
  EXPECT_EQ(st.darkFraction(), 1.0);
  double lo, hi;
  cv::Mat ch[2];
  cv::split(lik, ch);
  cv::minMaxLoc(ch[0], &lo, &hi);
  EXPECT_EQ(lo, hi);
  EXPECT_EQ(lo, std::lround(255 * p.foreground));
  // Overexposed: all white -> valid output, reported as saturated.
  st = cls.classify(uniform({255, 255, 255}), bg, lik);
  EXPECT_EQ(st.saturatedFraction(), 1.0);
  EXPECT_TRUE(std::isfinite(st.mean_foreground));
  std::printf("all-black frame: P'(F|c) = %d/255 everywhere; all-white frame: mean P'(F|c) %.3f\n",
              int(lo), st.mean_foreground);
}

TEST(PixelClassifier, SkinChannelHighOnSkinLowOnShirts) {
  const Rgb wall = {95, 105, 125};  // grey-blue office wall
  const BackgroundModel bg = learn(uniform(wall), 1.5, 21);
  PixelClassifier cls(skinModel(), {}, rigPriors());
  struct Case {
    const char* name;
    Rgb c;
    bool skin;
  };
  const std::vector<Case> cases = {
      {"light skin", {224, 172, 140}, true},   {"medium skin", {198, 134, 100}, true},
      {"dark skin", {120, 80, 58}, true},      {"blue shirt", {40, 60, 150}, false},
      {"green shirt", {60, 120, 70}, false},   {"red shirt", {190, 30, 40}, false},
      {"white shirt", {225, 225, 230}, false}, {"grey shirt", {110, 110, 110}, false},
      {"black shirt", {30, 30, 34}, false},
  };
  std::vector<Rgb> colours;
  for (const auto& c : cases) colours.push_back(c.c);
  const cv::Mat img = psfs_test::bandScene(W, H, colours);
  cv::Mat lik;
  cls.classify(img, bg, lik);
  const double prior_fs = cls.priors().foreground * cls.priors().skin;
  std::printf("prior P(F) P(S) = %.3f\n", prior_fs);
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const int x = int((2 * i + 1) * W / (2 * cases.size()));
    const auto [f, fs] = at(lik, x, H / 2);
    std::printf("%-12s (%3.0f,%3.0f,%3.0f): P'(F|c) %.3f  P'(F,S|c) %.3f\n", cases[i].name,
                cases[i].c[0], cases[i].c[1], cases[i].c[2], f, fs);
    if (cases[i].skin) {
      EXPECT_GT(f, 0.9) << cases[i].name;
      EXPECT_GT(fs, 0.9) << cases[i].name;
    } else if (cases[i].c[0] != cases[i].c[1] || cases[i].c[1] + 10 < cases[i].c[2]) {
      EXPECT_LT(fs, 0.1) << cases[i].name;  // saturated colours: far from skin in rg
    } else {
      // Achromatic shirts sit ~4 sigma from the skin cluster in rg (the UCI skin set holds
      // pale, low-saturation faces): not "low" in absolute terms, but well below the prior
      // P(F) P(S), so each view votes against a skin voxel in the fusion.
      EXPECT_LT(fs, 0.5 * prior_fs) << cases[i].name;
    }
  }
  // A pixel too dark for chroma, against the brighter wall: foreground by its intensity and
  // never skin (P'(S|c) = eS P(S)); the rg model gives it the priors (a neutral view).
  const auto dark_stats = cls.classify(uniform({3, 3, 4}), bg, lik);
  double f_dark, s_dark;
  cls.classifyPixel(3, 3, 4, bg, 5, 5, &f_dark, &s_dark, nullptr, dark_stats.gain);
  EXPECT_GT(at(lik, 5, 5).first, 0.9);
  EXPECT_NEAR(at(lik, 5, 5).second, f_dark * cls.params().skin_outlier * cls.priors().skin,
              0.5 / 255 + 1e-6);
  PixelClassifierParams rg_only;
  rg_only.intensity_model = false;
  PixelClassifier cls_rg(skinModel(), rg_only, rigPriors());
  cls_rg.classify(uniform({3, 3, 4}), bg, lik);
  EXPECT_NEAR(at(lik, 5, 5).second, prior_fs, 0.5 / 255 + 1e-6);
  // The wall itself: not foreground, not skin.
  cls.classify(uniform(wall), bg, lik);
  EXPECT_LT(at(lik, 3, 3).first, 0.1);
}

TEST(PixelClassifier, FastPathMatchesReference) {
  const cv::Mat office = psfs_test::officeBackground(W, H, 8);
  const BackgroundModel bg = learn(office, 2.0, 31);
  std::mt19937_64 rng(32);
  // Frame: the noisy background with a skin-coloured hand, a shirt and a shadow pasted in.
  cv::Mat img = psfs_test::addNoise(office, 2.0, rng);
  img(cv::Rect(60, 50, 80, 60)).setTo(cv::Scalar(210, 150, 120));
  img(cv::Rect(160, 120, 100, 100)).setTo(cv::Scalar(40, 60, 150));
  cv::Mat shade = img(cv::Rect(20, 150, 120, 60));
  shade.convertTo(shade, -1, 0.6);
  img = psfs_test::addNoise(img, 1.0, rng);
  PixelClassifier cls(skinModel(), {}, rigPriors());
  cv::Mat fast, ref;
  const auto sf = cls.classify(img, bg, fast);
  const auto sr = cls.classifyReference(img, bg, ref);
  cv::Mat diff;
  cv::absdiff(fast, ref, diff);
  double max_diff;
  cv::minMaxLoc(diff.reshape(1), nullptr, &max_diff);
  const int over1 = cv::countNonZero(diff.reshape(1) > 1);
  std::printf(
      "fast vs reference: max |diff| %d/255, %d of %d values differ by > 1; "
      "mean P'(F|c) %.4f vs %.4f\n",
      int(max_diff), over1, int(diff.total() * 2), sf.mean_foreground, sr.mean_foreground);
  // float vs double and a polynomial exp: rounding may flip the last level; a pixel exactly on
  // a cylinder/dark boundary may flip its decision (allowed for 1e-4 of the values).
  EXPECT_LE(over1, int(diff.total() * 2 / 10000));
  EXPECT_EQ(sf.dark_pixels, sr.dark_pixels);
  EXPECT_EQ(sf.saturated_pixels, sr.saturated_pixels);
  EXPECT_NEAR(sf.shadow_pixels, sr.shadow_pixels, 5);
  EXPECT_NEAR(sf.mean_foreground, sr.mean_foreground, 1e-4);
}

TEST(PixelClassifier, MultiCameraAndThreadCountGiveIdenticalOutput) {
  std::vector<BackgroundModel> bgs;
  std::vector<cv::Mat> imgs;
  std::mt19937_64 rng(41);
  for (int c = 0; c < 3; ++c) {
    const int w = c == 2 ? 160 : W, h = c == 2 ? 120 : H;  // cameras may differ in size
    const cv::Mat office = psfs_test::officeBackground(w, h, 50 + c);
    bgs.push_back(learn(office, 2.0, 60 + c));
    cv::Mat img = psfs_test::addNoise(office, 2.0, rng);
    img(cv::Rect(10, 10, 50, 50)).setTo(cv::Scalar(200, 140, 110));
    imgs.push_back(img);
  }
  std::vector<const BackgroundModel*> ptrs;
  for (const auto& b : bgs) ptrs.push_back(&b);
  PixelClassifier cls(skinModel(), {}, rigPriors());
  std::vector<cv::Mat> out1, out2;
  cls.classify(imgs, ptrs, out1, 1);
  const auto stats = cls.classify(imgs, ptrs, out2, 2);
  ASSERT_EQ(out2.size(), 3u);
  for (int c = 0; c < 3; ++c) {
    cv::Mat single;
    const auto s = cls.classify(imgs[c], bgs[c], single);
    EXPECT_EQ(cv::norm(out1[c], out2[c], cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(single, out2[c], cv::NORM_INF), 0.0);
    EXPECT_EQ(s.shadow_pixels, stats[c].shadow_pixels);
    EXPECT_EQ(out2[c].type(), CV_8UC2);
    EXPECT_EQ(out2[c].size(), imgs[c].size());
  }
}

TEST(PixelClassifier, RejectsBadInput) {
  const BackgroundModel bg = learn(uniform({100, 110, 120}), 1.0, 51);
  PixelClassifier cls(skinModel(), {}, rigPriors());
  cv::Mat lik;
  expectThrowContaining([&] { cls.classify(cv::Mat(), bg, lik); }, "empty image");
  expectThrowContaining([&] { cls.classify(cv::Mat(H, W, CV_8UC1), bg, lik); }, "CV_8UC3");
  expectThrowContaining([&] { cls.classify(cv::Mat(H, W, CV_16UC3), bg, lik); }, "CV_8UC3");
  expectThrowContaining([&] { cls.classify(cv::Mat(480, 640, CV_8UC3), bg, lik); },
                        "640x480 but the background model is 320x240");
  BackgroundModel unlearned(W, H);
  expectThrowContaining([&] { cls.classify(uniform({1, 2, 3}), unlearned, lik); }, "not learned");
  std::vector<cv::Mat> imgs = {uniform({1, 2, 3}), cv::Mat(H, W, CV_8UC4)};
  std::vector<const BackgroundModel*> bgs = {&bg, &bg};
  std::vector<cv::Mat> outs;
  expectThrowContaining([&] { cls.classify(imgs, bgs, outs); }, "cam1");
  bgs.pop_back();
  expectThrowContaining([&] { cls.classify(imgs, bgs, outs); }, "2 images but 1 background");
  expectThrowContaining([&] { cls.setPriors({std::nan(""), 0.5}); }, "P(F)");
  expectThrowContaining([&] { cls.setPriors({0.5, 1.5}); }, "P(S)");
  PixelClassifierParams bad;
  bad.foreground_outlier = -0.1f;
  expectThrowContaining([&] { cls.setParams(bad); }, "outlier");
  bad = {};
  bad.shadow_min_intensity_ratio = 2.0f;
  expectThrowContaining([&] { cls.setParams(bad); }, "shadow");
  EXPECT_THROW(PixelClassifier{GaussianMixture2D{}}, std::invalid_argument);
  // Non-contiguous input (an ROI of a larger image) is fine.
  cv::Mat big = psfs_test::bandScene(W + 20, H + 10, {{100, 110, 120}});
  EXPECT_NO_THROW(cls.classify(big(cv::Rect(5, 5, W, H)), bg, lik));
}

TEST(PixelClassifier, ShippedParameterFileMatchesDefaults) {
  const std::string path = psfs_test::configDir() + "/psfs.yaml";
  if (psfs_test::configDir().empty() || !psfs_test::fileExists(path))
    GTEST_SKIP() << "config/psfs.yaml not found (PSFS_RECONSTRUCTION_CONFIG_DIR)";
  const YAML::Node root = YAML::LoadFile(path);
  const YAML::Node c = root["pixel_classifier"], b = root["background_model"];
  ASSERT_TRUE(c && b);
  const PixelClassifierParams p;
  EXPECT_FLOAT_EQ(c["foreground_outlier"].as<float>(), p.foreground_outlier);
  EXPECT_FLOAT_EQ(c["skin_outlier"].as<float>(), p.skin_outlier);
  EXPECT_EQ(c["shadow_suppression"].as<bool>(), p.shadow_suppression);
  EXPECT_FLOAT_EQ(c["shadow_chroma_radius"].as<float>(), p.shadow_chroma_radius);
  EXPECT_FLOAT_EQ(c["shadow_min_intensity_ratio"].as<float>(), p.shadow_min_intensity_ratio);
  EXPECT_FLOAT_EQ(c["shadow_max_intensity_ratio"].as<float>(), p.shadow_max_intensity_ratio);
  EXPECT_FLOAT_EQ(c["min_chroma_intensity"].as<float>(), p.min_chroma_intensity);
  EXPECT_TRUE(
      psfs_test::fileExists(psfs_test::configDir() + "/" + c["skin_model"].as<std::string>()));
  const psfs::BackgroundModelParams bp;
  EXPECT_EQ(b["learning_frames"].as<int>(), bp.learning_frames);
  EXPECT_FLOAT_EQ(b["learning_rate"].as<float>(), bp.learning_rate);
  EXPECT_FLOAT_EQ(b["min_sigma_rg"].as<float>(), bp.min_sigma_rg);
  EXPECT_FLOAT_EQ(b["min_sigma_intensity"].as<float>(), bp.min_sigma_intensity);
}
