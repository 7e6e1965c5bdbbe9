#include "body_tracking/truncated_quadric.h"

#include <algorithm>
#include <cmath>

namespace body_tracking {

using Eigen::Matrix4d;
using Eigen::Vector3d;
using Eigen::Vector4d;

namespace {

// Local quadric / plane -> world: v_local = T^-1 v_world, so Q_w = T^-T Q_l T^-1, pi_w = T^-T pi_l.
Matrix4d inverseMatrix(const Eigen::Isometry3d& frame) { return frame.inverse().matrix(); }

Vector3d ellipseExtent(const Eigen::Matrix3d& R, double a, double c) {
  Vector3d e;
  for (int k = 0; k < 3; ++k) e[k] = std::hypot(a * R(k, 0), c * R(k, 2));
  return e;
}

}  // namespace

TruncatedQuadric TruncatedQuadric::cylinder(const Eigen::Isometry3d& frame, double length,
                                            double half_x, double half_z) {
  TruncatedQuadric q;
  q.shape = Shape::CYLINDER;
  q.frame = frame;
  q.length = length;
  q.semi = Vector3d(half_x, 0.5 * length, half_z);
  const Matrix4d Ti = inverseMatrix(frame);
  const Vector4d diag(1.0 / (half_x * half_x), 0.0, 1.0 / (half_z * half_z), -1.0);
  q.Q = Ti.transpose() * diag.asDiagonal() * Ti;
  q.planes[0] = Ti.transpose() * Vector4d(0, 1, 0, 0);
  q.planes[1] = Ti.transpose() * Vector4d(0, -1, 0, length);
  q.num_planes = 2;
  const Vector3d a = frame.translation();
  const Vector3d b = frame * Vector3d(0, length, 0);
  const Vector3d e = ellipseExtent(frame.linear(), half_x, half_z);
  q.bounds = Eigen::AlignedBox3d(a.cwiseMin(b) - e, a.cwiseMax(b) + e);
  return q;
}

TruncatedQuadric TruncatedQuadric::ellipsoid(const Eigen::Isometry3d& frame, const Vector3d& semi) {
  TruncatedQuadric q;
  q.shape = Shape::ELLIPSOID;
  q.frame = frame;
  q.semi = semi;
  const Matrix4d Ti = inverseMatrix(frame);
  const Vector4d diag(1.0 / (semi.x() * semi.x()), 1.0 / (semi.y() * semi.y()),
                      1.0 / (semi.z() * semi.z()), -1.0);
  q.Q = Ti.transpose() * diag.asDiagonal() * Ti;
  q.num_planes = 0;
  Vector3d e;
  const Eigen::Matrix3d& R = frame.linear();
  for (int k = 0; k < 3; ++k)
    e[k] = std::sqrt(std::pow(semi.x() * R(k, 0), 2) + std::pow(semi.y() * R(k, 1), 2) +
                     std::pow(semi.z() * R(k, 2), 2));
  q.bounds = Eigen::AlignedBox3d(frame.translation() - e, frame.translation() + e);
  return q;
}

double TruncatedQuadric::volume() const {
  if (shape == Shape::CYLINDER) return M_PI * semi.x() * semi.z() * length;
  return 4.0 / 3.0 * M_PI * semi.x() * semi.y() * semi.z();
}

Vector3d TruncatedQuadric::centre() const {
  if (shape == Shape::CYLINDER) return frame * Vector3d(0, 0.5 * length, 0);
  return frame.translation();
}

double localSignedDistance(const TruncatedQuadric& part, const Vector3d& q) {
  if (part.shape == TruncatedQuadric::Shape::CYLINDER) {
    const double r = std::hypot(q.x(), q.z());
    const double n = std::hypot(q.x() / part.semi.x(), q.z() / part.semi.z());  // 1 on the surface
    const double radial = n > 0 ? r * (1.0 - 1.0 / n) : -std::min(part.semi.x(), part.semi.z());
    const double axial = std::max(-q.y(), q.y() - part.length);  // > 0 beyond a cap
    if (radial > 0 && axial > 0) return std::hypot(radial, axial);  // off the rim
    return std::max(radial, axial);
  }
  const double r = q.norm();
  const double n = q.cwiseQuotient(part.semi).norm();
  return n > 0 ? r * (1.0 - 1.0 / n) : -part.semi.minCoeff();
}

double signedDistance(const TruncatedQuadric& part, const Vector3d& p) {
  return localSignedDistance(part, part.frame.inverse() * p);
}

}  // namespace body_tracking
