#include "psfs_reconstruction/gaussian_mixture.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include <Eigen/LU>
#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>
#include <yaml-cpp/yaml.h>

namespace psfs {
namespace {

constexpr double kTwoPi = 6.283185307179586476925;
constexpr int kYamlVersion = 1;

bool finite(const Eigen::Vector2d& v) { return std::isfinite(v.x()) && std::isfinite(v.y()); }
bool finite(const Eigen::Matrix2d& m) {
  return std::isfinite(m(0, 0)) && std::isfinite(m(0, 1)) && std::isfinite(m(1, 0)) &&
         std::isfinite(m(1, 1));
}

std::string fmt(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.10g", v);
  return buf;
}

}  // namespace

GaussianMixture2D::GaussianMixture2D(std::vector<GaussianComponent2D> components)
    : components_(std::move(components)) {
  if (components_.empty()) throw ModelError("Gaussian mixture: no components");
  double sum = 0.0;
  for (std::size_t k = 0; k < components_.size(); ++k) {
    const auto& c = components_[k];
    const std::string where = "Gaussian mixture component " + std::to_string(k) + ": ";
    if (!std::isfinite(c.weight) || c.weight <= 0.0)
      throw ModelError(where + "weight must be finite and > 0 (got " + fmt(c.weight) + ")");
    if (!finite(c.mean)) throw ModelError(where + "mean is not finite");
    if (!finite(c.covariance)) throw ModelError(where + "covariance is not finite");
    const auto& S = c.covariance;
    if (std::abs(S(0, 1) - S(1, 0)) > 1e-9 * (std::abs(S(0, 0)) + std::abs(S(1, 1))))
      throw ModelError(where + "covariance is not symmetric");
    const double det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    if (!(S(0, 0) > 0.0) || !(S(1, 1) > 0.0) || !(det > 0.0))
      throw ModelError(where + "covariance is not positive definite (var_r " + fmt(S(0, 0)) +
                       ", var_g " + fmt(S(1, 1)) + ", det " + fmt(det) + ")");
    sum += c.weight;
  }
  if (std::abs(sum - 1.0) > 1e-3)
    throw ModelError("Gaussian mixture: weights sum to " + fmt(sum) + ", expected 1");
  cached_.resize(components_.size());
  for (std::size_t k = 0; k < components_.size(); ++k) {
    auto& c = components_[k];
    c.weight /= sum;  // exact normalisation after the tolerance check
    c.covariance(1, 0) = c.covariance(0, 1);
    const double det = c.covariance.determinant();
    cached_[k].inverse = c.covariance.inverse();
    cached_[k].log_norm = std::log(c.weight) - std::log(kTwoPi * std::sqrt(det));
  }
}

double GaussianMixture2D::logDensity(double r, double g) const {
  if (components_.empty()) return -std::numeric_limits<double>::infinity();
  // log-sum-exp so far-away colours give a finite log density instead of log(0).
  double terms[16];
  std::vector<double> heap;
  double* t = terms;
  if (components_.size() > 16) {
    heap.resize(components_.size());
    t = heap.data();
  }
  double best = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < components_.size(); ++k) {
    const Eigen::Vector2d d(r - components_[k].mean.x(), g - components_[k].mean.y());
    t[k] = cached_[k].log_norm - 0.5 * d.dot(cached_[k].inverse * d);
    best = std::max(best, t[k]);
  }
  if (!std::isfinite(best)) return best;
  double s = 0.0;
  for (std::size_t k = 0; k < components_.size(); ++k) s += std::exp(t[k] - best);
  return best + std::log(s);
}

double GaussianMixture2D::density(double r, double g) const {
  double p = 0.0;
  for (std::size_t k = 0; k < components_.size(); ++k) {
    const Eigen::Vector2d d(r - components_[k].mean.x(), g - components_[k].mean.y());
    p += std::exp(cached_[k].log_norm - 0.5 * d.dot(cached_[k].inverse * d));
  }
  return p;
}

GaussianMixture2D GaussianMixture2D::train(const Eigen::MatrixX2d& rg,
                                           const GmmTrainingOptions& options) {
  const int K = options.components;
  if (K < 1) throw ModelError("GMM training: components must be >= 1");
  if (rg.rows() < 2 * K)
    throw ModelError("GMM training: " + std::to_string(rg.rows()) + " samples for " +
                     std::to_string(K) + " components");
  if (!rg.allFinite()) throw ModelError("GMM training: samples contain non-finite values");

  cv::Mat samples(int(rg.rows()), 2, CV_64F);
  for (int i = 0; i < samples.rows; ++i) {
    samples.at<double>(i, 0) = rg(i, 0);
    samples.at<double>(i, 1) = rg(i, 1);
  }
  auto em = cv::ml::EM::create();
  em->setClustersNumber(K);
  em->setCovarianceMatrixType(cv::ml::EM::COV_MAT_GENERIC);
  em->setTermCriteria(cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS,
                                       options.max_iterations, options.epsilon));
  // EM initialises with k-means on cv::theRNG() of this thread: seeding it makes training
  // deterministic.
  cv::theRNG().state = options.seed;
  bool ok = false;
  try {
    ok = em->trainEM(samples);
  } catch (const cv::Exception& e) {
    throw ModelError(std::string("GMM training: OpenCV EM failed: ") + e.what());
  }
  if (!ok) throw ModelError("GMM training: OpenCV EM did not converge");

  const cv::Mat weights = em->getWeights();
  const cv::Mat means = em->getMeans();
  std::vector<cv::Mat> covs;
  em->getCovs(covs);
  std::vector<GaussianComponent2D> comps(K);
  for (int k = 0; k < K; ++k) {
    comps[k].weight = weights.at<double>(0, k);
    comps[k].mean = Eigen::Vector2d(means.at<double>(k, 0), means.at<double>(k, 1));
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) comps[k].covariance(i, j) = covs[k].at<double>(i, j);
    comps[k].covariance = 0.5 * (comps[k].covariance + comps[k].covariance.transpose()).eval();
    comps[k].covariance.diagonal().array() += options.covariance_regularization;
  }
  // Order components by weight (largest first) so saved models are stable and readable.
  std::sort(comps.begin(), comps.end(),
            [](const GaussianComponent2D& a, const GaussianComponent2D& b) {
              return a.weight > b.weight;
            });
  return GaussianMixture2D(std::move(comps));
}

