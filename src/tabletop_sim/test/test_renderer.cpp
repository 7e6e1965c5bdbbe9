// Tests of the simulated rig (renderer, body model, scripts, oracle) against physics and the
// ground truth. Figures are printed so regressions show as numbers, not only as failures.
#include <cmath>
#include <cstdio>
#include <memory>

#include <gtest/gtest.h>

#include "tabletop_sim/body_model.h"
#include "tabletop_capture/default_rig.h"
#include "tabletop_sim/motion_script.h"
#include "tabletop_sim/oracle.h"
#include "tabletop_sim/renderer.h"
#include "tabletop_sim/scene.h"
#include "tabletop_sim/simulated_rig.h"

using namespace tabletop_capture;
using namespace tabletop_sim;
using Eigen::Vector3d;

namespace {

// One default rig shared by the tests (its per-camera precomputation is the slow part).
class SimRigTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    SimOptions o;
    o.render_masks = true;
    rig_ = new SimulatedRig(o);
  }
  static void TearDownTestSuite() {
    delete rig_;
    rig_ = nullptr;
  }
  static SimulatedRig* rig_;
};
SimulatedRig* SimRigTest::rig_ = nullptr;

bool nearestPixel(const CameraModel& cam, const Vector3d& p, int* x, int* y) {
  Eigen::Vector2d px;
  if (!cam.projectWorld(p, &px)) return false;
  *x = static_cast<int>(std::lround(px.x()));
  *y = static_cast<int>(std::lround(px.y()));
  return *x >= 0 && *y >= 0 && *x < cam.width && *y < cam.height;
}

bool anyDifference(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::absdiff(a, b, d);
  return cv::countNonZero(d.reshape(1)) > 0;
}

}  // namespace

// The true hand centroid, where a camera sees it, lands on a pixel of skin chromaticity.
TEST_F(SimRigTest, HandCentroidProjectsOnSkin) {
  const Vector3d skin = materialAlbedo(Material::SKIN);
  const double skin_r = skin.x() / skin.sum(), skin_g = skin.y() / skin.sum();
  const double sigma = rig_->options().noise_sigma;
  int visible = 0, on_skin = 0, frames = 0;
  double worst = 0;
  for (int f = rig_->options().empty_frames; f < rig_->scriptFrames(); f += 10, ++frames) {
    const SimFrame frame = rig_->render(f);
    const Oracle oracle = rig_->oracle(f);
    for (Side side : {Side::LEFT, Side::RIGHT}) {
      const Vector3d c = side == Side::LEFT ? frame.truth.left_hand : frame.truth.right_hand;
      for (size_t ci = 0; ci < rig_->rig().cameras.size(); ++ci) {
        const CameraModel& cam = rig_->rig().cameras[ci];
        int x, y;
        if (!nearestPixel(cam, c, &x, &y) || oracle.occluded(cam, c, handPart(side))) continue;
        ++visible;
        const cv::Vec3b px = frame.images[ci].at<cv::Vec3b>(y, x);
        const double s = px[0] + px[1] + px[2];
        // Chromaticity noise of a pixel of brightness s: about sigma * sqrt(2) / s; allow 4x.
        const double tol = 0.01 + 4.0 * sigma * std::sqrt(2.0) / std::max(s, 1.0);
        const double err = std::hypot(px[0] / s - skin_r, px[1] / s - skin_g);
        if (err <= tol) ++on_skin;
        worst = std::max(worst, err);
      }
    }
  }
  const double frac = visible ? static_cast<double>(on_skin) / visible : 0.0;
  std::printf("[ figures ] hand centroid on skin: %d / %d visible cases (%.1f%%) over %d frames\n",
              on_skin, visible, 100.0 * frac, frames);
  EXPECT_GT(visible, 500);
  EXPECT_GE(frac, 0.95);
}

