// Per-pixel skin-coloured-foreground classifier (thesis 4.2.1, DESIGN.md section 4). For each
// camera it turns an rgb8 image into the likelihood image the fusion stage samples:
//   CV_8UC2, channel 0 = round(255 P'(F|c)), channel 1 = round(255 P'(F,S|c)).
//
// With c = (r, g) in normalised rg (color_space.h, densities per unit rg area):
//   P(F|c)   = P(F) / (P(F) + p(c|notF) P(notF))   p(c|notF): the pixel's background Gaussian,
//                                                   p(c|F) = 1/256^2 per cell = 1 per unit area
//   P(S|c)   = p(c|S) P(S) / (p(c|S) P(S) + P(notS))  p(c|S): skin GMM, p(c|notS) uniform
//   shadow:  inside the cylinder around the background mean in rgI space (chroma distance
//            < shadow_chroma_radius and I / I_bg in [min, max]) P(F|c) = 0 (shadow/highlight)
//   outliers (Minka 2003): P'(F|c) = eF P(F) + (1-eF) P(F|c), P'(S|c) = eS P(S) + (1-eS) P(S|c)
//   P'(F,S|c) = P'(F|c) P'(S|c)
// Pixels too dark to have a chroma (I < min_chroma_intensity) carry no colour information:
// P'(F|c) = P(F), P'(S|c) = P(S) (a neutral view for the fusion), unless the intensity model
// is on: then P'(F|c) comes from intensity alone and P'(S|c) = eS P(S), since near-black is
// not skin (a black sleeve, certainly foreground, would otherwise vote for the skin hull in
// every view at the prior's P(S)).
//
// Speed (DESIGN.md section 6: 8 x 320x240 in <= 2 ms on 2 cores): one pass over each row with
// row-local float buffers; every inner loop is branch-free float arithmetic that GCC
// auto-vectorises (a polynomial exp instead of std::exp, selects instead of branches), compiled
// for AVX2/SSE4.1/baseline and picked at load time; the background parameters are read as
// float planes (BackgroundPlanes); OpenMP splits the rows of all cameras. The skin GMM is
// evaluated directly rather than through a colour table: with K = 2 that costs two vector
// exps per pixel, and it is exact, whereas the thesis' 256x256 rg table is off by up to 52/255
// on the steep flank of the skin cluster (3 % of all colours by more than 5/255).
// The per-pixel arithmetic of those loops is written once (src/pixel_arithmetic.h) and shared
// with the GPU pixel stage (gpu_pixel_stage.h), which therefore gives the same bytes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "psfs_reconstruction/background_model.h"
#include "psfs_reconstruction/colour_gaussian.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/skin_kernel_term.h"

