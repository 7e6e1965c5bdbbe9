#include "tabletop_capture/calibration/light_images.h"

#include <algorithm>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

namespace tabletop_capture {
namespace {

std::string baseName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

}  // namespace

LightImages detectLightInImages(const std::vector<std::string>& camera_names, const std::string& dir,
                                const LightBlobOptions& options,
                                const std::function<void(int, const LightImagesCamera&)>& progress) {
  std::vector<std::vector<std::string>> files(camera_names.size());
  LightImages result;
  for (size_t c = 0; c < camera_names.size(); ++c) {
    std::vector<cv::String> found;
    try {
      cv::glob(dir + "/" + camera_names[c] + "/*.png", found, false);
    } catch (const cv::Exception&) {
      // No such directory: the camera has no images (and says so in its statistics).
    }
    files[c].assign(found.begin(), found.end());
    std::sort(files[c].begin(), files[c].end());
    for (const auto& f : files[c]) result.instants.push_back(baseName(f));
  }
  std::sort(result.instants.begin(), result.instants.end());
  result.instants.erase(std::unique(result.instants.begin(), result.instants.end()), result.instants.end());
  if (result.instants.empty())
    throw std::runtime_error("no PNG image in " + dir + "/<camera name>/ for any camera of the rig");
  result.track = LightTrack(camera_names);
  result.cameras.resize(camera_names.size());
  for (size_t c = 0; c < camera_names.size(); ++c) {
    LightImagesCamera& stats = result.cameras[c];
    for (const auto& f : files[c]) {
      const cv::Mat image = cv::imread(f, cv::IMREAD_ANYCOLOR);
      if (image.empty()) throw std::runtime_error("cannot read " + f);
      ++stats.images;
      const LightBlob blob = detectLightBlob(image, options);
      if (!blob.found) {
        ++stats.rejected[blob.rejected.substr(0, blob.rejected.find(" ("))];
        continue;
      }
      const auto frame = std::lower_bound(result.instants.begin(), result.instants.end(), baseName(f));
      result.track.add(static_cast<int>(frame - result.instants.begin()), static_cast<int>(c), blob.pixel);
      ++stats.found;
    }
    if (progress) progress(static_cast<int>(c), stats);
  }
  return result;
}

}  // namespace tabletop_capture
