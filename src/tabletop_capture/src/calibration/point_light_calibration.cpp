#include "tabletop_capture/calibration/point_light_calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "point_light_problem.h"

namespace tabletop_capture {
namespace {

using point_light::format;
using point_light::initialisePair;
using point_light::Observation;
using point_light::placeNextCamera;
using point_light::Problem;
using point_light::triangulateAll;

Problem buildProblem(const RigDescription& rig, const LightTrack& track, int min_cameras) {
  Problem problem;
  problem.cameras = rig.cameras;
  const size_t n = rig.cameras.size();
  problem.camera_T_world.assign(n, Eigen::Isometry3d::Identity());
  problem.placed.assign(n, false);
  problem.of_camera.resize(n);
  for (const LightFrame& f : track.frames) {
    if (f.seenBy() < min_cameras) continue;
    const int p = static_cast<int>(problem.points.size());
    problem.points.emplace_back(Eigen::Vector3d::Zero());
    problem.point_frames.push_back(f.frame);
    problem.of_point.emplace_back();
    for (size_t c = 0; c < n; ++c) {
      if (!f.pixels[c]) continue;
      const CameraModel& m = rig.cameras[c];
      Observation o;
      o.point = p;
      o.camera = static_cast<int>(c);
      o.pixel = *f.pixels[c];
      o.normalised = m.undistort(Eigen::Vector2d((o.pixel.x() - m.cx) / m.fx, (o.pixel.y() - m.cy) / m.fy));
      problem.of_point[p].push_back(static_cast<int>(problem.observations.size()));
      problem.of_camera[c].push_back(static_cast<int>(problem.observations.size()));
      problem.observations.push_back(o);
    }
  }
  problem.triangulated.assign(problem.points.size(), false);
  return problem;
}


// Observations of points with fewer than 2 inliers cannot constrain anything.
void dropLonelyPoints(Problem& problem) {
  for (size_t p = 0; p < problem.points.size(); ++p) {
    int inliers = 0;
    for (int k : problem.of_point[p]) inliers += problem.observations[k].inlier;
    if (inliers < 2) problem.triangulated[p] = false;
  }
}

// Marks observations beyond max(outlier_min_px, outlier_sigmas x robust sigma) as outliers
// (and those within as inliers again). Returns how many flags changed.
int rejectOutliers(Problem& problem, const PointLightCalibrationOptions& options, double* threshold) {
  std::vector<double> errors;
  for (const Observation& o : problem.observations)
    if (o.inlier && problem.triangulated[o.point]) errors.push_back(problem.pixelError(o));
  if (errors.empty()) return 0;
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  *threshold = std::max(options.outlier_min_px, options.outlier_sigmas * 1.4826 * errors[errors.size() / 2]);
  int changed = 0;
  for (Observation& o : problem.observations) {
    if (!problem.triangulated[o.point] || !problem.placed[o.camera]) continue;
    const bool inlier = problem.pixelError(o) < *threshold;
    changed += inlier != o.inlier;
    o.inlier = inlier;
  }
  dropLonelyPoints(problem);
  return changed;
}

// A similarity x -> s R x + t applied to the calibrated poses and points.
void applySimilarity(Problem& problem, const Eigen::Matrix4d& similarity) {
  const double s = similarity.block<3, 1>(0, 0).norm();
  const Eigen::Matrix3d r = similarity.block<3, 3>(0, 0) / s;
  const Eigen::Vector3d t = similarity.block<3, 1>(0, 3);
  for (size_t c = 0; c < problem.cameras.size(); ++c) {
    if (!problem.placed[c]) continue;
    const Eigen::Isometry3d world_T_camera = problem.camera_T_world[c].inverse();
    Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
    moved.linear() = r * world_T_camera.linear();
    moved.translation() = s * r * world_T_camera.translation() + t;
    problem.camera_T_world[c] = moved.inverse();
  }
  for (auto& x : problem.points) x = s * r * x + t;
}

std::string chooseGauge(Problem& problem, const RigDescription& input, const PointLightCalibrationOptions& options) {
  const int n = static_cast<int>(problem.cameras.size());
  Eigen::Matrix3Xd estimated(3, n), given(3, n);
  for (int c = 0; c < n; ++c) {
    estimated.col(c) = problem.camera_T_world[c].inverse().translation();
    given.col(c) = input.cameras[c].center();
  }
  // Approximate input poses: centres spread in at least two directions (a similarity needs 3
  // points not on a line).
  const Eigen::Matrix3Xd spread = given.colwise() - given.rowwise().mean();
  const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::Matrix3Xd>(spread).singularValues();
  if (options.align_to_input_poses && sv(1) > 1e-3 * std::max(1.0, sv(0))) {
    const Eigen::Matrix4d similarity = Eigen::umeyama(estimated, given, true);
    applySimilarity(problem, similarity);
    double rms = 0;
    for (int c = 0; c < n; ++c) rms += (problem.camera_T_world[c].inverse().translation() - given.col(c)).squaredNorm();
    return format("world and scale of the input rig's approximate poses (similarity of the camera "
                  "centres; they differ from the input by %.3f m RMS)", std::sqrt(rms / n));
  }
  const double distance = (estimated.col(1) - estimated.col(0)).norm();
  Eigen::Matrix4d similarity = Eigen::Matrix4d::Identity();
  similarity.block<3, 4>(0, 0) = (options.reference_distance / distance) * problem.camera_T_world[0].matrix().topRows<3>();
  applySimilarity(problem, similarity);
  problem.camera_T_world[0].setIdentity();  // exactly, not to rounding
  return "world = " + problem.cameras[0].name + "'s optical frame; scale: |" + problem.cameras[0].name + " - " +
         problem.cameras[1].name + "| = " + format("%g", options.reference_distance) +
         " (arbitrary until the desk-marker step sets metres)";
}

void fillStats(const Problem& problem, const PointLightCalibrationOptions& options, PointLightCalibration* result) {
  const int n = static_cast<int>(problem.cameras.size());
  result->cameras.assign(n, {});
  std::vector<std::vector<cv::Point2f>> inlier_pixels(n);
  double sum = 0, sum2 = 0;
  int count = 0;
  for (const Observation& o : problem.observations) {
    auto& s = result->cameras[o.camera];
    ++s.observations;
    if (!o.inlier || !problem.triangulated[o.point]) continue;
    const double e = problem.pixelError(o);
    ++s.inliers;
    s.rms_px += e * e;
    sum += e;
    sum2 += e * e;
    ++count;
    inlier_pixels[o.camera].emplace_back(static_cast<float>(o.pixel.x()), static_cast<float>(o.pixel.y()));
  }
  result->mean_error_px = count ? sum / count : 0;
  result->rms_px = count ? std::sqrt(sum2 / count) : 0;
  for (int c = 0; c < n; ++c) {
    auto& s = result->cameras[c];
    const std::string& name = problem.cameras[c].name;
    s.outliers = s.observations - s.inliers;
    s.rms_px = s.inliers ? std::sqrt(s.rms_px / s.inliers) : 0;
    if (s.inliers < options.few_points_warning)
      result->warnings.push_back(name + format(": only %.0f light positions (want %.0f or more): wave the light longer in its view",
                                               s.inliers, options.few_points_warning));
    if (s.outliers > 0.2 * s.observations)
      result->warnings.push_back(name + format(": %.0f of %.0f detections rejected as outliers (reflections or other lights in its view?)",
                                               s.outliers, s.observations));
    if (inlier_pixels[c].size() >= 3) {
      std::vector<cv::Point2f> hull;
      cv::convexHull(inlier_pixels[c], hull);
      s.coverage = cv::contourArea(hull) / (static_cast<double>(problem.cameras[c].width) * problem.cameras[c].height);
    }
    if (s.coverage < options.coverage_warning)
      result->warnings.push_back(name + format(": the light covered only %.0f %% of its image: wave it through the whole workspace",
                                               100 * s.coverage));
    if (s.rms_px > 0.5) result->warnings.push_back(name + format(": reprojection error %.2f px RMS (over 0.5 px)", s.rms_px));
  }
}

}  // namespace

PointLightCalibration calibrateFromPointLight(const RigDescription& intrinsics, const LightTrack& track,
                                              const PointLightCalibrationOptions& options,
                                              const PointLightProgress& progress) {
  const int n = static_cast<int>(intrinsics.cameras.size());
  if (n < 3)
    throw PointLightCalibrationError("cannot calibrate: needs at least 3 cameras (a point seen by 2 "
                                     "cameras does not fix their poses), the rig has " + std::to_string(n));
  if (track.numCameras() != n)
    throw PointLightCalibrationError("cannot calibrate: the detections have " + std::to_string(track.numCameras()) +
                                     " cameras, the rig " + std::to_string(n));
  for (int c = 0; c < n; ++c)
    if (track.cameras[c] != intrinsics.cameras[c].name)
      throw PointLightCalibrationError("cannot calibrate: detection camera " + std::to_string(c) + " is '" +
                                       track.cameras[c] + "', the rig's is '" + intrinsics.cameras[c].name + "'");
  const int min_cameras = std::max(3, options.min_cameras_per_frame);
  Problem problem = buildProblem(intrinsics, track, min_cameras);
  if (problem.points.empty())
    throw PointLightCalibrationError("cannot calibrate: no frame in which at least " + std::to_string(min_cameras) +
                                     " cameras saw the light (of " + std::to_string(track.frames.size()) +
                                     " frames with a detection): keep the light where three cameras see it");
  for (int c = 0; c < n; ++c)
    if (problem.of_camera[c].empty())
      throw PointLightCalibrationError("cannot calibrate: camera " + intrinsics.cameras[c].name +
                                       " never saw the light in a frame that two other cameras saw too, so "
                                       "it cannot be connected to the others");
  if (progress) progress(format("%.0f frames seen by %.0f or more cameras, %.0f detections", problem.points.size(),
                                min_cameras, problem.observations.size()));

  PointLightCalibration result;
  int fixed = 0;
  initialisePair(problem, options, progress, &fixed);
  point_light::BundleOptions bundle;
  bundle.huber_px = options.huber_px;
  bundle.fixed = fixed;
  bundle.max_iterations = 20;  // the initialisation only needs to stay on track
  result.iterations += point_light::bundleAdjust(problem, bundle);
  while (std::count(problem.placed.begin(), problem.placed.end(), true) < n) {
    placeNextCamera(problem, options, progress);
    triangulateAll(problem, options.ransac_threshold_px);
    result.iterations += point_light::bundleAdjust(problem, bundle);
  }
  // The last placement's points with every camera, then the whole bundle adjustment with
  // outlier rejection.
  triangulateAll(problem, options.ransac_threshold_px);
  dropLonelyPoints(problem);
  bundle.max_iterations = options.max_iterations;
  bundle.refine_intrinsics = options.refine_intrinsics;
  for (int round = 0;; ++round) {
    const int iterations = point_light::bundleAdjust(problem, bundle);
    result.iterations += iterations;
    if (round == options.outlier_rounds) break;
    double threshold = 0;
    const int changed = rejectOutliers(problem, options, &threshold);
    if (progress)
      progress(format("bundle adjustment round %.0f: %.0f iterations; outlier threshold %.2f px, %.0f observations changed side",
                      round + 1, iterations, threshold, changed));
    if (changed == 0) break;
  }

  if (progress) {
    int outliers = 0;
    for (const Observation& o : problem.observations) outliers += !o.inlier || !problem.triangulated[o.point];
    progress(format("bundle adjustment done: %.0f solver iterations in all; %.0f of %.0f observations rejected as outliers",
                    result.iterations, outliers, problem.observations.size()));
  }
  result.gauge = chooseGauge(problem, intrinsics, options);
  result.rig = intrinsics;
  for (int c = 0; c < n; ++c) {
    CameraModel& m = result.rig.cameras[c];
    m.fx = problem.cameras[c].fx;
    m.fy = problem.cameras[c].fy;
    m.cx = problem.cameras[c].cx;
    m.cy = problem.cameras[c].cy;
    m.world_T_camera = problem.camera_T_world[c].inverse();
  }
  for (size_t p = 0; p < problem.points.size(); ++p)
    if (problem.triangulated[p]) {
      result.points.push_back(problem.points[p]);
      result.point_frames.push_back(problem.point_frames[p]);
    }
  result.frames_used = static_cast<int>(problem.points.size());
  fillStats(problem, options, &result);
  return result;
}

}  // namespace tabletop_capture

