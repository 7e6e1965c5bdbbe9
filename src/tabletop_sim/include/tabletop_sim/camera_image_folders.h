// Rendered images written as the per-camera PNG sequences that the rig calibration tools
// (calibrate_extrinsics, align_rig_to_marker) and the CameraCapture nodelet's file source read:
// DIR/<camera name>/NNNNN.png, the same number in every folder = the same instant. ROS-free.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "tabletop_capture/rig_description.h"

namespace tabletop_sim {

// Creates DIR/<camera name> for every camera of the rig. Throws std::runtime_error naming the
// folder that cannot be created.
void makeCameraFolders(const std::string& dir, const tabletop_capture::RigDescription& rig);

// Writes an rgb8 image as DIR/<camera>/NNNNN.png (frame zero-padded to 5 digits). Throws
// std::runtime_error naming the file that cannot be written.
void writeCameraImage(const std::string& dir, const std::string& camera, int frame, const cv::Mat& rgb);

}  // namespace tabletop_sim
