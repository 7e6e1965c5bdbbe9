// Private: the host side of the per-pixel stage's constants (pixel_arithmetic.h), built in one
// place from the public parameters for the CPU classifier, the GPU pixel stage and its host
// emulation, so that all three feed the shared arithmetic the same numbers.
#pragma once

#include <vector>

#include "pixel_arithmetic.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/pixel_classifier.h"

namespace psfs {

// The skin GMM's components pre-multiplied for skinDensity() (one per component, in order).
std::vector<detail::SkinKernelTerm> skinKernelTerms(const GaussianMixture2D& skin);
// Per-frame classification constants; gain = 1 (each camera sets its own).
pixel::PixelConstants pixelConstants(const PixelClassifierParams& params, const ClassPriors& priors);
// Whether the classifier divides out a global gain per frame, and the gain histogram's constants
// (PixelClassifier::estimateGain).
bool gainCompensated(const PixelClassifierParams& params);
pixel::GainConstants gainConstants(const PixelClassifierParams& params);

}  // namespace psfs
