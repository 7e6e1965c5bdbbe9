// Conversions between the ROS-free core types and ROS messages (ROS layer only).
#pragma once

#include <string>

#include <geometry_msgs/Transform.h>
#include <opencv2/core.hpp>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "tabletop_capture/camera_model.h"

namespace tabletop_capture {

// CameraInfo (K, D plumb_bob or empty, width, height) + the camera's pose in world.
sensor_msgs::CameraInfo toCameraInfo(const CameraModel& camera);
// Fills intrinsics from a CameraInfo. Returns false (and says why) for zero focal lengths,
// non-finite values, an unknown distortion model or zero image size.
bool fromCameraInfo(const sensor_msgs::CameraInfo& info, CameraModel* camera, std::string* why);

geometry_msgs::Transform toTransform(const Eigen::Isometry3d& pose);
// Returns false if the transform holds non-finite values or a non-unit quaternion.
bool fromTransform(const geometry_msgs::Transform& t, Eigen::Isometry3d* pose);

// Copies a CV_8UC3 (rgb8), CV_8UC1 (mono8 or the given Bayer encoding) image into a message.
void toImageMsg(const cv::Mat& image, const std::string& encoding, sensor_msgs::Image* msg);

}  // namespace tabletop_capture
