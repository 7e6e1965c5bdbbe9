// Private: the host side of the pixel stage's per-pixel arithmetic (pixel_arithmetic.h): the
// constants built from the public parameters, and the argument blocks of the per-thread
// functions. The CPU classifier, the GPU pixel stage (with device pointers) and its host
// emulation (with host pointers) all build them here, so the shared arithmetic sees the same
// numbers on every side.
#pragma once

#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

#include "pixel_arithmetic.h"
#include "psfs_reconstruction/background_model.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/pixel_classifier.h"

namespace psfs {

// ---- constants (pixel_classifier.cpp) ----
// The skin GMM's components pre-multiplied for skinDensity() (one per component, in order).
std::vector<detail::SkinKernelTerm> skinKernelTerms(const GaussianMixture2D& skin);
// Per-frame classification constants; gain = 1 (each camera sets its own).
pixel::PixelConstants pixelConstants(const PixelClassifierParams& params, const ClassPriors& priors);
// The clothing colour's term of p(c|notS), pre-multiplied by weight P(notS) / P(S) for
// likelihoodBytes (pixel_arithmetic.h).
detail::SkinKernelTerm clothingKernelTerm(const GaussianComponent2D& colour, double weight,
                                          const ClassPriors& priors);
// Whether the classifier divides out a global gain per frame, and the gain histogram's constants
// (PixelClassifier::estimateGain).
bool gainCompensated(const PixelClassifierParams& params);
pixel::GainConstants gainConstants(const PixelClassifierParams& params);

// A classifier's constants and clothing term as its kernels take them (the CPU rows, the GPU
// stage and its emulation): one place for the clothing colour's term.
struct ClassifierKernelConstants {
  pixel::PixelConstants k;
  bool has_clothing = false;
  detail::SkinKernelTerm clothing{};
  const detail::SkinKernelTerm* clothingTerm() const { return has_clothing ? &clothing : nullptr; }
};
ClassifierKernelConstants kernelConstants(const PixelClassifier& classifier);

// ---- argument blocks (pixel_stage_host.cpp) ----
// Throws std::invalid_argument for more than pixel::kMaxSkinTerms skin components.
// clothing: the clothing colour's term, or nullptr.
pixel::ClassifyArgs classifyArgs(const pixel::PixelConstants& constants,
                                 const std::vector<detail::SkinKernelTerm>& skin,
                                 const detail::SkinKernelTerm* clothing,
                                 const std::uint8_t* rgb, const BackgroundPlanes& background,
                                 std::uint8_t* likelihood, int width, int height,
                                 const float* gain);
pixel::GainArgs gainArgs(const pixel::GainConstants& constants, const std::uint8_t* rgb,
                         const BackgroundPlanes& background, int width, int height);
// The term table is ViewEvidence::logTerm's.
pixel::EvidenceArgs evidenceArgs(const std::uint8_t* likelihood, int channels, int channel,
                                 pixel::ActiveMode mode, const std::uint8_t* active, int width,
                                 int height, std::int16_t* terms, std::uint16_t* pairs);
pixel::UpdateArgs updateArgs(const BackgroundModelParams& params, const std::uint8_t* rgb,
                             const std::uint8_t* mask, const MutableBackgroundPlanes& background,
                             int pixels);

// The active-mask mode of a ViewImage::active mask (empty: all active; no nonzero pixel: the
// view is off) and its number of switched-off pixels.
pixel::ActiveMode activeMode(const cv::Mat& active, std::size_t* inactive_pixels);
// ClassificationStats from an image's totals; gain: the peak found, or nullptr (gain 1).
ClassificationStats classificationStats(const pixel::ClassifyTotals& totals, int pixels,
                                        const pixel::GainPeak* gain);
// A read-only view of writable planes.
BackgroundPlanes readOnly(const MutableBackgroundPlanes& planes);

}  // namespace psfs
