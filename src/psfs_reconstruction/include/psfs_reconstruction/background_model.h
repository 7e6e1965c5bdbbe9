// Per-pixel background model of one camera (thesis 4.2.1): a single Gaussian with diagonal
// covariance over normalised rg, p(c|notF) = N(r; mu_r, s_r^2) N(g; mu_g, s_g^2), plus the mean
// and variance of the intensity I = (R+G+B)/3 for the shadow cylinder.
//
// Life cycle: construct with the camera's size, feed the first N frames of the empty workspace
// (addLearningFrame; N = 25 by default), then call update() once per frame with the foreground
// mask f the tracker projects (selective update, Koller et al. 1994):
//   mu  <- f mu  + (1-f) (alpha c + (1-alpha) mu)
//   var <- f var + (1-f) (alpha (c - mu)^2 + (1-alpha) var)
// The thesis writes the second line for sigma; we average the squared deviation because an
// exponential average of |c - mu| would converge to sqrt(2/pi) sigma, not sigma.
// Variances never fall below a floor (sensor noise): 25 frames of a uint8 sensor often show a
// pixel with no variation at all, and a zero variance would make any change "foreground".
//
// Storage is structure-of-arrays float planes (one contiguous row-major plane per parameter),
// which is what the classifier's vectorised row loops read. Not thread-safe for concurrent
// update and classification of the same model; the nodelet runs them in sequence per frame.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "psfs_reconstruction/background_planes.h"

namespace psfs {

struct BackgroundModelParams {
  // Frames of the empty workspace used for the initial estimate (DESIGN.md: >= 25 recorded).
  int learning_frames = 25;
  // alpha of the selective update, per frame (dimensionless). 0.02 at 25 fps adapts to a
  // moved object in ~2 s (time constant 1/alpha = 50 frames) while a person sitting still
  // for a second under a mask that misses them barely leaks in. The thesis uses a constant
  // alpha without giving its value.
  float learning_rate = 0.02f;
  // Standard deviation floors. rg: 0.004 is about the rg noise of a mid-grey pixel
  // (R+G+B ~ 300) with 1.5 levels of sensor noise per channel, and about one cell of the
  // thesis' 256x256 rg grid. Intensity: 2 levels (8-bit).
  float min_sigma_rg = 0.004f;
  float min_sigma_intensity = 2.0f;
  // Learning only from empty frames: a learning frame is compared with the frames learned so
  // far, and a pixel counts as changed when it lies more than learning_change_sigmas standard
  // deviations away in intensity or (for pixels bright enough for colour) in rg; sigmas are
  // at least twice the floors above. A frame in which more than learning_change_fraction of a
  // camera's pixels changed shows something new (a person sitting down) and is not learned.
  // Sensor noise changes well under 0.1 % of the pixels at 5 sigma; a person fills 5-40 %.
  float learning_change_sigmas = 5.0f;
  float learning_change_fraction = 0.01f;
  // When such a frame arrives after at least min_learning_frames learned ones, learning ends
  // there (the recording's empty part was shorter than learning_frames, or its first sets were
  // missed) and the frame is reconstructed; before that, it is skipped.
  int min_learning_frames = 10;
  // The noise filter the camera's images pass before this model sees them (image_prefilter.h,
  // describeImagePrefilter: "none", "median 3x3", ...). Not a setting of the model: the
  // Reconstructor writes its own filter here, and a saved model carries it, so that a model
  // learned from filtered pixels is not loaded under another filter (its variances would be
  // those of other pixels). At most 15 printable characters.
  std::string image_filter = "none";
};

// The image_filter of a model loaded from a version-1 file, which does not record it.
inline constexpr const char* kUnrecordedImageFilter = "unrecorded";

class BackgroundModel {
 public:
  BackgroundModel() = default;
  // Throws std::invalid_argument for non-positive sizes or invalid parameters.
  BackgroundModel(int width, int height, const BackgroundModelParams& params = {});

  int width() const { return width_; }
  int height() const { return height_; }
  const BackgroundModelParams& params() const { return params_; }
  // Changes alpha or the floors later (e.g. from dynamic_reconfigure); floors apply from the
  // next update.
  void setParams(const BackgroundModelParams& params);

