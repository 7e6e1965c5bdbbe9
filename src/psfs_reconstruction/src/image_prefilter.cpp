#include "psfs_reconstruction/image_prefilter.h"

#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "cpu_dispatch.h"

namespace psfs {

void ImagePrefilterParams::validate() const {
  if (type == ImagePrefilter::kNone) return;
  if (size < 3 || size > 7 || size % 2 == 0)
    throw std::invalid_argument("psfs::ImagePrefilterParams: prefilter_size must be 3, 5 or 7");
}

ImagePrefilter parseImagePrefilter(const std::string& name) {
  if (name == "none") return ImagePrefilter::kNone;
  if (name == "median") return ImagePrefilter::kMedian;
  if (name == "box") return ImagePrefilter::kBox;
  throw std::invalid_argument("'" + name + "' is not none, median or box");
}

const char* imagePrefilterName(ImagePrefilter type) {
  switch (type) {
    case ImagePrefilter::kMedian: return "median";
    case ImagePrefilter::kBox: return "box";
    default: return "none";
  }
}

std::string describeImagePrefilter(const ImagePrefilterParams& params) {
  if (params.type == ImagePrefilter::kNone) return "none";
  const std::string n = std::to_string(params.size);
  return std::string(imagePrefilterName(params.type)) + " " + n + "x" + n;
}

void prefilterImages(const std::vector<cv::Mat>& rgb, const ImagePrefilterParams& params,
                     std::vector<cv::Mat>* out, int num_threads) {
  params.validate();
  // Checked here: an OpenCV exception inside the OpenMP region would end the process.
  for (size_t i = 0; i < rgb.size(); ++i)
    if (!rgb[i].empty() && rgb[i].type() != CV_8UC3)
      throw std::invalid_argument("prefilterImages: image " + std::to_string(i) + " is not rgb8");
  out->resize(rgb.size());
  const int n = static_cast<int>(rgb.size());
  if (params.type == ImagePrefilter::kNone) {
    for (int i = 0; i < n; ++i) (*out)[i] = rgb[i];
    return;
  }
  // One image per thread (8 images of a set on 2 cores: no finer split needed).
#pragma omp parallel for schedule(dynamic) num_threads(resolveThreads(num_threads))
  for (int i = 0; i < n; ++i) {
    cv::Mat& dst = (*out)[i];
    // A buffer shared with anyone else (e.g. a header on a caller's image left by kNone) is
    // not written into.
    if (rgb[i].empty() || (dst.u && dst.u->refcount > 1)) dst.release();
    if (rgb[i].empty()) continue;
    if (params.type == ImagePrefilter::kMedian)
      cv::medianBlur(rgb[i], dst, params.size);
    else
      cv::blur(rgb[i], dst, cv::Size(params.size, params.size), cv::Point(-1, -1),
               cv::BORDER_REPLICATE);
  }
}

}  // namespace psfs
