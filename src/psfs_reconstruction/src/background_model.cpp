#include "psfs_reconstruction/background_model.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "psfs_reconstruction/image_checks.h"
#include "classifier_kernels.h"
#include "cpu_dispatch.h"
#include "pixel_arithmetic.h"

namespace psfs {
namespace {

constexpr char kMagic[8] = {'P', 'S', 'F', 'S', 'B', 'G', 'M', '1'};
constexpr std::uint32_t kFormatVersion = 2;
constexpr std::uint32_t kFormatVersionWithoutFilter = 1;
constexpr std::size_t kFilterField = 16;  // bytes of the image filter's name (v2), NUL-padded
constexpr double kPi = 3.14159265358979323846;

struct FileHeader {
  char magic[8];
  std::uint32_t version;
  std::int32_t width, height, frames;
  std::int32_t learning_frames;
  float learning_rate, min_sigma_rg, min_sigma_intensity;
};
static_assert(sizeof(FileHeader) == 40, "FileHeader must have no padding");

// Unbiased sample variance from the learning sums of n frames (sum s, sum of squares s2); 0 for
// fewer than 2 frames.
double sampleVariance(double s, double s2, double n) {
  return n > 1 ? std::max(0.0, (s2 - s * s / n) / (n - 1.0)) : 0.0;
}

void validateParams(const BackgroundModelParams& p) {
  if (p.learning_frames < 2)
    throw std::invalid_argument("background model: learning_frames must be >= 2");
  if (!(p.learning_rate >= 0.0f && p.learning_rate <= 1.0f))
    throw std::invalid_argument("background model: learning_rate must be in [0, 1]");
  if (p.image_filter.empty() || p.image_filter.size() >= kFilterField ||
      !std::all_of(p.image_filter.begin(), p.image_filter.end(),
                   [](char c) { return c >= 0x20 && c < 0x7f; }))
    throw std::invalid_argument("background model: image_filter must be 1-" +
                                std::to_string(kFilterField - 1) + " printable characters");
  if (!(p.min_sigma_rg > 0.0f && std::isfinite(p.min_sigma_rg)))
    throw std::invalid_argument("background model: min_sigma_rg must be > 0");
  if (!(p.min_sigma_intensity > 0.0f && std::isfinite(p.min_sigma_intensity)))
    throw std::invalid_argument("background model: min_sigma_intensity must be > 0");
  if (!(p.learning_change_sigmas > 0.0f && std::isfinite(p.learning_change_sigmas)))
    throw std::invalid_argument("background model: learning_change_sigmas must be > 0");
  if (!(p.learning_change_fraction > 0.0f && p.learning_change_fraction <= 1.0f))
    throw std::invalid_argument("background model: learning_change_fraction must lie in (0, 1]");
  if (p.min_learning_frames < 2)
    throw std::invalid_argument("background model: min_learning_frames must be >= 2");
}

PSFS_ALWAYS_INLINE void updateRowParams(int w, const float* __restrict r, const float* __restrict g,
                                        const float* __restrict in, const float* __restrict k,
                                        float floor_rg, float floor_i, float* __restrict mr,
                                        float* __restrict mg, float* __restrict mi,
                                        float* __restrict vr, float* __restrict vg,
                                        float* __restrict vi, float* __restrict sr,
                                        float* __restrict sg) {
  for (int x = 0; x < w; ++x)
    pixel::updateBackgroundPixel({r[x], g[x], in[x]}, k[x], floor_rg, floor_i, mr[x], mg[x], mi[x],
                                 vr[x], vg[x], vi[x], sr[x], sg[x]);
}

// One row of the selective update. A function of its own so the restrict parameters let GCC
// vectorise it, compiled per instruction set (see classifier_kernels.h). `buf` is scratch of
// 4 * w floats.
PSFS_TARGET_CLONES
void updateRow(int w, const std::uint8_t* __restrict rgb, const std::uint8_t* __restrict mask,
               float alpha, float floor_rg, float floor_i, float* __restrict buf,
               float* __restrict mr, float* __restrict mg, float* __restrict mi,
               float* __restrict vr, float* __restrict vg, float* __restrict vi,
               float* __restrict sr, float* __restrict sg) {
  float* __restrict r = buf;
  float* __restrict g = buf + w;
  float* __restrict in = buf + 2 * w;
  float* __restrict k = buf + 3 * w;
  kernels::rgbRowToRgI(rgb, w, r, g, in);
  if (mask) {
    for (int x = 0; x < w; ++x) k[x] = pixel::updateWeight(mask[x], alpha);  // (1 - f) alpha
  } else {
    for (int x = 0; x < w; ++x) k[x] = alpha;
  }
  updateRowParams(w, r, g, in, k, floor_rg, floor_i, mr, mg, mi, vr, vg, vi, sr, sg);
}

bool littleEndianHost() {
  const std::uint16_t one = 1;
  std::uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

}  // namespace

BackgroundModel::BackgroundModel(int width, int height, const BackgroundModelParams& params)
    : width_(width), height_(height), params_(params) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("background model: size must be positive, got " +
                                std::to_string(width) + "x" + std::to_string(height));
  validateParams(params);
  const std::size_t n = std::size_t(width) * std::size_t(height);
  for (auto* v : {&mean_r_, &mean_g_, &mean_i_, &var_r_, &var_g_, &var_i_, &scale_r_, &scale_g_})
    v->assign(n, 0.0f);
  for (auto& s : sum_) s.assign(n, 0.0);
}

void BackgroundModel::setParams(const BackgroundModelParams& params) {
  validateParams(params);
  params_ = params;
}

void BackgroundModel::addLearningFrame(const cv::Mat& rgb) {
  if (width_ == 0) throw std::logic_error("background model: not initialised (size 0)");
  if (ready_) throw std::logic_error("background model: learning already finished");
  checkRgb8(rgb, width_, height_, "background learning frame");
  std::vector<float> r(width_), g(width_), in(width_);
  for (int y = 0; y < height_; ++y) {
    kernels::rgbRowToRgI(rgb.ptr<std::uint8_t>(y), width_, r.data(), g.data(), in.data());
    const std::size_t o = std::size_t(y) * width_;
    for (int x = 0; x < width_; ++x) {
      sum_[0][o + x] += r[x];
      sum_[1][o + x] += g[x];
      sum_[2][o + x] += in[x];
      sum_[3][o + x] += double(r[x]) * r[x];
      sum_[4][o + x] += double(g[x]) * g[x];
      sum_[5][o + x] += double(in[x]) * in[x];
    }
  }
  ++frames_;
  if (frames_ >= params_.learning_frames) finalizeLearning();
}

double BackgroundModel::changedFraction(const cv::Mat& rgb) const {
  if (width_ == 0) throw std::logic_error("background model: not initialised (size 0)");
  if (ready_ || frames_ < 1)
    throw std::logic_error("background model: changedFraction needs a model that is learning");
  checkRgb8(rgb, width_, height_, "background learning frame");
  const double n = frames_;
  const double k2 = double(params_.learning_change_sigmas) * params_.learning_change_sigmas;
  // Sigmas: the learned frames' own spread, at least twice the floors (a few frames give a
  // poor variance estimate).
  const double floor_rg2 = 4.0 * params_.min_sigma_rg * params_.min_sigma_rg;
  const double floor_i2 = 4.0 * params_.min_sigma_intensity * params_.min_sigma_intensity;
  // rg of dark pixels is mostly noise (a 2-level error at I = 10 moves r by 0.07).
  constexpr float kMinChromaIntensity = 40.0f;
  auto var = [n](double s, double s2) { return sampleVariance(s, s2, n); };
  std::vector<float> r(width_), g(width_), in(width_);
  // This camera's sensor noise, from the frame itself: the median absolute intensity
  // difference to the learned mean is noise-dominated while less than half of the image
  // changed (a person fills 5-40 %). With one or a few learned frames the per-pixel spread
  // says nothing yet, and fixed floors suit only the noise they were tuned for: here a
  // noisier or darker camera (vignetting) would see "changes" in every frame and never learn.
  std::vector<float> residual(std::size_t(width_) * height_);
  for (int y = 0; y < height_; ++y) {
    kernels::rgbRowToRgI(rgb.ptr<std::uint8_t>(y), width_, r.data(), g.data(), in.data());
    const std::size_t o = std::size_t(y) * width_;
    for (int x = 0; x < width_; ++x) residual[o + x] = std::abs(in[x] - float(sum_[2][o + x] / n));
  }
  auto mid = residual.begin() + residual.size() / 2;
  std::nth_element(residual.begin(), mid, residual.end());
  // 1.4826 MAD = sigma of a normal; the difference to a mean of n frames has (1 + 1/n) times
  // the variance of one frame, so the estimate below is one frame's intensity noise.
  const double noise_i2 = std::pow(1.4826 * double(*mid), 2) / (1.0 + 1.0 / n);
  // Per pixel, the variance of (frame - mean of n): the noise (learned spread, at least the
  // camera's noise and twice the floors) times (1 + 1/n). rg noise from intensity noise:
  // r = R / 3I moves by about 0.47 sigma_I / I for a grey pixel.
  const double spread = 1.0 + 1.0 / n;
  std::size_t changed = 0;
  for (int y = 0; y < height_; ++y) {
    kernels::rgbRowToRgI(rgb.ptr<std::uint8_t>(y), width_, r.data(), g.data(), in.data());
    const std::size_t o = std::size_t(y) * width_;
    for (int x = 0; x < width_; ++x) {
      const std::size_t i = o + x;
      const double mi = sum_[2][i] / n, di = in[x] - mi;
      bool c = di * di >
               k2 * spread * std::max({floor_i2, noise_i2, var(sum_[2][i], sum_[5][i])});
      if (!c && in[x] >= kMinChromaIntensity && mi >= kMinChromaIntensity) {
        const double dr = r[x] - sum_[0][i] / n, dg = g[x] - sum_[1][i] / n;
        const double noise_rg2 = 0.22 * noise_i2 / (mi * mi);
        c = dr * dr > k2 * spread * std::max({floor_rg2, noise_rg2, var(sum_[0][i], sum_[3][i])}) ||
            dg * dg > k2 * spread * std::max({floor_rg2, noise_rg2, var(sum_[1][i], sum_[4][i])});
      }
      changed += c;
    }
  }
  return double(changed) / (double(width_) * height_);
}

void BackgroundModel::finishLearning() {
  if (ready_) return;
  if (frames_ < 2)
    throw std::logic_error("background model: need >= 2 learning frames, have " +
                           std::to_string(frames_));
  finalizeLearning();
}

void BackgroundModel::finalizeLearning() {
  const double n = frames_;
  const float fr = params_.min_sigma_rg * params_.min_sigma_rg;
  const float fi = params_.min_sigma_intensity * params_.min_sigma_intensity;
  auto var = [n](double s, double s2) { return sampleVariance(s, s2, n); };
  for (std::size_t i = 0; i < mean_r_.size(); ++i) {
    mean_r_[i] = float(sum_[0][i] / n);
    mean_g_[i] = float(sum_[1][i] / n);
    mean_i_[i] = float(sum_[2][i] / n);
    var_r_[i] = std::max(fr, float(var(sum_[0][i], sum_[3][i])));  // unbiased sample variance
    var_g_[i] = std::max(fr, float(var(sum_[1][i], sum_[4][i])));
    var_i_[i] = std::max(fi, float(var(sum_[2][i], sum_[5][i])));
  }
  for (auto& s : sum_) std::vector<double>().swap(s);  // accumulators are not needed any more
  refreshScales(0, mean_r_.size());
  ready_ = true;
}

void BackgroundModel::refreshScales(std::size_t begin, std::size_t end) {
  for (std::size_t i = begin; i < end; ++i) {
    scale_r_[i] = pixel::backgroundScale(var_r_[i]);
    scale_g_[i] = pixel::backgroundScale(var_g_[i]);
  }
}

void BackgroundModel::update(const cv::Mat& rgb, const cv::Mat& foreground_mask, int num_threads) {
  if (!ready_)
    throw std::logic_error("background model: update before learning finished (" +
                           std::to_string(frames_) + "/" + std::to_string(params_.learning_frames) +
                           " frames)");
  checkRgb8(rgb, width_, height_, "background update");
  const bool has_mask = !foreground_mask.empty();
  if (has_mask) checkMask(foreground_mask, width_, height_, "background update");

  const float alpha = params_.learning_rate;
  const float fr = params_.min_sigma_rg * params_.min_sigma_rg;
  const float fi = params_.min_sigma_intensity * params_.min_sigma_intensity;
  // Rows are independent; the per-row scratch lives on each thread.
#ifdef _OPENMP
  const int nt = resolveThreads(num_threads);
#pragma omp parallel num_threads(nt)
#endif
  {
    std::vector<float> buf(std::size_t(width_) * 4);
#ifdef _OPENMP
#pragma omp for schedule(static)
#endif
    for (int y = 0; y < height_; ++y) {
      const std::size_t o = std::size_t(y) * width_;
      updateRow(width_, rgb.ptr<std::uint8_t>(y),
                has_mask ? foreground_mask.ptr<std::uint8_t>(y) : nullptr, alpha, fr, fi,
                buf.data(), mean_r_.data() + o, mean_g_.data() + o, mean_i_.data() + o,
                var_r_.data() + o, var_g_.data() + o, var_i_.data() + o, scale_r_.data() + o,
                scale_g_.data() + o);
    }
  }
}

BackgroundPlanes BackgroundModel::planes() const { return planesOf<BackgroundPlanes>(*this); }

MutableBackgroundPlanes BackgroundModel::mutablePlanes() {
  if (!ready_) throw std::logic_error("background model: planes are written only once learned");
  return planesOf<MutableBackgroundPlanes>(*this);
}

cv::Mat BackgroundModel::plane(const std::vector<float>& v) const {
  if (v.empty()) return cv::Mat();
  return cv::Mat(height_, width_, CV_32FC1, const_cast<float*>(v.data())).clone();
}

double BackgroundModel::density(int x, int y, double r, double g) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_)
    throw std::out_of_range("background model: pixel outside the image");
  const std::size_t i = std::size_t(y) * width_ + x;
  const double vr = var_r_[i], vg = var_g_[i];
  const double dr = r - mean_r_[i], dg = g - mean_g_[i];
  return std::exp(-0.5 * (dr * dr / vr + dg * dg / vg)) / (2.0 * kPi * std::sqrt(vr * vg));
}

