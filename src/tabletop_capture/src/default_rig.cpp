#include "tabletop_capture/default_rig.h"

#include <cmath>
#include <stdexcept>

namespace tabletop_capture {

Eigen::Isometry3d lookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - center).normalized();
  Eigen::Vector3d up(0, 0, 1);
  if (std::abs(z.dot(up)) > 0.999) up = Eigen::Vector3d(0, 1, 0);
  const Eigen::Vector3d x = z.cross(up).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = center;
  return T;
}

double focalToFit(const CameraModel& cam, const Eigen::AlignedBox3d& box, double margin,
                  double aspect) {
  double f = 1e9;
  const Eigen::Isometry3d camera_T_world = cam.world_T_camera.inverse();
  const double room_x = std::min(cam.cx, cam.width - 1 - cam.cx) - margin;
  const double room_y = std::min(cam.cy, cam.height - 1 - cam.cy) - margin;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d p =
        camera_T_world * box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k));
    if (!(p.z() > 1e-6)) throw std::invalid_argument("focalToFit: a box corner is behind the camera");
    const double x = std::abs(p.x() / p.z()), y = std::abs(p.y() / p.z());
    if (x > 1e-9) f = std::min(f, room_x / x);
    if (y > 1e-9) f = std::min(f, room_y / y / aspect);
  }
  return f;
}

RigDescription makeDefaultRig(const DefaultRigOptions& o) {
  if (o.num_cameras < 1 || o.num_cameras > 16)
    throw std::invalid_argument("makeDefaultRig: num_cameras must be in 1..16");
  if (o.width < 16 || o.height < 16)
    throw std::invalid_argument("makeDefaultRig: image size must be at least 16x16");
  RigDescription rig;
  rig.name = "tabletop_sim";
  rig.world_frame = "world";
  // Azimuths (degrees about world z, 0 = +x = user's right, -90 = behind the user): 8 slots
  // over the 260 degrees in front of and beside the user; fewer cameras take a spread subset.
  const double slots[8] = {-40, 0, 35, 70, 110, 145, 180, 220};
  const Eigen::Vector3d target(0.0, -0.05, 0.25);
  const double scale = o.width / 320.0;
  for (int i = 0; i < o.num_cameras; ++i) {
    const double slot = (o.num_cameras <= 8) ? slots[(i * 8) / o.num_cameras]
                                             : -40.0 + 260.0 * i / (o.num_cameras - 1);
    const double az = slot * M_PI / 180.0;
    const double radius = 1.35 + 0.05 * (i % 3);
    const double height = (i % 2 == 0) ? 1.05 : 1.4;
    const Eigen::Vector3d c(radius * std::cos(az), -0.05 + radius * std::sin(az), height);
    CameraModel cam;
    cam.name = "cam" + std::to_string(i);
    cam.frame_id = cam.name + "_optical_frame";
    cam.width = o.width;
    cam.height = o.height;
    cam.cx = (o.width - 1) / 2.0 + 1.5 * ((i % 3) - 1) * scale;
    cam.cy = (o.height - 1) / 2.0 - 1.0 * ((i % 2) ? 1 : -1) * scale;
    if (o.distortion)
      cam.distortion = {{-0.12 + 0.01 * (i % 3), 0.03, 4e-4 * ((i % 2) ? 1 : -1), -3e-4, 0.0}};
    cam.world_T_camera = lookAt(c, target);
    // Zoom so that the whole workspace box fills the sensor (thesis 4.1: "the whole sensor
    // area is exposed to user space"): the largest focal length that keeps every corner of the
    // box 4 px inside the image without distortion (barrel distortion only pulls corners in).
    const double f = focalToFit(
        cam, Eigen::AlignedBox3d(Eigen::Vector3d(-0.5, -0.5, 0.0), Eigen::Vector3d(0.5, 0.5, 0.75)),
        4.0 * scale);
    cam.fx = f;
    cam.fy = f * 1.002;
    rig.cameras.push_back(cam);
  }
  return rig;
}

}  // namespace tabletop_capture
