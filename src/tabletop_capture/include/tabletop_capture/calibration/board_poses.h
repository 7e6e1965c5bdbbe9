// Random checkerboard poses in front of a camera, with every corner inside the image, as a user
// takes calibration views (the board fills a good part of the view at varied tilts): the views
// of the calibration tests and of the simulated calibration sequences (tabletop_sim). ROS-free.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "tabletop_capture/calibration/checkerboard.h"
#include "tabletop_capture/camera_model.h"

namespace tabletop_capture {

// n camera_T_board poses (fewer if the board cannot fit): the board's centre 0.3-0.6 m in front
// of the camera, anywhere in the image, tilted up to 40 deg about both image axes and rolled
// freely, its inner corners and its outline (outer squares and a one-square white border) at
// least `margin` px inside the image. Deterministic in `seed`.
inline std::vector<Eigen::Isometry3d> randomBoardPoses(const CameraModel& cam, const CheckerboardSpec& board,
                                                 int n, unsigned seed, double margin = 4.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Eigen::Vector3d centre((board.cols - 1) * board.square / 2, (board.rows - 1) * board.square / 2, 0);
  std::vector<Eigen::Isometry3d> poses;
  for (int attempt = 0; static_cast<int>(poses.size()) < n && attempt < 100000; ++attempt) {
    const Eigen::Vector2d px(u(rng) * cam.width, u(rng) * cam.height);
    const double depth = 0.3 + 0.3 * u(rng);
    const Eigen::Vector3d ray = cam.rayCamera(px);
    const double tilt = 40.0 * M_PI / 180.0;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = (Eigen::AngleAxisd((2 * u(rng) - 1) * tilt, Eigen::Vector3d::UnitX()) *
                  Eigen::AngleAxisd((2 * u(rng) - 1) * tilt, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(2 * M_PI * u(rng), Eigen::Vector3d::UnitZ()))
                     .toRotationMatrix();
    T.translation() = ray / ray.z() * depth - T.linear() * centre;
    // The inner corners and the board's outline (its outer squares and a one-square white border,
    // which the detector needs to see) inside the image.
    std::vector<Eigen::Vector3d> points = board.boardPoints();
    const double s = board.square;
    for (double x : {-2 * s, (board.cols + 1) * s})
      for (double y : {-2 * s, (board.rows + 1) * s}) points.emplace_back(x, y, 0.0);
    bool inside = true;
    for (const auto& p : points) {
      Eigen::Vector2d q;
      if (!cam.projectCamera(T * p, &q) || q.x() < margin || q.y() < margin ||
          q.x() > cam.width - 1 - margin || q.y() > cam.height - 1 - margin) {
        inside = false;
        break;
      }
    }
    if (inside) poses.push_back(T);
  }
  return poses;
}

}  // namespace tabletop_capture