// A binary visual hull carved from the renderer's own masks contains the oracle's person.
TEST_F(SimRigTest, VisualHullFromMasksContainsOracle) {
  const double voxel = 0.016;
  const Vector3d lo(-0.5, -0.5, 0.0);
  const int nx = 62, ny = 62, nz = 46;  // 0.992 x 0.992 x 0.736 m
  const auto& cams = rig_->rig().cameras;
  const int e = rig_->options().empty_frames;
  long total_occ = 0, total_kept = 0, total_hull = 0;
  for (int f : {e + 120, e + 430, e + 620}) {
    const SimFrame frame = rig_->render(f);
    const Oracle oracle = rig_->oracle(f);
    long occ = 0, kept = 0, hull = 0;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const Vector3d p = lo + voxel * Vector3d(i + 0.5, j + 0.5, k + 0.5);
          bool in_hull = true;
          for (size_t c = 0; c < cams.size() && in_hull; ++c) {
            int x, y;
            if (!nearestPixel(cams[c], p, &x, &y)) continue;
            // A camera sees the voxel unless the static scene is in front of it there.
            const double dist = (p - cams[c].center()).norm();
            if (rig_->renderer().backgroundDepth(c).at<float>(y, x) < dist) continue;
            in_hull = frame.person_masks[c].at<uint8_t>(y, x) == 255;
          }
          const bool in_person = oracle.insidePerson(p);
          occ += in_person;
          kept += in_person && in_hull;
          hull += in_hull;
        }
    std::printf("[ figures ] frame %d: oracle voxels %ld, inside hull %ld (%.2f%%), hull %ld\n", f,
                occ, kept, 100.0 * kept / std::max(occ, 1L), hull);
    total_occ += occ;
    total_kept += kept;
    total_hull += hull;
  }
  EXPECT_GT(total_occ, 5000);
  EXPECT_GE(static_cast<double>(total_kept) / total_occ, 0.99);
  // The hull is a superset but not absurdly larger (8 views carve well).
  EXPECT_LT(total_hull, 3 * total_occ);
}

// Empty frames: no person, and the image is the background plus zero-mean noise of sigma.
TEST_F(SimRigTest, EmptyFramesAreBackgroundPlusNoise) {
  const double sigma = rig_->options().noise_sigma;
  for (int f : {0, rig_->options().empty_frames - 1}) {
    const SimFrame frame = rig_->render(f);
    EXPECT_FALSE(frame.truth.person_present);
    EXPECT_TRUE(std::isnan(frame.truth.left_hand.x()));
    EXPECT_TRUE(rig_->oracle(f).primitives().empty());
    double sum = 0, sum2 = 0;
    long n = 0;
    for (size_t c = 0; c < frame.images.size(); ++c) {
      EXPECT_EQ(cv::countNonZero(frame.person_masks[c]), 0);
      const cv::Mat& bg = rig_->renderer().backgroundColour(c);
      for (int y = 0; y < bg.rows; ++y)
        for (int x = 0; x < bg.cols; ++x)
          for (int k = 0; k < 3; ++k) {
            const float b = bg.at<cv::Vec3f>(y, x)[k];
            if (b < 10 || b > 245) continue;  // clipping would bias the statistics
            const double d = frame.images[c].at<cv::Vec3b>(y, x)[k] - b;
            sum += d;
            sum2 += d * d;
            ++n;
          }
    }
    const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
    std::printf(
        "[ figures ] empty frame %d: image - background mean %.3f, sd %.3f (sigma %.1f, "
        "+ quantisation -> %.3f)\n",
        f, mean, sd, sigma, std::sqrt(sigma * sigma + 1.0 / 12));
    EXPECT_LT(std::abs(mean), 0.05);
    EXPECT_NEAR(sd, std::sqrt(sigma * sigma + 1.0 / 12), 0.05 * sigma);
  }
}

