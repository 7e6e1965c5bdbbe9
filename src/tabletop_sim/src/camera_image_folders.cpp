#include "tabletop_sim/camera_image_folders.h"

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <system_error>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace tabletop_sim {

void makeCameraFolders(const std::string& dir, const tabletop_capture::RigDescription& rig) {
  for (const auto& cam : rig.cameras) {
    const std::string folder = dir + "/" + cam.name;
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec) throw std::runtime_error("cannot create " + folder + ": " + ec.message());
  }
}

void writeCameraImage(const std::string& dir, const std::string& camera, int frame, const cv::Mat& rgb) {
  char name[32];
  std::snprintf(name, sizeof name, "/%05d.png", frame);
  const std::string path = dir + "/" + camera + name;
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  if (!cv::imwrite(path, bgr)) throw std::runtime_error("cannot write " + path);
}

}  // namespace tabletop_sim
