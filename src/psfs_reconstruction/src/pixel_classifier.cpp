#include "psfs_reconstruction/pixel_classifier.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>

#include <Eigen/LU>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "psfs_reconstruction/color_space.h"
#include "psfs_reconstruction/image_checks.h"
#include "classifier_kernels.h"
#include "cpu_dispatch.h"
#include "pixel_stage_host.h"

namespace psfs {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Priors are clamped into [kMinPrior, 1 - kMinPrior] so the odds ratios stay finite; a prior
// of exactly 0 or 1 would make every pixel certain regardless of the image anyway.
constexpr double kMinPrior = 1e-6;

double clampPrior(double p) { return std::min(1.0 - kMinPrior, std::max(kMinPrior, p)); }

void validatePriors(const ClassPriors& p) {
  if (!(p.foreground >= 0.0 && p.foreground <= 1.0))
    throw std::invalid_argument("pixel classifier: P(F) must be in [0, 1], got " +
                                std::to_string(p.foreground));
  if (!(p.skin >= 0.0 && p.skin <= 1.0))
    throw std::invalid_argument("pixel classifier: P(S) must be in [0, 1], got " +
                                std::to_string(p.skin));
}

void validateParams(const PixelClassifierParams& p) {
  auto unit = [](float v) { return v >= 0.0f && v <= 1.0f; };
  if (!unit(p.foreground_outlier) || !unit(p.skin_outlier))
    throw std::invalid_argument("pixel classifier: outlier probabilities must be in [0, 1]");
  if (!(p.shadow_chroma_radius >= 0.0f && std::isfinite(p.shadow_chroma_radius)))
    throw std::invalid_argument("pixel classifier: shadow_chroma_radius must be >= 0");
  if (!(p.shadow_min_intensity_ratio >= 0.0f &&
        p.shadow_max_intensity_ratio >= p.shadow_min_intensity_ratio &&
        std::isfinite(p.shadow_max_intensity_ratio)))
    throw std::invalid_argument(
        "pixel classifier: need 0 <= shadow_min_intensity_ratio <= shadow_max_intensity_ratio");
  if (!(p.min_chroma_intensity >= 0.0f && std::isfinite(p.min_chroma_intensity)))
    throw std::invalid_argument("pixel classifier: min_chroma_intensity must be >= 0");
  if (!(p.shadow_weight >= 0.0f && p.shadow_weight < 1.0f))
    throw std::invalid_argument("pixel classifier: shadow_weight must be in [0, 1)");
  if (!(p.gain_tolerance >= 0.0f && std::isfinite(p.gain_tolerance)))
    throw std::invalid_argument("pixel classifier: gain_tolerance must be >= 0");
  if (p.intensity_model && !(p.shadow_max_intensity_ratio > p.shadow_min_intensity_ratio))
    throw std::invalid_argument(
        "pixel classifier: the intensity model needs shadow_min_intensity_ratio < "
        "shadow_max_intensity_ratio");
}

std::uint8_t toByte(double p) {
  const double v = std::floor(p * 255.0 + 0.5);
  return std::uint8_t(v < 0.0 ? 0.0 : (v > 255.0 ? 255.0 : v));
}

struct RowStats {
  int dark = 0, saturated = 0, shadow = 0;
  int sum_foreground_bytes = 0;  // sum of channel 0 over the row
};

}  // namespace

ClassPriors ClassPriors::fromOccupancy(double hull_foreground, double hull_skin, int cameras) {
  if (cameras < 1) throw std::invalid_argument("ClassPriors: need >= 1 camera");
  if (!(hull_foreground > 0.0 && hull_foreground <= 1.0) || !(hull_skin >= 0.0 && hull_skin <= 1.0))
    throw std::invalid_argument("ClassPriors: occupancy ratios must be probabilities (P(H_F) > 0)");
  ClassPriors p;
  p.foreground = std::pow(hull_foreground, 1.0 / cameras);
  p.skin = std::pow(hull_skin, 1.0 / cameras) / p.foreground;
  if (p.skin > 1.0 + 1e-12)
    throw std::invalid_argument("ClassPriors: skin occupancy P(H) must not exceed P(H_F)");
  p.skin = std::min(1.0, p.skin);
  return p;
}

PixelClassifier::PixelClassifier(const GaussianMixture2D& skin, const PixelClassifierParams& params,
                                 const ClassPriors& priors)
    : skin_(skin), params_(params), priors_(priors) {
  if (skin_.empty()) throw std::invalid_argument("pixel classifier: empty skin model");
  validateParams(params_);
  validatePriors(priors_);
  rebuild();
}