std::string GaussianMixture2D::toYaml(const std::string& header_comment) const {
  std::ostringstream os;
  if (!header_comment.empty()) {
    std::istringstream lines(header_comment);
    std::string line;
    while (std::getline(lines, line)) os << "# " << line << "\n";
  }
  os << "type: gaussian_mixture_2d\n"
     << "version: " << kYamlVersion << "\n"
     << "space: normalized_rg  # r = R/(R+G+B), g = G/(R+G+B); density per unit rg area\n"
     << "components:\n";
  for (const auto& c : components_) {
    os << "  - weight: " << fmt(c.weight) << "\n"
       << "    mean: [" << fmt(c.mean.x()) << ", " << fmt(c.mean.y()) << "]  # r, g\n"
       << "    covariance: [[" << fmt(c.covariance(0, 0)) << ", " << fmt(c.covariance(0, 1))
       << "], [" << fmt(c.covariance(1, 0)) << ", " << fmt(c.covariance(1, 1)) << "]]\n";
  }
  return os.str();
}

void GaussianMixture2D::save(const std::string& path, const std::string& header_comment) const {
  std::ofstream f(path);
  if (!f) throw ModelError("cannot write Gaussian mixture to '" + path + "'");
  f << toYaml(header_comment);
  if (!f) throw ModelError("error writing Gaussian mixture to '" + path + "'");
}

GaussianMixture2D GaussianMixture2D::fromYaml(const std::string& text, const std::string& source) {
  const std::string where = "Gaussian mixture '" + source + "': ";
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) throw ModelError(where + "not a YAML map");
    if (root["type"] && root["type"].as<std::string>() != "gaussian_mixture_2d")
      throw ModelError(where + "type is '" + root["type"].as<std::string>() +
                       "', expected gaussian_mixture_2d");
    if (root["version"] && root["version"].as<int>() != kYamlVersion)
      throw ModelError(where + "unsupported version " + root["version"].as<std::string>());
    if (root["space"] && root["space"].as<std::string>() != "normalized_rg")
      throw ModelError(where + "space is '" + root["space"].as<std::string>() +
                       "', expected normalized_rg");
    const YAML::Node list = root["components"];
    if (!list || !list.IsSequence() || list.size() == 0)
      throw ModelError(where + "missing or empty 'components' list");
    std::vector<GaussianComponent2D> comps;
    for (std::size_t k = 0; k < list.size(); ++k) {
      const YAML::Node n = list[k];
      const std::string cw = where + "component " + std::to_string(k) + ": ";
      if (!n["weight"] || !n["mean"] || !n["covariance"])
        throw ModelError(cw + "needs weight, mean and covariance");
      GaussianComponent2D c;
      c.weight = n["weight"].as<double>();
      const auto m = n["mean"].as<std::vector<double>>();
      if (m.size() != 2) throw ModelError(cw + "mean must have 2 entries (r, g)");
      c.mean = Eigen::Vector2d(m[0], m[1]);
      const YAML::Node cov = n["covariance"];
      if (!cov.IsSequence() || cov.size() != 2)
        throw ModelError(cw + "covariance must be [[rr, rg], [gr, gg]]");
      for (int i = 0; i < 2; ++i) {
        const auto row = cov[i].as<std::vector<double>>();
        if (row.size() != 2) throw ModelError(cw + "covariance must be [[rr, rg], [gr, gg]]");
        c.covariance(i, 0) = row[0];
        c.covariance(i, 1) = row[1];
      }
      comps.push_back(c);
    }
    try {
      return GaussianMixture2D(std::move(comps));
    } catch (const ModelError& e) {
      throw ModelError(where + e.what());
    }
  } catch (const YAML::Exception& e) {
    throw ModelError(where + "YAML error: " + e.what());
  }
}

GaussianMixture2D GaussianMixture2D::load(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw ModelError("cannot open Gaussian mixture file '" + path + "'");
  std::stringstream ss;
  ss << f.rdbuf();
  return fromYaml(ss.str(), path);
}

}  // namespace psfs
