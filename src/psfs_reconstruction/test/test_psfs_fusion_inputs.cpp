// The inputs of the fusion and their checks: voxel grids, projection tables (against the camera
// model, and the lens model's range), view evidence (terms, masks, pairs), and clear errors for
// bad grids, cameras, images and options. Part of test_psfs_fusion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "fusion_test_utils.h"
#include "psfs_fusion_test_support.h"
#include "psfs_reconstruction/binary_sfs.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "tabletop_capture/default_rig.h"

namespace psfs {
namespace {

using tabletop_capture::CameraModel;
using namespace fusion_test;  // NOLINT: the shared scene and comparison helpers

TEST(VoxelGrid, ReferenceResolutionsAndIndexing) {
  const VoxelGrid g16 = referenceGrid(Resolution::k16mm);
  EXPECT_EQ(g16.dims, Eigen::Vector3i(64, 64, 48));
  EXPECT_DOUBLE_EQ(g16.voxel_size, 1.0 / 64);
  EXPECT_TRUE(g16.origin.isApprox(Eigen::Vector3d(-0.5, -0.5, 0.0)));
  EXPECT_TRUE(g16.maxCorner().isApprox(Eigen::Vector3d(0.5, 0.5, 0.75)));
  EXPECT_EQ(referenceGrid(Resolution::k8mm).dims, Eigen::Vector3i(128, 128, 96));
  EXPECT_EQ(referenceGrid(Resolution::k4mm).dims, Eigen::Vector3i(256, 256, 192));
  const size_t i = g16.index(5, 7, 11);
  EXPECT_EQ(g16.coords(i), Eigen::Vector3i(5, 7, 11));
  Eigen::Vector3i v;
  ASSERT_TRUE(g16.voxelOf(g16.centre(i), &v));
  EXPECT_EQ(v, Eigen::Vector3i(5, 7, 11));
  EXPECT_FALSE(g16.voxelOf(Eigen::Vector3d(0.6, 0, 0.1), &v));
  // voxelRange: the voxels a box meets, clipped; every voxel centre inside the box among them.
  Eigen::Vector3i lo, hi;
  const Eigen::Vector3d bmin(-0.123, 0.031, 0.2), bmax(0.077, 0.1, 0.35);
  ASSERT_TRUE(g16.voxelRange(bmin, bmax, &lo, &hi));
  for (size_t k = 0; k < g16.numVoxels(); ++k) {
    const Eigen::Vector3d c = g16.centre(k);
    const Eigen::Vector3i x = g16.coords(k);
    const bool in_range = (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all();
    if ((c.array() >= bmin.array()).all() && (c.array() <= bmax.array()).all()) {
      EXPECT_TRUE(in_range) << k;
    }
    if (in_range) {  // ...and only voxels that meet the box: centres at most half a voxel out
      EXPECT_TRUE(((c - bmin).array() >= -0.5 * g16.voxel_size - 1e-12).all() &&
                  ((bmax - c).array() >= -0.5 * g16.voxel_size - 1e-12).all()) << k;
    }
  }
  ASSERT_TRUE(g16.voxelRange(Eigen::Vector3d(-2, -2, -2), Eigen::Vector3d(2, 2, 2), &lo, &hi));  // clipped
  EXPECT_EQ(lo, Eigen::Vector3i(0, 0, 0));
  EXPECT_EQ(hi, Eigen::Vector3i(63, 63, 47));
  EXPECT_FALSE(g16.voxelRange(Eigen::Vector3d(0.6, 0, 0), Eigen::Vector3d(0.7, 0.1, 0.1), &lo, &hi));  // off the grid
  EXPECT_FALSE(g16.voxelRange(bmax, bmin, &lo, &hi));  // empty box
  EXPECT_FALSE(g16.voxelRange(Eigen::Vector3d::Constant(NAN), bmax, &lo, &hi));
  const VoxelGrid hand = cubeGrid(Eigen::Vector3d(0.1, 0.2, 0.3), 0.3, 83);
  EXPECT_NEAR(hand.voxel_size, 0.3 / 83, 1e-15);
  EXPECT_TRUE(((hand.origin + hand.maxCorner()) / 2).isApprox(Eigen::Vector3d(0.1, 0.2, 0.3)));
  const VoxelGrid snapped = snappedCubeGrid(Eigen::Vector3d(0.1234, 0.2, 0.3), 0.3, 83);
  for (int a = 0; a < 3; ++a) {
    const double k = snapped.origin[a] / snapped.voxel_size;
    EXPECT_NEAR(k, std::round(k), 1e-9);
  }
}

TEST(ProjectionTable, MatchesCameraModelWithDistortion) {
  const auto rig = tabletop_capture::makeDefaultRig();
  const VoxelGrid grid = referenceGrid(Resolution::k16mm);
  ProjectionTableOptions o;
  o.multi_projection = true;
  o.storage = TableStorage::kPrecomputed;
  ProjectionTable pre(grid, rig.cameras, o);
  o.storage = TableStorage::kOnTheFly;
  ProjectionTable fly(grid, rig.cameras, o);
  EXPECT_TRUE(pre.precomputed());
  EXPECT_FALSE(fly.precomputed());
  EXPECT_EQ(fly.memoryBytes(), 0u);
  double max_err = 0;
  size_t observed = 0, checked = 0;
  for (int z = 0; z < grid.dims.z(); z += 3)
    for (int y = 0; y < grid.dims.y(); y += 3)
      for (int x = 0; x < grid.dims.x(); ++x)
        for (int c = 0; c < pre.numCameras(); ++c) {
          const uint32_t a = pre.centre(c, x, y, z);
          ASSERT_EQ(a, fly.centre(c, x, y, z));
          const CameraModel& cam = rig.cameras[c];
          Eigen::Vector2d px;
          const bool ok = cam.projectWorld(grid.centre(x, y, z), &px) && px.x() >= -0.5 &&
                          px.y() >= -0.5 && px.x() < cam.width - 0.5 && px.y() < cam.height - 0.5;
          ++checked;
          if (a == PackedUV::notObserved(cam.height)) {
            // Only points within float rounding of the border may disagree.
            if (ok) {
              const double d = std::min({px.x() + 0.5, px.y() + 0.5, cam.width - 0.5 - px.x(),
                                         cam.height - 0.5 - px.y()});
              EXPECT_LT(d, 1e-2);
            }
            continue;
          }
          ASSERT_TRUE(ok) << "packed a point the camera model puts outside the image";
          ++observed;
          max_err = std::max({max_err, std::abs(PackedUV::u(a) - px.x()), std::abs(PackedUV::v(a) - px.y())});
        }
  std::printf("projection table: %zu of %zu voxel-camera pairs observed, max |error| %.4f px "
              "(1/16 px packing), precomputed %.1f MB\n",
              observed, checked, max_err, pre.memoryBytes() / 1e6);
  EXPECT_LT(max_err, 1.0 / 16 + 1e-3);
  // The default rig sees the whole workspace from every camera.
  EXPECT_GT(observed, checked * 95 / 100);
  // The rebuild rule: unchanged inputs do not rebuild, a moved camera does.
  EXPECT_FALSE(pre.update(grid, rig.cameras));
  auto moved = rig.cameras;
  moved[3].world_T_camera.translation().x() += 0.01;
  EXPECT_TRUE(pre.update(grid, moved));
}

TEST(ProjectionTable, LensModelRangeIsLimited) {
  // Strong barrel distortion folds far-off-axis points back into the image; the table must
  // not accept them.
  CameraModel cam = test::ringCameras(1, Eigen::Vector3d(0, 0, 0), 1.0)[0];
  cam.distortion = {{-0.35, 0.0, 0.0, 0.0, 0.0}};
  VoxelGrid grid = cubeGrid(Eigen::Vector3d(0, 0, 0), 6.0, 60);  // far wider than the view
  ProjectionTable t(grid, {cam});
  size_t wrong = 0;
  for (size_t i = 0; i < grid.numVoxels(); ++i) {
    const Eigen::Vector3i v = grid.coords(i);
    const uint32_t a = t.centre(0, v.x(), v.y(), v.z());
    if (a == PackedUV::notObserved(cam.height)) continue;
    const Eigen::Vector3d pc = cam.cameraTWorld() * grid.centre(i);
    const double r = std::hypot(pc.x() / pc.z(), pc.y() / pc.z());
    // The image border is at |x| = 160 / 300 = 0.53 undistorted-ish: anything at r > 1.2 that
    // was accepted is a fold-back.
    wrong += r > 1.2;
  }
  EXPECT_EQ(wrong, 0u);
}

TEST(ViewEvidence, TermsMasksAndPairs) {
  // Odd sizes (incl. 1-pixel-wide) and a two-channel image: the terms are the log table of
  // the selected channel, switched-off pixels and the guard say "no evidence", and every pair
  // holds a pixel and the one below it with the border replicated.
  for (const cv::Size size : {cv::Size(37, 23), cv::Size(1, 5), cv::Size(6, 1)}) {
    cv::Mat img(size, CV_8UC2);
    cv::randu(img, 0, 256);
    ViewImage v;
    v.likelihood = img;
    v.channel = 1;
    v.active = cv::Mat(size, CV_8UC1, cv::Scalar(1));
    v.active.at<uint8_t>(0, 0) = 0;
    ViewEvidence ev;
    ev.set({v}, true);
    const int W = size.width, H = size.height, P = ViewEvidence::kQuadPad;
    auto L = [&](int x, int y) {
      return int(img.at<cv::Vec2b>(std::clamp(y, 0, H - 1), std::clamp(x, 0, W - 1))[1]);
    };
    EXPECT_TRUE(ev.hasInactivePixels(0));
    EXPECT_FALSE(ev.observed(0, 0));
    EXPECT_FALSE(ev.observed(0, W * H));  // guard
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        if (x + y > 0) {
          ASSERT_EQ(ev.terms(0)[y * W + x], ViewEvidence::logTerm(L(x, y)));
        }
        ASSERT_EQ(ev.likelihood(0)[y * W + x], L(x, y));
      }
    for (int y = -P; y < H + P; ++y)
      for (int x = -P; x < W + P; ++x) {
        const uint16_t q = ev.pairs(0)[(y + P) * ev.quadStride(0) + (x + P)];
        ASSERT_EQ(q, uint16_t(L(x, y) | L(x, y + 1) << 8)) << size << " at " << x << ", " << y;
      }
  }
  EXPECT_EQ(ViewEvidence::logTerm(255), 0);
  EXPECT_EQ(ViewEvidence::logTerm(0), std::lround(1024 * std::log(0.5 / 255)));
}

TEST(PsfsFusion, BadInputsGiveClearErrors) {
  const Scene s = ringScene(4);
  VoxelGrid g = sphereGrid(8);
  VoxelGrid bad = g;
  bad.origin.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ProjectionTable(bad, s.cams), std::invalid_argument);
  bad = g;
  bad.dims = Eigen::Vector3i(0, 8, 8);
  EXPECT_THROW(ProjectionTable(bad, s.cams), std::invalid_argument);
  bad = g;
  bad.voxel_size = 0;
  EXPECT_THROW(ProjectionTable(bad, s.cams), std::invalid_argument);
  EXPECT_THROW(ProjectionTable(g, {}), std::invalid_argument);
  auto cams = s.cams;
  cams[1].fx = std::numeric_limits<double>::quiet_NaN();
  try {
    ProjectionTable t(g, cams);
    FAIL() << "NaN focal length accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fx"), std::string::npos) << e.what();
  }
  cams = s.cams;
  cams[2].width = 0;
  EXPECT_THROW(ProjectionTable(g, cams), std::invalid_argument);
  EXPECT_THROW(cubeGrid(Eigen::Vector3d(0, 0, 0), 0.0, 10), std::invalid_argument);
  EXPECT_THROW(cubeGrid(Eigen::Vector3d(0, 0, 0), 0.3, 0), std::invalid_argument);

  ViewEvidence ev;
  EXPECT_THROW(ev.set({}, false), std::invalid_argument);
  EXPECT_THROW(ev.set({ViewImage()}, false), std::invalid_argument);
  ViewImage f32;
  f32.likelihood = cv::Mat(240, 320, CV_32FC1, cv::Scalar(0.5));
  EXPECT_THROW(ev.set({f32}, false), std::invalid_argument);
  ViewImage wrong_channel;
  wrong_channel.likelihood = cv::Mat(240, 320, CV_8UC2, cv::Scalar(0, 0));
  wrong_channel.channel = 2;
  EXPECT_THROW(ev.set({wrong_channel}, false), std::invalid_argument);
  ViewImage bad_mask;
  bad_mask.likelihood = cv::Mat(240, 320, CV_8UC1, cv::Scalar(0));
  bad_mask.active = cv::Mat(100, 100, CV_8UC1, cv::Scalar(1));
  EXPECT_THROW(ev.set({bad_mask}, false), std::invalid_argument);

  ProjectionTable table(g, s.cams);
  ProbabilityVolume out;
  PsfsFusion fusion;
  ev.set(test::toViews({s.images[0], s.images[1], s.images[2]}), false);
  EXPECT_THROW(fusion.fuse(table, ev, &out), std::invalid_argument);  // 3 views, 4 cameras
  std::vector<cv::Mat> small(4, cv::Mat(120, 160, CV_8UC1, cv::Scalar(0)));
  ev.set(test::toViews(small), false);
  EXPECT_THROW(fusion.fuse(table, ev, &out), std::invalid_argument);  // size mismatch
  ev.set(test::toViews(s.images), false);
  EXPECT_THROW(fusion.fuse(table, ev, nullptr), std::invalid_argument);
  PsfsOptions mo;
  mo.multi_projection = true;
  EXPECT_THROW(PsfsFusion(mo).fuse(table, ev, &out), std::invalid_argument);  // table lacks it

  PsfsOptions o;
  o.floor_z = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(PsfsFusion{o}, std::invalid_argument);
  o.floor_z = std::numeric_limits<double>::infinity();  // nothing would be left
  EXPECT_THROW(PsfsFusion{o}, std::invalid_argument);
  o = PsfsOptions();
  o.threshold = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(PsfsFusion{o}, std::invalid_argument);
  o.threshold = 0.4;
  EXPECT_THROW(PsfsFusion{o}, std::invalid_argument);
  o = PsfsOptions();
  o.occluded_views = 5;
  EXPECT_THROW(PsfsFusion{o}, std::invalid_argument);
  o = PsfsOptions();
  o.min_views = 0;
  EXPECT_THROW(PsfsFusion{o}, std::invalid_argument);
  o = PsfsOptions();
  o.hull_prior = -1;
  EXPECT_THROW(PsfsFusion{o}, std::invalid_argument);
  BinarySfsOptions bo;
  bo.threshold = std::numeric_limits<double>::infinity();
  EXPECT_THROW(BinarySfs{bo}, std::invalid_argument);
  BinarySfs bin;
  EXPECT_THROW(bin.carve(table, &out), std::invalid_argument);  // no silhouettes yet
}

}  // namespace
}  // namespace psfs