void PixelClassifier::setParams(const PixelClassifierParams& params) {
  validateParams(params);
  params_ = params;
}

void PixelClassifier::setPriors(const ClassPriors& priors) {
  validatePriors(priors);
  priors_ = priors;
}

namespace {

detail::SkinKernelTerm gaussianTerm(const Eigen::Vector2d& mean, const Eigen::Matrix2d& covariance,
                                    double weight) {
  const Eigen::Matrix2d half_inv = 0.5 * covariance.inverse();
  detail::SkinKernelTerm t;
  t.mean_r = float(mean.x());
  t.mean_g = float(mean.y());
  t.a = float(half_inv(0, 0));
  t.b2 = float(2.0 * half_inv(0, 1));
  t.c = float(half_inv(1, 1));
  t.weight = float(weight / (2.0 * kPi * std::sqrt(covariance.determinant())));
  return t;
}

}  // namespace

std::vector<detail::SkinKernelTerm> skinKernelTerms(const GaussianMixture2D& skin) {
  std::vector<detail::SkinKernelTerm> terms;
  for (const auto& c : skin.components())
    terms.push_back(gaussianTerm(c.mean, c.covariance, c.weight));
  return terms;
}

detail::SkinKernelTerm clothingKernelTerm(const GaussianComponent2D& colour, double weight,
                                          const ClassPriors& priors) {
  const double pS = clampPrior(priors.skin);
  return gaussianTerm(colour.mean, colour.covariance, weight * (1.0 - pS) / pS);
}

pixel::PixelConstants pixelConstants(const PixelClassifierParams& params,
                                     const ClassPriors& priors) {
  pixel::PixelConstants k;
  const double pF = clampPrior(priors.foreground), pS = clampPrior(priors.skin);
  k.odds_bg = float((1.0 - pF) / pF);
  k.odds_skin = float((1.0 - pS) / pS);
  k.priorF = float(priors.foreground);
  k.priorS = float(priors.skin);
  k.outF = params.foreground_outlier * k.priorF;
  k.keepF = 1.0f - params.foreground_outlier;
  k.outS = params.skin_outlier * k.priorS;
  k.keepS = 1.0f - params.skin_outlier;
  k.shadow_r2 = params.shadow_suppression
                    ? params.shadow_chroma_radius * params.shadow_chroma_radius
                    : -1.0f;
  k.lo = params.shadow_min_intensity_ratio;
  k.hi = params.shadow_max_intensity_ratio;
  k.min_i = params.min_chroma_intensity;
  k.use_i = params.intensity_model ? 1.0f : 0.0f;
  k.gain = 1.0f;
  k.tol2 = params.gain_tolerance * params.gain_tolerance;
  k.keep_n = 256.0f * (1.0f - params.shadow_weight);
  k.band_u = params.intensity_model
                 ? 256.0f * params.shadow_weight /
                       (params.shadow_max_intensity_ratio - params.shadow_min_intensity_ratio)
                 : 0.0f;
  k.dark_skin = params.intensity_model ? k.outS : k.priorS;
  return k;
}

ClassifierKernelConstants kernelConstants(const PixelClassifier& classifier) {
  ClassifierKernelConstants c;
  const GaussianMixture2D* clothing = classifier.clothingModel();
  c.k = pixelConstants(classifier.params(), classifier.priors());
  if (clothing) {
    c.has_clothing = true;
    c.clothing = clothingKernelTerm(clothing->components()[0], classifier.clothingWeight(),
                                    classifier.priors());
  }
  return c;
}

bool gainCompensated(const PixelClassifierParams& params) {
  return params.intensity_model && params.gain_compensation;
}

pixel::GainConstants gainConstants(const PixelClassifierParams& params) {
  pixel::GainConstants g;
  // Background chroma: within twice the shadow cylinder (a shadow keeps the chroma, a person
  // mostly does not), so the mode is the light's gain even with half the view occluded.
  const float rad = 2.0f * std::max(params.shadow_chroma_radius, 0.01f);
  g.chroma_r2 = rad * rad;
  g.min_intensity = std::max(params.min_chroma_intensity, 1.0f);
  return g;
}

void PixelClassifier::rebuild() { skin_terms_ = skinKernelTerms(skin_); }

