// Internal to the point-light calibration (calibration/point_light_calibration.h): the problem
// as the initialisation and the bundle adjustment share it. Poses are camera_T_world (world ->
// camera), the frame being that of the first camera placed until the gauge is chosen.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tabletop_capture/calibration/point_light_calibration.h"
#include "tabletop_capture/camera_model.h"

namespace tabletop_capture {
namespace point_light {

struct Observation {
  int point = 0, camera = 0;
  Eigen::Vector2d pixel;       // as detected
  Eigen::Vector2d normalised;  // distortion removed, (x/z, y/z)
  bool inlier = true;
};

struct Problem {
  std::vector<CameraModel> cameras;             // intrinsics (and the pose given, unused)
  std::vector<Eigen::Isometry3d> camera_T_world;
  std::vector<bool> placed;                     // per camera
  std::vector<Eigen::Vector3d> points;
  std::vector<bool> triangulated;               // per point
  std::vector<int> point_frames;
  std::vector<Observation> observations;
  std::vector<std::vector<int>> of_point, of_camera;  // observation indices

  // Reprojection error in pixels of one observation (through the camera's distortion);
  // infinity behind the camera.
  double pixelError(const Observation& o) const;
  double pixelError(const Observation& o, const Eigen::Vector3d& point) const;
};

// Robust triangulation of point p from its observations in placed cameras: the pair of
// observations whose triangulation most others agree with (within threshold_px) wins, then
// all that agree are triangulated together (linear, normalised coordinates). Sets the inlier
// flags of those observations; false (point untriangulated) if fewer than 2 agree.
bool triangulatePoint(Problem& problem, int p, double threshold_px);

// Bundle adjustment of the placed cameras and the triangulated points over the inlier
// observations (Huber loss of huber_px); camera `fixed` is held. Returns the iterations used.
struct BundleOptions {
  double huber_px = 1.0;
  int max_iterations = 100;
  bool refine_intrinsics = false;
  int fixed = 0;
};
int bundleAdjust(Problem& problem, const BundleOptions& options);

// Triangulates every point seen by >= 2 placed cameras (triangulatePoint); returns how many.
int triangulateAll(Problem& problem, double threshold_px);
// Places the first two cameras (the first one fixed: *fixed) and triangulates their points.
// Throws PointLightCalibrationError if no pair agrees on a relative pose.
void initialisePair(Problem& problem, const PointLightCalibrationOptions& options,
                    const PointLightProgress& progress, int* fixed);
// Places the unplaced camera that sees most triangulated points by PnP (RANSAC). Throws
// PointLightCalibrationError naming it if it sees too few.
void placeNextCamera(Problem& problem, const PointLightCalibrationOptions& options,
                     const PointLightProgress& progress);

// printf into a string, for the progress lines and warnings (numbers as doubles: %.0f, %.3f).
inline std::string format(const char* fmt, double a = 0, double b = 0, double c = 0, double d = 0) {
  char text[256];
  std::snprintf(text, sizeof text, fmt, a, b, c, d);
  return text;
}

}  // namespace point_light
}  // namespace tabletop_capture