TEST_F(SimRigTest, DeterministicAndCullingIsExact) {
  const int f = rig_->options().empty_frames + 300;
  const SimFrame a = rig_->render(f), b = rig_->render(f);
  const std::vector<Primitive> person = rig_->person(f);
  RenderOutput naive;
  rig_->renderer().renderWithoutCulling(person, f, true, &naive);
  RenderOptions one_thread;
  one_thread.threads = 1;
  Renderer r1(rig_->rig(), one_thread), r_seed2(rig_->rig(), [] {
    RenderOptions o;
    o.seed = 2;
    return o;
  }());
  RenderOutput single, other_seed;
  r1.render(person, f, true, &single);
  r_seed2.render(person, f, false, &other_seed);
  double abs_sum = 0;
  long n = 0;
  for (size_t c = 0; c < a.images.size(); ++c) {
    EXPECT_FALSE(anyDifference(a.images[c], b.images[c])) << "camera " << c;
    EXPECT_FALSE(anyDifference(a.images[c], naive.images[c])) << "culling, camera " << c;
    EXPECT_FALSE(anyDifference(a.person_masks[c], naive.person_masks[c])) << "camera " << c;
    EXPECT_FALSE(anyDifference(a.skin_masks[c], naive.skin_masks[c])) << "camera " << c;
    EXPECT_FALSE(anyDifference(a.images[c], single.images[c])) << "threads, camera " << c;
    cv::Mat d;
    cv::absdiff(a.images[c], other_seed.images[c], d);
    abs_sum += cv::sum(d)[0] + cv::sum(d)[1] + cv::sum(d)[2];
    n += 3L * d.total();
  }
  // Two independent N(0, s^2) noises differ by N(0, 2 s^2): E|d| = 2 s / sqrt(pi).
  const double s = rig_->options().noise_sigma;
  std::printf("[ figures ] seed 1 vs seed 2: mean |difference| %.3f grey levels (expected %.3f)\n",
              abs_sum / n, 2 * s / std::sqrt(M_PI));
  EXPECT_NEAR(abs_sum / n, 2 * s / std::sqrt(M_PI), 0.15 * s);
}

// Culling stays exact where bounds are hard: a camera amid the person (primitives straddle
// its image plane) and a wide lens with strong barrel distortion.
TEST(SimRenderer, CullingExactForCloseAndDistortedCameras) {
  const BodyModel model;
  const BodyPose pose = MotionScript::create("fold_hands", model).poseAt(2.0);
  const std::vector<Primitive> person = model.build(pose);
  RigDescription rig;
  for (int i = 0; i < 2; ++i) {
    CameraModel cam;
    cam.name = "cam" + std::to_string(i);
    cam.frame_id = cam.name + "_optical_frame";
    cam.width = 160;
    cam.height = 120;
    cam.fx = cam.fy = i == 0 ? 60.0 : 70.0;
    cam.cx = 79.5;
    cam.cy = 59.5;
    if (i == 1) cam.distortion = {{-0.3, 0.08, 0.001, -0.001, 0.0}};
    const Vector3d palm = model.palmCentre(pose, Side::LEFT);
    cam.world_T_camera = i == 0 ? tabletop_capture::lookAt(palm + Vector3d(0.05, 0.02, 0.12), palm)
                                : tabletop_capture::lookAt(Vector3d(0.3, 0.3, 0.6), palm);
    rig.cameras.push_back(cam);
  }
  const Renderer r(rig);
  RenderOutput culled, naive;
  r.render(person, 7, true, &culled);
  r.renderWithoutCulling(person, 7, true, &naive);
  for (int c = 0; c < 2; ++c) {
    EXPECT_GT(cv::countNonZero(culled.person_masks[c]), 500) << c;
    EXPECT_FALSE(anyDifference(culled.images[c], naive.images[c])) << c;
    EXPECT_FALSE(anyDifference(culled.person_masks[c], naive.person_masks[c])) << c;
  }
}

