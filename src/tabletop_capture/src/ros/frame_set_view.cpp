#include "tabletop_capture/ros/frame_set_view.h"

#include "tabletop_capture/ros/conversions.h"

namespace tabletop_capture {

bool unpackFrameSet(const tabletop_msgs::MultiViewFrame& f, std::vector<cv::Mat>* rgb,
                    std::vector<CameraModel>* cams, std::string* why) {
  const size_t n = f.images.size();
  if (n == 0 || f.camera_infos.size() != n || f.camera_poses.size() != n ||
      f.camera_names.size() != n) {
    *why = "inconsistent bundle (" + std::to_string(n) + " images, " +
           std::to_string(f.camera_infos.size()) + " camera_infos, " +
           std::to_string(f.camera_poses.size()) + " poses, " +
           std::to_string(f.camera_names.size()) + " names)";
    return false;
  }
  size_t missing_views = 0;
  for (size_t i = 0; i < n; ++i) {
    const auto& im = f.images[i];
    const std::string& name = f.camera_names[i];
    if (im.encoding != "rgb8") {
      *why = name + ": encoding '" + im.encoding + "', expected rgb8";
      return false;
    }
    const bool missing = im.width == 0 && im.height == 0 && im.data.empty();
    if (!missing && (im.width == 0 || im.height == 0 || im.step < 3 * im.width ||
                     im.data.size() < size_t(im.step) * im.height)) {
      *why = name + ": image buffer too small for " + std::to_string(im.width) + "x" +
             std::to_string(im.height) + " rgb8";
      return false;
    }
    missing_views += missing;
    CameraModel cam;
    std::string reason;
    if (!fromCameraInfo(f.camera_infos[i], &cam, &reason)) {
      *why = name + ": invalid camera_info: " + reason;
      return false;
    }
    if (!fromTransform(f.camera_poses[i], &cam.world_T_camera)) {
      *why = name + ": camera pose is not finite or its quaternion is not unit";
      return false;
    }
    cam.name = name;
    cam.frame_id = f.camera_infos[i].header.frame_id;
    cams->push_back(cam);
    if (missing)
      rgb->emplace_back();
    else
      rgb->emplace_back(im.height, im.width, CV_8UC3, const_cast<uint8_t*>(im.data.data()), im.step);
  }
  if (missing_views == n) {
    *why = "no camera delivered an image";
    return false;
  }
  return true;
}

}  // namespace tabletop_capture
