#include "pixel_stage_emulation.h"

#include <algorithm>
#include <stdexcept>

#include "psfs_reconstruction/image_checks.h"
#include "pixel_stage_host.h"

namespace psfs {
namespace emulation {

pixel::GainPeak gain(const pixel::GainArgs& a) {
  std::vector<int> hist(pixel::kGainBins, 0);
  const int samples = a.samplesX() * a.samplesY();
  for (int s = 0; s < samples; ++s) {  // the histogram kernel
    const int bin = pixel::gainSampleThread(a, s);
    if (bin >= 0) ++hist[bin];
  }
  // The peak kernel: every bin's window, their maximum and the sample count (block
  // reductions on the device), the brightest candidate (an atomic max), then the walk.
  std::vector<int> window(pixel::kGainBins);
  int max_window = 0, count = 0;
  for (int b = 0; b < pixel::kGainBins; ++b) {
    window[b] = pixel::gainWindow(hist.data(), b);
    max_window = std::max(max_window, window[b]);
    count += hist[b];
  }
  int candidate = -1;
  for (int b = 0; b < pixel::kGainBins; ++b)
    if (pixel::gainCandidate(window[b], max_window)) candidate = std::max(candidate, b);
  return pixel::gainPeakOf(window.data(), candidate, count);
}

pixel::ClassifyTotals classify(const pixel::ClassifyArgs& a) {
  pixel::ClassifyTotals t{0, 0, 0, 0};
  const int n = a.width * a.height;
  for (int i = 0; i < n; ++i) {
    const pixel::PixelCounts c = pixel::classifyThread(a, i);
    t.dark += c.dark;
    t.shadow += c.shadow;
    t.saturated += c.saturated;
    t.foreground_bytes += c.foreground_bytes;
  }
  return t;
}

void evidenceTerms(const pixel::EvidenceArgs& a) {
  const int n = a.pixels() + pixel::kTermGuard;
  for (int i = 0; i < n; ++i) pixel::evidenceTermThread(a, i);
}

void evidencePairs(const pixel::EvidenceArgs& a) {
  const int n = a.pairCount();
  for (int i = 0; i < n; ++i) pixel::evidencePairThread(a, i);
}

void update(const pixel::UpdateArgs& a) {
  for (int i = 0; i < a.pixels; ++i) pixel::updateThread(a, i);
}

ClassificationStats classify(const PixelClassifier& classifier, const cv::Mat& rgb,
                             const BackgroundModel& background, cv::Mat& likelihood) {
  if (!background.ready())
    throw std::invalid_argument("pixel stage emulation: background model not learned yet");
  checkRgb8(rgb, background.width(), background.height(), "pixel stage emulation");
  // The GPU stage stages each image contiguously (pinned buffer).
  const cv::Mat image = rgb.isContinuous() ? rgb : rgb.clone();
  likelihood.create(rgb.rows, rgb.cols, CV_8UC2);
  const PixelClassifierParams& params = classifier.params();
  const BackgroundPlanes planes = background.planes();
  pixel::GainPeak peak{0, 0, 1.0f};
  const bool compensate = gainCompensated(params);
  if (compensate)
    peak = gain(gainArgs(gainConstants(params), image.data, planes, rgb.cols, rgb.rows));
  const ClassifierKernelConstants kc = kernelConstants(classifier);
  const pixel::ClassifyArgs args =
      classifyArgs(kc.k, skinKernelTerms(classifier.skinModel()), kc.clothingTerm(), image.data,
                   planes, likelihood.data,
                   rgb.cols, rgb.rows, compensate ? &peak.gain : nullptr);
  const pixel::ClassifyTotals totals = classify(args);
  return classificationStats(totals, rgb.rows * rgb.cols, compensate ? &peak : nullptr);
}

void evidence(const cv::Mat& likelihood, int channel, const cv::Mat& active, bool bilinear,
              std::vector<std::int16_t>* terms, std::vector<std::uint16_t>* pairs) {
  if (likelihood.empty() || likelihood.depth() != CV_8U || !likelihood.isContinuous() ||
      channel < 0 || channel >= likelihood.channels())
    throw std::invalid_argument("pixel stage emulation: need a continuous 8-bit likelihood image");
  if (!active.empty() && (active.type() != CV_8UC1 || active.size() != likelihood.size() ||
                          !active.isContinuous()))
    throw std::invalid_argument("pixel stage emulation: active mask must be CV_8UC1 of its size");
  std::size_t inactive = 0;
  const pixel::ActiveMode mode = activeMode(active, &inactive);
  pixel::EvidenceArgs a =
      evidenceArgs(likelihood.data, likelihood.channels(), channel, mode, active.data,
                   likelihood.cols, likelihood.rows, nullptr, nullptr);
  terms->assign(std::size_t(a.pixels()) + pixel::kTermGuard, 0);
  a.terms = terms->data();
  evidenceTerms(a);
  pairs->clear();
  if (!bilinear) return;
  pairs->assign(std::size_t(a.pairCount()), 0);
  a.pairs = pairs->data();
  evidencePairs(a);
}

void updateBackground(BackgroundModel& model, const cv::Mat& rgb, const cv::Mat& mask) {
  checkRgb8(rgb, model.width(), model.height(), "pixel stage emulation (update)");
  if (!mask.empty()) checkMask(mask, model.width(), model.height(), "pixel stage emulation");
  const cv::Mat image = rgb.isContinuous() ? rgb : rgb.clone();
  const cv::Mat m = mask.empty() || mask.isContinuous() ? mask : mask.clone();
  update(updateArgs(model.params(), image.data, m.empty() ? nullptr : m.data,
                    model.mutablePlanes(), model.width() * model.height()));
}

}  // namespace emulation
}  // namespace psfs
