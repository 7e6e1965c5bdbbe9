// The initialisation of the point-light calibration: the first pair of cameras from their
// essential matrix, then each further camera by PnP against the points triangulated so far.
#include <algorithm>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "point_light_problem.h"

namespace tabletop_capture {
namespace point_light {
namespace {

double meanFocal(const CameraModel& a, const CameraModel& b) { return 0.25 * (a.fx + a.fy + b.fx + b.fy); }

// The relative pose of cameras a and b from their essential matrix; b's pose in a's frame with
// |t| = 1. Returns the number of points that agree (RANSAC and in front of both), 0 on failure.
int pairPose(const Problem& problem, int a, int b, double threshold_px, unsigned seed,
             Eigen::Isometry3d* b_T_a) {
  std::vector<cv::Point2d> xa, xb;
  for (const auto& obs : problem.of_point) {
    const Observation *oa = nullptr, *ob = nullptr;
    for (int k : obs) {
      const Observation& o = problem.observations[k];
      if (o.camera == a) oa = &o;
      if (o.camera == b) ob = &o;
    }
    if (!oa || !ob) continue;
    xa.emplace_back(oa->normalised.x(), oa->normalised.y());
    xb.emplace_back(ob->normalised.x(), ob->normalised.y());
  }
  if (xa.size() < 8) return 0;
  const cv::Mat identity = cv::Mat::eye(3, 3, CV_64F);
  const double threshold = threshold_px / meanFocal(problem.cameras[a], problem.cameras[b]);
  cv::theRNG().state = seed;  // findEssentialMat's RANSAC draws from it
  cv::Mat mask;
  const cv::Mat e = cv::findEssentialMat(xa, xb, identity, cv::RANSAC, 0.9999, threshold, 2000, mask);
  int best = 0;
  // Five-point solutions come stacked (3 rows each): keep the one most points agree with.
  for (int r = 0; r + 3 <= e.rows; r += 3) {
    cv::Mat rotation, translation, good = mask.clone();
    const int n = cv::recoverPose(e.rowRange(r, r + 3), xa, xb, identity, rotation, translation, good);
    if (n <= best) continue;
    best = n;
    Eigen::Matrix3d rot;
    Eigen::Vector3d t;
    cv::cv2eigen(rotation, rot);
    cv::cv2eigen(translation, t);
    b_T_a->setIdentity();
    b_T_a->linear() = rot;
    b_T_a->translation() = t.normalized();
  }
  return best;
}

}  // namespace

int triangulateAll(Problem& problem, double threshold_px) {
  int n = 0;
  for (size_t p = 0; p < problem.points.size(); ++p) n += point_light::triangulatePoint(problem, static_cast<int>(p), threshold_px);
  return n;
}

// The first two cameras: the pair with the most frames in common whose relative pose most of
// those frames agree with.
void initialisePair(Problem& problem, const PointLightCalibrationOptions& options,
                    const PointLightProgress& progress, int* fixed) {
  const int n = static_cast<int>(problem.cameras.size());
  Eigen::MatrixXi shared = Eigen::MatrixXi::Zero(n, n);
  for (const auto& obs : problem.of_point)
    for (size_t i = 0; i < obs.size(); ++i)
      for (size_t j = i + 1; j < obs.size(); ++j)
        ++shared(problem.observations[obs[i]].camera, problem.observations[obs[j]].camera);
  std::vector<std::pair<int, int>> pairs;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (shared(a, b) >= options.min_shared_points) pairs.emplace_back(a, b);
  std::stable_sort(pairs.begin(), pairs.end(), [&](const auto& x, const auto& y) {
    return shared(x.first, x.second) > shared(y.first, y.second);
  });
  for (size_t k = 0; k < std::min<size_t>(pairs.size(), 6); ++k) {
    const auto [a, b] = pairs[k];
    Eigen::Isometry3d b_T_a;
    const int agree = pairPose(problem, a, b, options.ransac_threshold_px, options.seed, &b_T_a);
    if (progress)
      progress("init: " + problem.cameras[a].name + "-" + problem.cameras[b].name + format(": %.0f frames in common, %.0f agree with the essential matrix", shared(a, b), agree));
    if (agree < std::max(options.min_shared_points, shared(a, b) / 2)) continue;
    problem.camera_T_world[a] = Eigen::Isometry3d::Identity();
    problem.camera_T_world[b] = b_T_a;
    problem.placed[a] = problem.placed[b] = true;
    *fixed = a;
    const int points = triangulateAll(problem, options.ransac_threshold_px);
    if (points < options.min_shared_points) {
      problem.placed[a] = problem.placed[b] = false;
      continue;
    }
    return;
  }
  throw PointLightCalibrationError(
      "cannot calibrate: no pair of cameras shares at least " + std::to_string(options.min_shared_points) +
      " light positions that agree with one relative pose (wave the light where several cameras see it)");
}

// The unplaced camera that sees most triangulated points, placed by PnP (RANSAC).
void placeNextCamera(Problem& problem, const PointLightCalibrationOptions& options,
                     const PointLightProgress& progress) {
  const int n = static_cast<int>(problem.cameras.size());
  std::vector<int> seen(n, 0);
  for (const Observation& o : problem.observations)
    if (!problem.placed[o.camera] && problem.triangulated[o.point]) ++seen[o.camera];
  int next = -1;
  for (int c = 0; c < n; ++c)
    if (!problem.placed[c] && (next < 0 || seen[c] > seen[next])) next = c;
  std::vector<cv::Point3d> world;
  std::vector<cv::Point2d> image;
  for (int k : problem.of_camera[next]) {
    const Observation& o = problem.observations[k];
    if (!problem.triangulated[o.point]) continue;
    const Eigen::Vector3d& x = problem.points[o.point];
    world.emplace_back(x.x(), x.y(), x.z());
    image.emplace_back(o.normalised.x(), o.normalised.y());
  }
  const CameraModel& m = problem.cameras[next];
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  if (static_cast<int>(world.size()) >= options.min_shared_points) {
    cv::theRNG().state = options.seed + next;
    const cv::Mat identity = cv::Mat::eye(3, 3, CV_64F);
    cv::solvePnPRansac(world, image, identity, cv::noArray(), rvec, tvec, false, 500,
                       options.ransac_threshold_px * 2 / (m.fx + m.fy), 0.999, inliers);
    if (static_cast<int>(inliers.size()) >= options.min_shared_points) {
      std::vector<cv::Point3d> w;
      std::vector<cv::Point2d> i;
      for (int k : inliers) {
        w.push_back(world[k]);
        i.push_back(image[k]);
      }
      cv::solvePnP(w, i, identity, cv::noArray(), rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
    }
  }
  if (static_cast<int>(inliers.size()) < options.min_shared_points) {
    std::string unplaced;
    for (int c = 0; c < n; ++c)
      if (!problem.placed[c])
        unplaced += (unplaced.empty() ? "" : ", ") + problem.cameras[c].name + " (" + std::to_string(seen[c]) + ")";
    throw PointLightCalibrationError(
        "cannot calibrate: camera " + m.name + " cannot be connected to the others: it saw only " +
        std::to_string(inliers.empty() ? seen[next] : static_cast<int>(inliers.size())) +
        " light positions that placed cameras saw too (need " + std::to_string(options.min_shared_points) +
        "; not placed, with such positions: " + unplaced + "). Wave the light where it and two others see it.");
  }
  cv::Mat rotation;
  cv::Rodrigues(rvec, rotation);
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  cv::cv2eigen(rotation, r);
  cv::cv2eigen(tvec, t);
  problem.camera_T_world[next].setIdentity();
  problem.camera_T_world[next].linear() = r;
  problem.camera_T_world[next].translation() = t;
  problem.placed[next] = true;
  if (progress)
    progress("init: " + m.name + format(" placed by PnP from %.0f of %.0f points", inliers.size(), world.size()));
}

}  // namespace point_light
}  // namespace tabletop_capture
