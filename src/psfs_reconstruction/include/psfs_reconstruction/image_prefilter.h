// The noise filter every camera image passes before the background model and the pixel
// classifier see it (both: the model's variances must be those of the pixels it classifies).
//
// Why: the classifier's evidence is the pixel's distance from its background Gaussian in
// normalised rg and intensity. Sensor noise of 2-4 levels per channel on a pixel of intensity
// 50 (dark clothes, a dimly lit desk) gives r and g a standard deviation of 0.015-0.03, as wide
// as the difference between a dark sleeve and a dark chair, or between a brown hand and a wooden
// desk (0.01-0.02). A 3x3 median over each channel cuts that noise by about 2.4 without moving
// edges (a mean would smear a face's skin chroma a pixel into dark hair around it and grow the
// skin hull), and a 15.6 mm voxel spans 3-8 pixels.
// Off by default: measured on 72 generated scenarios (docs/benchmarks.md, "MPF: the head's
// birth behind long hair; pSfS: a noise filter before the classifier"), a 3x3 median lowered
// the MPF's hand error in every set of 24 (medians 30.7 / 59.3 / 35.3 -> 23.0 / 44.8 / 34.8
// mm) and raised body IoU in two (0.506 / 0.499 -> 0.524 / 0.531), but the gain is on noisy
// cameras: with sensor noise under ~1.75 levels it made 7 of 20 scenarios' hands worse and 2
// better, and on the default rig (noise 2.0) the hands went 7.3 -> 8.1 mm (the design bar is
// 8) and the skin IoU 0.33-0.38 -> 0.28-0.30 (a more complete, hence fuller, skin hull); the
// noise of raw pixels had carved some of the hull's phantom voxels at random. The thesis
// classifies raw pixels. Next: choose it per camera from the learned noise.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace psfs {

enum class ImagePrefilter {
  kNone,    // raw pixels (the thesis)
  kMedian,  // per-channel median over a size x size window (cv::medianBlur)
  kBox,     // per-channel mean over a size x size window (cv::blur): more noise removed, but
            // edges smeared by a pixel
};

struct ImagePrefilterParams {
  ImagePrefilter type = ImagePrefilter::kNone;
  int size = 3;  // window edge (px): odd, 3-7; unused with kNone
  // Throws std::invalid_argument naming the field.
  void validate() const;
};

// "none", "median", "box"; throws std::invalid_argument for anything else.
ImagePrefilter parseImagePrefilter(const std::string& name);
const char* imagePrefilterName(ImagePrefilter type);
// What the filter does, for logs, diagnostics and saved background models: "none", or the
// name and window ("median 3x3"); the size is left out with kNone (it is unused there).
std::string describeImagePrefilter(const ImagePrefilterParams& params);

// Filters each non-empty rgb8 image of `rgb` into (*out)[i] (an empty image stays empty; kNone
// copies the header, not the pixels). OpenMP over the images with num_threads (<= 0: OpenMP
// default). `out` must not alias `rgb`.
void prefilterImages(const std::vector<cv::Mat>& rgb, const ImagePrefilterParams& params,
                     std::vector<cv::Mat>* out, int num_threads = 0);

}  // namespace psfs
