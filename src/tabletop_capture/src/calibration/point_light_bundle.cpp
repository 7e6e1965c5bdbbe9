// Bundle adjustment of the point-light calibration (Ceres): poses as angle-axis + translation
// (world -> camera), the pixel error through each camera's own plumb_bob distortion.
#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Geometry>

#include "point_light_problem.h"

namespace tabletop_capture {
namespace point_light {
namespace {

struct PixelError {
  PixelError(const Eigen::Vector2d& pixel, const std::array<double, 5>& distortion)
      : u(pixel.x()), v(pixel.y()), d(distortion) {}

  // pose: angle-axis, translation; intrinsics: fx, fy, cx, cy.
  template <typename T>
  bool operator()(const T* pose, const T* intrinsics, const T* point, T* residual) const {
    T p[3];
    ceres::AngleAxisRotatePoint(pose, point, p);
    p[0] += pose[3];
    p[1] += pose[4];
    p[2] += pose[5];
    const T x = p[0] / p[2], y = p[1] / p[2];
    const T r2 = x * x + y * y;
    const T radial = 1.0 + r2 * (d[0] + r2 * (d[1] + r2 * d[4]));
    const T xd = x * radial + 2.0 * d[2] * x * y + d[3] * (r2 + 2.0 * x * x);
    const T yd = y * radial + d[2] * (r2 + 2.0 * y * y) + 2.0 * d[3] * x * y;
    residual[0] = intrinsics[0] * xd + intrinsics[2] - u;
    residual[1] = intrinsics[1] * yd + intrinsics[3] - v;
    return true;
  }

  double u, v;
  std::array<double, 5> d;
};

}  // namespace

int bundleAdjust(Problem& problem, const BundleOptions& options) {
  const size_t n_cameras = problem.cameras.size();
  std::vector<std::array<double, 6>> poses(n_cameras);
  std::vector<std::array<double, 4>> intrinsics(n_cameras);
  for (size_t c = 0; c < n_cameras; ++c) {
    const Eigen::AngleAxisd aa(problem.camera_T_world[c].rotation());
    const Eigen::Vector3d r = aa.angle() * aa.axis(), t = problem.camera_T_world[c].translation();
    poses[c] = {r.x(), r.y(), r.z(), t.x(), t.y(), t.z()};
    const CameraModel& m = problem.cameras[c];
    intrinsics[c] = {m.fx, m.fy, m.cx, m.cy};
  }
  ceres::Problem ba;
  // Shared by all blocks; the problem owns it (and counts its users).
  ceres::LossFunction* loss = new ceres::HuberLoss(options.huber_px);
  std::vector<bool> used(n_cameras, false);
  for (const Observation& o : problem.observations) {
    if (!o.inlier || !problem.placed[o.camera] || !problem.triangulated[o.point]) continue;
    auto* cost = new ceres::AutoDiffCostFunction<PixelError, 2, 6, 4, 3>(
        new PixelError(o.pixel, problem.cameras[o.camera].distortion));
    ba.AddResidualBlock(cost, loss, poses[o.camera].data(), intrinsics[o.camera].data(),
                        problem.points[o.point].data());
    used[o.camera] = true;
  }
  for (size_t c = 0; c < n_cameras; ++c) {
    if (!used[c]) continue;
    if (!options.refine_intrinsics) ba.SetParameterBlockConstant(intrinsics[c].data());
    if (static_cast<int>(c) == options.fixed) ba.SetParameterBlockConstant(poses[c].data());
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_SCHUR;  // a few cameras, thousands of points
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = 1;
  solver.function_tolerance = 1e-10;
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &ba, &summary);
  for (size_t c = 0; c < n_cameras; ++c) {
    if (!used[c]) continue;
    const Eigen::Vector3d r(poses[c][0], poses[c][1], poses[c][2]);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    if (r.norm() > 0) pose.linear() = Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix();
    pose.translation() = Eigen::Vector3d(poses[c][3], poses[c][4], poses[c][5]);
    problem.camera_T_world[c] = pose;
    if (options.refine_intrinsics) {
      problem.cameras[c].fx = intrinsics[c][0];
      problem.cameras[c].fy = intrinsics[c][1];
      problem.cameras[c].cx = intrinsics[c][2];
      problem.cameras[c].cy = intrinsics[c][3];
    }
  }
  return static_cast<int>(summary.iterations.size());
}

}  // namespace point_light
}  // namespace tabletop_capture
