// Shared by test_gpu_fusion's sources and test_empty_space_skipping: frames of the simulated
// rig turned into likelihood images as test_fusion_sim does (renderer masks, classifier-like
// noise, CV_8UC2: 0 body, 1 skin), and the fusion cases the GPU path must reproduce byte for
// byte: the 64x64x48 tracking volume with and without the multi-projection test, a 83^3 hand
// sub-volume projected on the fly, a grid partly outside some views (one camera zoomed in, a grid larger than the
// user space), switched-off pixels, footprint levels, a floor (PsfsOptions::floor_z), and
// occluded_views 0..2.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "fusion_test_utils.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/view_evidence.h"
#include "tabletop_sim/simulated_rig.h"

namespace psfs {
namespace gpu_test {

namespace sim = tabletop_sim;

inline const sim::SimulatedRig& simRig() {
  static const sim::SimulatedRig rig = [] {
    sim::SimOptions so;
    so.script = "wave";
    so.empty_frames = 0;
    so.render_masks = true;
    so.short_sleeves = true;  // forearms are skin too: larger skin volumes
    return sim::SimulatedRig(so);
  }();
  return rig;
}

struct SimScene {
  std::vector<tabletop_capture::CameraModel> cameras;
  std::vector<cv::Mat> likelihoods;  // CV_8UC2 per camera
  std::vector<cv::Mat> masks;        // CV_8UC1 active masks (empty: all active)
  Eigen::Vector3d right_hand, left_hand;
  // channel 0 = body (P'(F|c)), 1 = skin (P'(F,S|c)).
  std::vector<ViewImage> views(int channel) const {
    std::vector<ViewImage> v;
    for (size_t c = 0; c < likelihoods.size(); ++c) v.push_back(ViewImage{likelihoods[c], channel, masks[c]});
    return v;
  }
};

// Frame `frame` of the wave script with noisy likelihoods. inactive: two cameras get a
// switched-off patch (known occlusion), one of them across the person.
inline SimScene simScene(int frame, bool inactive) {
  const sim::SimulatedRig& rig = simRig();
  const sim::SimFrame fr = rig.render(frame);
  SimScene s;
  s.cameras = rig.rig().cameras;
  s.right_hand = fr.truth.right_hand;
  s.left_hand = fr.truth.left_hand;
  for (size_t c = 0; c < fr.person_masks.size(); ++c) {
    cv::Mat l;
    cv::merge(std::vector<cv::Mat>{test::classifierLikelihood(fr.person_masks[c], true, 1000 * frame + c),
                                   test::classifierLikelihood(fr.skin_masks[c], true, 1000 * frame + c + 7919)},
              l);
    s.likelihoods.push_back(l);
    cv::Mat active;
    if (inactive && (c == 2 || c == 5)) {
      active = cv::Mat(l.rows, l.cols, CV_8UC1, cv::Scalar(1));
      active(cv::Rect(c == 2 ? 120 : 10, 60, 90, 110)).setTo(0);
    }
    s.masks.push_back(active);
  }
  return s;
}

// One fusion the GPU path must reproduce: options, grid, table storage, evidence class.
struct FusionCase {
  std::string name;
  VoxelGrid grid;
  PsfsOptions options;
  TableStorage storage = TableStorage::kAuto;
  int channel = 0;           // 0 body, 1 skin
  bool inactive = false;     // switched-off patches in two views
  bool zoom = false;         // camera 1 zoomed in: part of the grid outside its image
  int footprint_levels = 0;  // with PsfsOptions::footprint

