// One camera's intrinsics from the YAML file that ROS's camera_calibration writes (and
// camera_info_url points to): image_width, image_height, camera_name, camera_matrix (3x3,
// row-major data), distortion_model (plumb_bob or none) and distortion_coefficients (5 values;
// rectification and projection matrices are ignored). The capture nodelet's alternative to a
// rig file when only camera_info is wanted (no pose). ROS-free.
#pragma once

#include <string>

#include "tabletop_capture/camera_model.h"

namespace tabletop_capture {

// Loads `path` (a plain path or a file:// URL). The camera is named `camera_name` with frame
// `<camera_name>_optical_frame`; the pose stays identity. Throws RigError naming the file and
// the field, and checks the intrinsics like the rig loader (validateCamera).
CameraModel loadCameraCalibrationYaml(const std::string& path, const std::string& camera_name);

}  // namespace tabletop_capture
