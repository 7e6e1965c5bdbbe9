// Private: the per-pixel arithmetic of the pixel stage (issue 20), written once as PSFS_HD
// functions for three callers: the CPU path's vectorised row loops (pixel_classifier.cpp,
// background_model.cpp, view_evidence.cpp call them in their loop bodies), the CUDA kernels
// (cuda/pixel_pipeline.cu: one thread per pixel around the *Thread functions below) and the
// host emulation of those kernels (pixel_stage_emulation.cpp: the same *Thread functions in
// plain loops), which the unit tests compare byte for byte with the CPU path.
//
// Identical bytes on every side need identical IEEE operations in the same order: every
// function is branch-free float arithmetic with selects (so GCC still vectorises the row loops),
// nothing is contracted into an FMA (the CPU clones do not enable FMA, nvcc runs with
// --fmad=false), division and square root are correctly rounded on both sides (-prec-div,
// -prec-sqrt), and the only transcendental, exp, is the polynomial expNeg below rather than a
// library call whose last bit differs between libm and CUDA. No OpenCV, Eigen or CUDA types.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "host_device.h"
#include "psfs_reconstruction/background_planes.h"
#include "psfs_reconstruction/skin_kernel_term.h"

namespace psfs {
namespace pixel {

// ---- helpers ---------------------------------------------------------------------------------

PSFS_HD float floatFromBits(std::int32_t bits) {
#if defined(__CUDA_ARCH__)
  return __int_as_float(bits);
#else
  float f;
  std::memcpy(&f, &bits, sizeof(f));
  return f;
#endif
}

PSFS_HD int clampInt(int v, int lo, int hi) { return v < lo ? lo : (v > hi ? hi : v); }

// exp(-x) for x >= 0 (x is clamped to [0, 87]), relative error < 4e-6: 2^t = 2^i * 2^f with
// i = trunc(t), f in (-1, 0] and a degree-4 polynomial for 2^f (relative least-squares fit on
// [-1, 0]). Branch-free and vectorisable, where std::exp is a library call that blocks
// vectorisation. The output needs 1/255; P = 1/(1 + e) moves by < 1e-6 for this error.
PSFS_HD float expNeg(float x) {
  x = x < 0.0f ? 0.0f : (x > 87.0f ? 87.0f : x);
  const float t = -x * 1.4426950408889634f;  // log2(e)
  const int i = int(t);                      // trunc towards 0 = ceil for t <= 0
  const float f = t - float(i);              // (-1, 0]
  const float p =
      1.0f + f * (0.69306009f + f * (0.23943884f + f * (0.053195773f + f * 0.0068184414f)));
  return p * floatFromBits((i + 127) << 23);  // 2^i, i >= -126 so always a normal float
}

// ---- colour -------------------------------------------------------------------------------

// Normalised r, g and intensity I = (R+G+B)/3 (color_space.h); black gets the grey point.
struct RgI {
  float r, g, intensity;
};
PSFS_HD RgI rgbToRgI(std::uint8_t R8, std::uint8_t G8, std::uint8_t B8) {
  const float R = float(R8), G = float(G8), B = float(B8);
  const float s = R + G + B;
  const float inv = 1.0f / (s > 0.0f ? s : 1.0f);
  RgI c;
  c.r = s > 0.0f ? R * inv : (1.0f / 3.0f);
  c.g = s > 0.0f ? G * inv : (1.0f / 3.0f);
  c.intensity = s * (1.0f / 3.0f);
  return c;
}

PSFS_HD int saturated(std::uint8_t R, std::uint8_t G, std::uint8_t B) {
  return (R == 255) | (G == 255) | (B == 255);
}

// ---- classification (pixel_classifier.h for the model) ---------------------------------------

// Per-frame constants of one camera, from the priors, the parameters and the camera's gain
// (pixelConstants() in pixel_stage_host.h builds them).
struct PixelConstants {
  float odds_bg;                   // P(notF) / P(F), priors clamped
  float odds_skin;                 // P(notS) / P(S)
  float outF, keepF, outS, keepS;  // outlier model: eF P(F), 1 - eF, eS P(S), 1 - eS
  float priorF, priorS;
  float shadow_r2;  // squared cylinder radius; < 0 disables the cylinder
  float lo, hi;     // intensity ratio bounds
  float min_i;      // dark-pixel threshold
  float use_i;      // intensity model on: 1, off: 0
  float gain;       // this camera's g (set per frame)
  float tol2;       // gain_tolerance^2
  float keep_n;     // 256 (1 - w): the Gaussian's share, per 1/256 fg density
  float band_u;     // 256 w / (max - min): the band's density times g I_bg
  float dark_skin;  // P'(S|c) of a dark pixel: P(S), or eS P(S) (intensity model)
};

// P'(F|c) of one pixel, and the flags the diagnostics count (1 or 0).
struct ForegroundTerm {
  float p;       // P'(F|c)
  float dark;    // I < min_chroma_intensity
  float shadow;  // the shadow cylinder turned a foreground call (P(F|c) > 0.5) into background
};

// Background Gaussian (rg, and intensity with the model on), shadow cylinder, outlier model and
// the dark-pixel rule. mr..vi: the pixel's background parameters (BackgroundPlanes).
PSFS_HD ForegroundTerm foregroundTerm(const PixelConstants& k, RgI c, float mr, float mg, float mi,
                                      float sr, float sg, float vi) {
  const float inv_pi = float(1.0 / 3.14159265358979323846);
  const float dr = c.r - mr, dg = c.g - mg;
  const float ur = dr * sr, ug = dg * sg;
  const float ix = c.intensity, mix = k.gain * mi;
  const float d = ix < k.min_i ? 1.0f : 0.0f;
  // p(rg|notF) = exp(-m^2/2) / (2 pi s_r s_g) = (scale_r scale_g / pi) exp(-(ur^2 + ug^2));
  // a dark pixel's chroma is noise: the same density as the foreground's (1).
  const float p_rg = sr * sg * inv_pi * expNeg(ur * ur + ug * ug);
  // 256 p(I|notF): Gaussian around g I_bg plus the uniform shadow/highlight band.
  const float di = ix - mix;
  const float half_inv_var = 0.5f / (vi + k.tol2 * mix * mix);
  const float n_i = sqrtf(half_inv_var * inv_pi) * expNeg(di * di * half_inv_var);
  const float in_band = (ix >= k.lo * mix ? 1.0f : 0.0f) * (ix <= k.hi * mix ? 1.0f : 0.0f);
  const float q_i = k.keep_n * n_i + in_band * k.band_u / (mix > 1.0f ? mix : 1.0f);
  const float p_rg_i = d * 1.0f + (1.0f - d) * p_rg;
  const float p_bg = k.use_i * (p_rg_i * q_i) + (1.0f - k.use_i) * p_rg;
  const float p_fc = 1.0f / (1.0f + k.odds_bg * p_bg);
  const float sh_chroma = dr * dr + dg * dg < k.shadow_r2 ? 1.0f : 0.0f;
  const float sh = sh_chroma * in_band * (1.0f - d);  // the cylinder: chroma and the band
  const float f = k.outF + k.keepF * (1.0f - sh) * p_fc;
  const float prior_if_dark = (1.0f - k.use_i) * d;  // without intensity, dark = no evidence
  ForegroundTerm t;
  t.p = prior_if_dark * k.priorF + (1.0f - prior_if_dark) * f;
  t.dark = d;
  t.shadow = p_fc > 0.5f ? sh : 0.0f;  // counted only where the cylinder changed the call
  return t;
}

// One skin GMM component's density p(c|S) at (r, g); the components are summed in their order
// starting from 0.
PSFS_HD float skinDensity(const detail::SkinKernelTerm& t, float r, float g) {
  const float dr = r - t.mean_r, dg = g - t.mean_g;
  return t.weight * expNeg(t.a * dr * dr + t.b2 * dr * dg + t.c * dg * dg);
}

// The likelihood image's two channels: round(255 P'(F|c)), round(255 P'(F|c) P'(S|c)).
struct LikelihoodBytes {
  std::uint8_t foreground, skin;
};
// pf: P'(F|c); ps: p(c|S) (the skin GMM's density); pn: the clothing colour's part of
// p(c|notS), weight q(c), times P(notS) / P(S) (0 without one); dark: ForegroundTerm::dark.
PSFS_HD LikelihoodBytes likelihoodBytes(const PixelConstants& k, float pf, float ps, float pn,
                                        float dark) {
  // = p P(S) / (p P(S) + p(c|notS) P(notS)), p(c|notS) = 1 + weight q(c)
  const float p_sc = ps / (ps + k.odds_skin + pn);
  const float s = dark * k.dark_skin + (1.0f - dark) * (k.outS + k.keepS * p_sc);
  LikelihoodBytes b;
  b.foreground = std::uint8_t(int(pf * 255.0f + 0.5f));
  b.skin = std::uint8_t(int(pf * s * 255.0f + 0.5f));
  return b;
}

// Everything the classification of one camera image reads and writes (contiguous images).
constexpr int kMaxSkinTerms = 8;  // GMM components a kernel argument holds (K = 2 in practice)
struct ClassifyArgs {
  PixelConstants k;  // k.gain is replaced by *gain when gain is set
  detail::SkinKernelTerm skin[kMaxSkinTerms];
  int skin_terms = 0;
  detail::SkinKernelTerm clothing{};  // the clothing colour in p(c|notS) (clothing_colour.h)
  int clothing_terms = 0;           // 0 or 1
  const std::uint8_t* rgb = nullptr;  // rgb8, 3 * width bytes per row
  BackgroundPlanes background;
  std::uint8_t* likelihood = nullptr;  // CV_8UC2 layout, 2 * width bytes per row
  const float* gain = nullptr;         // this frame's gain (&GainPeak::gain), or nullptr
  int width = 0, height = 0;
};

// What one pixel adds to ClassificationStats (integers: any summation order gives the same).
struct PixelCounts {
  int dark, shadow, saturated, foreground_bytes;
};
// Their sums over an image.
struct ClassifyTotals {
  unsigned long long dark, shadow, saturated, foreground_bytes;
};

// Classifies pixel i (row-major index) and writes its two likelihood bytes: one GPU thread.
PSFS_HD PixelCounts classifyThread(const ClassifyArgs& a, int i) {
  PixelConstants k = a.k;
  if (a.gain) k.gain = *a.gain;
  const std::uint8_t* px = a.rgb + 3 * std::size_t(i);
  const RgI c = rgbToRgI(px[0], px[1], px[2]);
  const BackgroundPlanes& P = a.background;
  const ForegroundTerm f = foregroundTerm(k, c, P.mean_r[i], P.mean_g[i], P.mean_intensity[i],
                                          P.scale_r[i], P.scale_g[i], P.var_intensity[i]);
  float ps = 0.0f;
  for (int j = 0; j < a.skin_terms; ++j) ps += skinDensity(a.skin[j], c.r, c.g);
  const float pn = a.clothing_terms ? skinDensity(a.clothing, c.r, c.g) : 0.0f;
  const LikelihoodBytes b = likelihoodBytes(k, f.p, ps, pn, f.dark);
  a.likelihood[2 * std::size_t(i)] = b.foreground;
  a.likelihood[2 * std::size_t(i) + 1] = b.skin;
  PixelCounts n;
  n.dark = int(f.dark);
  n.shadow = int(f.shadow);
  n.saturated = saturated(px[0], px[1], px[2]);
  n.foreground_bytes = b.foreground;
  return n;
}

// ---- global gain (PixelClassifier::estimateGain) ------------------------------------------

// The histogram of I / I_bg: [0, 4) in steps of 1/256, over every 2nd row and column.
constexpr int kGainBinsPerUnit = 256;
constexpr int kGainBins = 4 * kGainBinsPerUnit;
constexpr int kGainMinSamples = 64;
constexpr int kGainWindowHalf = 2;  // peaks are counted over 5 bins
// Background intensities below this (8-bit levels) are too noisy for a ratio.
constexpr float kGainMinBackground = 16.0f;
constexpr float kGainMaxIntensity = 250.0f;  // saturated pixels clip the ratio

struct GainConstants {
  float chroma_r2;      // squared rg radius of "background chroma"
  float min_intensity;  // darker pixels have no reliable chroma
};

// The histogram bin of one pixel, or -1 where it does not qualify (dark, bright, dark
// background, foreign chroma, ratio >= 4).
PSFS_HD int gainBin(const GainConstants& g, std::uint8_t R8, std::uint8_t G8, std::uint8_t B8,
                    float mr, float mg, float mi) {
  const float R = R8, G = G8, B = B8;
  const float sum = R + G + B;
  const float I = sum * (1.0f / 3.0f);
  if (I < g.min_intensity || I > kGainMaxIntensity || mi < kGainMinBackground) return -1;
  const float dr = R / sum - mr, dg = G / sum - mg;
  if (dr * dr + dg * dg >= g.chroma_r2) return -1;
  const int bin = int(I / mi * float(kGainBinsPerUnit));
  return bin < kGainBins ? bin : -1;
}

// Pixels in bins b-2..b+2.
PSFS_HD int gainWindow(const int* hist, int b) {
  const int lo = b - kGainWindowHalf < 0 ? 0 : b - kGainWindowHalf;
  const int hi = b + kGainWindowHalf > kGainBins - 1 ? kGainBins - 1 : b + kGainWindowHalf;
  int n = 0;
  for (int j = lo; j <= hi; ++j) n += hist[j];
  return n;
}

// A peak may be the gain if it holds at least half as many pixels as the largest: the gain is
// the brightest such bin (shadows only darken), moved to the top of its peak (gainPeakTop).
PSFS_HD bool gainCandidate(int window, int max_window) { return 2 * window >= max_window; }
PSFS_HD int gainPeakTop(const int* window, int b) {
  while (b > 0 && window[b - 1] > window[b]) --b;
  return b;
}
// The gain of the chosen bin, 1 with too few samples; clamped to [0.25, 4]. Exact in float
// ((2b + 1) / 512 has at most 11 significant bits), so the CPU's double is the same number.
PSFS_HD float gainOfBin(int bin, int samples) {
  if (samples < kGainMinSamples) return 1.0f;
  const float g = (float(bin) + 0.5f) / float(kGainBinsPerUnit);
  return g < 0.25f ? 0.25f : (g > 4.0f ? 4.0f : g);
}

// The gain chosen for one image: the histogram bin (after the walk to the top of its peak), the
// number of qualifying samples and the gain itself (gainOfBin).
struct GainPeak {
  int bin, samples;
  float gain;
};
// Given every bin's window, the brightest candidate bin and the number of samples.
PSFS_HD GainPeak gainPeakOf(const int* window, int candidate, int samples) {
  GainPeak p;
  p.bin = gainPeakTop(window, candidate);
  p.samples = samples;
  p.gain = gainOfBin(p.bin, samples);
  return p;
}

struct GainArgs {
  GainConstants c;
  const std::uint8_t* rgb = nullptr;  // contiguous rgb8
  const float* mean_r = nullptr;
  const float* mean_g = nullptr;
  const float* mean_intensity = nullptr;
  int width = 0, height = 0;
  PSFS_HD int samplesX() const { return (width + 1) / 2; }
  PSFS_HD int samplesY() const { return (height + 1) / 2; }
};

// Histogram bin of sample s (row-major over the samples grid), or -1: one GPU thread.
PSFS_HD int gainSampleThread(const GainArgs& a, int s) {
  const int x = 2 * (s % a.samplesX()), y = 2 * (s / a.samplesX());
  const std::size_t i = std::size_t(y) * a.width + x;
  const std::uint8_t* px = a.rgb + 3 * i;
  return gainBin(a.c, px[0], px[1], px[2], a.mean_r[i], a.mean_g[i], a.mean_intensity[i]);
}

// ---- view evidence (view_evidence.h) --------------------------------------------------------

constexpr std::int16_t kNoEvidenceTerm = 1;  // ViewEvidence::kNoEvidence
constexpr int kPairPad = 8;                  // ViewEvidence::kQuadPad
constexpr int kTermGuard = 3;                // "no evidence" entries after the terms
constexpr int kPairGuard = 2;                // zero entries after the pairs

PSFS_HD std::int16_t maskedTerm(std::int16_t term, std::uint8_t active) {
  return active == 0 ? kNoEvidenceTerm : term;
}
// A pixel's byte and the byte below it (one 32-bit load reads a 2x2 neighbourhood).
PSFS_HD std::uint16_t evidencePair(std::uint8_t top, std::uint8_t below) {
  return std::uint16_t(top | below << 8);
}

// One class of one camera. The active mask: none (all pixels give evidence), a CV_8UC1 mask,
// or the whole view switched off.
enum class ActiveMode : int { kAll = 0, kMask = 1, kNone = 2 };
struct EvidenceArgs {
  std::int16_t term_of_byte[256];  // ViewEvidence::logTerm
  const std::uint8_t* likelihood = nullptr;  // interleaved, `channels` bytes per pixel
  int channels = 2, channel = 0;
  ActiveMode active_mode = ActiveMode::kAll;
  const std::uint8_t* active = nullptr;  // width * height bytes (kMask)
  int width = 0, height = 0;
  std::int16_t* terms = nullptr;   // width * height + kTermGuard
  std::uint16_t* pairs = nullptr;  // pairCount() entries
  PSFS_HD int pixels() const { return width * height; }
  PSFS_HD int pairStride() const { return width + 2 * kPairPad; }
  PSFS_HD int pairCount() const { return pairStride() * (height + 2 * kPairPad) + kPairGuard; }
  PSFS_HD std::uint8_t byteAt(int u, int v) const {
    return likelihood[(std::size_t(v) * width + u) * channels + channel];
  }
};

// Term entry i of [0, pixels() + kTermGuard): one GPU thread.
PSFS_HD void evidenceTermThread(const EvidenceArgs& a, int i) {
  const int n = a.pixels();
  if (i >= n) {
    a.terms[i] = kNoEvidenceTerm;
    return;
  }
  const std::int16_t t = a.term_of_byte[a.likelihood[std::size_t(i) * a.channels + a.channel]];
  const std::uint8_t act = a.active_mode == ActiveMode::kAll    ? std::uint8_t(1)
                           : a.active_mode == ActiveMode::kNone ? std::uint8_t(0)
                                                                : a.active[i];
  a.terms[i] = maskedTerm(t, act);
}

// Pair entry i of [0, pairCount()): (u, v) from -kPairPad, clamped to the image.
PSFS_HD void evidencePairThread(const EvidenceArgs& a, int i) {
  const int QS = a.pairStride(), QH = a.height + 2 * kPairPad;
  if (i >= QS * QH) {
    a.pairs[i] = 0;
    return;
  }
  const int vv = i / QS, uu = i - vv * QS;
  const int u = clampInt(uu - kPairPad, 0, a.width - 1);
  const int v0 = clampInt(vv - kPairPad, 0, a.height - 1);
  const int v1 = clampInt(vv - kPairPad + 1, 0, a.height - 1);
  a.pairs[i] = evidencePair(a.byteAt(u, v0), a.byteAt(u, v1));
}

// ---- selective background update (background_model.h) ------------------------------------

// 1 / (sigma sqrt(2)) of a variance (BackgroundPlanes::scale_r).
PSFS_HD float backgroundScale(float variance) { return 1.0f / sqrtf(2.0f * variance); }

// The update's weight of a pixel: (1 - f) alpha with f the (binary) foreground mask.
PSFS_HD float updateWeight(std::uint8_t foreground, float alpha) {
  return foreground ? 0.0f : alpha;
}

// mu <- mu + k (c - mu), var <- var + k ((c - mu_old)^2 - var), floored; scales follow.
PSFS_HD void updateBackgroundPixel(RgI c, float k, float floor_rg, float floor_i, float& mr,
                                   float& mg, float& mi, float& vr, float& vg, float& vi,
                                   float& sr, float& sg) {
  const float dr = c.r - mr, dg = c.g - mg, di = c.intensity - mi;
  mr += k * dr;
  mg += k * dg;
  mi += k * di;
  // Variance from the deviation to the previous mean, as in an exponential moving average.
  const float nvr = vr + k * (dr * dr - vr);
  const float nvg = vg + k * (dg * dg - vg);
  const float nvi = vi + k * (di * di - vi);
  vr = nvr > floor_rg ? nvr : floor_rg;
  vg = nvg > floor_rg ? nvg : floor_rg;
  vi = nvi > floor_i ? nvi : floor_i;
  sr = backgroundScale(vr);
  sg = backgroundScale(vg);
}

struct UpdateArgs {
  const std::uint8_t* rgb = nullptr;   // contiguous rgb8
  const std::uint8_t* mask = nullptr;  // width * height, nonzero = foreground; nullptr: none
  float alpha = 0.0f, floor_rg = 0.0f, floor_i = 0.0f;  // learning rate, variance floors
  MutableBackgroundPlanes background;
  int pixels = 0;
};

// Updates pixel i: one GPU thread.
PSFS_HD void updateThread(const UpdateArgs& a, int i) {
  const std::uint8_t* px = a.rgb + 3 * std::size_t(i);
  const RgI c = rgbToRgI(px[0], px[1], px[2]);
  const float k = a.mask ? updateWeight(a.mask[i], a.alpha) : a.alpha;
  const MutableBackgroundPlanes& P = a.background;
  updateBackgroundPixel(c, k, a.floor_rg, a.floor_i, P.mean_r[i], P.mean_g[i],
                        P.mean_intensity[i], P.var_r[i], P.var_g[i], P.var_intensity[i],
                        P.scale_r[i], P.scale_g[i]);
}

}  // namespace pixel
}  // namespace psfs
