// A MultiViewFrame (DESIGN.md section 3) as the core types: the images wrapped as rgb8 cv::Mats
// (no pixel copy) and a CameraModel per camera, after checking the bundle against its contract.
// Shared by the stages that consume /tabletop/frames.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <tabletop_msgs/MultiViewFrame.h>

#include "tabletop_capture/camera_model.h"

namespace tabletop_capture {

// False, with the reason (naming the camera), for an inconsistent bundle (array sizes), an image
// that is not a complete rgb8 buffer, an invalid camera_info or a non-finite / non-unit pose, or
// a set with no image at all. A camera missing from a degraded set (empty image,
// MultiViewFrame.msg) gets an empty Mat and its camera model.
// The Mats point into `frame`'s buffers: they are valid, read-only, while the message lives.
bool unpackFrameSet(const tabletop_msgs::MultiViewFrame& frame, std::vector<cv::Mat>* rgb,
                    std::vector<CameraModel>* cameras, std::string* why);

}  // namespace tabletop_capture