namespace psfs {

// Class priors per camera pixel. The fusion computes them from expected occupancy ratios of
// the workspace: P(F) = P(H_F)^(1/C), P(S) = P(H)^(1/C) / P(F) (thesis 4.2.2).
struct ClassPriors {
  double foreground = 0.5;  // P(F)
  double skin = 0.5;        // P(S)
  // hull_foreground = P(H_F), expected fraction of the volume inside the foreground hull;
  // hull_skin = P(H), inside the skin-coloured hull (<= P(H_F)); cameras = C.
  // Throws std::invalid_argument when the inputs are not probabilities or P(S) > 1.
  static ClassPriors fromOccupancy(double hull_foreground, double hull_skin, int cameras);
};

struct PixelClassifierParams {
  // Outlier probabilities eF, eS in [0, 1] (dimensionless): the chance that the background or
  // skin model is simply wrong for a pixel (noise, moved background, odd lighting). They bound
  // each likelihood away from 0 and 1 so one bad view cannot veto a voxel. The thesis gives
  // no values; 0.05 keeps P'(F|c) within [0.05 P(F), 0.95 + 0.05 P(F)].
  float foreground_outlier = 0.05f;
  float skin_outlier = 0.05f;
  // Shadow cylinder (Horprasert et al. 1999, in normalised rgI as in thesis 4.2.3), around
  // the pixel's background mean. Radius in rg units: cast shadows and highlights under office
  // light shift the chroma by ~0.01 (the ambient light's colour), skin differs from a beige
  // desk by ~0.04 and from grey or blue backgrounds by more; 0.02 lies in between. A pixel
  // inside the cylinder is background whatever the Gaussian says, so the radius also bounds
  // how similar to the background a foreground colour may be and still be seen.
  bool shadow_suppression = true;
  float shadow_chroma_radius = 0.02f;
  // Intensity ratio I / I_bg (dimensionless) accepted as shadow (< 1) or highlight (> 1).
  // The darkest cast shadow keeps only the ambient share of the light, 0.2-0.4 in the
  // scenario generator's rooms (and in offices): 0.2 accepts it. 1.25 accepts a mild
  // highlight. The thesis chose its cylinder empirically and does not publish the values.
  // (0.4 before the intensity model: the hands' shadows on a beige desk, darker than that,
  // then became skin-coloured foreground and grew the hand meshes by 2-8 mm.)
  float shadow_min_intensity_ratio = 0.2f;
  float shadow_max_intensity_ratio = 1.25f;
  // Below this intensity (8-bit levels, I = (R+G+B)/3) chroma is noise: with 2 levels of
  // sensor noise per channel, r has a standard deviation of ~0.1 at I = 6.
  float min_chroma_intensity = 6.0f;
  // Intensity in the background likelihood (not in the thesis, which uses rg alone):
  //   p(c|notF) = p(rg|notF) p(I|notF),  p(c|F) = 1 per unit rg area x 1/256 per level,
  //   p(I|notF) = (1 - w) N(I; g I_bg, var_I + (t g I_bg)^2) + w U(I; [min, max] g I_bg)
  // with w = shadow_weight, t = gain_tolerance, [min, max] the shadow ratios above and g the
  // camera's gain this frame (below). Normalised rg cannot tell a grey, white or black shirt
  // from a grey wall, nor a dark sleeve from a dark desk; intensity can, once the light's
  // global changes (exposure steps, drift, flicker, a lamp switched on) are divided out.
  // Pixels too dark for a chroma then keep the intensity evidence (dark on a bright
  // background is foreground) instead of getting the priors. false: the thesis' rg model.
  bool intensity_model = true;
  // Share of the background's intensity density spread uniformly over the shadow/highlight
  // band (dimensionless, [0, 1)): cast shadows darken the desk without changing its chroma.
  float shadow_weight = 0.2f;
  // Standard deviation of the background intensity that the global gain does not explain
  // (vignetting changes, local light), as a fraction of I_bg (dimensionless).
  float gain_tolerance = 0.05f;
  // Per frame and camera, divide out a global gain g = the brightest major peak of I / I_bg
  // (estimateGain) over the pixels
  // whose chroma is still the background's (sampled on every 2nd row and column). Needs
  // intensity_model; false: g = 1.
  bool gain_compensation = true;
};

// What the classifier saw in one image: lets the nodelet report degraded input (a camera
// that is covered, off or overexposed) in its diagnostics without a second pass.
struct ClassificationStats {
  int pixels = 0;
  int dark_pixels = 0;       // I < min_chroma_intensity (no chroma: see the class comment)
  int saturated_pixels = 0;  // at least one channel at 255 (chroma may be clipped)
  // Inside the shadow cylinder where the background Gaussian alone would have said foreground
  // (P(F|c) > 0.5): the shadows and highlights the cylinder removed.
  int shadow_pixels = 0;
  double mean_foreground = 0.0;  // mean P'(F|c) (of the quantised channel 0)
  double gain = 1.0;             // the global gain g divided out (1 without compensation)
  double darkFraction() const { return pixels ? double(dark_pixels) / pixels : 0.0; }
  double saturatedFraction() const { return pixels ? double(saturated_pixels) / pixels : 0.0; }
};

class PixelClassifier {
 public:
  // Throws std::invalid_argument for an empty skin model or invalid parameters/priors.
  explicit PixelClassifier(const GaussianMixture2D& skin, const PixelClassifierParams& params = {},
                           const ClassPriors& priors = {});

