// Skin-colour GMM: YAML persistence and validation, normalisation of the density (the
// classifier compares it with the uniform density 1 per unit rg area, so its units matter),
// EM recovery of a known mixture, and the ROC AUC on the UCI skin data's held-back split.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include "psfs_reconstruction/color_space.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/labelled_pixels.h"
#include "test_data_path.h"

namespace {

using psfs::GaussianComponent2D;
using psfs::GaussianMixture2D;
using psfs::ModelError;

const char* kUciFile = "uci_skin_segmentation/Skin_NonSkin.txt";

GaussianMixture2D twoComponents() {
  GaussianComponent2D a, b;
  a.weight = 0.7;
  a.mean = {0.43, 0.31};
  a.covariance << 5e-4, -4e-5, -4e-5, 1e-4;
  b.weight = 0.3;
  b.mean = {0.50, 0.32};
  b.covariance << 3e-4, 3e-5, 3e-5, 2e-4;
  return GaussianMixture2D({a, b});
}

std::string tempPath(const std::string& name) {
  return (::testing::TempDir().empty() ? std::string("/tmp/") : ::testing::TempDir()) + name;
}

// Expects fromYaml(text) to throw ModelError whose message contains `needle`.
void expectYamlError(const std::string& text, const std::string& needle) {
  try {
    GaussianMixture2D::fromYaml(text, "test");
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << "message '" << e.what() << "' lacks '" << needle << "'";
  }
}

}  // namespace

TEST(GaussianMixture, DensityIntegratesToOneOverRg) {
  // Riemann sum on a fine grid: the density is per unit rg area, as the classifier assumes.
  const auto gmm = twoComponents();
  const int n = 1000;
  double sum = 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) sum += gmm.density((i + 0.5) / n, (j + 0.5) / n);
  sum /= double(n) * n;
  std::printf("integral of p(c|S) over the unit rg square: %.6f\n", sum);
  EXPECT_NEAR(sum, 1.0, 1e-4);
  EXPECT_NEAR(std::log(gmm.density(0.45, 0.3)), gmm.logDensity(0.45, 0.3), 1e-12);
  // Far away: density underflows to 0, log density stays finite.
  EXPECT_EQ(gmm.density(0.0, 1.0), 0.0);
  EXPECT_TRUE(std::isfinite(gmm.logDensity(0.0, 1.0)));
}

TEST(GaussianMixture, YamlRoundTrip) {
  const auto gmm = twoComponents();
  const std::string path = tempPath("psfs_gmm_roundtrip.yaml");
  gmm.save(path, "test model\nsecond comment line");
  const auto back = GaussianMixture2D::load(path);
  ASSERT_EQ(back.size(), 2);
  for (int k = 0; k < 2; ++k) {
    const auto& a = gmm.components()[k];
    const auto& b = back.components()[k];
    EXPECT_NEAR(a.weight, b.weight, 1e-9);
    EXPECT_NEAR((a.mean - b.mean).norm(), 0.0, 1e-9);
    EXPECT_NEAR((a.covariance - b.covariance).norm(), 0.0, 1e-12);
  }
  EXPECT_NEAR(gmm.density(0.44, 0.31), back.density(0.44, 0.31), 1e-6 * gmm.density(0.44, 0.31));
  std::remove(path.c_str());
}

