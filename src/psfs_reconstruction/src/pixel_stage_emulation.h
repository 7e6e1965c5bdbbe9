// Private: the GPU pixel stage (gpu_pixel_stage.h) run on the host. Each function runs the same
// per-thread functions of pixel_arithmetic.h that the CUDA kernels run (cuda/pixel_pipeline.cu),
// over all "threads" in a plain loop, in the kernels' order of stages (gain histogram, gain
// peak, classification; evidence terms and pairs; selective update). It is compiled into the
// core in every build, so the unit tests check here, without a GPU, that the kernels' code
// gives the CPU path's bytes; the GPU tests then check the device against the same CPU path.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "pixel_arithmetic.h"
#include "psfs_reconstruction/background_model.h"
#include "psfs_reconstruction/pixel_classifier.h"

namespace psfs {
namespace emulation {

// ---- the kernels' loops ----
// Gain histogram (one thread per sample) and peak (one thread per bin, then the walk).
pixel::GainPeak gain(const pixel::GainArgs& args);
// Classification, one thread per pixel; the counts summed.
pixel::ClassifyTotals classify(const pixel::ClassifyArgs& args);
void evidenceTerms(const pixel::EvidenceArgs& args);
void evidencePairs(const pixel::EvidenceArgs& args);
void update(const pixel::UpdateArgs& args);

// ---- whole images, as GpuPixelStage feeds the kernels ----
// One camera: likelihood (CV_8UC2) and the stats, with the classifier's model, parameters and
// priors. Throws like PixelClassifier::classify.
ClassificationStats classify(const PixelClassifier& classifier, const cv::Mat& rgb,
                             const BackgroundModel& background, cv::Mat& likelihood);
// One class of one view, as ViewEvidence::set without footprint levels: terms (width * height
// + 3 entries) and, when bilinear, the pairs (ViewEvidence::quadStride * (height + 16) + 2).
void evidence(const cv::Mat& likelihood, int channel, const cv::Mat& active, bool bilinear,
              std::vector<std::int16_t>* terms, std::vector<std::uint16_t>* pairs);
// BackgroundModel::update (mask empty: every pixel).
void updateBackground(BackgroundModel& model, const cv::Mat& rgb, const cv::Mat& mask);

}  // namespace emulation
}  // namespace psfs