  // --- learning phase --------------------------------------------------------------------
  // Adds one empty-scene rgb8 frame; after params().learning_frames frames the model becomes
  // ready() by itself. Throws std::invalid_argument on a bad frame (empty, wrong type or size)
  // and std::logic_error when the model is already ready.
  void addLearningFrame(const cv::Mat& rgb);
  // Ends learning early (needs >= 2 frames); throws std::logic_error otherwise.
  void finishLearning();
  int learnedFrames() const { return frames_; }
  // While learning, after at least one frame: the fraction of this frame's pixels that changed
  // against the frames learned so far (see BackgroundModelParams::learning_change_sigmas).
  // Throws like addLearningFrame, and std::logic_error when no frame was learned or the model
  // is ready.
  double changedFraction(const cv::Mat& rgb) const;
  bool ready() const { return ready_; }

  // --- selective update -------------------------------------------------------------------
  // mask: CV_8UC1 of the same size, nonzero (255) = foreground (kept), 0 = background (updated).
  // An empty mask updates every pixel. Throws like addLearningFrame, and std::logic_error when
  // the model is not ready. OpenMP over rows with num_threads (<= 0: OpenMP default).
  void update(const cv::Mat& rgb, const cv::Mat& foreground_mask, int num_threads = 0);

  // --- parameters ---------------------------------------------------------------------------
  BackgroundPlanes planes() const;
  // Writable planes of a ready model, for the selective update done elsewhere: the GPU pixel
  // stage copies its device planes back here (GpuPixelStage::downloadBackgrounds), and its
  // host emulation updates through them. The writer keeps every variance at or above the
  // floors and the scales at 1 / sqrt(2 var) (pixel_arithmetic.h, backgroundScale). Throws
  // std::logic_error while the model is learning (the planes are not final yet).
  MutableBackgroundPlanes mutablePlanes();
  // CV_32FC1 copies of the parameter planes (for tests, visualisation, tools).
  cv::Mat meanR() const { return plane(mean_r_); }
  cv::Mat meanG() const { return plane(mean_g_); }
  cv::Mat meanIntensity() const { return plane(mean_i_); }
  cv::Mat varianceR() const { return plane(var_r_); }
  cv::Mat varianceG() const { return plane(var_g_); }
  cv::Mat varianceIntensity() const { return plane(var_i_); }
  // Density p(c|notF) per unit rg area at pixel (x, y) (double precision, for tests/tools).
  double density(int x, int y, double r, double g) const;

  // --- persistence ----------------------------------------------------------------------------
  // Binary file: magic "PSFSBGM1", format version (2), width, height, frames, parameters, the
  // image filter (16 bytes, NUL-padded), then the six float planes (little-endian IEEE). Only
  // ready models can be saved. Version 1 files (no filter field) load with image_filter
  // kUnrecordedImageFilter: most were learned from raw pixels (the filter came later and is off
  // by default), but one saved with the filter on cannot be told apart.
  void save(const std::string& path) const;
  // Throws std::runtime_error for unreadable, truncated or corrupt files (bad magic/version,
  // non-finite or non-positive variances) and when expected_width/height (if > 0) differ.
  static BackgroundModel load(const std::string& path, int expected_width = 0,
                              int expected_height = 0);

 private:
  // planes() and mutablePlanes(): the same eight pointers, const or not.
  template <class Planes, class Model>
  static Planes planesOf(Model& m) {
    Planes p;
    p.mean_r = m.mean_r_.data();
    p.mean_g = m.mean_g_.data();
    p.mean_intensity = m.mean_i_.data();
    p.scale_r = m.scale_r_.data();
    p.scale_g = m.scale_g_.data();
    p.var_intensity = m.var_i_.data();
    p.var_r = m.var_r_.data();
    p.var_g = m.var_g_.data();
    return p;
  }
  cv::Mat plane(const std::vector<float>& v) const;
  void finalizeLearning();
  void refreshScales(std::size_t begin, std::size_t end);

  int width_ = 0;
  int height_ = 0;
  BackgroundModelParams params_;
  int frames_ = 0;
  bool ready_ = false;
  std::vector<float> mean_r_, mean_g_, mean_i_, var_r_, var_g_, var_i_, scale_r_, scale_g_;
  std::vector<double> sum_[6];  // learning accumulators: r, g, I, r^2, g^2, I^2
};

}  // namespace psfs
