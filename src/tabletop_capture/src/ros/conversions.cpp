#include "tabletop_capture/ros/conversions.h"

#include <cmath>
#include <cstring>

namespace tabletop_capture {

sensor_msgs::CameraInfo toCameraInfo(const CameraModel& c) {
  sensor_msgs::CameraInfo info;
  info.header.frame_id = c.frame_id;
  info.width = c.width;
  info.height = c.height;
  info.distortion_model = "plumb_bob";
  info.D.assign(c.distortion.begin(), c.distortion.end());
  info.K = {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {c.fx, 0, c.cx, 0, 0, c.fy, c.cy, 0, 0, 0, 1, 0};
  return info;
}

bool fromCameraInfo(const sensor_msgs::CameraInfo& info, CameraModel* c, std::string* why) {
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (info.width == 0 || info.height == 0) return fail("camera_info has zero width or height");
  for (double k : info.K)
    if (!std::isfinite(k)) return fail("camera_info K holds non-finite values");
  if (!(info.K[0] > 0) || !(info.K[4] > 0)) return fail("camera_info K has a zero focal length");
  std::array<double, 5> d{{0, 0, 0, 0, 0}};
  if (!info.D.empty()) {
    if (info.distortion_model != "plumb_bob" && info.distortion_model != "rational_polynomial")
      return fail("unsupported distortion model '" + info.distortion_model + "'");
    if (info.distortion_model == "rational_polynomial") {
      for (size_t i = 5; i < info.D.size(); ++i)
        if (info.D[i] != 0.0)
          return fail("rational_polynomial with non-zero k4..k6 is not supported");
    }
    for (size_t i = 0; i < info.D.size() && i < 5; ++i) {
      if (!std::isfinite(info.D[i])) return fail("camera_info D holds non-finite values");
      d[i] = info.D[i];
    }
  }
  c->width = static_cast<int>(info.width);
  c->height = static_cast<int>(info.height);
  c->fx = info.K[0];
  c->fy = info.K[4];
  c->cx = info.K[2];
  c->cy = info.K[5];
  c->distortion = d;
  if (!info.header.frame_id.empty()) c->frame_id = info.header.frame_id;
  return true;
}

geometry_msgs::Transform toTransform(const Eigen::Isometry3d& pose) {
  geometry_msgs::Transform t;
  const Eigen::Quaterniond q(pose.linear());
  t.translation.x = pose.translation().x();
  t.translation.y = pose.translation().y();
  t.translation.z = pose.translation().z();
  t.rotation.w = q.w();
  t.rotation.x = q.x();
  t.rotation.y = q.y();
  t.rotation.z = q.z();
  return t;
}

bool fromTransform(const geometry_msgs::Transform& t, Eigen::Isometry3d* pose) {
  const Eigen::Quaterniond q(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
  const Eigen::Vector3d p(t.translation.x, t.translation.y, t.translation.z);
  if (!p.allFinite() || !q.coeffs().allFinite()) return false;
  if (std::abs(q.norm() - 1.0) > 1e-3) return false;
  pose->setIdentity();
  pose->linear() = q.normalized().toRotationMatrix();
  pose->translation() = p;
  return true;
}

void toImageMsg(const cv::Mat& image, const std::string& encoding, sensor_msgs::Image* msg) {
  msg->encoding = encoding;
  msg->width = image.cols;
  msg->height = image.rows;
  msg->is_bigendian = 0;
  msg->step = static_cast<uint32_t>(image.cols * image.elemSize());
  msg->data.resize(static_cast<size_t>(msg->step) * image.rows);
  for (int r = 0; r < image.rows; ++r)
    std::memcpy(&msg->data[static_cast<size_t>(r) * msg->step], image.ptr(r), msg->step);
}

}  // namespace tabletop_capture
