// Reprojection and robust multi-view triangulation for the point-light calibration.
#include <cmath>
#include <limits>

#include <Eigen/SVD>

#include "point_light_problem.h"
#include "tabletop_capture/calibration/triangulation.h"

namespace tabletop_capture {
namespace point_light {
namespace {

// Linear (DLT) triangulation of observations `obs` in the problem's frame (NaN at infinity).
Eigen::Vector3d triangulateLinear(const Problem& problem, const std::vector<int>& obs) {
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector2d> normalised;
  for (int k : obs) {
    const Observation& o = problem.observations[k];
    poses.push_back(problem.camera_T_world[o.camera]);
    normalised.push_back(o.normalised);
  }
  const Eigen::Vector4d x = tabletop_capture::triangulateLinear(poses, normalised);
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