TEST(GaussianMixture, RejectsInvalidModels) {
  const std::string good_comp =
      "  - weight: 1.0\n    mean: [0.4, 0.3]\n    covariance: [[1e-4, 0], [0, 1e-4]]\n";
  EXPECT_NO_THROW(GaussianMixture2D::fromYaml("components:\n" + good_comp));
  expectYamlError(
      "components:\n  - weight: 1.0\n    mean: [0.4, 0.3]\n"
      "    covariance: [[1e-4, 2e-4], [2e-4, 1e-4]]\n",
      "positive definite");
  expectYamlError(
      "components:\n  - weight: 1.0\n    mean: [0.4, 0.3]\n"
      "    covariance: [[-1e-4, 0], [0, 1e-4]]\n",
      "positive definite");
  expectYamlError(
      "components:\n  - weight: 0.7\n    mean: [0.4, 0.3]\n"
      "    covariance: [[1e-4, 0], [0, 1e-4]]\n",
      "weights sum to 0.7");
  expectYamlError(
      "components:\n  - weight: 1.0\n    mean: [.nan, 0.3]\n"
      "    covariance: [[1e-4, 0], [0, 1e-4]]\n",
      "not finite");
  expectYamlError(
      "components:\n  - weight: 1.0\n    mean: [0.4, 0.3]\n"
      "    covariance: [[1e-4, 1e-5], [0, 1e-4]]\n",
      "not symmetric");
  expectYamlError(
      "components:\n  - weight: 1.0\n    mean: [0.4]\n"
      "    covariance: [[1e-4, 0], [0, 1e-4]]\n",
      "mean must have 2 entries");
  expectYamlError("components: []\n", "components");
  expectYamlError("type: something_else\ncomponents:\n" + good_comp, "type");
  expectYamlError("version: 7\ncomponents:\n" + good_comp, "version");
  expectYamlError("components: [unclosed\n", "YAML error");
  EXPECT_THROW(GaussianMixture2D::load("/nonexistent/skin.yaml"), ModelError);
}

TEST(GaussianMixture, EmRecoversKnownMixtureDeterministically) {
  const auto truth = twoComponents();
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n01;
  std::uniform_real_distribution<double> u01;
  const int N = 20000;
  Eigen::MatrixX2d samples(N, 2);
  for (int i = 0; i < N; ++i) {
    const auto& c = truth.components()[u01(rng) < truth.components()[0].weight ? 0 : 1];
    const Eigen::Matrix2d L = c.covariance.llt().matrixL();
    samples.row(i) = (c.mean + L * Eigen::Vector2d(n01(rng), n01(rng))).transpose();
  }
  const auto fit = GaussianMixture2D::train(samples);
  const auto fit2 = GaussianMixture2D::train(samples);
  ASSERT_EQ(fit.size(), 2);
  for (int k = 0; k < 2; ++k) {
    const auto& t = truth.components()[k];
    const auto& f = fit.components()[k];  // both ordered by weight
    std::printf("component %d: weight %.4f (true %.2f), mean (%.4f, %.4f) (true (%.2f, %.2f))\n", k,
                f.weight, t.weight, f.mean.x(), f.mean.y(), t.mean.x(), t.mean.y());
    // Sampling error of N = 20000: weight ~0.003, mean ~2e-4; the overlapping components make
    // the split less certain, hence the wider bounds.
    EXPECT_NEAR(f.weight, t.weight, 0.03);
    EXPECT_NEAR((f.mean - t.mean).norm(), 0.0, 0.003);
    EXPECT_NEAR(std::sqrt(f.covariance(0, 0)), std::sqrt(t.covariance(0, 0)), 0.003);
    EXPECT_EQ(f.weight, fit2.components()[k].weight) << "training must be deterministic";
    EXPECT_EQ(f.mean, fit2.components()[k].mean);
  }
  EXPECT_THROW(GaussianMixture2D::train(samples.topRows(3)), ModelError);
}

TEST(LabelledPixels, ParsesFormatsAndRejectsBadLines) {
  const std::string path = tempPath("psfs_labelled.csv");
  {
    std::ofstream f(path);
    f << "r,g,b,skin\n10,20,30,1\n# comment\n40 50 60 2\n\n70;80;90;1\n";
  }
  const auto bgr = psfs::loadLabelledPixels(path, psfs::ChannelOrder::BGR, 1);
  ASSERT_EQ(bgr.size(), 3u);
  EXPECT_EQ(bgr.rgb[0][0], 30);  // B,G,R columns -> R = third column
  EXPECT_EQ(bgr.rgb[0][2], 10);
  EXPECT_EQ(bgr.skin[0], 1);
  EXPECT_EQ(bgr.skin[1], 0);
  const auto rgb = psfs::loadLabelledPixels(path, psfs::ChannelOrder::RGB, 1);
  EXPECT_EQ(rgb.rgb[2][0], 70);
  {
    std::ofstream f(path);
    f << "1,2,3,1\n1,2,300,1\n";
  }
  EXPECT_THROW(psfs::loadLabelledPixels(path), std::runtime_error);
  {
    std::ofstream f(path);
    f << "1,2,3,1\n1,2,3\n";
  }
  EXPECT_THROW(psfs::loadLabelledPixels(path), std::runtime_error);
  std::remove(path.c_str());
}