  std::vector<tabletop_capture::CameraModel> cameras(const SimScene& s) const {
    auto cams = s.cameras;
    if (zoom) {
      cams[1].fx *= 2.5;
      cams[1].fy *= 2.5;
    }
    return cams;
  }
  std::unique_ptr<ProjectionTable> table(const SimScene& s) const {
    ProjectionTableOptions to;
    to.multi_projection = options.multi_projection;
    to.footprint_levels = footprint_levels;
    to.storage = storage;
    return std::make_unique<ProjectionTable>(grid, cameras(s), to);
  }
  ViewEvidence evidence(const SimScene& s) const {
    ViewEvidence ev;
    ev.set(s.views(channel), options.multi_projection, 0,
           footprint_levels ? FootprintFilter{footprint_levels, FootprintStatistic::kMedian} : FootprintFilter());
    return ev;
  }
};

inline std::vector<FusionCase> fusionCases(const SimScene& s) {
  auto opts = [](bool multi, int k) {
    PsfsOptions o;
    o.multi_projection = multi;
    o.occluded_views = k;
    return o;
  };
  const VoxelGrid tracking = referenceGrid(Resolution::k16mm);  // 64x64x48
  const VoxelGrid hand = snappedCubeGrid(s.right_hand, 0.30, 83);
  const VoxelGrid wide = cubeGrid(Eigen::Vector3d(0.1, 0.0, 0.4), 1.8, 40);  // beyond the user space
  const VoxelGrid odd = cubeGrid(Eigen::Vector3d(0.0, -0.2, 0.4), 0.7, 37);  // rows padded 37 -> 40
  std::vector<FusionCase> cases;
  cases.push_back({"64x64x48 multi-projection body k0", tracking, opts(true, 0)});
  cases.push_back({"64x64x48 multi-projection skin k1", tracking, opts(true, 1), TableStorage::kAuto, 1});
  cases.push_back({"64x64x48 single projection body k0", tracking, opts(false, 0)});
  {
    FusionCase c{"64x64x48 single skin k1, inactive pixels, priors, zero outside", tracking, opts(false, 1),
                 TableStorage::kAuto, 1, true};
    c.options.hull_prior = 0.005;
    c.options.view_prior = 0.4;
    c.options.zero_outside_hull = true;
    cases.push_back(c);
  }
  cases.push_back({"64x64x48 multi-projection body k1, inactive pixels", tracking, opts(true, 1),
                   TableStorage::kAuto, 0, true});
  cases.push_back({"hand 83^3 on the fly, single skin k1", hand, opts(false, 1), TableStorage::kOnTheFly, 1});
  {
    PsfsOptions o = opts(false, 1);
    o.floor_z = s.right_hand.z();  // PsfsOptions::floor_z (the desk top): half the cube cleared
    cases.push_back({"hand 83^3 on the fly, single skin k1, floor through the hand", hand, o,
                     TableStorage::kOnTheFly, 1});
  }
  {
    PsfsOptions o = opts(true, 0);
    o.floor_z = s.right_hand.z();  // the device skips these threads, the CPU clears them
    cases.push_back({"hand 83^3 on the fly, multi-projection body k0, floor through the hand", hand,
                     o, TableStorage::kOnTheFly, 0});
  }
  cases.push_back({"hand 83^3 on the fly, multi-projection body k0", hand, opts(true, 0), TableStorage::kOnTheFly, 0});
  cases.push_back({"40^3 beyond the views, camera 1 zoomed, multi-projection k0, inactive", wide, opts(true, 0),
                   TableStorage::kPrecomputed, 0, true, true});
  cases.push_back({"40^3 beyond the views, camera 1 zoomed, single k1, on the fly", wide, opts(false, 1),
                   TableStorage::kOnTheFly, 0, false, true});
  {
    FusionCase c{"37^3 padded rows, multi-projection k2, min_views 3, drop 0.5", odd, opts(true, 2),
                 TableStorage::kOnTheFly, 0, true};
    c.options.min_views = 3;
    c.options.drop_threshold = 0.5;
    cases.push_back(c);
  }
  {
    FusionCase c{"64x64x48 footprint levels 3, body k0", tracking, opts(false, 0)};
    c.options.footprint = true;
    c.footprint_levels = 3;
    cases.push_back(c);
  }
  {
    FusionCase c{"hand 83^3 on the fly, footprint levels 2, skin k1", hand, opts(false, 1), TableStorage::kOnTheFly, 1};
    c.options.footprint = true;
    c.footprint_levels = 2;
    cases.push_back(c);
  }
  return cases;
}

}  // namespace gpu_test
}  // namespace psfs