TEST(Bayer, MosaicKeepsTheRightChannel) {
  cv::Mat rgb(6, 8, CV_8UC3);
  for (int y = 0; y < rgb.rows; ++y)
    for (int x = 0; x < rgb.cols; ++x) rgb.at<cv::Vec3b>(y, x) = cv::Vec3b(10 + x, 100 + y, 200);
  const struct {
    const char* enc;
    const char* letters;
  } cases[4] = {{"bayer_rggb8", "rggb"},
                {"bayer_bggr8", "bggr"},
                {"bayer_gbrg8", "gbrg"},
                {"bayer_grbg8", "grbg"}};
  for (const auto& k : cases) {
    const cv::Mat m = mosaicBayer(rgb, k.enc);
    ASSERT_EQ(m.type(), CV_8UC1);
    for (int y = 0; y < rgb.rows; ++y)
      for (int x = 0; x < rgb.cols; ++x) {
        const char l = k.letters[2 * (y & 1) + (x & 1)];
        const int ch = l == 'r' ? 0 : (l == 'g' ? 1 : 2);
        EXPECT_EQ(m.at<uint8_t>(y, x), rgb.at<cv::Vec3b>(y, x)[ch])
            << k.enc << " " << y << "," << x;
      }
  }
  EXPECT_THROW(mosaicBayer(rgb, "bayer_rgbg8"), std::invalid_argument);
  EXPECT_THROW(mosaicBayer(cv::Mat(4, 4, CV_8UC1), "bayer_rggb8"), std::invalid_argument);
}

TEST_F(SimRigTest, BayerOptionMosaicsTheRgbFrame) {
  SimOptions o;
  o.bayer = "bayer_grbg8";
  o.num_cameras = 2;
  const SimulatedRig bayer_rig(o);
  o.bayer = "none";
  const SimulatedRig rgb_rig(o);
  const int f = 200;
  const SimFrame a = bayer_rig.render(f), b = rgb_rig.render(f);
  ASSERT_EQ(a.images.size(), 2u);
  for (size_t c = 0; c < 2; ++c) {
    EXPECT_EQ(a.images[c].type(), CV_8UC1);
    EXPECT_FALSE(anyDifference(a.images[c], mosaicBayer(b.images[c], "bayer_grbg8")));
  }
}

// Each hand leaves the workspace box once, for about 1.5 s, and comes back.
TEST(SimScripts, LeaveReenterLeavesAndReturns) {
  SimOptions o;
  o.script = "leave_reenter";
  o.num_cameras = 1;
  const SimulatedRig rig(o);
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    int exits = 0, entries = 0, out_frames = 0;
    bool prev = true;
    for (int f = o.empty_frames; f < rig.scriptFrames(); ++f) {
      const GroundTruth g = rig.truth(f);
      const bool in = side == Side::LEFT ? g.left_hand_in_workspace : g.right_hand_in_workspace;
      exits += prev && !in;
      entries += !prev && in;
      out_frames += !in;
      prev = in;
      EXPECT_TRUE(g.head_in_workspace);
    }
    std::printf("[ figures ] leave_reenter %s hand: %d exit(s), %d re-entry(ies), %.2f s out\n",
                side == Side::LEFT ? "left" : "right", exits, entries, out_frames / o.fps);
    EXPECT_EQ(exits, 1);
    EXPECT_EQ(entries, 1);
    EXPECT_TRUE(prev);
    EXPECT_GE(out_frames / o.fps, 1.2);
    EXPECT_LE(out_frames / o.fps, 2.5);
  }
}