void PixelClassifier::setClothingColour(const ColourGaussian* colour, double weight) {
  if (!(weight >= 0.0 && std::isfinite(weight)))
    throw std::invalid_argument(
        "pixel classifier: the clothing colour's weight must be finite and >= 0");
  if (!colour || weight == 0.0) {
    clothing_ = GaussianMixture2D();
    clothing_weight_ = 0.0;
    return;
  }
  GaussianComponent2D c;
  c.weight = 1.0;
  c.mean = colour->mean;
  c.covariance = colour->covariance;
  try {
    clothing_ = GaussianMixture2D({c});
  } catch (const ModelError& e) {
    throw std::invalid_argument(std::string("pixel classifier: the clothing colour: ") + e.what());
  }
  clothing_weight_ = weight;
}

// ---- fast path ------------------------------------------------------------------------------

namespace {

// Scratch for one row: 8 float rows (10 KB at 320 px: stays in L1).
struct RowScratch {
  std::vector<float> f;
  explicit RowScratch(int w) : f(std::size_t(w) * 8) {}
};

// The row loops. Each is straight-line float code over contiguous arrays (selects, no
// calls) in a function of its own, because GCC only trusts `restrict` on parameters: with
// the no-alias guarantee and -fno-trapping-math every loop vectorises at -O3.

// Foreground term: background Gaussian, shadow cylinder, outlier model, dark-pixel rule.
PSFS_ALWAYS_INLINE void foregroundRow(const pixel::PixelConstants& constants, int w,
                                      const float* __restrict r, const float* __restrict g,
                                      const float* __restrict in, const float* __restrict mr,
                                      const float* __restrict mg, const float* __restrict mi,
                                      const float* __restrict sr, const float* __restrict sg,
                                      const float* __restrict vi, float* __restrict pf,
                                      float* __restrict dark, float* __restrict shadow) {
  const pixel::PixelConstants k = constants;  // a local copy stays in registers
  for (int x = 0; x < w; ++x) {
    const pixel::ForegroundTerm t =
        pixel::foregroundTerm(k, {r[x], g[x], in[x]}, mr[x], mg[x], mi[x], sr[x], sg[x], vi[x]);
    pf[x] = t.p;
    dark[x] = t.dark;
    shadow[x] = t.shadow;
  }
}

// Adds one skin GMM component's density to ps.
PSFS_ALWAYS_INLINE void skinComponentRow(const detail::SkinKernelTerm& t, int w,
                                         const float* __restrict r, const float* __restrict g,
                                         float* __restrict ps) {
  for (int x = 0; x < w; ++x) ps[x] += pixel::skinDensity(t, r[x], g[x]);
}

// P'(S|c), the product, and quantisation to the two interleaved output channels.
PSFS_ALWAYS_INLINE void outputRow(const pixel::PixelConstants& constants, int w,
                                  const float* __restrict pf, const float* __restrict ps,
                                  const float* __restrict pn, const float* __restrict dark,
                                  std::uint8_t* __restrict dst) {
  const pixel::PixelConstants k = constants;
  for (int x = 0; x < w; ++x) {
    const pixel::LikelihoodBytes b = pixel::likelihoodBytes(k, pf[x], ps[x], pn[x], dark[x]);
    dst[2 * x + 0] = b.foreground;
    dst[2 * x + 1] = b.skin;
  }
}

// Counts for the diagnostics. Integer reductions only: GCC may reorder those across vector
// lanes, while a float sum would be kept in source order (one add per element, serially).
PSFS_ALWAYS_INLINE RowStats rowStats(int w, const float* __restrict dark,
                                     const float* __restrict shadow,
                                     const std::uint8_t* __restrict rgb,
                                     const std::uint8_t* __restrict out) {
  int n_dark = 0, n_shadow = 0, n_sat = 0, sum_f = 0;
  for (int x = 0; x < w; ++x) {
    n_dark += int(dark[x]);
    n_shadow += int(shadow[x]);
  }
  for (int x = 0; x < w; ++x)
    n_sat += pixel::saturated(rgb[3 * x], rgb[3 * x + 1], rgb[3 * x + 2]);
  for (int x = 0; x < w; ++x) sum_f += out[2 * x];
  RowStats st;
  st.dark = n_dark;
  st.shadow = n_shadow;
  st.saturated = n_sat;
  st.sum_foreground_bytes = sum_f;
  return st;
}

// The unit of work of the OpenMP loop, compiled per instruction set (PSFS_TARGET_CLONES).
PSFS_TARGET_CLONES
RowStats classifyRow(const pixel::PixelConstants& k, const detail::SkinKernelTerm* terms, int K,
                     const detail::SkinKernelTerm* clothing, const std::uint8_t* src, int w,
                     const BackgroundPlanes& P, std::size_t o,
                     RowScratch& scratch, std::uint8_t* dst) {
  float* r = scratch.f.data();
  float* g = r + w;
  float* in = g + w;
  float* pf = in + w;
  float* ps = pf + w;
  float* dark = ps + w;
  float* shadow = dark + w;
  float* pn = shadow + w;
  kernels::rgbRowToRgI(src, w, r, g, in);
  foregroundRow(k, w, r, g, in, P.mean_r + o, P.mean_g + o, P.mean_intensity + o, P.scale_r + o,
                P.scale_g + o, P.var_intensity + o, pf, dark, shadow);
  std::fill(ps, ps + w, 0.0f);
  for (int j = 0; j < K; ++j) skinComponentRow(terms[j], w, r, g, ps);
  std::fill(pn, pn + w, 0.0f);
  if (clothing) skinComponentRow(*clothing, w, r, g, pn);
  outputRow(k, w, pf, ps, pn, dark, dst);
  return rowStats(w, dark, shadow, src, dst);
}

}  // namespace

