// Shared by the fusion tests and the benchmark: synthetic cameras and exact silhouettes of
// spheres (a ray through a pixel centre either hits a sphere or not), and the analytic visual
// hull of spheres (intersection of the viewing cones).
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/view_evidence.h"
#include "tabletop_capture/camera_model.h"
#include "tabletop_capture/default_rig.h"

namespace psfs {
namespace test {

struct Sphere {
  Eigen::Vector3d centre;
  double radius;
};

// N pinhole cameras on a ring of `radius` around `target`, alternately 0.6 and 0.9 of the
// radius above it, all looking at it.
inline std::vector<tabletop_capture::CameraModel> ringCameras(int n, const Eigen::Vector3d& target,
                                                              double radius, int width = 320,
                                                              int height = 240, double f = 300.0) {
  std::vector<tabletop_capture::CameraModel> cams;
  for (int i = 0; i < n; ++i) {
    const double az = 2.0 * M_PI * (i + 0.13) / n;
    const double h = (i % 2 ? 0.9 : 0.6) * radius;
    tabletop_capture::CameraModel c;
    c.name = "cam" + std::to_string(i);
    c.width = width, c.height = height;
    c.fx = f, c.fy = f;
    c.cx = (width - 1) / 2.0, c.cy = (height - 1) / 2.0;
    c.world_T_camera = tabletop_capture::lookAt(
        target + Eigen::Vector3d(radius * std::cos(az), radius * std::sin(az), h), target);
    cams.push_back(c);
  }
  return cams;
}

inline bool rayHitsSphere(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Sphere& s) {
  const Eigen::Vector3d oc = s.centre - o;
  const double along = oc.dot(d);
  if (along <= 0.0) return false;
  return (oc - along * d).squaredNorm() <= s.radius * s.radius;
}

// Likelihood image: `inside` where the pixel-centre ray hits any sphere, `outside` elsewhere.
inline cv::Mat sphereLikelihood(const tabletop_capture::CameraModel& cam,
                                const std::vector<Sphere>& spheres, uint8_t inside = 230,
                                uint8_t outside = 25) {
  cv::Mat img(cam.height, cam.width, CV_8UC1, cv::Scalar(outside));
  const Eigen::Vector3d o = cam.center();
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d = cam.rayWorld(Eigen::Vector2d(u, v));
      for (const Sphere& s : spheres)
        if (rayHitsSphere(o, d, s)) {
          img.at<uint8_t>(v, u) = inside;
          break;
        }
    }
  return img;
}

// Signed angular margin (radians) of point p inside camera `cam`'s viewing cone of sphere s:
// > 0 inside the cone, < 0 outside.
inline double coneMargin(const tabletop_capture::CameraModel& cam, const Sphere& s,
                         const Eigen::Vector3d& p) {
  const Eigen::Vector3d a = s.centre - cam.center(), b = p - cam.center();
  const double half = std::asin(std::min(1.0, s.radius / a.norm()));
  const double ang = std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
  return half - ang;
}

// Voxelised analytic visual hull of spheres (centre test) over the given cameras, and a mask
// of voxels whose membership a tolerance can flip: a camera's verdict is uncertain within
// `band_px` pixels (converted to an angle with the camera's focal length) plus `band_m` metres
// (seen from the camera) of its cone; a voxel is certain if it is inside all cones of a sphere
// beyond the band, or outside some cone of every sphere beyond the band.
struct AnalyticHull {
  ProbabilityVolume hull;       // 255 inside all cones (of some sphere), else 0
  std::vector<uint8_t> uncertain;
  size_t num_uncertain = 0;
};

inline AnalyticHull analyticHull(const VoxelGrid& grid,
                                 const std::vector<tabletop_capture::CameraModel>& cams,
                                 const std::vector<Sphere>& spheres, double band_px,
                                 double band_m) {
  AnalyticHull h;
  h.hull.grid = grid;
  h.hull.data.assign(grid.numVoxels(), 0);
  h.uncertain.assign(grid.numVoxels(), 0);
  for (size_t i = 0; i < grid.numVoxels(); ++i) {
    const Eigen::Vector3d p = grid.centre(i);
    // Per sphere: certainly inside all cones, certainly outside one, or undecidable.
    bool certain_in = false, possibly_in = false;
    for (const Sphere& s : spheres) {
      bool all_in = true, all_clear = true, one_far_out = false;
      for (const auto& cam : cams) {
        const double m = coneMargin(cam, s, p);
        const double band = band_px / cam.fx + band_m / (p - cam.center()).norm();
        if (m < 0) all_in = false;
        if (m <= band) all_clear = false;
        if (m < -band) one_far_out = true;
      }
      certain_in = certain_in || (all_in && all_clear);
      possibly_in = possibly_in || !one_far_out;
      h.hull.data[i] = h.hull.data[i] || all_in ? 255 : 0;
    }
    const bool unsure = !certain_in && possibly_in;
    h.uncertain[i] = unsure;
    h.num_uncertain += unsure;
  }
  return h;
}

inline std::vector<ViewImage> toViews(const std::vector<cv::Mat>& images) {
  std::vector<ViewImage> v(images.size());
  for (size_t i = 0; i < images.size(); ++i) v[i].likelihood = images[i];
  return v;
}

// Adds zero-mean Gaussian noise (sigma grey levels) and a fraction of salt-and-pepper pixels
// (classifier outliers) to a likelihood image.
inline cv::Mat noisy(const cv::Mat& img, double sigma, double outliers, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  cv::Mat out = img.clone();
  for (int v = 0; v < out.rows; ++v)
    for (int x = 0; x < out.cols; ++x) {
      double val = out.at<uint8_t>(v, x) + g(rng);
      if (u(rng) < outliers) val = u(rng) < 0.5 ? 0 : 255;
      out.at<uint8_t>(v, x) = static_cast<uint8_t>(std::clamp(std::lround(val), 0L, 255L));
    }
  return out;
}

// Likelihood image as the pixel classifier would give it for a known mask: P(class|c) of 0.97
// inside and 0.005 outside, with optional classifier noise (Gaussian, sigma 0.15, and 2 % of
// pixels replaced by a uniformly random posterior), passed through the outlier model of
// thesis 4.2.1 (P' = eF P + (1 - eF) P(class|c), eF = 0.05, P = 0.5), so it stays within
// [0.025, 0.975] like the real classifier's output.
inline cv::Mat classifierLikelihood(const cv::Mat& mask, bool noise, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 0.15);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  cv::Mat out(mask.size(), CV_8UC1);
  for (int v = 0; v < mask.rows; ++v)
    for (int x = 0; x < mask.cols; ++x) {
      double p = mask.at<uint8_t>(v, x) ? 0.97 : 0.005;
      if (noise) {
        p += g(rng);
        if (u(rng) < 0.02) p = u(rng);
      }
      p = 0.05 * 0.5 + 0.95 * std::clamp(p, 0.0, 1.0);
      out.at<uint8_t>(v, x) = static_cast<uint8_t>(std::lround(255.0 * p));
    }
  return out;
}

