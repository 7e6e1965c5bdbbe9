// Triangulation of one 3-D point from its pixels in two or more calibrated cameras (thesis
// 3.2.4, "stereometric triangulation"): the linear (DLT) solution on undistorted normalised
// coordinates, then Gauss-Newton steps on the reprojection error in pixels through each
// camera's full model with distortion (the linear solution weighs far cameras less and ignores
// the pixel metric). ROS-free.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tabletop_capture/camera_model.h"

namespace tabletop_capture {

struct Triangulation {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // in the cameras' frame
  std::vector<double> residuals_px;                 // per camera, after the refinement
  double rms_px = 0;
  bool ok = false;  // false: < 2 cameras, or the point is not in front of every camera
};

// The linear (DLT) step alone, for callers that hold poses and undistorted coordinates already
// (the point-light calibration's own frame): camera_T_world[i] (world -> camera) saw the point
// at normalised[i]. Returns the homogeneous point, w not divided out (|w| near 0: at infinity).
Eigen::Vector4d triangulateLinear(const std::vector<Eigen::Isometry3d>& camera_T_world,
                                  const std::vector<Eigen::Vector2d>& normalised);

// cameras[i] saw the point at pixels[i] (same length). iterations: Gauss-Newton steps.
Triangulation triangulatePoint(const std::vector<const CameraModel*>& cameras,
                               const std::vector<Eigen::Vector2d>& pixels, int iterations = 10);

}  // namespace tabletop_capture
