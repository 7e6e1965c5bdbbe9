// Pinhole camera with plumb_bob (Brown-Conrady) distortion and its pose in the world frame.
// ROS-free; the single camera model every stage uses for projection.
#pragma once

#include <array>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace tabletop_capture {

struct CameraModel {
  std::string name;      // e.g. "cam0"
  std::string frame_id;  // e.g. "cam0_optical_frame" (REP 103: z forward, x right, y down)
  int width = 0;         // pixels
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;  // pixels
  // plumb_bob coefficients k1, k2, p1, p2, k3 (all zero = no distortion).
  std::array<double, 5> distortion{{0, 0, 0, 0, 0}};
  // Pose of the optical frame in world: p_world = world_T_camera * p_camera.
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();

  bool hasDistortion() const;
  Eigen::Vector3d center() const { return world_T_camera.translation(); }
  Eigen::Isometry3d cameraTWorld() const { return world_T_camera.inverse(); }

  // Normalised image coordinates (x/z, y/z) -> distorted normalised coordinates.
  Eigen::Vector2d distort(const Eigen::Vector2d& xn) const;
  // Inverse of distort() by fixed-point iteration (converges for the mild distortion of
  // real lenses; the residual is below 1e-9 in normalised units after the loop).
  Eigen::Vector2d undistort(const Eigen::Vector2d& xd) const;

  // Camera-frame point -> pixel (with distortion). False if the point is not in front
  // (z <= 1e-9); *pixel is then left unchanged.
  bool projectCamera(const Eigen::Vector3d& p_camera, Eigen::Vector2d* pixel) const;
  // World point -> pixel (with distortion). Same contract as projectCamera.
  bool projectWorld(const Eigen::Vector3d& p_world, Eigen::Vector2d* pixel) const;
  // Pixel -> unit ray direction in the camera frame (distortion removed).
  Eigen::Vector3d rayCamera(const Eigen::Vector2d& pixel) const;
  // Pixel -> unit ray direction in the world frame; the ray starts at center().
  Eigen::Vector3d rayWorld(const Eigen::Vector2d& pixel) const;
  // True if the pixel coordinate lies inside [0,width) x [0,height).
  bool inImage(const Eigen::Vector2d& pixel) const {
    return pixel.x() >= 0 && pixel.y() >= 0 && pixel.x() < width && pixel.y() < height;
  }
};

}  // namespace tabletop_capture
