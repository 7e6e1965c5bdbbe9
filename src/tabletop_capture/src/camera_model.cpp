#include "tabletop_capture/camera_model.h"

namespace tabletop_capture {

bool CameraModel::hasDistortion() const {
  for (double d : distortion)
    if (d != 0.0) return true;
  return false;
}

Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d& xn) const {
  const double k1 = distortion[0], k2 = distortion[1], p1 = distortion[2], p2 = distortion[3],
               k3 = distortion[4];
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  return {x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
          y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y};
}

Eigen::Vector2d CameraModel::undistort(const Eigen::Vector2d& xd) const {
  if (!hasDistortion()) return xd;
  // Fixed-point iteration x = (xd - tangential(x)) / radial(x), as cv::undistortPoints does,
  // followed by Newton polishing so the result inverts distort() to ~1e-12.
  Eigen::Vector2d x = xd;
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d d = distort(x);
    const Eigen::Vector2d err = xd - d;
    if (err.squaredNorm() < 1e-24) break;
    // Numerical Jacobian of distort (2x2); cheap and robust for plumb_bob.
    const double h = 1e-7;
    Eigen::Matrix2d J;
    J.col(0) = (distort(x + Eigen::Vector2d(h, 0)) - d) / h;
    J.col(1) = (distort(x + Eigen::Vector2d(0, h)) - d) / h;
    const double det = J.determinant();
    if (std::abs(det) < 1e-12) break;
    x += J.inverse() * err;
  }
  return x;
}

bool CameraModel::projectCamera(const Eigen::Vector3d& p, Eigen::Vector2d* pixel) const {
  if (!(p.z() > 1e-9)) return false;
  const Eigen::Vector2d xd = distort(Eigen::Vector2d(p.x() / p.z(), p.y() / p.z()));
  *pixel = Eigen::Vector2d(fx * xd.x() + cx, fy * xd.y() + cy);
  return true;
}

bool CameraModel::projectWorld(const Eigen::Vector3d& p_world, Eigen::Vector2d* pixel) const {
  const Eigen::Vector3d p_camera =
      world_T_camera.linear().transpose() * (p_world - world_T_camera.translation());
  return projectCamera(p_camera, pixel);
}

Eigen::Vector3d CameraModel::rayCamera(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d xd((pixel.x() - cx) / fx, (pixel.y() - cy) / fy);
  const Eigen::Vector2d xn = undistort(xd);
  return Eigen::Vector3d(xn.x(), xn.y(), 1.0).normalized();
}

Eigen::Vector3d CameraModel::rayWorld(const Eigen::Vector2d& pixel) const {
  return world_T_camera.linear() * rayCamera(pixel);
}

}  // namespace tabletop_capture