// Over the whole `all` script (and across the loop): the IK reaches every scripted palm
// target, the arm is never overstretched, hands move at human speeds.
TEST(SimScripts, HandsReachableAndHumanSpeed) {
  const BodyModel model;
  const MotionScript script = MotionScript::create("all", model);
  const double fps = 25.0;
  const int frames = static_cast<int>(std::ceil(script.duration() * fps));
  double worst_residual = 0, max_speed = 0, max_reach = 0;
  Vector3d prev[2];
  for (int f = 0; f <= frames; ++f) {
    const double t = (f % frames) / fps;  // f == frames: the first frame of the next loop
    const BodyPose pose = script.poseAt(t);
    const std::vector<Primitive> prims = model.build(pose);
    const BodyFrames fr = model.forward(pose);
    for (Side side : {Side::LEFT, Side::RIGHT}) {
      const int i = static_cast<int>(side);
      worst_residual = std::max(worst_residual,
                                (model.palmCentre(pose, side) - script.palmTarget(t, side)).norm());
      max_reach = std::max(max_reach, (fr.wrist[i] - fr.shoulder[i]).norm());
      const Vector3d c = handCentroid(prims, side);
      if (f > 0) max_speed = std::max(max_speed, (c - prev[i]).norm() * fps);
      prev[i] = c;
    }
  }
  std::printf(
      "[ figures ] all script %.1f s: worst IK residual %.2f mm, max shoulder-wrist "
      "%.3f m (arm %.3f m), max hand speed %.2f m/s\n",
      script.duration(), 1e3 * worst_residual, max_reach,
      BodyModel::kUpperArm + BodyModel::kForearm, max_speed);
  EXPECT_LT(worst_residual, 0.005);
  EXPECT_LE(max_reach, BodyModel::kUpperArm + BodyModel::kForearm + 1e-9);
  EXPECT_LE(max_speed, 1.5);
}

// Hands over the desk rest on it: no hand primitive reaches below the desk top in any script
// (the truth would otherwise hold volume no camera sees), and the lift that guarantees this
// stays small (the scripts' palm heights are plausible to begin with).
TEST(SimScripts, HandsNeverSinkIntoTheDesk) {
  const BodyModel model;
  const MotionScript script = MotionScript::create("all", model);
  const DeskTop desk;
  double lowest = 1.0, max_lift = 0.0;
  int on_desk = 0;
  for (double t = 0.0; t <= script.duration(); t += 0.04) {
    const BodyPose pose = script.poseAt(t);
    const std::vector<Primitive> prims = model.build(pose);
    for (Side side : {Side::LEFT, Side::RIGHT}) {
      const Vector3d palm = model.palmCentre(pose, side);
      if (palm.x() < desk.x_min || palm.x() > desk.x_max || palm.y() < desk.y_min ||
          palm.y() > desk.y_max || palm.z() < -0.02)
        continue;  // off the desk (e.g. in the lap): no contact
      ++on_desk;
      for (const Primitive& p : prims)
        if (p.part == handPart(side)) lowest = std::min(lowest, p.bounds().min().z());
      max_lift = std::max(max_lift, script.palmTarget(t, side).z() - script.keyAt(t).arms[int(side)].palm.z());
    }
  }
  std::printf("[ figures ] all script: %d hand-frames over the desk, lowest hand point %.2f mm "
              "above the desk top, largest palm lift %.1f mm\n",
              on_desk, 1e3 * lowest, 1e3 * max_lift);
  EXPECT_GT(on_desk, 1000);
  EXPECT_GE(lowest, 0.0);
  EXPECT_LT(max_lift, 0.06);
}

TEST(SimScripts, NamesLoopingAndRestPose) {
  EXPECT_EQ(MotionScript::names().size(), 8u);
  try {
    MotionScript::create("dance");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("reach_targets"), std::string::npos) << e.what();
  }
  const BodyModel model;
  const BodyPose rest = BodyModel::restPose();
  const BodyPose start = MotionScript::create("wave", model).poseAt(0.0);
  for (int i = 0; i < dof::COUNT; ++i) EXPECT_NEAR(rest.state[i], start.state[i], 1e-6) << i;
  SimOptions o;
  o.script = "static";
  o.num_cameras = 1;
  const SimulatedRig rig(o);
  const int first = o.empty_frames;
  EXPECT_FALSE(rig.personPresent(first - 1));
  EXPECT_TRUE(rig.personPresent(rig.scriptFrames()));  // loops without new empty frames
  EXPECT_DOUBLE_EQ(rig.scriptTime(rig.scriptFrames()), 0.0);
  EXPECT_LT((rig.truth(first).head - rig.truth(rig.scriptFrames()).head).norm(), 1e-12);
  // The head sits where DESIGN.md puts a seated user, inside the workspace.
  const Vector3d head = model.headCentre(rest);
  std::printf("[ figures ] rest head centre (%.3f, %.3f, %.3f)\n", head.x(), head.y(), head.z());
  EXPECT_LT((head - Vector3d(0, -0.42, 0.58)).norm(), 0.03);
}