namespace psfs {
namespace fusion_test {
namespace {

// PsfsOptions::floor_z (the hand sub-volumes' desk top): the layers below it are 0 and the
// others are what fusing everything gives, to the byte, whether the layers are skipped (single
// projection, a stored or an on-the-fly table) or computed and cleared (multi-projection), and
// whatever the output buffer held before.
TEST(PsfsFusion, FloorLayersAreZeroAndTheRestUnchanged) {
  const Scene s = ringScene(6);
  const VoxelGrid g = sphereGrid(40);  // z from 0.15 to 0.45 m; the sphere 0.2 to 0.4 m
  const double floor = 0.27;            // through the sphere, 16 of 40 layers below
  const int below = layersBelow(g, floor);
  ASSERT_EQ(below, 16);
  for (const bool multi : {false, true})
    for (const TableStorage storage : {TableStorage::kAuto, TableStorage::kOnTheFly}) {
      PsfsOptions o;
      o.multi_projection = multi;
      ProbabilityVolume all = fusePsfs(g, s.cams, test::toViews(s.images), o, storage);
      ASSERT_GT(countAbove(all, thresholdByte(0.5)), 0u);
      ProjectionTableOptions to;
      to.multi_projection = multi;
      to.storage = storage;
      const ProjectionTable table(g, s.cams, to);
      ViewEvidence ev;
      ev.set(test::toViews(s.images), multi);
      o.floor_z = floor;
      ProbabilityVolume floored;
      floored.grid = g;
      floored.data.assign(g.numVoxels(), 255);  // a stale buffer
      PsfsFusion(o).fuse(table, ev, &floored);
      size_t cleared_in_hull = 0;
      const size_t layer = size_t(g.dims.x()) * size_t(g.dims.y());
      for (size_t i = 0; i < below * layer; ++i) cleared_in_hull += all.data[i] > thresholdByte(0.5);
      EXPECT_GT(cleared_in_hull, 0u) << "the floor cuts through the sphere";
      EXPECT_EQ(clearBelow(floor, &all), below);
      EXPECT_TRUE(floored.data == all.data) << (multi ? "multi-projection" : "single projection")
                                            << (storage == TableStorage::kOnTheFly ? ", on the fly" : "");
    }
}

}  // namespace
}  // namespace fusion_test
}  // namespace psfs
