// The posterior rule of pSfS on uniform evidence: monotone in the evidence, the priors from the
// expected occupancy, and an empty scene. Part of test_psfs_fusion.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "psfs_fusion_test_support.h"
#include "psfs_reconstruction/psfs_fusion.h"

namespace psfs {
namespace {

using namespace fusion_test;  // NOLINT: the shared scene and comparison helpers

TEST(PsfsFusion, PosteriorIsMonotoneInTheEvidence) {
  const Scene s = ringScene(6);
  const VoxelGrid grid = cubeGrid(Eigen::Vector3d(0, 0, 0.3), 0.02, 2);
  ProjectionTable table(grid, s.cams);
  PsfsOptions o;
  o.min_views = 1;
  PsfsFusion fusion(o);
  ViewEvidence ev;
  ProbabilityVolume out;
  int prev = -1;
  // Uniform evidence v in all views: the normalised posterior is v itself.
  for (int v = 0; v <= 255; ++v) {
    std::vector<cv::Mat> imgs(6, cv::Mat(240, 320, CV_8UC1, cv::Scalar(v)));
    ev.set(test::toViews(imgs), false);
    fusion.fuse(table, ev, &out);
    for (uint8_t b : out.data) {
      EXPECT_GE(b, prev);
      if (v > 0) {
        EXPECT_NEAR(b, v, 1) << v;
      }
    }
    prev = out.data[0];
  }
  // One view varies, the others fixed at 200: non-decreasing.
  prev = -1;
  for (int v = 0; v <= 255; v += 5) {
    std::vector<cv::Mat> imgs(6, cv::Mat(240, 320, CV_8UC1, cv::Scalar(200)));
    imgs[2] = cv::Mat(240, 320, CV_8UC1, cv::Scalar(v));
    ev.set(test::toViews(imgs), false);
    fusion.fuse(table, ev, &out);
    EXPECT_GE(out.data[0], prev);
    prev = out.data[0];
  }
  // The stored byte carries the decision exactly: in hull iff byte > thresholdByte(t).
  EXPECT_EQ(thresholdByte(0.6), 153);
}

TEST(PsfsFusion, EmptySceneGivesEmptyVolume) {
  const Scene s = ringScene(8);
  std::vector<cv::Mat> bg(8, cv::Mat(240, 320, CV_8UC1, cv::Scalar(kOut)));
  const ProbabilityVolume v = fusePsfs(sphereGrid(32), s.cams, test::toViews(bg), PsfsOptions());
  EXPECT_EQ(countAbove(v, thresholdByte(0.6)), 0u);
  std::vector<cv::Mat> zero(8, cv::Mat(240, 320, CV_8UC1, cv::Scalar(0)));
  PsfsOptions o;
  o.occluded_views = 2;
  o.multi_projection = true;
  const ProbabilityVolume z = fusePsfs(sphereGrid(32), s.cams, test::toViews(zero), o);
  EXPECT_EQ(countAbove(z, thresholdByte(0.6)), 0u);
}

TEST(PsfsFusion, PriorsFromExpectedOccupancy) {
  EXPECT_NEAR(foregroundViewPrior(0.1, 8), std::pow(0.1, 1.0 / 8), 1e-12);
  const double ps = skinViewPrior(0.01, 0.1, 8);
  EXPECT_NEAR(foregroundViewPrior(0.1, 8) * ps, std::pow(0.01, 1.0 / 8), 1e-12);
  EXPECT_THROW(skinViewPrior(0.2, 0.1, 8), std::invalid_argument);
  EXPECT_THROW(foregroundViewPrior(0.0, 8), std::invalid_argument);
  // Images computed with a per-view prior half of P(H)^(1/C): every view's evidence doubles.
  const Scene s = ringScene(4);
  const VoxelGrid grid = cubeGrid(Eigen::Vector3d(0, 0, 0.3), 0.02, 2);
  std::vector<cv::Mat> imgs(4, cv::Mat(240, 320, CV_8UC1, cv::Scalar(100)));
  PsfsOptions o;
  o.hull_prior = 0.0625;  // P(H)^(1/4) = 0.5
  o.view_prior = 0.25;
  const ProbabilityVolume v = fusePsfs(grid, s.cams, test::toViews(imgs), o);
  EXPECT_NEAR(v.data[0], 200, 1);
}

}  // namespace
}  // namespace psfs