// Every camera of the default rig sees the head and both hands of the resting person.
TEST_F(SimRigTest, WholePersonInView) {
  const GroundTruth g = rig_->truth(rig_->options().empty_frames);
  for (const CameraModel& cam : rig_->rig().cameras)
    for (const Vector3d& p : {g.head, g.left_hand, g.right_hand}) {
      int x, y;
      EXPECT_TRUE(nearestPixel(cam, p, &x, &y)) << cam.name;
    }
}

// The person's shadow darkens desk pixels when a hand is held above the desk.
TEST_F(SimRigTest, ShadowsDarkenTheDesk) {
  // A frame of the `point` part: the right hand points above the desk.
  int f = -1;
  for (int k = rig_->options().empty_frames; k < rig_->scriptFrames(); ++k) {
    const GroundTruth g = rig_->truth(k);
    if (g.right_hand.z() > 0.18 && g.right_hand.y() > -0.1) {
      f = k;
      break;
    }
  }
  ASSERT_GE(f, 0);
  RenderOptions no_shadow;
  no_shadow.shadows = false;
  const Renderer flat(rig_->rig(), no_shadow);
  const SimFrame lit = rig_->render(f);
  RenderOutput out;
  flat.render(rig_->person(f), f, true, &out);
  long darker = 0, brighter = 0, on_person = 0;
  double drop = 0;
  for (size_t c = 0; c < lit.images.size(); ++c)
    for (int y = 0; y < lit.images[c].rows; ++y)
      for (int x = 0; x < lit.images[c].cols; ++x) {
        const cv::Vec3b a = lit.images[c].at<cv::Vec3b>(y, x),
                        b = out.images[c].at<cv::Vec3b>(y, x);
        const int d = (b[0] + b[1] + b[2]) - (a[0] + a[1] + a[2]);
        if (d > 30) {
          ++darker;
          drop += d / 3.0;
          // The desk darkens, not the person: a darkened pixel marked as person can only be
          // a silhouette-rim pixel whose footprint is partly desk (masks are conservative).
          on_person += lit.person_masks[c].at<uint8_t>(y, x) == 255;
        }
        brighter += d < 0;
      }
  std::printf(
      "[ figures ] frame %d: %ld pixels darkened by the person's shadow (%ld on the "
      "silhouette rim), mean drop %.1f grey levels\n",
      f, darker, on_person, darker ? drop / darker : 0.0);
  EXPECT_GT(darker, 100);
  EXPECT_LT(on_person, darker / 5);
  EXPECT_EQ(brighter, 0);
}

// short_sleeves turns the forearm into skin in the ground truth (long sleeves: shirt).
TEST(SimBody, ShortSleevesMakeForearmsSkin) {
  SimOptions o;
  o.num_cameras = 1;
  o.script = "static";
  const SimulatedRig long_rig(o);
  o.short_sleeves = true;
  const SimulatedRig short_rig(o);
  const int f = o.empty_frames;
  const BodyFrames fr = long_rig.body().forward(long_rig.pose(f));
  for (int i = 0; i < 2; ++i) {
    const Vector3d mid = 0.5 * (fr.elbow[i] + fr.wrist[i]);
    EXPECT_TRUE(long_rig.oracle(f).insidePerson(mid));
    EXPECT_FALSE(long_rig.oracle(f).insideSkin(mid));
    EXPECT_TRUE(short_rig.oracle(f).insideSkin(mid));
  }
  // Face is skin, the back of the head is hair, the palm is skin.
  const BodyPose pose = long_rig.pose(f);
  const Oracle oracle = long_rig.oracle(f);
  EXPECT_TRUE(oracle.insideSkin(long_rig.body().headCentre(pose)) ||
              oracle.insidePart(long_rig.body().headCentre(pose), BodyPart::HEAD));
  EXPECT_TRUE(oracle.insideSkin(long_rig.body().palmCentre(pose, Side::LEFT)));
  const Vector3d back_of_head = fr.head * Vector3d(0, -0.08, 0.17);
  EXPECT_TRUE(oracle.insidePerson(back_of_head));
  EXPECT_FALSE(oracle.insideSkin(back_of_head));
}

