// Foreground-class pSfS, all-classes pSfS and binary SfS on analytic scenes: spheres seen by
// synthetic cameras with exact silhouettes, where the visual hull is known in closed form.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include <cmath>
#include <cstdio>
#include <limits>

#include "../src/fusion_common.h"  // private: the face walk, checked against a brute force below
#include "../src/psfs_kernels.h"
#include "fusion_test_utils.h"
#include "psfs_reconstruction/all_classes_fusion.h"
#include "psfs_reconstruction/binary_sfs.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/simd_dispatch.h"
#include "tabletop_capture/default_rig.h"

namespace psfs {
namespace {

using tabletop_capture::CameraModel;
using test::Sphere;

constexpr uint8_t kIn = 230, kOut = 25;
// Distance (voxels) from a cone within which a multi-projection voxel may go either way: the
// face samples sit at +-1/2 voxel, and the median follows the centre once two axes' pairs are
// on its side, i.e. beyond 1/2 * sqrt(1/2) voxel.
constexpr double kFaceBand = 0.36;

// The threshold that separates "all views agree" from "one view disagrees" with these
// likelihood levels and C views: geometric middle of the two normalised posteriors.
double separatingThreshold(int C) {
  const double all = std::log(kIn / 255.0);
  const double one = ((C - 1) * std::log(kIn / 255.0) + std::log(kOut / 255.0)) / C;
  return std::exp(0.5 * (all + one));
}

struct Scene {
  std::vector<CameraModel> cams;
  std::vector<Sphere> spheres;
  std::vector<cv::Mat> images;
};

Scene ringScene(int n_cams = 8) {
  Scene s;
  s.spheres = {{Eigen::Vector3d(0.02, -0.01, 0.3), 0.1}};
  s.cams = test::ringCameras(n_cams, Eigen::Vector3d(0, 0, 0.3), 1.2);
  for (const auto& c : s.cams) s.images.push_back(test::sphereLikelihood(c, s.spheres, kIn, kOut));
  return s;
}

VoxelGrid sphereGrid(int n = 64) { return cubeGrid(Eigen::Vector3d(0.02, -0.01, 0.3), 0.3, n); }

ProbabilityVolume fusePsfs(const VoxelGrid& grid, const std::vector<CameraModel>& cams,
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
Comparison compare(const ProbabilityVolume& vol, uint8_t tb, const test::AnalyticHull& h) {
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

double sphereIoU(const ProbabilityVolume& vol, uint8_t tb, const std::vector<Sphere>& spheres) {
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

// ------------------------------------------------------------------------------------------

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

TEST(PsfsFusion, ScalarAndVectorKernelsGiveIdenticalBytes) {
  if (!avx2Available()) {
    GTEST_SKIP() << "no AVX2 on this CPU: only the scalar kernels exist";
  }
  const auto rig = tabletop_capture::makeDefaultRig();
  const std::vector<Sphere> spheres = {{Eigen::Vector3d(0.0, 0.0, 0.3), 0.2},
                                       {Eigen::Vector3d(0.2, 0.1, 0.5), 0.08}};
  std::vector<ViewImage> views;
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    ViewImage v;
    v.likelihood = test::noisy(test::sphereLikelihood(rig.cameras[c], spheres), 40, 0.05, 7 + c);
    if (c == 2) {
      v.active = cv::Mat(240, 320, CV_8UC1, cv::Scalar(1));
      v.active(cv::Rect(100, 50, 80, 120)).setTo(0);
    }
    views.push_back(v);
  }
  // Camera 1 zoomed in: it sees only part of the grid, so rows, columns and layers switch
  // between observed and unobserved voxels (the face kernels' fallbacks).
  auto cams = rig.cameras;
  cams[1].fx *= 2.5;
  cams[1].fy *= 2.5;
  // The reference grid, and one 37 voxels wide: rows padded to 40, so the AVX-512 kernel's
  // last step per row has a single chunk of 8 (5 voxels and 3 of padding).
  const VoxelGrid grids[2] = {referenceGrid(Resolution::k16mm),
                              cubeGrid(Eigen::Vector3d(0.0, 0.0, 0.3), 0.6, 37)};
  for (const VoxelGrid& grid : grids)
  for (bool multi : {false, true})
    for (int k : {0, 1, 2, 4}) {
      PsfsOptions o;
      o.multi_projection = multi;
      o.occluded_views = k;
      ProjectionTableOptions to;
      to.multi_projection = multi;
      ProjectionTable table(grid, cams, to);
      ViewEvidence ev;
      ev.set(views, multi);
      ProbabilityVolume vec, sca, vec2;
      PsfsFusion(o).fuse(table, ev, &vec);  // AVX-512 where the CPU has it, else AVX2
      forceAvx2Kernels(true);
      PsfsFusion(o).fuse(table, ev, &vec2);
      forceAvx2Kernels(false);
      forceScalarKernels(true);
      PsfsFusion(o).fuse(table, ev, &sca);
      forceScalarKernels(false);
      ASSERT_EQ(vec.data, sca.data) << grid.describe() << " multi " << multi << " k " << k
                                    << (avx512KernelsActive() ? " (AVX-512)" : " (AVX2)");
      ASSERT_EQ(vec2.data, sca.data) << grid.describe() << " multi " << multi << " k " << k << " (AVX2)";
      // Each thread walks its own range of layers: the split must not show in the bytes.
      for (int threads : {1, 3, 5}) {
        o.threads = threads;
        ProbabilityVolume t;
        PsfsFusion(o).fuse(table, ev, &t);
        ASSERT_EQ(t.data, vec.data) << grid.describe() << " multi " << multi << " k " << k << ", "
                                    << threads << " threads";
      }
    }
}

// The shared face samples follow the rule of psfs_kernels.h whatever the walk: a brute force
// per voxel (each face from the table and the likelihood bytes directly) against the walk the
// reference variants use, on a rig where one camera sees only part of the grid.
TEST(PsfsFusion, FaceSamplesFollowTheSharingRule) {
  const auto rig = tabletop_capture::makeDefaultRig();
  auto cams = rig.cameras;
  cams[1].fx *= 2.5;
  cams[1].fy *= 2.5;
  const std::vector<Sphere> spheres = {{Eigen::Vector3d(0.0, 0.0, 0.3), 0.2}};
  std::vector<ViewImage> views;
  std::vector<cv::Mat> images;
  for (size_t c = 0; c < cams.size(); ++c) {
    images.push_back(test::noisy(test::sphereLikelihood(cams[c], spheres), 40, 0.05, 31 + c));
    views.push_back(ViewImage{images.back(), 0, cv::Mat()});
  }
  // A switched-off patch: it takes evidence away, but which samples a face uses must not change.
  views[2].active = cv::Mat(240, 320, CV_8UC1, cv::Scalar(1));
  views[2].active(cv::Rect(100, 50, 80, 120)).setTo(0);
  const VoxelGrid grid = cubeGrid(Eigen::Vector3d(0.0, 0.0, 0.3), 0.6, 20);  // 20^3, 30 mm
  ProjectionTableOptions to;
  to.multi_projection = true;
  const ProjectionTable table(grid, cams, to);
  ViewEvidence ev;
  ev.set(views, true);
  const std::vector<detail::KernelView> kv = detail::kernelViews(ev);
  const int C = table.numCameras(), nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const int nxp = table.paddedRowLength(), chunks = table.chunksPerRow();

  // Bilinear sample of camera c at packed centre uv + sign * packed offset, straight from the
  // bytes with clamped coordinates (1/16 px weights).
  auto sample = [&](int c, uint32_t uv, uint32_t off, int sign) {
    const int U = int(uv & 0xFFFF) + sign * int(int16_t(off & 0xFFFF)) - 8;  // 16 * (u - pixel 0)
    const int V = int(uv >> 16) + sign * (int32_t(off) >> 16) - 8;
    const int u0 = U >> 4, v0 = V >> 4, fu = U & 15, fv = V & 15;  // floor for negatives too
    auto at = [&](int u, int v) {
      return int(images[c].at<uint8_t>(std::clamp(v, 0, images[c].rows - 1), std::clamp(u, 0, images[c].cols - 1)));
    };
    return (at(u0, v0) * (16 - fv) + at(u0, v0 + 1) * fv) * (16 - fu) +
           (at(u0 + 1, v0) * (16 - fv) + at(u0 + 1, v0 + 1) * fv) * fu;
  };
  std::vector<uint32_t> scratch(table.offsetScratchSize());
  auto offset = [&](int c, int x, int y, int z, int axis) {
    return table.rowOffsets(size_t(y) + size_t(ny) * z, scratch.data())[(c * chunks + x / ProjectionTable::kChunk) * 3 + axis];
  };
  size_t checked = 0, unobserved = 0, fallbacks = 0;
  std::vector<int32_t> walk(grid.numVoxels() * C);
  for (int threads : {1, 2, 3}) {
    detail::forEachFaceRow(table, kv, threads, [&](size_t r, const uint32_t* centres, const uint32_t* offsets,
                                                   uint16_t* yface, uint16_t* zface) {
      std::vector<int32_t> pairs(size_t(C) * nxp);
      detail::medianPairsOfRow(kv.data(), C, nxp, centres, offsets, yface, zface, pairs.data());
      for (int c = 0; c < C; ++c)
        for (int x = 0; x < nx; ++x) walk[(r * nx + x) * C + c] = pairs[size_t(c) * nxp + x];
    });
    for (int z = 0; z < nz; ++z)
      for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x)
          for (int c = 0; c < C; ++c) {
            const uint32_t no = PackedUV::notObserved(cams[c].height);
            const uint32_t p = table.centre(c, x, y, z);
            if (p == no) {
              ++unobserved;
              continue;
            }
            const int lower[3][3] = {{x - 1, y, z}, {x, y - 1, z}, {x, y, z - 1}};
            int32_t f[6];
            for (int a = 0; a < 3; ++a) {
              f[2 * a + 1] = sample(c, p, offset(c, x, y, z, a), 1);
              const int* l = lower[a];
              const bool has = l[0] >= 0 && l[1] >= 0 && l[2] >= 0;
              const uint32_t q = has ? table.centre(c, l[0], l[1], l[2]) : no;
              fallbacks += has && q == no;
              f[2 * a] = q != no ? sample(c, q, offset(c, l[0], l[1], l[2], a), 1)
                                 : sample(c, p, offset(c, x, y, z, a), -1);
            }
            std::sort(f, f + 6);
            ASSERT_EQ(walk[(grid.index(x, y, z)) * C + c], f[2] + f[3])
                << "voxel (" << x << ", " << y << ", " << z << ") camera " << c << ", " << threads << " threads";
            ++checked;
          }
  }
  std::printf("face samples: %zu voxel-camera medians match the brute force (%zu unobserved, %zu "
              "faces sampled from the upper voxel because the lower one is unobserved)\n",
              checked, unobserved, fallbacks);
  EXPECT_GT(unobserved, 0u);
  EXPECT_GT(fallbacks, 0u);
}

// The AVX-512 and AVX2 row projections do the same float operations per lane: their tables
// must be identical to the bit (volumes then agree across CPUs with either extension).
TEST(ProjectionTable, Avx512AndAvx2ProjectionsAreIdentical) {
  if (!avx512Available()) GTEST_SKIP() << "no AVX-512 on this CPU: only the AVX2 projection runs";
  const auto rig = tabletop_capture::makeDefaultRig();
  ProjectionTableOptions o;
  o.multi_projection = true;
  o.storage = TableStorage::kPrecomputed;
  const ProjectionTable wide(referenceGrid(Resolution::k16mm), rig.cameras, o);
  forceAvx2Kernels(true);
  const ProjectionTable narrow(referenceGrid(Resolution::k16mm), rig.cameras, o);
  forceAvx2Kernels(false);
  for (size_t r = 0; r < wide.grid().numRows(); ++r) {
    const uint32_t* a = wide.rowCentres(r, nullptr);
    const uint32_t* b = narrow.rowCentres(r, nullptr);
    ASSERT_EQ(0, std::memcmp(a, b, wide.centreScratchSize() * sizeof(uint32_t))) << "row " << r;
  }
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
