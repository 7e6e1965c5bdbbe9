// Foreground-class pSfS, all-classes pSfS and binary SfS against the analytic visual hull:
// spheres seen by synthetic cameras with exact silhouettes, single and multi-projection, a hand
// sub-volume, and noisy likelihoods. Part of test_psfs_fusion.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "fusion_test_utils.h"
#include "psfs_fusion_test_support.h"
#include "psfs_reconstruction/all_classes_fusion.h"
#include "psfs_reconstruction/binary_sfs.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "tabletop_capture/default_rig.h"

namespace psfs {
namespace {

using test::Sphere;
using namespace fusion_test;  // NOLINT: the shared scene and comparison helpers

TEST(PsfsFusion, SphereMatchesAnalyticVisualHull) {
  const Scene s = ringScene(8);
  const VoxelGrid grid = sphereGrid(64);  // 4.7 mm voxels, ~4 mm pixels at 1.2 m
  PsfsOptions o;
  o.threshold = separatingThreshold(8);
  const ProbabilityVolume vol = fusePsfs(grid, s.cams, test::toViews(s.images), o);
  // Nearest-pixel lookup: a voxel centre is classified by a pixel-centre ray up to 0.71 px
  // away (plus 1/32 px packing).
  const auto hull = test::analyticHull(grid, s.cams, s.spheres, 0.75, 0.0);
  const Comparison c = compare(vol, thresholdByte(o.threshold), hull);
  const double best_sphere = sphereIoU(hull.hull, 0, s.spheres);
  const double sphere = sphereIoU(vol, thresholdByte(o.threshold), s.spheres);
  std::printf("sphere, 8 pinhole views, %s, t = %.3f: IoU vs analytic hull %.4f (mismatches %zu, "
              "all within the %zu-voxel pixel-quantisation band: %zu outside it); IoU vs sphere "
              "%.4f (analytic hull vs sphere %.4f)\n",
              grid.describe().c_str(), o.threshold, c.iou, c.mismatches, c.uncertain,
              c.certain_mismatches, sphere, best_sphere);
  EXPECT_EQ(c.certain_mismatches, 0u);
  EXPECT_GE(c.iou, 1.0 - double(c.uncertain) / c.union_count);
  EXPECT_GT(c.iou, 0.9);
  EXPECT_GT(sphere, best_sphere - double(c.uncertain) / c.union_count);
  // Contains the sphere: every voxel whose centre is deeper inside than the band.
  const double band = 0.75 / 300.0 * 1.4;  // metres at the farthest camera distance
  for (size_t i = 0; i < grid.numVoxels(); ++i)
    if ((grid.centre(i) - s.spheres[0].centre).norm() < s.spheres[0].radius - band) {
      ASSERT_GT(vol.data[i], thresholdByte(o.threshold)) << "voxel " << i;
    }
}

TEST(PsfsFusion, MultiProjectionOnDefaultRigAt16mm) {
  // The design's configuration: 8 distorted 320x240 cameras, 64x64x48, multi-projection.
  const auto rig = tabletop_capture::makeDefaultRig();
  const std::vector<Sphere> spheres = {{Eigen::Vector3d(0.05, -0.02, 0.35), 0.15}};
  std::vector<cv::Mat> images;
  for (const auto& c : rig.cameras) images.push_back(test::sphereLikelihood(c, spheres, kIn, kOut));
  const VoxelGrid grid = referenceGrid(Resolution::k16mm);
  PsfsOptions o;
  o.threshold = separatingThreshold(8);
  o.multi_projection = true;
  const ProbabilityVolume vol = fusePsfs(grid, rig.cameras, test::toViews(images), o);
  // Median of the 6 face samples (+-1/2 voxel per axis): a voxel follows its centre once at
  // least two axes' sample pairs lie on the centre's side of the cone, i.e. once the centre is
  // farther than 1/2 * sqrt(1/2) = 0.354 voxel from it; plus the pixel quantisation
  // (distortion: ~1 px in angle).
  const auto hull = test::analyticHull(grid, rig.cameras, spheres, 1.0, kFaceBand * grid.voxel_size);
  const Comparison c = compare(vol, thresholdByte(o.threshold), hull);
  o.multi_projection = false;
  const ProbabilityVolume single = fusePsfs(grid, rig.cameras, test::toViews(images), o);
  const Comparison cs = compare(single, thresholdByte(o.threshold), test::analyticHull(grid, rig.cameras, spheres, 1.0, 0.0));
  std::printf("sphere r = 15 cm, default rig, %s: IoU vs analytic hull %.4f multi-projection "
              "(%zu mismatches outside the band), %.4f single; vs sphere %.4f (hull vs sphere %.4f)\n",
              grid.describe().c_str(), c.iou, c.certain_mismatches, cs.iou,
              sphereIoU(vol, thresholdByte(o.threshold), spheres), sphereIoU(hull.hull, 0, spheres));
  EXPECT_EQ(c.certain_mismatches, 0u);
  EXPECT_EQ(cs.certain_mismatches, 0u);
  EXPECT_GT(c.iou, 0.85);
}

TEST(PsfsFusion, AllClassesAndForegroundClassAgreeOnCleanData) {
  const Scene s = ringScene(8);
  const VoxelGrid grid = sphereGrid(40);
  ProjectionTable table(grid, s.cams);
  ViewEvidence ev;
  ev.set(test::toViews(s.images), false);
  PsfsOptions o;
  o.threshold = separatingThreshold(8);
  ProbabilityVolume fg, all, bin;
  PsfsFusion(o).fuse(table, ev, &fg);
  AllClassesFusion().fuse(table, ev, &all);
  BinarySfs().fuse(table, ev, &bin);
  size_t differ = 0, differ_bin = 0, in = 0;
  for (size_t i = 0; i < grid.numVoxels(); ++i) {
    const bool a = fg.data[i] > thresholdByte(o.threshold), b = all.data[i] > 0;
    differ += a != b;
    differ_bin += b != (bin.data[i] > 0);
    in += b;
  }
  std::printf("clean sphere, 8 views, %s: all-classes %zu voxels in hull, foreground-class "
              "differs in %zu, binary SfS in %zu\n",
              grid.describe().c_str(), in, differ, differ_bin);
  EXPECT_GT(in, 1000u);
  EXPECT_EQ(differ, 0u);
  EXPECT_EQ(differ_bin, 0u);

  // Multi-projection: the all-classes variant reads the same shared face samples (as bytes).
  // Bilinear samples at the silhouette edges take values between the two levels, where the
  // two decision rules may differ, so both are held to the analytic hull instead.
  ProjectionTableOptions to;
  to.multi_projection = true;
  const VoxelGrid coarse = sphereGrid(20);  // 15 mm voxels: the resolution the test is for
  ProjectionTable mtable(coarse, s.cams, to);
  ev.set(test::toViews(s.images), true);
  o.multi_projection = true;
  AllClassesOptions ao;
  ao.multi_projection = true;
  PsfsFusion(o).fuse(mtable, ev, &fg);
  AllClassesFusion(ao).fuse(mtable, ev, &all);
  const auto hull = test::analyticHull(coarse, s.cams, s.spheres, 0.75, kFaceBand * coarse.voxel_size);
  const Comparison cf = compare(fg, thresholdByte(o.threshold), hull), ca = compare(all, 0, hull);
  std::printf("multi-projection, %s: IoU vs analytic hull: foreground-class %.4f, all-classes "
              "%.4f (mismatches outside the band: %zu, %zu)\n",
              coarse.describe().c_str(), cf.iou, ca.iou, cf.certain_mismatches, ca.certain_mismatches);
  EXPECT_EQ(cf.certain_mismatches, 0u);
  EXPECT_EQ(ca.certain_mismatches, 0u);
  EXPECT_GT(cf.iou, 0.85);
  EXPECT_GT(ca.iou, 0.85);
}

TEST(PsfsFusion, HandSubVolumeOnTheFlyEqualsPrecomputed) {
  const auto rig = tabletop_capture::makeDefaultRig();
  const std::vector<Sphere> hand = {{Eigen::Vector3d(0.12, -0.05, 0.3), 0.05}};
  std::vector<cv::Mat> imgs;
  for (const auto& c : rig.cameras) imgs.push_back(test::sphereLikelihood(c, hand, kIn, kOut));
  const VoxelGrid grid = snappedCubeGrid(hand[0].centre, 0.3, 83);
  PsfsOptions o;
  o.threshold = separatingThreshold(8);
  const ProbabilityVolume a = fusePsfs(grid, rig.cameras, test::toViews(imgs), o, TableStorage::kOnTheFly);
  const ProbabilityVolume b = fusePsfs(grid, rig.cameras, test::toViews(imgs), o, TableStorage::kPrecomputed);
  EXPECT_EQ(a.data, b.data);
  const auto hull = test::analyticHull(grid, rig.cameras, hand, 1.0, 0.0);
  const Comparison c = compare(a, thresholdByte(o.threshold), hull);
  std::printf("hand sub-volume %s: IoU vs analytic hull %.4f (%zu mismatches outside the band), "
              "vs sphere %.4f (hull vs sphere %.4f)\n",
              grid.describe().c_str(), c.iou, c.certain_mismatches,
              sphereIoU(a, thresholdByte(o.threshold), hand), sphereIoU(hull.hull, 0, hand));
  EXPECT_EQ(c.certain_mismatches, 0u);
  EXPECT_GT(c.iou, 0.9);
}

TEST(PsfsFusion, NoisyLikelihoodsBeatBinarySfs) {
  // Classifier noise: Gaussian (sigma 50 grey levels) and 3 % outlier pixels. pSfS averages
  // the evidence in the log domain (and the multi-projection median suppresses single bad
  // pixels); binary SfS lets any one bad pixel carve a hole.
  const auto rig = tabletop_capture::makeDefaultRig();
  const std::vector<Sphere> spheres = {{Eigen::Vector3d(0.0, 0.0, 0.35), 0.16},
                                       {Eigen::Vector3d(0.25, 0.1, 0.3), 0.06}};
  std::vector<cv::Mat> clean, noisy;
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    clean.push_back(test::sphereLikelihood(rig.cameras[c], spheres, kIn, kOut));
    noisy.push_back(test::noisy(clean.back(), 50, 0.03, 100 + c));
  }
  for (Resolution r : {Resolution::k16mm, Resolution::k8mm}) {
    const VoxelGrid grid = referenceGrid(r);
    const bool multi = r == Resolution::k16mm;
    const auto hull = test::analyticHull(grid, rig.cameras, spheres, 1.0, multi ? kFaceBand * grid.voxel_size : 0.0);
    ProjectionTableOptions to;
    to.multi_projection = multi;
    ProjectionTable table(grid, rig.cameras, to);
    ViewEvidence ev;
    ev.set(test::toViews(noisy), multi);
    PsfsOptions o;
    o.multi_projection = multi;
    ProbabilityVolume p, b;
    PsfsFusion(o).fuse(table, ev, &p);
    BinarySfs().fuse(table, ev, &b);
    const double ip = compare(p, thresholdByte(o.threshold), hull).iou;
    const double ib = compare(b, 0, hull).iou;
    std::printf("noisy likelihoods, %s: IoU vs analytic hull: pSfS%s %.4f, binary SfS %.4f\n",
                grid.describe().c_str(), multi ? " (multi-projection)" : "", ip, ib);
    EXPECT_GT(ip, ib);
    EXPECT_GT(ip, 0.7);
  }
}

}  // namespace
}  // namespace psfs