void PixelClassifier::classifyRows(const cv::Mat* rgb, const BackgroundModel* const* bg,
                                   cv::Mat* out, ClassificationStats* stats, int cameras,
                                   int num_threads) const {
  std::vector<int> row_start(cameras + 1, 0);
  int max_width = 0;
  for (int c = 0; c < cameras; ++c) {
    row_start[c + 1] = row_start[c] + rgb[c].rows;
    max_width = std::max(max_width, rgb[c].cols);
  }
  const int total_rows = row_start[cameras];
  std::vector<RowStats> row_stats(total_rows);

  const ClassifierKernelConstants kc = kernelConstants(*this);
  const pixel::PixelConstants& k = kc.k;
  const detail::SkinKernelTerm* clothing = kc.clothingTerm();
  // Per camera: its gain this frame.
  std::vector<pixel::PixelConstants> ks(cameras, k);
  std::vector<double> gains(cameras, 1.0);
  // The views' gains side by side (a histogram of a quarter of the pixels each, divisions per
  // pixel: a tenth of the classifier's time on one thread). An input error is rethrown here,
  // the first camera's, as the serial loop would.
  std::vector<std::exception_ptr> errors(cameras);
#ifdef _OPENMP
#pragma omp parallel for num_threads(resolveThreads(num_threads)) schedule(dynamic, 1)
#endif
  for (int c = 0; c < cameras; ++c) {
    try {
      gains[c] = estimateGain(rgb[c], *bg[c]);
    } catch (...) {
      errors[c] = std::current_exception();
    }
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  for (int c = 0; c < cameras; ++c) ks[c].gain = float(gains[c]);
  const detail::SkinKernelTerm* terms = skin_terms_.data();
  const int K = int(skin_terms_.size());

#ifdef _OPENMP
  const int nt = resolveThreads(num_threads);
#pragma omp parallel num_threads(nt)
#endif
  {
    RowScratch scratch(max_width);
    // Static split of all rows: each thread gets a contiguous half of the frame set. (A
    // dynamic schedule measured no better, also with other processes on the cores.)
#ifdef _OPENMP
#pragma omp for schedule(static)
#endif
    for (int row = 0; row < total_rows; ++row) {
      int cam = 0;
      while (row >= row_start[cam + 1]) ++cam;
      const int y = row - row_start[cam];
      const int w = rgb[cam].cols;
      row_stats[row] =
          classifyRow(ks[cam], terms, K, clothing, rgb[cam].ptr<std::uint8_t>(y), w,
                      bg[cam]->planes(), std::size_t(y) * std::size_t(w), scratch,
                      out[cam].ptr<std::uint8_t>(y));
    }
  }

  for (int c = 0; c < cameras; ++c) {
    ClassificationStats s;
    s.pixels = rgb[c].rows * rgb[c].cols;
    double sum = 0.0;
    for (int row = row_start[c]; row < row_start[c + 1]; ++row) {
      s.dark_pixels += row_stats[row].dark;
      s.saturated_pixels += row_stats[row].saturated;
      s.shadow_pixels += row_stats[row].shadow;
      sum += row_stats[row].sum_foreground_bytes;
    }
    s.mean_foreground = s.pixels ? sum / (255.0 * s.pixels) : 0.0;
    s.gain = gains[c];
    stats[c] = s;
  }
}

double PixelClassifier::estimateGain(const cv::Mat& rgb, const BackgroundModel& background) const {
  if (!gainCompensated(params_)) return 1.0;
  checkRgb8(rgb, background.width(), background.height(), "pixel classifier (gain)");
  const BackgroundPlanes P = background.planes();
  const pixel::GainConstants c = gainConstants(params_);
  std::vector<int> hist(pixel::kGainBins, 0);
  int n = 0;
  for (int y = 0; y < rgb.rows; y += 2) {
    const std::uint8_t* src = rgb.ptr<std::uint8_t>(y);
    const std::size_t row = std::size_t(y) * std::size_t(rgb.cols);
    for (int x = 0; x < rgb.cols; x += 2) {
      const int bin = pixel::gainBin(c, src[3 * x], src[3 * x + 1], src[3 * x + 2],
                                     P.mean_r[row + x], P.mean_g[row + x],
                                     P.mean_intensity[row + x]);
      if (bin < 0) continue;
      ++hist[bin];
      ++n;
    }
  }
  if (n < pixel::kGainMinSamples) return 1.0;
  // Peaks over 5 bins (+-0.8 %, about the noise of a ratio): the lit background is one sharp
  // peak, a person's background-coloured clothes spread over many ratios, and a cast shadow
  // forms a second, darker peak that may be as large. Shadows only darken: the gain is the
  // brightest peak that holds at least half as many pixels as the largest.
  std::vector<int> window(pixel::kGainBins, 0);
  int max_count = 0;
  for (int b = 0; b < pixel::kGainBins; ++b) {
    window[b] = pixel::gainWindow(hist.data(), b);
    max_count = std::max(max_count, window[b]);
  }
  int candidate = pixel::kGainBins - 1;
  while (candidate > 0 && !pixel::gainCandidate(window[candidate], max_count)) --candidate;
  return pixel::gainPeakOf(window.data(), candidate, n).gain;  // at the top of its peak
}

ClassificationStats PixelClassifier::classify(const cv::Mat& rgb, const BackgroundModel& background,
                                              cv::Mat& likelihood, int num_threads) const {
  if (!background.ready())
    throw std::invalid_argument("pixel classifier: background model not learned yet (" +
                                std::to_string(background.learnedFrames()) + " frames)");
  checkRgb8(rgb, background.width(), background.height(), "pixel classifier");
  likelihood.create(rgb.rows, rgb.cols, CV_8UC2);
  const BackgroundModel* bg = &background;
  ClassificationStats stats;
  classifyRows(&rgb, &bg, &likelihood, &stats, 1, num_threads);
  return stats;
}

std::vector<ClassificationStats> PixelClassifier::classify(
    const std::vector<cv::Mat>& rgb, const std::vector<const BackgroundModel*>& backgrounds,
    std::vector<cv::Mat>& likelihoods, int num_threads) const {
  if (rgb.size() != backgrounds.size())
    throw std::invalid_argument("pixel classifier: " + std::to_string(rgb.size()) + " images but " +
                                std::to_string(backgrounds.size()) + " background models");
  for (std::size_t c = 0; c < rgb.size(); ++c) {
    const std::string cam = "cam" + std::to_string(c);
    if (!backgrounds[c]) throw std::invalid_argument(cam + ": no background model");
    if (!backgrounds[c]->ready())
      throw std::invalid_argument(cam + ": background model not learned yet (" +
                                  std::to_string(backgrounds[c]->learnedFrames()) + " frames)");
    checkRgb8(rgb[c], backgrounds[c]->width(), backgrounds[c]->height(), cam);
  }
  likelihoods.resize(rgb.size());
  for (std::size_t c = 0; c < rgb.size(); ++c)
    likelihoods[c].create(rgb[c].rows, rgb[c].cols, CV_8UC2);
  std::vector<ClassificationStats> stats(rgb.size());
  if (!rgb.empty())
    classifyRows(rgb.data(), backgrounds.data(), likelihoods.data(), stats.data(), int(rgb.size()),
                 num_threads);
  return stats;
}

// ---- reference path --------------------------------------------------------------------------

void PixelClassifier::classifyPixel(std::uint8_t R, std::uint8_t G, std::uint8_t B,
                                    const BackgroundModel& background, int x, int y,
                                    double* p_foreground, double* p_skin,
                                    bool* suppressed_shadow, double gain) const {
  const NormalizedRgI c = toNormalizedRgI(R, G, B);
  const double PF = priors_.foreground, PS = priors_.skin;
  const double pF = clampPrior(PF), pS = clampPrior(PS);
  const double eF = params_.foreground_outlier, eS = params_.skin_outlier;
  const std::size_t i = std::size_t(y) * background.width() + x;
  const BackgroundPlanes P = background.planes();
  const double mi = gain * P.mean_intensity[i];
  // The shadow/highlight band of I / (g I_bg): the intensity model's uniform part and the
  // shadow cylinder's intensity test.
  const double lo = params_.shadow_min_intensity_ratio, hi = params_.shadow_max_intensity_ratio;
  const bool in_band = c.intensity >= lo * mi && c.intensity <= hi * mi;
  // 256 p(I|notF) of the intensity model (pixel_classifier.h).
  auto intensityTerm = [&]() {
    const double w = params_.shadow_weight, tol = params_.gain_tolerance;
    const double var = P.var_intensity[i] + tol * tol * mi * mi;
    const double di = c.intensity - mi;
    const double n = std::exp(-0.5 * di * di / var) / std::sqrt(2.0 * kPi * var);
    return 256.0 * ((1.0 - w) * n + (in_band ? w / ((hi - lo) * std::max(mi, 1.0)) : 0.0));
  };
  bool shadow = false;
  double f, s;
  if (c.intensity < params_.min_chroma_intensity) {
    if (params_.intensity_model) {
      const double p_bg = intensityTerm();  // the chroma is noise: rg densities cancel
      f = eF * PF + (1.0 - eF) * pF / (pF + p_bg * (1.0 - pF));
      s = eS * PS;  // near black: not skin (a dark sleeve is foreground, and must not be skin)
    } else {
      f = PF;
      s = PS;
    }
  } else {
    double p_bg = background.density(x, y, c.r, c.g);
    if (params_.intensity_model) p_bg *= intensityTerm();
    double p_fc = pF / (pF + p_bg * (1.0 - pF));
    if (params_.shadow_suppression) {
      const double dr = c.r - P.mean_r[i], dg = c.g - P.mean_g[i];
      const double rad = params_.shadow_chroma_radius;
      const bool inside = dr * dr + dg * dg < rad * rad && in_band;
      shadow = inside && p_fc > 0.5;  // the cylinder changed the call
      if (inside) p_fc = 0.0;
    }
    const double p_skin = skin_.density(c.r, c.g);
    // p(c|notS) = 1 + weight q(c), q the clothing colour's Gaussian
    const double p_notskin =
        clothing_.empty() ? 1.0 : 1.0 + clothing_weight_ * clothing_.density(c.r, c.g);
    const double p_sc = p_skin * pS / (p_skin * pS + (1.0 - pS) * p_notskin);
    f = eF * PF + (1.0 - eF) * p_fc;
    s = eS * PS + (1.0 - eS) * p_sc;
  }
  if (p_foreground) *p_foreground = f;
  if (p_skin) *p_skin = s;
  if (suppressed_shadow) *suppressed_shadow = shadow;
}

ClassificationStats PixelClassifier::classifyReference(const cv::Mat& rgb,
                                                       const BackgroundModel& background,
                                                       cv::Mat& likelihood) const {
  if (!background.ready())
    throw std::invalid_argument("pixel classifier: background model not learned yet");
  checkRgb8(rgb, background.width(), background.height(), "pixel classifier (reference)");
  likelihood.create(rgb.rows, rgb.cols, CV_8UC2);
  ClassificationStats st;
  st.pixels = rgb.rows * rgb.cols;
  st.gain = estimateGain(rgb, background);
  double sum = 0.0;
  for (int y = 0; y < rgb.rows; ++y) {
    const std::uint8_t* src = rgb.ptr<std::uint8_t>(y);
    std::uint8_t* dst = likelihood.ptr<std::uint8_t>(y);
    for (int x = 0; x < rgb.cols; ++x) {
      const std::uint8_t R = src[3 * x], G = src[3 * x + 1], B = src[3 * x + 2];
      double f, s;
      bool shadow;
      classifyPixel(R, G, B, background, x, y, &f, &s, &shadow, st.gain);
      dst[2 * x] = toByte(f);
      dst[2 * x + 1] = toByte(f * s);
      st.dark_pixels += toNormalizedRgI(R, G, B).intensity < params_.min_chroma_intensity;
      st.saturated_pixels += (R == 255 || G == 255 || B == 255);
      st.shadow_pixels += shadow;
      sum += dst[2 * x];
    }
  }
  st.mean_foreground = st.pixels ? sum / (255.0 * st.pixels) : 0.0;
  return st;
}

}  // namespace psfs