TEST(SimPrimitives, RayInsideNormalAgree) {
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Primitive prims[3] = {
      Primitive::sphere({0.1, 0.2, 0.3}, 0.05, Material::SKIN, BodyPart::HEAD),
      Primitive::capsule({0, 0, 0}, {0.2, 0.1, 0.05}, 0.03, Material::SKIN, BodyPart::LEFT_HAND),
      Primitive::ellipsoid({0.0, 0.1, 0.0}, R, {0.08, 0.04, 0.02}, Material::SHIRT,
                           BodyPart::TORSO)};
  for (const Primitive& p : prims) {
    Vector3d c;
    double r;
    p.boundingSphere(&c, &r);
    for (int k = 0; k < 200; ++k) {
      const Vector3d o = c + Vector3d::Random().normalized() * 1.0;
      const Vector3d target = c + Vector3d::Random() * r;
      const Vector3d d = (target - o).normalized();
      double t;
      if (!p.intersect(o, d, &t)) {
        EXPECT_FALSE(p.contains(target));
        continue;
      }
      const Vector3d hit = o + t * d;
      EXPECT_TRUE(p.contains(hit - 1e-6 * p.normal(hit)));
      EXPECT_FALSE(p.contains(hit + 1e-6 * p.normal(hit)));
      EXPECT_FALSE(p.contains(o + (t - 1e-6) * d));
      EXPECT_TRUE(p.bounds().contains(hit));
      // From inside, the ray exits through the surface.
      double t_out;
      ASSERT_TRUE(p.intersect(hit + 1e-4 * d, d, &t_out));
      EXPECT_FALSE(p.contains(hit + 1e-4 * d + (t_out + 1e-6) * d));
    }
  }
}

TEST(SimRig, BadOptionsThrow) {
  auto throws = [](auto change) {
    SimOptions o;
    o.num_cameras = 1;
    change(o);
    EXPECT_THROW(SimulatedRig rig(o), std::invalid_argument);
  };
  throws([](SimOptions& o) { o.fps = 0; });
  throws([](SimOptions& o) { o.fps = NAN; });
  throws([](SimOptions& o) { o.empty_frames = -1; });
  throws([](SimOptions& o) { o.noise_sigma = -1; });
  throws([](SimOptions& o) { o.bayer = "rggb"; });
  throws([](SimOptions& o) { o.script = "dance"; });
  throws([](SimOptions& o) { o.num_cameras = 0; });
  throws([](SimOptions& o) { o.num_cameras = 17; });
  throws([](SimOptions& o) { o.width = 8; });
  throws([](SimOptions& o) { o.threads = -1; });
  throws([](SimOptions& o) { o.workspace_size = Vector3d(1, 0, 1); });
  SimOptions o;
  EXPECT_THROW(SimulatedRig(o, RigDescription()), std::invalid_argument);
  RigDescription bad_rig;
  bad_rig.cameras.push_back(CameraModel());  // zero focal length and size
  EXPECT_THROW(SimulatedRig(o, bad_rig), std::invalid_argument);
  o.num_cameras = 1;
  const SimulatedRig rig(o);
  EXPECT_THROW(rig.truth(-1), std::invalid_argument);
}
