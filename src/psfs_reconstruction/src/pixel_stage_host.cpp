#include "pixel_stage_host.h"

#include <stdexcept>
#include <string>

#include "psfs_reconstruction/view_evidence.h"

namespace psfs {

pixel::ClassifyArgs classifyArgs(const pixel::PixelConstants& constants,
                                 const std::vector<detail::SkinKernelTerm>& skin,
                                 const detail::SkinKernelTerm* clothing,
                                 const std::uint8_t* rgb, const BackgroundPlanes& background,
                                 std::uint8_t* likelihood, int width, int height,
                                 const float* gain) {
  if (skin.size() > std::size_t(pixel::kMaxSkinTerms))
    throw std::invalid_argument("pixel stage: the skin model has " + std::to_string(skin.size()) +
                                " components, the GPU kernel takes at most " +
                                std::to_string(pixel::kMaxSkinTerms));
  pixel::ClassifyArgs a;
  a.k = constants;
  for (std::size_t j = 0; j < skin.size(); ++j) a.skin[j] = skin[j];
  a.skin_terms = int(skin.size());
  if (clothing) {
    a.clothing = *clothing;
    a.clothing_terms = 1;
  }
  a.rgb = rgb;
  a.background = background;
  a.likelihood = likelihood;
  a.gain = gain;
  a.width = width;
  a.height = height;
  return a;
}

pixel::GainArgs gainArgs(const pixel::GainConstants& constants, const std::uint8_t* rgb,
                         const BackgroundPlanes& background, int width, int height) {
  pixel::GainArgs a;
  a.c = constants;
  a.rgb = rgb;
  a.mean_r = background.mean_r;
  a.mean_g = background.mean_g;
  a.mean_intensity = background.mean_intensity;
  a.width = width;
  a.height = height;
  return a;
}

pixel::EvidenceArgs evidenceArgs(const std::uint8_t* likelihood, int channels, int channel,
                                 pixel::ActiveMode mode, const std::uint8_t* active, int width,
                                 int height, std::int16_t* terms, std::uint16_t* pairs) {
  pixel::EvidenceArgs a;
  for (int b = 0; b < 256; ++b) a.term_of_byte[b] = ViewEvidence::logTerm(b);
  a.likelihood = likelihood;
  a.channels = channels;
  a.channel = channel;
  a.active_mode = mode;
  a.active = active;
  a.width = width;
  a.height = height;
  a.terms = terms;
  a.pairs = pairs;
  return a;
}

pixel::UpdateArgs updateArgs(const BackgroundModelParams& params, const std::uint8_t* rgb,
                             const std::uint8_t* mask, const MutableBackgroundPlanes& background,
                             int pixels) {
  // The floors as BackgroundModel::update computes them.
  pixel::UpdateArgs a;
  a.rgb = rgb;
  a.mask = mask;
  a.alpha = params.learning_rate;
  a.floor_rg = params.min_sigma_rg * params.min_sigma_rg;
  a.floor_i = params.min_sigma_intensity * params.min_sigma_intensity;
  a.background = background;
  a.pixels = pixels;
  return a;
}

pixel::ActiveMode activeMode(const cv::Mat& active, std::size_t* inactive_pixels) {
  *inactive_pixels = 0;
  if (active.empty()) return pixel::ActiveMode::kAll;
  const std::size_t on = std::size_t(cv::countNonZero(active));
  *inactive_pixels = active.total() - on;
  return on == 0 ? pixel::ActiveMode::kNone : pixel::ActiveMode::kMask;
}

ClassificationStats classificationStats(const pixel::ClassifyTotals& totals, int pixels,
                                        const pixel::GainPeak* gain) {
  ClassificationStats s;
  s.pixels = pixels;
  s.dark_pixels = int(totals.dark);
  s.shadow_pixels = int(totals.shadow);
  s.saturated_pixels = int(totals.saturated);
  // As PixelClassifier sums its row totals: exact in double, so the same quotient.
  s.mean_foreground = pixels ? double(totals.foreground_bytes) / (255.0 * pixels) : 0.0;
  s.gain = gain ? double(gain->gain) : 1.0;
  return s;
}

BackgroundPlanes readOnly(const MutableBackgroundPlanes& p) {
  BackgroundPlanes r;
  r.mean_r = p.mean_r;
  r.mean_g = p.mean_g;
  r.mean_intensity = p.mean_intensity;
  r.scale_r = p.scale_r;
  r.scale_g = p.scale_g;
  r.var_intensity = p.var_intensity;
  r.var_r = p.var_r;
  r.var_g = p.var_g;
  return r;
}

}  // namespace psfs
