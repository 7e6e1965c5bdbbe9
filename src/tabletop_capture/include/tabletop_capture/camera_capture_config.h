// The camera capture nodelet's parameter file (config/camera_capture.yaml, which documents each
// key), read through the strict loader every stage uses (tabletop_common/config_schema.h), and
// the checks that need no ROS: values in range, and the rig camera's size against the output.
#pragma once

#include <string>

#include "tabletop_capture/camera_model.h"
#include "tabletop_capture/frame_source.h"
#include "tabletop_capture/half_resolution_debayer.h"
#include "tabletop_common/config_schema.h"

namespace tabletop_capture {

struct CameraCaptureConfig {
  std::string device = "/dev/video0";  // or a /dev/v4l/by-id/... path, or file:<path|pattern>
  std::string camera_name = "cam0";
  std::string rig_file = "";          // "" = no camera_info (unless camera_info_file)
  std::string camera_info_file = "";  // camera_calibration YAML (path or file:// URL)
  int width = 640;
  int height = 480;
  double fps = 25.0;
  std::string fourcc = "";
  double exposure = -1;
  double gain = -1;
  double white_balance = -1;
  std::string bayer = "none";
  bool half_resolution = false;
  bool loop = true;
  std::string trigger = "none";
  double reopen_interval = 2.0;  // s
  int queue_size = 4;

  // Throws std::invalid_argument "<key>: <problem>" for values out of range.
  void validate() const;
  BayerPattern bayerPattern() const;  // after validate()
  int outputWidth() const { return half_resolution ? width / 2 : width; }
  int outputHeight() const { return half_resolution ? height / 2 : height; }
  // The source's settings (device, size, rate, controls, raw data when bayer is set).
  FrameSourceSettings sourceSettings() const;
};

void addCameraCaptureKeys(CameraCaptureConfig* c, tabletop_common::ConfigSchema* s);

// The file alone, checked. Throws std::runtime_error "<path>: <key>: <problem>".
CameraCaptureConfig loadCameraCaptureConfig(const std::string& path);

// "" when the calibrated camera's size is the size the nodelet publishes, otherwise the error
// (the calibration would not fit the images: with half_resolution it must be the half size).
// `source` names the rig or calibration file in the error.
std::string checkRigCameraSize(const CameraModel& camera, const CameraCaptureConfig& c,
                               const std::string& source);

}  // namespace tabletop_capture
