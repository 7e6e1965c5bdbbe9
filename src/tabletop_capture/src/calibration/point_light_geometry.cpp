// Reprojection and robust multi-view triangulation for the point-light calibration.
#include <cmath>
#include <limits>

#include <Eigen/SVD>

#include "point_light_problem.h"

namespace tabletop_capture {
namespace point_light {
namespace {

// Linear (DLT) triangulation from normalised coordinates: each view gives x P3 - P1 = 0 and
// y P3 - P2 = 0 for its 3x4 [R|t].
Eigen::Vector3d triangulateLinear(const Problem& problem, const std::vector<int>& obs) {
  Eigen::MatrixXd a(2 * obs.size(), 4);
  for (size_t k = 0; k < obs.size(); ++k) {
    const Observation& o = problem.observations[obs[k]];
    const Eigen::Matrix<double, 3, 4> p = problem.camera_T_world[o.camera].matrix().topRows<3>();
    a.row(2 * k) = o.normalised.x() * p.row(2) - p.row(0);
    a.row(2 * k + 1) = o.normalised.y() * p.row(2) - p.row(1);
  }
  const Eigen::Vector4d x = Eigen::JacobiSVD<Eigen::MatrixXd>(a, Eigen::ComputeFullV).matrixV().col(3);
  if (std::abs(x(3)) < 1e-12) return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  return x.head<3>() / x(3);
}

}  // namespace

double Problem::pixelError(const Observation& o) const {
  return pixelError(o, points[o.point]);
}

double Problem::pixelError(const Observation& o, const Eigen::Vector3d& x) const {
  const Eigen::Vector3d pc = camera_T_world[o.camera] * x;
  Eigen::Vector2d pixel;
  if (!x.allFinite() || !cameras[o.camera].projectCamera(pc, &pixel)) return std::numeric_limits<double>::infinity();
  return (pixel - o.pixel).norm();
}

bool triangulatePoint(Problem& problem, int p, double threshold_px) {
  std::vector<int> obs;
  for (int k : problem.of_point[p])
    if (problem.placed[problem.observations[k].camera]) obs.push_back(k);
  problem.triangulated[p] = false;
  if (obs.size() < 2) return false;
  std::vector<int> best;
  double best_error = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < obs.size(); ++i)
    for (size_t j = i + 1; j < obs.size(); ++j) {
      const Eigen::Vector3d x = triangulateLinear(problem, {obs[i], obs[j]});
      std::vector<int> agree;
      double error = 0;
      for (int k : obs) {
        const double e = problem.pixelError(problem.observations[k], x);
        if (e < threshold_px) {
          agree.push_back(k);
          error += e;
        }
      }
      if (agree.size() > best.size() || (agree.size() == best.size() && error < best_error)) {
        best = agree;
        best_error = error;
      }
    }
  for (int k : obs) problem.observations[k].inlier = false;
  if (best.size() < 2) return false;
  const Eigen::Vector3d x = triangulateLinear(problem, best);
  if (!x.allFinite()) return false;
  problem.points[p] = x;
  problem.triangulated[p] = true;
  for (int k : obs) problem.observations[k].inlier = problem.pixelError(problem.observations[k]) < threshold_px;
  return true;
}

}  // namespace point_light
}  // namespace tabletop_capture
