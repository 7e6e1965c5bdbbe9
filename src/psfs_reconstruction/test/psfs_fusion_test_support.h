// Shared by the test_psfs_fusion sources (one executable): the likelihood levels, the analytic
// sphere scene on a ring of pinhole cameras, one-call fusion and the comparison of a volume with
// the analytic visual hull. The cameras, silhouettes and hull themselves are in
// fusion_test_utils.h (also used by the benchmark).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "fusion_test_utils.h"
#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/view_evidence.h"
#include "psfs_reconstruction/voxel_grid.h"
#include "tabletop_capture/camera_model.h"

namespace psfs {
namespace fusion_test {

inline constexpr uint8_t kIn = 230, kOut = 25;
// Distance (voxels) from a cone within which a multi-projection voxel may go either way: the
// face samples sit at +-1/2 voxel, and the median follows the centre once two axes' pairs are
// on its side, i.e. beyond 1/2 * sqrt(1/2) voxel.
inline constexpr double kFaceBand = 0.36;

// The threshold that separates "all views agree" from "one view disagrees" with these
// likelihood levels and C views: geometric middle of the two normalised posteriors.
inline double separatingThreshold(int C) {
  const double all = std::log(kIn / 255.0);
  const double one = ((C - 1) * std::log(kIn / 255.0) + std::log(kOut / 255.0)) / C;
  return std::exp(0.5 * (all + one));
}

struct Scene {
  std::vector<tabletop_capture::CameraModel> cams;
  std::vector<test::Sphere> spheres;
  std::vector<cv::Mat> images;
};

inline Scene ringScene(int n_cams = 8) {
  Scene s;
  s.spheres = {{Eigen::Vector3d(0.02, -0.01, 0.3), 0.1}};
  s.cams = test::ringCameras(n_cams, Eigen::Vector3d(0, 0, 0.3), 1.2);
  for (const auto& c : s.cams) s.images.push_back(test::sphereLikelihood(c, s.spheres, kIn, kOut));
  return s;
}

inline VoxelGrid sphereGrid(int n = 64) {
  return cubeGrid(Eigen::Vector3d(0.02, -0.01, 0.3), 0.3, n);
}

inline ProbabilityVolume fusePsfs(const VoxelGrid& grid,
                                  const std::vector<tabletop_capture::CameraModel>& cams,
                                  const std::vector<ViewImage>& views, PsfsOptions o,
                                  TableStorage storage = TableStorage::kAuto) {
  ProjectionTableOptions to;
  to.multi_projection = o.multi_projection;
  to.storage = storage;
  ProjectionTable table(grid, cams, to);
  ViewEvidence ev;
  ev.set(views, o.multi_projection);
  ProbabilityVolume out;
  PsfsFusion(o).fuse(table, ev, &out);
  return out;
}

struct Comparison {
  double iou = 0;
  size_t certain_mismatches = 0, mismatches = 0, uncertain = 0, union_count = 0;
};

// Compares {vol > tb} with the analytic hull; mismatches inside the uncertainty band are
// allowed (pixel quantisation), the others counted.
inline Comparison compare(const ProbabilityVolume& vol, uint8_t tb, const test::AnalyticHull& h) {
  Comparison c;
  size_t inter = 0;
  for (size_t i = 0; i < vol.data.size(); ++i) {
    const bool a = vol.data[i] > tb, b = h.hull.data[i] > 0;
    inter += a && b;
    c.union_count += a || b;
    if (a != b) {
      ++c.mismatches;
      if (!h.uncertain[i]) ++c.certain_mismatches;
    }
  }
  c.uncertain = h.num_uncertain;
  c.iou = c.union_count ? double(inter) / c.union_count : 1.0;
  return c;
}

inline double sphereIoU(const ProbabilityVolume& vol, uint8_t tb,
                        const std::vector<test::Sphere>& spheres) {
  size_t inter = 0, uni = 0;
  for (size_t i = 0; i < vol.data.size(); ++i) {
    const Eigen::Vector3d p = vol.grid.centre(i);
    bool s = false;
    for (const auto& sp : spheres) s = s || (p - sp.centre).norm() <= sp.radius;
    const bool a = vol.data[i] > tb;
    inter += a && s;
    uni += a || s;
  }
  return uni ? double(inter) / uni : 1.0;
}

}  // namespace fusion_test
}  // namespace psfs
