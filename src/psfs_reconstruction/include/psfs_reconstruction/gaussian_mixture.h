// K-component Gaussian mixture over normalised rg (thesis 4.2.1, skin model p(c|S) with K = 2
// after Caetano et al. 2002). Densities are per unit rg area (see color_space.h), so the
// skin classifier compares p(c|S) with the uniform non-skin density 1.
//
// Training uses OpenCV's EM (k-means initialisation, full covariances) with a fixed RNG seed,
// so the same data always gives the same model. Models are stored as YAML; loading validates
// everything (finite values, weights summing to 1, positive-definite covariances) because a
// bad model file would otherwise silently turn into NaN likelihood images.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace psfs {

struct GaussianComponent2D {
  double weight = 0.0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
};

// Thrown for invalid model parameters or unreadable/ill-formed model files.
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct GmmTrainingOptions {
  int components = 2;               // K; the thesis uses 2 for skin
  int max_iterations = 100;         // EM iterations (OpenCV default)
  double epsilon = 1e-6;            // EM stops when the log-likelihood changes by less (relative)
  unsigned long long seed = 12345;  // seeds cv::theRNG() for the k-means initialisation
  // Added to every covariance diagonal after EM (rg units^2): keeps a component that collapsed
  // onto a handful of identical training colours (the UCI set has many duplicates) from
  // becoming a spike; 1e-6 is (1/1000 rg)^2, far below the sensor noise in rg.
  double covariance_regularization = 1e-6;
};

class GaussianMixture2D {
 public:
  GaussianMixture2D() = default;
  // Validates (throws ModelError): K >= 1, finite values, weights > 0 summing to 1 (within
  // 1e-3; renormalised exactly), covariances symmetric positive definite.
  explicit GaussianMixture2D(std::vector<GaussianComponent2D> components);

  int size() const { return int(components_.size()); }
  bool empty() const { return components_.empty(); }
  const std::vector<GaussianComponent2D>& components() const { return components_; }

  // p(c) per unit rg area. Never NaN for finite c; 0 far from all components.
  double density(double r, double g) const;
  double density(const Eigen::Vector2d& c) const { return density(c.x(), c.y()); }
  // log p(c), accurate also where density() underflows.
  double logDensity(double r, double g) const;

  // Fits K components to the rows of `rg` (N x 2, double). Throws ModelError when there are
  // fewer samples than components or EM fails.
  static GaussianMixture2D train(const Eigen::MatrixX2d& rg,
                                 const GmmTrainingOptions& options = {});

  // YAML I/O. `header_comment` (may be multi-line) is written as leading '#' lines.
  void save(const std::string& path, const std::string& header_comment = "") const;
  std::string toYaml(const std::string& header_comment = "") const;
  static GaussianMixture2D load(const std::string& path);
  static GaussianMixture2D fromYaml(const std::string& text,
                                    const std::string& source = "<string>");

 private:
  struct Cached {
    Eigen::Matrix2d inverse;
    double log_norm = 0.0;  // log(w / (2 pi sqrt(det)))
  };
  std::vector<GaussianComponent2D> components_;
  std::vector<Cached> cached_;
};

}  // namespace psfs
