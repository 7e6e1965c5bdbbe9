#include "tabletop_capture/calibration/camera_pose_errors.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>

namespace tabletop_capture {
namespace {

const CameraModel& referenceOf(const CameraModel& camera, const RigDescription& reference) {
  const int i = reference.findCamera(camera.name);
  if (i < 0) throw std::invalid_argument("the reference rig has no camera '" + camera.name + "'");
  return reference.cameras[i];
}

}  // namespace

std::vector<CameraPoseError> cameraPoseErrors(const RigDescription& rig, const RigDescription& reference,
                                              const Eigen::Matrix4d& similarity) {
  const double scale = similarity.block<3, 1>(0, 0).norm();
  const Eigen::Matrix3d rotation = similarity.block<3, 3>(0, 0) / scale;
  const Eigen::Vector3d translation = similarity.block<3, 1>(0, 3);
  std::vector<CameraPoseError> errors;
  for (const auto& c : rig.cameras) {
    const Eigen::Isometry3d& e = c.world_T_camera;
    const Eigen::Isometry3d& t = referenceOf(c, reference).world_T_camera;
    CameraPoseError err;
    err.camera = c.name;
    err.position_m = (scale * rotation * e.translation() + translation - t.translation()).norm();
    err.rotation_deg = Eigen::AngleAxisd(t.linear().transpose() * rotation * e.linear()).angle() * 180 / M_PI;
    errors.push_back(err);
  }
  return errors;
}

Eigen::Matrix4d cameraCentreSimilarity(const RigDescription& rig, const RigDescription& reference) {
  const int n = static_cast<int>(rig.cameras.size());
  Eigen::Matrix3Xd from(3, n), to(3, n);
  for (int c = 0; c < n; ++c) {
    from.col(c) = rig.cameras[c].center();
    to.col(c) = referenceOf(rig.cameras[c], reference).center();
  }
  return Eigen::umeyama(from, to, true);
}

CameraPoseError worstPoseError(const std::vector<CameraPoseError>& errors) {
  CameraPoseError worst;
  worst.camera = "worst";
  for (const auto& e : errors) {
    worst.position_m = std::max(worst.position_m, e.position_m);
    worst.rotation_deg = std::max(worst.rotation_deg, e.rotation_deg);
  }
  return worst;
}

}  // namespace tabletop_capture