TEST(Roc, AucOfKnownRankings) {
  EXPECT_DOUBLE_EQ(psfs::rocAuc({0.1, 0.2, 0.8, 0.9}, {0, 0, 1, 1}), 1.0);
  EXPECT_DOUBLE_EQ(psfs::rocAuc({0.9, 0.8, 0.2, 0.1}, {0, 0, 1, 1}), 0.0);
  EXPECT_DOUBLE_EQ(psfs::rocAuc({0.5, 0.5, 0.5, 0.5}, {0, 1, 0, 1}), 0.5);
  EXPECT_DOUBLE_EQ(psfs::rocAuc({0.1, 0.4, 0.35, 0.8}, {0, 0, 1, 1}), 0.75);
  EXPECT_TRUE(std::isnan(psfs::rocAuc({0.1, 0.2}, {1, 1})));
}

TEST(SkinModel, UciHeldBackAuc) {
  const std::string path = psfs_test::findSharedData(kUciFile);
  if (path.empty())
    GTEST_SKIP() << "UCI skin data not found (shared/data/" << kUciFile
                 << "); set PSFS_SHARED_DATA_DIR to the shared data directory";
  const auto all = psfs::loadLabelledPixels(path, psfs::ChannelOrder::BGR, 1);
  ASSERT_EQ(all.size(), 245057u) << "unexpected UCI file";
  ASSERT_EQ(all.countSkin(), 50859u);
  psfs::LabelledPixels train, test;
  psfs::splitHoldout(all, psfs::kDefaultHoldoutFraction, psfs::kDefaultSplitSeed, &train, &test);

  auto auc_of = [&](const GaussianMixture2D& gmm) {
    std::vector<double> scores(test.size());
    for (std::size_t i = 0; i < test.size(); ++i) {
      const auto c = psfs::toNormalizedRgI(test.rgb[i][0], test.rgb[i][1], test.rgb[i][2]);
      scores[i] = gmm.logDensity(c.r, c.g);  // P(S|c) is monotonic in p(c|S)
    }
    return psfs::rocAuc(scores, test.skin);
  };

  const auto t0 = std::chrono::steady_clock::now();
  const auto trained = GaussianMixture2D::train(psfs::normalizedRgOf(train, 1));
  const double train_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double auc_trained = auc_of(trained);
  std::printf("UCI: %zu training (%zu skin), %zu held back (%zu skin); EM %.1f s\n", train.size(),
              train.countSkin(), test.size(), test.countSkin(), train_s);
  std::printf("held-back ROC AUC, freshly trained 2-component GMM: %.4f\n", auc_trained);
  EXPECT_GE(auc_trained, 0.95);

  const std::string cfg = psfs_test::configDir() + "/skin_gmm.yaml";
  if (psfs_test::configDir().empty() || !psfs_test::fileExists(cfg)) {
    std::printf("shipped config/skin_gmm.yaml not found; skipped its AUC\n");
    return;
  }
  const auto shipped = GaussianMixture2D::load(cfg);
  const double auc_shipped = auc_of(shipped);
  std::printf("held-back ROC AUC, shipped config/skin_gmm.yaml:     %.4f\n", auc_shipped);
  EXPECT_GE(auc_shipped, 0.95);
  // The shipped file was made by train_skin_model with the same split and EM seed.
  EXPECT_NEAR(auc_shipped, auc_trained, 0.005);
}