void BackgroundModel::save(const std::string& path) const {
  if (!ready_) throw std::logic_error("background model: only a learned model can be saved");
  if (!littleEndianHost()) throw std::runtime_error("background model: big-endian host");
  FileHeader h{};
  std::memcpy(h.magic, kMagic, sizeof(kMagic));
  h.version = kFormatVersion;
  h.width = width_;
  h.height = height_;
  h.frames = frames_;
  h.learning_frames = params_.learning_frames;
  h.learning_rate = params_.learning_rate;
  h.min_sigma_rg = params_.min_sigma_rg;
  h.min_sigma_intensity = params_.min_sigma_intensity;
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error("background model: cannot write '" + path + "'");
  f.write(reinterpret_cast<const char*>(&h), sizeof(h));
  char filter[kFilterField] = {};
  std::memcpy(filter, params_.image_filter.data(), params_.image_filter.size());
  f.write(filter, sizeof(filter));
  for (const auto* v : {&mean_r_, &mean_g_, &mean_i_, &var_r_, &var_g_, &var_i_})
    f.write(reinterpret_cast<const char*>(v->data()), std::streamsize(v->size() * sizeof(float)));
  if (!f) throw std::runtime_error("background model: error writing '" + path + "'");
}

BackgroundModel BackgroundModel::load(const std::string& path, int expected_width,
                                      int expected_height) {
  const std::string where = "background model '" + path + "': ";
  if (!littleEndianHost()) throw std::runtime_error(where + "big-endian host");
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(where + "cannot open");
  FileHeader h{};
  if (!f.read(reinterpret_cast<char*>(&h), sizeof(h)))
    throw std::runtime_error(where + "truncated header");
  if (std::memcmp(h.magic, kMagic, sizeof(kMagic)) != 0)
    throw std::runtime_error(where + "not a background model file (bad magic)");
  if (h.version != kFormatVersion && h.version != kFormatVersionWithoutFilter)
    throw std::runtime_error(where + "unsupported format version " + std::to_string(h.version));
  std::string image_filter = kUnrecordedImageFilter;
  if (h.version >= 2) {
    char filter[kFilterField];
    if (!f.read(filter, sizeof(filter))) throw std::runtime_error(where + "truncated header");
    // The name, then NULs only (at least one).
    const char* const last = filter + kFilterField;
    const char* const end = std::find(static_cast<const char*>(filter), last, '\0');
    if (end == last || std::any_of(end, last, [](char c) { return c != '\0'; }))
      throw std::runtime_error(where + "corrupt image filter field");
    image_filter.assign(static_cast<const char*>(filter), end);
  }
  if (h.width <= 0 || h.height <= 0 || h.width > 16384 || h.height > 16384)
    throw std::runtime_error(where + "implausible size " + std::to_string(h.width) + "x" +
                             std::to_string(h.height));
  if (expected_width > 0 && expected_height > 0 &&
      (h.width != expected_width || h.height != expected_height))
    throw std::runtime_error(where + "size " + std::to_string(h.width) + "x" +
                             std::to_string(h.height) + " does not match the camera's " +
                             std::to_string(expected_width) + "x" +
                             std::to_string(expected_height));
  BackgroundModelParams p;
  p.learning_frames = h.learning_frames;
  p.learning_rate = h.learning_rate;
  p.min_sigma_rg = h.min_sigma_rg;
  p.min_sigma_intensity = h.min_sigma_intensity;
  p.image_filter = image_filter;
  BackgroundModel m;
  try {
    m = BackgroundModel(h.width, h.height, p);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(where + "invalid stored parameters: " + e.what());
  }
  for (auto& s : m.sum_) std::vector<double>().swap(s);
  for (auto* v : {&m.mean_r_, &m.mean_g_, &m.mean_i_, &m.var_r_, &m.var_g_, &m.var_i_})
    if (!f.read(reinterpret_cast<char*>(v->data()), std::streamsize(v->size() * sizeof(float))))
      throw std::runtime_error(where + "truncated data (expected " +
                               std::to_string(6 * v->size() * sizeof(float) + sizeof(h) +
                                              (h.version >= 2 ? kFilterField : 0)) +
                               " bytes)");
  if (f.peek() != std::char_traits<char>::eof())
    throw std::runtime_error(where + "trailing bytes after the model data");
  for (std::size_t i = 0; i < m.mean_r_.size(); ++i) {
    const bool ok = std::isfinite(m.mean_r_[i]) && std::isfinite(m.mean_g_[i]) &&
                    std::isfinite(m.mean_i_[i]) && std::isfinite(m.var_r_[i]) &&
                    std::isfinite(m.var_g_[i]) && std::isfinite(m.var_i_[i]) &&
                    m.var_r_[i] > 0.0f && m.var_g_[i] > 0.0f && m.var_i_[i] > 0.0f;
    if (!ok)
      throw std::runtime_error(where + "non-finite or non-positive parameter at pixel (" +
                               std::to_string(i % h.width) + ", " + std::to_string(i / h.width) +
                               ")");
  }
  m.frames_ = h.frames;
  m.refreshScales(0, m.mean_r_.size());
  m.ready_ = true;
  return m;
}

}  // namespace psfs