// IoU of the voxels above byte threshold `tb` with an oracle's occupancy (nonzero = inside).
inline double occupancyIoU(const ProbabilityVolume& v, uint8_t tb, const std::vector<uint8_t>& truth) {
  size_t inter = 0, uni = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    const bool a = v.data[i] > tb, b = truth[i] != 0;
    inter += a && b;
    uni += a || b;
  }
  return uni ? double(inter) / uni : 1.0;
}

// The kernels' comparison scene: two spheres seen by every camera with classifier-like noise,
// and a switched-off rectangle in camera 2 (the active-mask path).
inline std::vector<ViewImage> twoSpheresWithMaskedView(const std::vector<tabletop_capture::CameraModel>& cams) {
  const std::vector<Sphere> spheres = {{Eigen::Vector3d(0.0, 0.0, 0.3), 0.2},
                                       {Eigen::Vector3d(0.2, 0.1, 0.5), 0.08}};
  std::vector<ViewImage> views;
  for (size_t c = 0; c < cams.size(); ++c) {
    ViewImage v;
    v.likelihood = noisy(sphereLikelihood(cams[c], spheres), 40, 0.05, static_cast<uint32_t>(7 + c));
    if (c == 2) {
      v.active = cv::Mat(cams[c].height, cams[c].width, CV_8UC1, cv::Scalar(1));
      v.active(cv::Rect(100, 50, 80, 120)).setTo(0);
    }
    views.push_back(v);
  }
  return views;
}

}  // namespace test
}  // namespace psfs