  void setParams(const PixelClassifierParams& params);  // validates; throws invalid_argument
  void setPriors(const ClassPriors& priors);            // validates; throws invalid_argument
  // The person's clothing colour in p(c|notS) = 1 + weight q(c), q its Gaussian
  // (clothing_colour.h); nullptr (the default) or weight 0: the thesis' uniform p(c|notS) = 1.
  // Throws std::invalid_argument for a negative or non-finite weight, or a covariance that is
  // not positive definite.
  void setClothingColour(const ColourGaussian* colour, double weight);
  // The clothing colour in use as a one-component mixture, or nullptr; its weight.
  const GaussianMixture2D* clothingModel() const { return clothing_.empty() ? nullptr : &clothing_; }
  double clothingWeight() const { return clothing_weight_; }
  const PixelClassifierParams& params() const { return params_; }
  const ClassPriors& priors() const { return priors_; }
  const GaussianMixture2D& skinModel() const { return skin_; }

  // One camera. `likelihood` is (re)allocated as CV_8UC2 of the image size only if needed;
  // otherwise its buffer is overwritten in place, so never pass a buffer that was already
  // handed on (e.g. inside a published message).
  // Throws std::invalid_argument for an empty image, a type other than CV_8UC3, a size that
  // differs from the background model, or a background model that is not ready().
  // Thread-safe (const); uses OpenMP over rows with num_threads (<= 0: OpenMP default).
  ClassificationStats classify(const cv::Mat& rgb, const BackgroundModel& background,
                               cv::Mat& likelihood, int num_threads = 0) const;

  // All cameras of a frame set in one parallel loop over the rows of all images (better load
  // balance than one camera per thread). Sizes of `rgb` and `backgrounds` must match; camera i
  // is named "cam<i>" in errors. Every input is validated before any work is done.
  std::vector<ClassificationStats> classify(const std::vector<cv::Mat>& rgb,
                                            const std::vector<const BackgroundModel*>& backgrounds,
                                            std::vector<cv::Mat>& likelihoods,
                                            int num_threads = 0) const;

  // Plain per-pixel double-precision implementation of the same formulas with std::exp and
  // the GMM's own density(): the reference for tests and the baseline for the benchmark.
  ClassificationStats classifyReference(const cv::Mat& rgb, const BackgroundModel& background,
                                        cv::Mat& likelihood) const;

  // P'(F|c), P'(S|c) of one pixel (reference path, double): for tests and tools.
  // gain: the camera's global gain this frame (estimateGain).
  void classifyPixel(std::uint8_t R, std::uint8_t G, std::uint8_t B,
                     const BackgroundModel& background, int x, int y, double* p_foreground,
                     double* p_skin, bool* suppressed_shadow = nullptr, double gain = 1.0) const;

  // The global gain g of an rgb8 image against its background (PixelClassifierParams::
  // gain_compensation): the brightest peak of I / I_bg holding at least half as many pixels
  // as the largest (histogram in steps of 1/256, counted over 5 steps; a shadow may be as
  // large as the lit background, but is darker) over every 2nd row and column, taking only pixels of
  // background chroma (within twice the shadow cylinder's radius) that are neither dark nor
  // saturated, clamped to [0.25, 4]. 1 when compensation is off or fewer than 64 pixels
  // qualify. Deterministic (an integer histogram).
  double estimateGain(const cv::Mat& rgb, const BackgroundModel& background) const;

 private:
  void rebuild();
  void classifyRows(const cv::Mat* rgb, const BackgroundModel* const* bg, cv::Mat* out,
                    ClassificationStats* stats, int cameras, int num_threads) const;

  GaussianMixture2D skin_;
  PixelClassifierParams params_;
  ClassPriors priors_;
  std::vector<detail::SkinKernelTerm> skin_terms_;
  GaussianMixture2D clothing_;  // empty: none (its constructor validates the Gaussian)
  double clothing_weight_ = 0.0;
};

}  // namespace psfs
