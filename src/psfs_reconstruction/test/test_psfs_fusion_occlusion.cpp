// Views that give no evidence: a blanked or masked-off view with k occluded views allowed, and
// voxels outside a camera's view (with min_views). Part of test_psfs_fusion.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "fusion_test_utils.h"
#include "psfs_fusion_test_support.h"
#include "psfs_reconstruction/all_classes_fusion.h"
#include "psfs_reconstruction/psfs_fusion.h"

namespace psfs {
namespace {

using tabletop_capture::CameraModel;
using namespace fusion_test;  // NOLINT: the shared scene and comparison helpers

TEST(PsfsFusion, OneBlankedViewIsToleratedWithK1) {
  Scene s = ringScene(8);
  s.images[3] = cv::Mat(240, 320, CV_8UC1, cv::Scalar(0));  // camera 3 sees nothing at all
  const VoxelGrid grid = sphereGrid(48);
  std::vector<CameraModel> others = s.cams;
  others.erase(others.begin() + 3);
  PsfsOptions o;
  o.threshold = separatingThreshold(7);
  // Reference: the hull of the 7 good cameras.
  const auto hull7 = test::analyticHull(grid, others, s.spheres, 0.75, 0.0);
  const size_t n7 = countAbove(hull7.hull, 0);

  o.occluded_views = 0;
  const ProbabilityVolume k0 = fusePsfs(grid, s.cams, test::toViews(s.images), o);
  o.occluded_views = 1;
  const ProbabilityVolume k1 = fusePsfs(grid, s.cams, test::toViews(s.images), o);
  const Comparison c1 = compare(k1, thresholdByte(o.threshold), hull7);
  // Switching the view off with the active mask instead (known occlusion), k = 0.
  std::vector<ViewImage> masked = test::toViews(s.images);
  masked[3].active = cv::Mat(240, 320, CV_8UC1, cv::Scalar(0));
  o.occluded_views = 0;
  const ProbabilityVolume off = fusePsfs(grid, s.cams, masked, o);
  const Comparison coff = compare(off, thresholdByte(o.threshold), hull7);
  // All-classes with one beta view allowed (eq. 4.8).
  ProjectionTable table(grid, s.cams);
  ViewEvidence ev;
  ev.set(test::toViews(s.images), false);
  AllClassesOptions ao;
  ao.occluded_views = 1;
  ProbabilityVolume all;
  AllClassesFusion(ao).fuse(table, ev, &all);
  const Comparison call = compare(all, 0, hull7);
  std::printf("camera 3 blanked: k = 0 keeps %zu voxels; k = 1 IoU %.4f vs the 7-view hull "
              "(%zu voxels); masked off IoU %.4f; all-classes k = 1 IoU %.4f\n",
              countAbove(k0, thresholdByte(o.threshold)), c1.iou, n7, coff.iou, call.iou);
  EXPECT_EQ(countAbove(k0, thresholdByte(o.threshold)), 0u);
  EXPECT_EQ(c1.certain_mismatches, 0u);
  EXPECT_GT(c1.iou, 0.9);
  EXPECT_EQ(coff.certain_mismatches, 0u);
  EXPECT_GT(call.iou, 0.9);
}

TEST(PsfsFusion, VoxelsOutsideAViewGetNoEvidenceFromIt) {
  // Camera 0 is zoomed in so that it sees only part of the grid. Where it does not look, the
  // result must be what the other cameras alone give; where fewer than min_views cameras
  // look, the voxel is empty.
  Scene s = ringScene(6);
  s.cams[0].fx = s.cams[0].fy = 1500.0;
  s.images[0] = test::sphereLikelihood(s.cams[0], s.spheres, kIn, kOut);
  const VoxelGrid grid = sphereGrid(40);
  PsfsOptions o;
  o.threshold = separatingThreshold(6);
  const ProbabilityVolume all6 = fusePsfs(grid, s.cams, test::toViews(s.images), o);
  std::vector<CameraModel> five(s.cams.begin() + 1, s.cams.end());
  std::vector<cv::Mat> five_img(s.images.begin() + 1, s.images.end());
  const ProbabilityVolume only5 = fusePsfs(grid, five, test::toViews(five_img), o);
  ProjectionTable t0(grid, {s.cams[0]});
  size_t unseen = 0, seen = 0, same = 0;
  for (size_t i = 0; i < grid.numVoxels(); ++i) {
    const Eigen::Vector3i v = grid.coords(i);
    if (t0.centre(0, v.x(), v.y(), v.z()) == PackedUV::notObserved(240)) {
      ++unseen;
      same += all6.data[i] == only5.data[i];
    } else {
      ++seen;
    }
  }
  std::printf("out-of-view rule: camera 0 sees %zu voxels, not %zu; identical to the 5-view "
              "fusion on %zu of those\n", seen, unseen, same);
  ASSERT_GT(unseen, 1000u);
  ASSERT_GT(seen, 1000u);
  EXPECT_EQ(same, unseen);
  // min_views: a single camera never builds a hull on its own.
  o.min_views = 2;
  const ProbabilityVolume one = fusePsfs(grid, {s.cams[0]}, test::toViews({s.images[0]}), o);
  EXPECT_EQ(countAbove(one, 0), 0u);
  o.min_views = 1;
  const ProbabilityVolume cone = fusePsfs(grid, {s.cams[0]}, test::toViews({s.images[0]}), o);
  EXPECT_GT(countAbove(cone, thresholdByte(o.threshold)), 0u);
}

}  // namespace
}  // namespace psfs
