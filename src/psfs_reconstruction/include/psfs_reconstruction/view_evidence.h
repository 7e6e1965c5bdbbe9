// The per-frame input of fusion: one likelihood image per camera, converted once per frame and
// class into the forms the fusion loops read, and then shared by every grid fused from that
// frame (the tracking volume and the hand sub-volumes).
//
//  * terms: per pixel the fixed-point log term round(1024 * ln P), or +1 ("no evidence") where
//    the pixel is switched off, plus one guard pixel after the image that is always +1. Unobserved
//    voxels point at the guard (PackedUV), so the single-projection loop is one gather and a few
//    adds per voxel and camera. The log turns the product over cameras into a sum; doing it per
//    pixel (77k per camera) instead of per voxel and camera (1.6M at 128x128x96) saves a lookup.
//  * pairs (multi-projection only): per pixel its byte and the byte below it, 16 bits, with a
//    replicated border. One 32-bit load at pixel (u, v) reads two neighbouring pairs, i.e. the
//    whole 2x2 neighbourhood, so a bilinear sample is one 32-bit gather plus two multiply-adds
//    (what the thesis got from the GPU's texture unit). Two bytes per pixel rather than a
//    packed 2x2 quad per pixel keeps the 8 views' images (1.4 MB) near the core's L2.
//  * likelihood: the plain bytes, for the reference variants (all-classes, binary SfS).
//  * footprint levels (FootprintFilter; ReconstructorParams body/skin.footprint): terms holds L term
//    images one above the other, level l at row l * (height + 1) (each followed by a guard row
//    of "no evidence"): level 0 the plain terms, level l the terms of the likelihood filtered
//    over a (2l + 1)^2 window. A projection table built with footprint levels points each voxel
//    at the level of its projected size, so the single-projection kernel reads the footprint's
//    statistic with one lookup (see ProjectionTableOptions::footprint_levels).
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace psfs {

struct ViewImage {
  // round(255 * P(class | colour)) per pixel. CV_8UC1, or a multi-channel CV_8U image with
  // `channel` selecting the class: the classifier's CV_8UC2 has 0 = P'(F|c) (body volumes) and
  // 1 = P'(F,S|c) (skin volumes).
  cv::Mat likelihood;
  int channel = 0;
  // Optional CV_8UC1 of the same size: 0 = pixel switched off (known occluded, or masked out);
  // such a pixel gives no evidence at all, as if the voxel were outside that camera's image.
  cv::Mat active;
};

// Footprint statistic over a (2l + 1)^2 window, replicated border. Both are exact integer
// arithmetic (every instruction-set clone gives the same bytes):
//  * kMedian: separable median (the median of the 2l + 1 row medians: a close, much cheaper
//    stand-in for the 2-D median), taken on the log terms directly (the median commutes with
//    the monotone byte -> term map, so no second table lookup per pixel and level);
//  * kMean: box mean of the likelihood bytes, rounded to the nearest byte, then the term.
// The active mask is applied after filtering, at each level's centre pixel (the face samples
// of the multi-projection test ignore it the same way).
enum class FootprintStatistic { kMedian, kMean };
struct FootprintFilter {
  int levels = 0;  // 0 = no footprint levels; else 2..3 (must cover the table's)
  FootprintStatistic statistic = FootprintStatistic::kMedian;
};

class ViewEvidence {
 public:
  static constexpr int kLogScale = 1024;   // fixed-point scale of the log terms
  static constexpr int16_t kNoEvidence = 1;  // term of a switched-off pixel and of the guard
  static constexpr int kQuadPad = 8;       // replicated border of the pair images (pixels)

  // Validates and converts one frame set (one image per camera, in the cameras' order).
  // bilinear: also build the quad images (needed by the multi-projection test).
  // Throws std::invalid_argument naming the view and the problem (empty image, not 8-bit,
  // channel out of range, mask of another size or type, side above PackedUV::kMaxImageSide = 4080 px).
  void set(const std::vector<ViewImage>& views, bool bilinear, int threads = 0);
  // The same, with footprint levels (throws std::invalid_argument if footprint.levels is not
  // 0 or 2..3, or an image is too high for them: (height + 1) * levels <= 4095).
  void set(const std::vector<ViewImage>& views, bool bilinear, int threads,
           const FootprintFilter& footprint);

  int numViews() const { return static_cast<int>(views_.size()); }
  int width(int v) const { return views_[v].width; }
  int height(int v) const { return views_[v].height; }
  bool bilinear() const { return bilinear_; }
  const FootprintFilter& footprint() const { return footprint_; }

  // Kernel access. terms/likelihood have width*height + 1 entries (the last is the guard) and
  // are readable 4 bytes past it (gathers load 32 bits). With footprint levels, terms has
  // levels * (height + 1) rows (see the file comment), also readable 4 bytes past the end.
  const int16_t* terms(int v) const { return views_[v].terms.data(); }
  const uint8_t* likelihood(int v) const { return views_[v].likelihood.data(); }
  // pairs[(v + kQuadPad) * quadStride + u + kQuadPad] = L(u, v) | L(u, v + 1) << 8, with u, v
  // clamped to the image; readable one entry past the end.
  const uint16_t* pairs(int v) const { return views_[v].pairs.data(); }
  int quadStride(int v) const { return views_[v].width + 2 * kQuadPad; }
  // True if some pixel of view v is switched off by its active mask.
  bool hasInactivePixels(int v) const { return views_[v].inactive_pixels > 0; }
  // Pixel index (or the guard) gives evidence.
  bool observed(int v, int pixel_index) const { return views_[v].terms[pixel_index] <= 0; }

  // round(kLogScale * ln(max(byte, 0.5) / 255)): a byte of 0 is read as half a quantisation step
  // rather than as impossible, so one bad pixel lowers a voxel but cannot veto it outright.
  static int16_t logTerm(int byte);

 private:
  struct View {
    int width = 0, height = 0;
    size_t inactive_pixels = 0;
    std::vector<int16_t> terms;
    std::vector<uint8_t> likelihood;
    std::vector<uint16_t> pairs;
  };
  std::vector<View> views_;
  bool bilinear_ = false;
  FootprintFilter footprint_;
};

}  // namespace psfs
