// Known occlusions of the hand sub-volumes (occluder_depth.h): the body's distance per pixel and
// the masks it gives a point behind or in front of it, on the default rig's cameras.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "psfs_reconstruction/occluder_depth.h"
#include "tabletop_capture/default_rig.h"

namespace psfs {
namespace {

// A trunk-sized box of occupied voxels (0.30 x 0.20 x 0.40 m) where the default person sits.
struct Scene {
  std::vector<tabletop_capture::CameraModel> cameras = tabletop_capture::makeDefaultRig().cameras;
  ProbabilityVolume volume;
  Eigen::Vector3d centre{0.0, -0.3, 0.35}, half{0.15, 0.10, 0.20};
  Scene() {
    volume.grid = referenceGrid(Resolution::k16mm);
    volume.data.assign(volume.grid.numVoxels(), 20);  // outside: low posterior
    for (size_t i = 0; i < volume.data.size(); ++i)
      if (((volume.grid.centre(i) - centre).cwiseAbs() - half).maxCoeff() <= 0) volume.data[i] = 230;
  }
  Eigen::Vector2d pixel(int c, const Eigen::Vector3d& p) const {
    Eigen::Vector2d px;
    EXPECT_TRUE(cameras[c].projectWorld(p, &px));
    return px;
  }
  float depthAt(const cv::Mat& d, const Eigen::Vector2d& px) const {
    return d.at<float>(int(std::lround(px.y())), int(std::lround(px.x())));
  }
  uint8_t maskAt(const cv::Mat& m, const Eigen::Vector2d& px) const {
    return m.at<uint8_t>(int(std::lround(px.y())), int(std::lround(px.x())));
  }
};

TEST(OccluderDepth, TheBodysDistanceAndTheMasksOfPointsBehindAndInFront) {
  Scene s;
  const uint8_t t = thresholdByte(0.75);
  const std::vector<cv::Mat> depth = occluderDepths(s.volume, t, s.cameras, nullptr, 1);
  ASSERT_EQ(depth.size(), s.cameras.size());
  const double half_diag = 0.5 * std::sqrt(3.0) * s.volume.grid.voxel_size;
  for (size_t c = 0; c < s.cameras.size(); ++c) {
    const auto& cam = s.cameras[c];
    const Eigen::Vector3d ray = (s.centre - cam.center()).normalized();
    const double to_centre = (s.centre - cam.center()).norm();
    // Through the box's centre: its near face, between the centre's distance less the box's
    // half diagonal (and a voxel's) and the centre's distance.
    const float d = s.depthAt(depth[c], s.pixel(c, s.centre));
    EXPECT_GT(d, to_centre - s.half.norm() - half_diag) << cam.name;
    EXPECT_LT(d, to_centre) << cam.name;
    // A hand 0.3 m behind the trunk is hidden in this view; one 0.3 m in front of it is not.
    const Eigen::Vector3d behind = s.centre + 0.3 * ray, front = s.centre - 0.45 * ray;
    EXPECT_EQ(s.maskAt(frontOcclusionMask(depth[c], cam, behind, 0.12), s.pixel(c, behind)), 0) << cam.name;
    EXPECT_EQ(s.maskAt(frontOcclusionMask(depth[c], cam, front, 0.12), s.pixel(c, front)), 255) << cam.name;
    // A point on the box's near surface is not masked by the box itself (the margin).
    const Eigen::Vector3d surface = cam.center() + double(d) * ray;
    EXPECT_EQ(s.maskAt(frontOcclusionMask(depth[c], cam, surface, 0.12), s.pixel(c, surface)), 255) << cam.name;
    // Far from the box's image: nothing in front of anything.
    int none = 0, pixels = 0;
    for (int v = 0; v < cam.height; v += 8)
      for (int u = 0; u < cam.width; u += 8) ++pixels, none += std::isinf(depth[c].at<float>(v, u));
    EXPECT_GT(none, pixels / 4) << cam.name;
  }
  // The stored projection table gives the same occluded points.
  ProjectionTable table(s.volume.grid, s.cameras);
  const std::vector<cv::Mat> from_table = occluderDepths(s.volume, t, s.cameras, &table, 2);
  for (size_t c = 0; c < s.cameras.size(); ++c) {
    const Eigen::Vector3d behind =
        s.centre + 0.3 * (s.centre - s.cameras[c].center()).normalized();
    EXPECT_EQ(s.maskAt(frontOcclusionMask(from_table[c], s.cameras[c], behind, 0.12), s.pixel(c, behind)), 0);
    EXPECT_NEAR(s.depthAt(from_table[c], s.pixel(c, s.centre)), s.depthAt(depth[c], s.pixel(c, s.centre)),
                2 * half_diag);
  }
}

// The min filter over the drawn pixels' neighbourhood only is the min filter of the whole
// image: random sparse drawings, boxes touching the image's borders, radii 1-9.
TEST(OccluderDepth, SpreadingOnlyNearTheDrawnPixelsIsTheWholeFilter) {
  cv::RNG rng(3);
  const float inf = std::numeric_limits<float>::infinity();
  for (int trial = 0; trial < 60; ++trial) {
    const int w = 40 + rng.uniform(0, 300), h = 30 + rng.uniform(0, 220);
    cv::Mat d(h, w, CV_32F, cv::Scalar(inf));
    const int bu0 = rng.uniform(0, w), bv0 = rng.uniform(0, h);
    const int bu1 = std::min(w - 1, bu0 + rng.uniform(0, w / 2)), bv1 = std::min(h - 1, bv0 + rng.uniform(0, h / 2));
    int u0 = w, v0 = h, u1 = -1, v1 = -1;
    for (int i = 0; i < 1 + rng.uniform(0, 200); ++i) {
      const int u = rng.uniform(bu0, bu1 + 1), v = rng.uniform(bv0, bv1 + 1);
      d.at<float>(v, u) = float(rng.uniform(0.3, 2.0));
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
    const int r = rng.uniform(1, 10);
    cv::Mat whole;
    cv::erode(d, whole, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1)), cv::Point(-1, -1), 1,
              cv::BORDER_CONSTANT, cv::Scalar(inf));
    spreadNearest(&d, r, cv::Rect(u0, v0, u1 - u0 + 1, v1 - v0 + 1));
    ASSERT_EQ(cv::norm(d != whole, cv::NORM_L1), 0.0) << "trial " << trial << ", " << w << "x" << h << ", r " << r;
  }
  cv::Mat f(4, 4, CV_8U);
  EXPECT_THROW(spreadNearest(&f, 1, cv::Rect(0, 0, 1, 1)), std::invalid_argument);
}

TEST(OccluderDepth, AnEmptyVolumeHidesNothing) {
  Scene s;
  s.volume.data.assign(s.volume.data.size(), 100);
  const std::vector<cv::Mat> depth = occluderDepths(s.volume, thresholdByte(0.75), s.cameras, nullptr);
  for (size_t c = 0; c < s.cameras.size(); ++c) {
    double lo = 0;
    cv::minMaxLoc(depth[c], &lo);
    EXPECT_TRUE(std::isinf(lo));
    EXPECT_EQ(cv::countNonZero(frontOcclusionMask(depth[c], s.cameras[c], s.centre, 0.12)),
              depth[c].rows * depth[c].cols);
  }
  // A volume whose data do not match its grid (a broken input) gives the same.
  s.volume.data.resize(10);
  EXPECT_TRUE(std::isinf(occluderDepths(s.volume, 0, s.cameras, nullptr)[0].at<float>(0, 0)));
}

TEST(OccluderDepth, BadArgumentsAreRefused) {
  Scene s;
  const cv::Mat depth(s.cameras[0].height, s.cameras[0].width, CV_32F, cv::Scalar(1.0f));
  EXPECT_THROW(frontOcclusionMask(depth, s.cameras[0], s.centre, -0.1), std::invalid_argument);
  EXPECT_THROW(frontOcclusionMask(depth, s.cameras[0], Eigen::Vector3d(NAN, 0, 0), 0.1), std::invalid_argument);
  EXPECT_THROW(frontOcclusionMask(cv::Mat(4, 4, CV_8UC1), s.cameras[0], s.centre, 0.1), std::invalid_argument);
}

}  // namespace
}  // namespace psfs
