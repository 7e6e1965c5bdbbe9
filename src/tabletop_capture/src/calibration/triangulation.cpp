#include "tabletop_capture/calibration/triangulation.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

namespace tabletop_capture {
namespace {

// Residuals (projection - pixel) stacked, false if the point is behind a camera.
bool residuals(const std::vector<const CameraModel*>& cameras, const std::vector<Eigen::Vector2d>& pixels,
               const Eigen::Vector3d& X, Eigen::VectorXd* r) {
  r->resize(2 * cameras.size());
  for (size_t i = 0; i < cameras.size(); ++i) {
    Eigen::Vector2d q;
    if (!cameras[i]->projectWorld(X, &q)) return false;
    r->segment<2>(2 * i) = q - pixels[i];
  }
  return true;
}

}  // namespace

Eigen::Vector4d triangulateLinear(const std::vector<Eigen::Isometry3d>& camera_T_world,
                                  const std::vector<Eigen::Vector2d>& normalised) {
  if (camera_T_world.size() != normalised.size()) throw std::invalid_argument("triangulateLinear: size mismatch");
  // DLT: x (P3 X) - P1 X = 0, y (P3 X) - P2 X = 0 with P = [R | t] (camera_T_world) and (x, y)
  // the undistorted normalised coordinates; the homogeneous solution by SVD.
  Eigen::MatrixXd A(2 * normalised.size(), 4);
  for (size_t i = 0; i < normalised.size(); ++i) {
    const Eigen::Matrix<double, 3, 4> P = camera_T_world[i].matrix().topRows<3>();
    A.row(2 * i) = normalised[i].x() * P.row(2) - P.row(0);
    A.row(2 * i + 1) = normalised[i].y() * P.row(2) - P.row(1);
  }
  return Eigen::JacobiSVD<Eigen::MatrixXd>(A, Eigen::ComputeFullV).matrixV().col(3);
}

Triangulation triangulatePoint(const std::vector<const CameraModel*>& cameras,
                               const std::vector<Eigen::Vector2d>& pixels, int iterations) {
  if (cameras.size() != pixels.size()) throw std::invalid_argument("triangulatePoint: size mismatch");
  Triangulation t;
  const size_t n = cameras.size();
  if (n < 2) return t;
  std::vector<Eigen::Isometry3d> poses(n);
  std::vector<Eigen::Vector2d> normalised(n);
  for (size_t i = 0; i < n; ++i) {
    const CameraModel& c = *cameras[i];
    normalised[i] = c.undistort(Eigen::Vector2d((pixels[i].x() - c.cx) / c.fx, (pixels[i].y() - c.cy) / c.fy));
    poses[i] = c.cameraTWorld();
  }
  const Eigen::Vector4d h = triangulateLinear(poses, normalised);
  if (std::abs(h(3)) < 1e-15) return t;
  Eigen::Vector3d X = h.head<3>() / h(3);
  Eigen::VectorXd r;
  if (!residuals(cameras, pixels, X, &r)) return t;
  // Gauss-Newton with a numerical Jacobian (3 unknowns; the step scales with the distance).
  double scale = 0;
  for (const auto* c : cameras) scale = std::max(scale, (c->center() - X).norm());
  const double eps = 1e-7 * std::max(scale, 1e-9);
  for (int it = 0; it < iterations; ++it) {
    Eigen::MatrixXd J(2 * n, 3);
    bool ok = true;
    for (int k = 0; k < 3 && ok; ++k) {
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      d(k) = eps;
      Eigen::VectorXd rp, rm;
      ok = residuals(cameras, pixels, X + d, &rp) && residuals(cameras, pixels, X - d, &rm);
      if (ok) J.col(k) = (rp - rm) / (2 * eps);
    }
    if (!ok) break;
    const Eigen::Vector3d step = (J.transpose() * J).ldlt().solve(-J.transpose() * r);
    Eigen::VectorXd r_new;
    if (!step.allFinite() || !residuals(cameras, pixels, X + step, &r_new) || r_new.squaredNorm() > r.squaredNorm())
      break;
    X += step;
    r = r_new;
    if (step.norm() < 1e-12 * scale) break;
  }
  t.point = X;
  t.residuals_px.resize(n);
  for (size_t i = 0; i < n; ++i) t.residuals_px[i] = r.segment<2>(2 * i).norm();
  t.rms_px = std::sqrt(r.squaredNorm() / n);
  t.ok = true;
  return t;
}

}  // namespace tabletop_capture
