// The per-pixel stage of pSfS on the GPU (issue 20; thesis 6.2, "image-based classification
// part" and "background learning"): per frame and camera the fused classifier (one thread per
// pixel: colour conversion, background Gaussian with the shadow cylinder, skin GMM from kernel
// arguments, i.e. constant memory, outlier model), the view evidence of the body and the skin
// class for the GPU volume kernels, and the selective background update, with the background
// models kept in device memory between frames.
//
// Same bytes as the CPU path: every kernel runs the per-pixel functions the CPU loops run
// (src/pixel_arithmetic.h), so the likelihood images equal PixelClassifier::classify's, the
// evidence equals ViewEvidence::set's (terms with the guard, pairs with the border; no footprint
// levels) and the updated planes equal BackgroundModel::update's.
//
// Frame flow: classify(rgb) -> buildEvidence(active) -> (volume kernels read bodyEvidence() /
// skinEvidence()) -> updateBackground(masks). Images go through pinned staging buffers, one
// stream per camera; device and pinned memory is allocated when the cameras or their sizes
// change (uploadBackgrounds), never per frame (deviceAllocations() counts it).
//
// Without a usable device (no CUDA backend in this build, no GPU, TABLETOP_CUDA_DEVICE=-1)
// usable() is false and reason() says why; every GPU call then throws std::runtime_error. A CUDA
// failure also throws std::runtime_error with the CUDA error string. The caller falls back to
// the CPU path (classifier(), ViewEvidence, BackgroundModel) in both cases.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "psfs_reconstruction/background_model.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/gpu_evidence.h"
#include "psfs_reconstruction/pixel_classifier.h"

namespace psfs {

class GpuPixelStage {
 public:
  // Throws std::invalid_argument like PixelClassifier (empty skin model, bad parameters or
  // priors) and for a skin model of more than 8 components; never for a missing device.
  explicit GpuPixelStage(const GaussianMixture2D& skin, const PixelClassifierParams& params = {},
                         const ClassPriors& priors = {});
  ~GpuPixelStage();
  GpuPixelStage(GpuPixelStage&&) noexcept;
  GpuPixelStage& operator=(GpuPixelStage&&) noexcept;

  bool usable() const;
  const std::string& reason() const;  // why not usable ("" when usable)

  // The CPU classifier with the same model, parameters and priors (the fallback).
  const PixelClassifier& classifier() const;
  void setParams(const PixelClassifierParams& params);  // validates; applies from the next frame
  void setPriors(const ClassPriors& priors);
  // PixelClassifier::setClothingColour, from the next frame.
  void setClothingColour(const ColourGaussian* colour, double weight);

  // --- background models ---
  // Copies the models (one per camera, ready, in the cameras' order) to the device, with their
  // learning rate and floors for updateBackground; (re)allocates the buffers if the camera
  // count or a size changed. Call once after learning, and again after a relearn or a
  // BackgroundModel::setParams. Throws std::invalid_argument for a missing or unready model.
  void uploadBackgrounds(const std::vector<const BackgroundModel*>& models);
  // Copies the device's models (after updateBackground) into `models`, which must be ready and
  // of the uploaded sizes: keeps the CPU fallback and BackgroundModel::save current.
  void downloadBackgrounds(const std::vector<BackgroundModel*>& models) const;
  int cameras() const;  // as uploaded (0 before)

  // --- per frame ---
  // Classifies one frame set (one rgb8 image per uploaded camera; an empty Mat = the camera is
  // missing: its likelihood is 0, its stats are empty). likelihoods (optional): the CV_8UC2
  // images read back to the host, (re)created only if needed. Throws std::invalid_argument like
  // PixelClassifier for bad images.
  std::vector<ClassificationStats> classify(const std::vector<cv::Mat>& rgb,
                                            std::vector<cv::Mat>* likelihoods = nullptr);
  // The view evidence of the last classified frame, as ViewEvidence::set builds it from channel
  // 0 (body) and channel 1 (skin) without footprint levels. active: per camera an optional
  // CV_8UC1 mask (0 = pixel switched off; all zero = view off), shared by both classes; empty
  // vector = all active. with_skin: also the skin class.
  void buildEvidence(const std::vector<cv::Mat>& active, bool body_bilinear, bool skin_bilinear,
                     bool with_skin = true);
  // Device arrays of the last buildEvidence (ViewEvidence's layout), valid until the next
  // buildEvidence or uploadBackgrounds; pairs are nullptr for a class built without bilinear.
  const GpuEvidence& bodyEvidence() const;
  const GpuEvidence& skinEvidence() const;
  // A copy of one view's evidence on the host (diagnostics and tests).
  void readEvidence(int camera, bool skin, std::vector<std::int16_t>* terms,
                    std::vector<std::uint16_t>* pairs) const;
  // Selective update of the device models with the last classified frame's images. masks: per
  // camera CV_8UC1 (nonzero = foreground, kept) or empty (every pixel updated); update: which
  // cameras to update (empty = every camera that had an image). Throws std::logic_error for a
  // camera without an image in the last frame, std::invalid_argument for a bad mask; both
  // before any model changes.
  void updateBackground(const std::vector<cv::Mat>& masks, const std::vector<bool>& update = {});

  // Device and pinned allocations made so far: constant from the second frame on.
  std::size_t deviceAllocations() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace psfs
