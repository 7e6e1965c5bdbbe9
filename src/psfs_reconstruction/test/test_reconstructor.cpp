// The whole per-frame pipeline (background learning -> classifier -> pSfS) on images of the
// simulated rig: 8 distorted 320x240 cameras, sensor noise, shadows, a cluttered office, a
// waving person in long sleeves. Volumes are compared with the occupancy oracle at the voxel
// centres; bad frame sets must be rejected with a clear message and leave the state intact.
#include <gtest/gtest.h>

#include <cstdio>
#include <unistd.h>

#include <filesystem>

#include <opencv2/imgproc.hpp>

#include <cstring>
#include <fstream>

#include "psfs_reconstruction/cuda_device.h"
#include "psfs_reconstruction/reconstructor.h"
#include "psfs_reconstruction/reconstructor_config.h"
#include "tabletop_sim/simulated_rig.h"
#include "expect_throw.h"
#include "test_data_path.h"

namespace psfs {
namespace {

namespace sim = tabletop_sim;
namespace fs = std::filesystem;

constexpr int kLearn = 25;  // empty frames the rig renders and the model learns from

struct Scores {
  double body = 0, skin = 0;
};

struct Overlap {
  size_t reconstructed = 0, truth = 0, both = 0;
  double iou() const {
    const size_t uni = reconstructed + truth - both;
    return uni ? double(both) / uni : 1.0;
  }
  double precision() const { return reconstructed ? double(both) / reconstructed : 1.0; }
  double recall() const { return truth ? double(both) / truth : 1.0; }
};

Overlap overlap(const ProbabilityVolume& v, uint8_t tb, const std::vector<uint8_t>& truth) {
  Overlap o;
  for (size_t i = 0; i < truth.size(); ++i) {
    const bool a = v.data[i] > tb, b = truth[i] != 0;
    o.reconstructed += a;
    o.truth += b;
    o.both += a && b;
  }
  return o;
}

double iou(const ProbabilityVolume& v, uint8_t tb, const std::vector<uint8_t>& truth) {
  return overlap(v, tb, truth).iou();
}

class ReconstructorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    sim::SimOptions o;
    o.script = "wave";
    o.empty_frames = kLearn;
    o.render_masks = true;
    rig_ = std::make_unique<sim::SimulatedRig>(o);
    params_.threads = 2;
  }

  GaussianMixture2D skin() const {
    return GaussianMixture2D::load(psfs_test::configDir() + "/skin_gmm.yaml");
  }
  const std::vector<tabletop_capture::CameraModel>& cameras() const { return rig_->rig().cameras; }

  void learn(Reconstructor* r) {
    for (int f = 0; f < kLearn; ++f) {
      const FrameResult res = r->process(rig_->render(f).images, cameras());
      ASSERT_EQ(res.status, FrameResult::Status::kLearningBackground);
      ASSERT_EQ(res.background_frames, f + 1);
    }
    ASSERT_TRUE(r->backgroundReady());
  }

  // Learns the background and saves it into `dir` (created).
  void learnAndSave(Reconstructor* r, const fs::path& dir) {
    learn(r);
    fs::create_directories(dir);
    r->saveBackground(dir.string());
  }

  // A set with the person in view gives the same volumes from a reconstructor that learned the
  // background and from one that loaded it.
  void expectSameVolumes(Reconstructor* learned, Reconstructor* loaded) {
    const auto images = rig_->render(kLearn + 20).images;
    const FrameResult a = learned->process(images, cameras());
    const FrameResult b = loaded->process(images, cameras());
    ASSERT_EQ(b.status, FrameResult::Status::kReconstructed);
    EXPECT_EQ(a.body.data, b.body.data);
    EXPECT_EQ(a.skin.data, b.skin.data);
  }

  Scores score(const FrameResult& res, int frame, const ReconstructorParams& p) const {
    std::vector<uint8_t> person, skin;
    const VoxelGrid& g = res.body.grid;
    rig_->oracle(frame).sampleGrid(g.origin, g.voxel_size, g.dims, &person, &skin);
    return {iou(res.body, thresholdByte(p.body.threshold), person),
            iou(res.skin, thresholdByte(p.skin.threshold), skin)};
  }

  std::unique_ptr<sim::SimulatedRig> rig_;
  ReconstructorParams params_;
};

// The figures of the real pipeline (classifier included) at the tracking resolution, measured
// 2026-12-01: body IoU 0.69-0.72 (precision 0.84, recall 0.80), skin IoU 0.33-0.38 (recall
// 0.67-0.70). Why not higher: sampling at voxel centres on a 15.6 mm grid misclassifies a shell
// of about half a voxel around every surface (for the body, ~6000 voxels with ~2500 on the
// surface), the visual hull of 8 views is fatter than the body between arms and torso, and the
// skin solids (face, hands: ~540 voxels) are so small that the shell dominates them and their
// hull bloats by a voxel on each side. The bars sit ~0.05 below the measured figures, about the
// frame-to-frame spread.
TEST_F(ReconstructorTest, LearnsTheBackgroundThenMatchesTheOracle) {
  Reconstructor r(skin(), params_);
  learn(&r);
  const int n = rig_->scriptFrames();
  Scores sum;
  int count = 0;
  for (int f : {kLearn + 5, kLearn + (n - kLearn) / 3, kLearn + 2 * (n - kLearn) / 3, n - 3}) {
    const FrameResult res = r.process(rig_->render(f).images, cameras());
    ASSERT_EQ(res.status, FrameResult::Status::kReconstructed);
    EXPECT_TRUE(res.warnings.empty()) << res.warnings.front();
    const Scores s = score(res, f, params_);
    {
      std::vector<uint8_t> person, skin;
      const VoxelGrid& g = res.body.grid;
      rig_->oracle(f).sampleGrid(g.origin, g.voxel_size, g.dims, &person, &skin);
      const Overlap b = overlap(res.body, thresholdByte(params_.body.threshold), person);
      const Overlap k = overlap(res.skin, thresholdByte(params_.skin.threshold), skin);
      std::printf("[ figures  ] frame %d: body precision %.3f recall %.3f (%zu vs %zu voxels), "
                  "skin precision %.3f recall %.3f (%zu vs %zu)\n", f, b.precision(), b.recall(),
                  b.reconstructed, b.truth, k.precision(), k.recall(), k.reconstructed, k.truth);
    }
    std::printf("[ figures  ] frame %d: body IoU %.3f, skin IoU %.3f at %s; classify %.1f ms, "
                "body %.1f ms, skin %.1f ms, total %.1f ms\n",
                f, s.body, s.skin, res.body.grid.describe().c_str(), res.times.classify,
                res.times.body, res.times.skin, res.times.total);
    EXPECT_GE(s.body, 0.63) << "frame " << f;
    EXPECT_GE(s.skin, 0.28) << "frame " << f;
    sum.body += s.body;
    sum.skin += s.skin;
    ++count;
  }
  std::printf("[ figures  ] mean body IoU %.3f, skin IoU %.3f\n", sum.body / count,
              sum.skin / count);
  EXPECT_GE(sum.body / count, 0.65);
  EXPECT_GE(sum.skin / count, 0.30);
}

// The mask that protects the background model is the body volume projected back: it must cover
// the image of the person's part inside the workspace (the true volume projected back the same
// way; what lies outside the workspace box has no voxels to project) without swallowing the
// frame (else the background never adapts).
TEST_F(ReconstructorTest, BackProjectedVolumeCoversThePerson) {
  Reconstructor r(skin(), params_);
  learn(&r);
  const int f = kLearn + 40;
  const sim::SimFrame frame = rig_->render(f);
  const FrameResult res = r.process(frame.images, cameras());
  const auto masks = r.backProject(res.body, thresholdByte(params_.body.threshold),
                                   params_.mask_margin_px);
  ProbabilityVolume truth;
  truth.grid = res.body.grid;
  rig_->oracle(f).sampleGrid(truth.grid.origin, truth.grid.voxel_size, truth.grid.dims,
                             &truth.data, nullptr);
  const auto truth_masks = r.backProject(truth, 0, 0);
  ASSERT_EQ(masks.size(), truth_masks.size());
  for (size_t c = 0; c < masks.size(); ++c) {
    cv::Mat person;  // the true in-workspace silhouette: volume footprint AND rendered person
    cv::bitwise_and(truth_masks[c], frame.person_masks[c], person);
    cv::Mat covered;
    cv::bitwise_and(masks[c], person, covered);
    const double n_person = cv::countNonZero(person);
    const double coverage = cv::countNonZero(covered) / std::max(1.0, n_person);
    const double area = cv::countNonZero(masks[c]) / double(masks[c].total());
    const double person_area = n_person / double(masks[c].total());
    std::printf("[ figures  ] cam%zu: mask covers %.1f %% of the person in the workspace, mask "
                "%.1f %% of the image (that person %.1f %%)\n", c, 100 * coverage, 100 * area,
                100 * person_area);
    EXPECT_GE(coverage, 0.95) << "cam" << c;
    EXPECT_LE(area, 2.0 * person_area + 0.02) << "cam" << c;
  }
}

// Live tuning: the three thresholds change together, and a value PsfsFusion rejects changes none.
TEST_F(ReconstructorTest, FusionThresholdsAreTunedLive) {
  Reconstructor r(skin(), params_);
  r.setFusionThresholds(0.8, 0.85, 0.9);
  EXPECT_EQ(r.params().body.threshold, 0.8);
  EXPECT_EQ(r.params().skin.threshold, 0.85);
  EXPECT_EQ(r.params().hand.threshold, 0.9);
  EXPECT_THROW(r.setFusionThresholds(0.7, 0.4, 0.7), std::invalid_argument);  // t must exceed 0.5
  EXPECT_EQ(r.params().body.threshold, 0.8);
  EXPECT_EQ(r.params().skin.threshold, 0.85);
  EXPECT_EQ(r.params().body.multi_projection, params_.body.multi_projection);  // the rest stays
}

TEST_F(ReconstructorTest, BadFrameSetsAreRejectedAndTheStateSurvives) {
  Reconstructor r(skin(), params_);
  learn(&r);
  const int f = kLearn + 30;
  const sim::SimFrame frame = rig_->render(f);
  const FrameResult good = r.process(frame.images, cameras());
  const Scores good_scores = score(good, f, params_);

  auto expectRejected = [&](const std::vector<cv::Mat>& images,
                            const std::vector<tabletop_capture::CameraModel>& cams,
                            const std::string& fragment) {
    psfs_test::expectThrowContaining<std::invalid_argument>([&] { r.process(images, cams); },
                                                           fragment);
  };
  // NaN calibration.
  auto cams = cameras();
  cams[3].fx = std::numeric_limits<double>::quiet_NaN();
  expectRejected(frame.images, cams, "cam3");
  // Non-rotation pose.
  cams = cameras();
  cams[1].world_T_camera.linear() *= 2.0;
  expectRejected(frame.images, cams, "cam1");
  // Image count differs from the camera count.
  std::vector<cv::Mat> fewer(frame.images.begin(), frame.images.end() - 1);
  expectRejected(fewer, cameras(), "7 images but 8 cameras");
  // Image size disagrees with the calibration.
  std::vector<cv::Mat> images = frame.images;
  cv::resize(images[5], images[5], cv::Size(160, 120));
  expectRejected(images, cameras(), "cam5: image is 160x120");
  // Wrong encoding.
  images = frame.images;
  cv::cvtColor(frame.images[2], images[2], cv::COLOR_RGB2GRAY);
  expectRejected(images, cameras(), "cam2");

  // None of that touched the models: the same frame gives a valid volume again.
  const FrameResult again = r.process(frame.images, cameras());
  ASSERT_EQ(again.status, FrameResult::Status::kReconstructed);
  EXPECT_EQ(again.background_frames, kLearn);
  EXPECT_NEAR(score(again, f, params_).body, good_scores.body, 0.02);

  // A covered lens (all black): that view is switched off and reported; the other 7 still
  // reconstruct the person.
  images = frame.images;
  images[4].setTo(cv::Scalar::all(0));
  FrameResult dark = r.process(images, cameras());
  ASSERT_EQ(dark.status, FrameResult::Status::kReconstructed);
  EXPECT_FALSE(dark.camera_active[4]);
  ASSERT_FALSE(dark.warnings.empty());
  EXPECT_NE(dark.warnings[0].find("cam4"), std::string::npos) << dark.warnings[0];
  const Scores dark_scores = score(dark, f, params_);
  std::printf("[ figures  ] cam4 black: body IoU %.3f (all views %.3f)\n", dark_scores.body,
              good_scores.body);
  EXPECT_GE(dark_scores.body, good_scores.body - 0.1);

  // A saturated camera is reported; the frame is still processed.
  images = frame.images;
  images[6].setTo(cv::Scalar::all(255));
  const FrameResult bright = r.process(images, cameras());
  ASSERT_EQ(bright.status, FrameResult::Status::kReconstructed);
  bool reported = false;
  for (const auto& w : bright.warnings)
    reported = reported || (w.find("cam6") != std::string::npos && w.find("saturated") != std::string::npos);
  EXPECT_TRUE(reported);

  // A different rig (one camera less, on purpose: camera_info and images agree) relearns.
  std::vector<tabletop_capture::CameraModel> seven(cameras().begin(), cameras().end() - 1);
  const FrameResult relearn = r.process(fewer, seven);
  EXPECT_EQ(relearn.status, FrameResult::Status::kLearningBackground);
  ASSERT_FALSE(relearn.warnings.empty());
  EXPECT_NE(relearn.warnings[0].find("relearning"), std::string::npos) << relearn.warnings[0];
}

// A degraded frame set (the synchroniser's max_missing_cameras) has empty images where cameras
// delivered nothing: those views are left out exactly like a covered lens (the same volumes as
// black images there), and such a set is not learned into the background.
TEST_F(ReconstructorTest, CamerasMissingFromASetAreLeftOut) {
  Reconstructor r(skin(), params_), covered(skin(), params_), full(skin(), params_);
  {
    std::vector<cv::Mat> images = rig_->render(0).images;
    images[2] = cv::Mat();
    const FrameResult res = r.process(images, cameras());
    EXPECT_EQ(res.status, FrameResult::Status::kLearningBackground);
    EXPECT_TRUE(res.learning_skipped);
    EXPECT_EQ(res.background_frames, 0);
    ASSERT_FALSE(res.warnings.empty());
    EXPECT_NE(res.warnings[0].find("no image from cam2"), std::string::npos) << res.warnings[0];
  }
  learn(&r);
  learn(&covered);
  learn(&full);
  const int f = kLearn + 30;
  const sim::SimFrame frame = rig_->render(f);
  std::vector<cv::Mat> missing = frame.images, black = frame.images;
  for (int c : {4, 6}) {
    missing[c] = cv::Mat();
    // (A new buffer: assigning Mat::zeros() to the shared header would blacken frame.images.)
    black[c] = cv::Mat(frame.images[c].size(), frame.images[c].type(), cv::Scalar::all(0));
  }
  const FrameResult res = r.process(missing, cameras());
  const FrameResult dark = covered.process(black, cameras());
  const FrameResult all = full.process(frame.images, cameras());
  ASSERT_EQ(res.status, FrameResult::Status::kReconstructed);
  for (int c = 0; c < 8; ++c) EXPECT_EQ(res.camera_active[c], c != 4 && c != 6) << "cam" << c;
  EXPECT_TRUE(res.body.data == dark.body.data);
  EXPECT_TRUE(res.skin.data == dark.skin.data);
  // Two of eight views fewer: the hull is looser (measured 2026-12-03: 0.774 against 0.813 with
  // all views; the allowance of one covered lens in BadFrameSetsAreRejectedAndTheStateSurvives).
  const Scores degraded = score(res, f, params_), complete = score(all, f, params_);
  std::printf("[ figures  ] cam4 and cam6 missing: body IoU %.3f, skin IoU %.3f (all views %.3f, "
              "%.3f)\n", degraded.body, degraded.skin, complete.body, complete.skin);
  EXPECT_GE(degraded.body, complete.body - 0.1);

  // A set without any image is refused; the models stay as they were.
  psfs_test::expectThrowContaining<std::invalid_argument>(
      [&] { r.process(std::vector<cv::Mat>(8), cameras()); }, "no image");
  EXPECT_TRUE(r.backgroundReady());
}

// backend cuda gives the CPU's volumes: on the GPU where one is usable (issue 20: classification
// and fusion give the same bytes), else on the CPU after one warning that says why.
TEST_F(ReconstructorTest, CudaBackendGivesTheCpuVolumesOrFallsBackOnce) {
  ReconstructorParams gp = params_;
  gp.backend = ReconstructorParams::Backend::kCuda;
  Reconstructor cpu(skin(), params_), gpu(skin(), gp);
  const bool usable = cuda::device().usable;
  EXPECT_EQ(gpu.activeBackend(), usable ? ReconstructorParams::Backend::kCuda
                                        : ReconstructorParams::Backend::kCpu);
  int fallback_warnings = 0;
  const Eigen::Vector3d hand = rig_->truth(kLearn + 20).right_hand;
  for (int f = 0; f < kLearn + 3; ++f) {
    const int frame = f < kLearn ? f : kLearn + 20 + f;
    const auto images = rig_->render(frame).images;
    const FrameResult a = cpu.process(images, cameras(), {hand});
    const FrameResult b = gpu.process(images, cameras(), {hand});
    for (const auto& w : b.warnings)
      fallback_warnings += w.find("backend cuda: no usable CUDA device") != std::string::npos;
    EXPECT_EQ(b.backend, gpu.activeBackend());
    ASSERT_EQ(a.status, b.status) << "frame " << frame;
    if (a.status != FrameResult::Status::kReconstructed) continue;
    EXPECT_EQ(a.body.data, b.body.data) << "frame " << frame;
    EXPECT_EQ(a.skin.data, b.skin.data) << "frame " << frame;
    ASSERT_EQ(a.hands.size(), 1u);
    ASSERT_EQ(b.hands.size(), 1u);
    EXPECT_EQ(a.hands[0].data, b.hands[0].data) << "frame " << frame;
  }
  EXPECT_EQ(fallback_warnings, usable ? 0 : 1) << "the fallback is reported once, with the reason";
}

TEST_F(ReconstructorTest, SavedBackgroundReloadsToTheSameVolumes) {
  const fs::path dir = fs::temp_directory_path() / ("psfs_bg_" + std::to_string(::getpid()));
  Reconstructor a(skin(), params_);
  learnAndSave(&a, dir);

  Reconstructor b(skin(), params_);
  // A missing model is a clear error naming the file; nothing is loaded.
  psfs_test::expectThrowContaining<std::runtime_error>(
      [&] { b.loadBackground((dir / "nowhere").string(), cameras()); }, "nowhere/cam0.bgm");
  b.loadBackground(dir.string(), cameras());
  expectSameVolumes(&a, &b);
  fs::remove_all(dir);
}

// A model learned from filtered pixels has the filtered pixels' variances: loading it into a
// reconstructor that classifies raw pixels, through another window, or the other way round, is
// refused, naming both; a refused load leaves the background to be learned.
TEST_F(ReconstructorTest, ASavedBackgroundLoadsOnlyUnderItsOwnPrefilter) {
  const fs::path dir = fs::temp_directory_path() / ("psfs_bgf_" + std::to_string(::getpid()));
  ReconstructorParams median = params_;
  median.prefilter = ImagePrefilterParams{ImagePrefilter::kMedian, 3};
  Reconstructor a(skin(), median);
  learnAndSave(&a, dir);

  Reconstructor raw(skin(), params_);
  psfs_test::expectThrowContaining<std::runtime_error>(
      [&] { raw.loadBackground(dir.string(), cameras()); }, "prefilter 'median 3x3'");
  psfs_test::expectThrowContaining<std::runtime_error>(
      [&] { raw.loadBackground(dir.string(), cameras()); },
      "pixel_classifier/prefilter and prefilter_size give 'none'");
  EXPECT_EQ(raw.process(rig_->render(0).images, cameras()).status,
            FrameResult::Status::kLearningBackground);
  ReconstructorParams median5 = median;
  median5.prefilter.size = 5;
  Reconstructor other(skin(), median5);
  psfs_test::expectThrowContaining<std::runtime_error>(
      [&] { other.loadBackground(dir.string(), cameras()); }, "give 'median 5x5'");
  // The other way round: raw pixels' models under the filter.
  const fs::path raw_dir = dir / "raw";
  Reconstructor r(skin(), params_);
  learnAndSave(&r, raw_dir);
  Reconstructor filtering(skin(), median);
  psfs_test::expectThrowContaining<std::runtime_error>(
      [&] { filtering.loadBackground(raw_dir.string(), cameras()); }, "prefilter 'none'");
  // Version-1 files (no filter recorded) pass as raw pixels' models only.
  for (const auto& e : fs::directory_iterator(raw_dir)) {
    std::ifstream in(e.path(), std::ios::binary);
    std::string b((std::istreambuf_iterator<char>(in)), {});
    in.close();
    const uint32_t one = 1;
    std::memcpy(&b[8], &one, 4);
    b.erase(40, 16);
    std::ofstream(e.path(), std::ios::binary | std::ios::trunc).write(b.data(), std::streamsize(b.size()));
  }
  psfs_test::expectThrowContaining<std::runtime_error>(
      [&] { filtering.loadBackground(raw_dir.string(), cameras()); }, "format version 1");
  Reconstructor legacy(skin(), params_);
  legacy.loadBackground(raw_dir.string(), cameras());
  EXPECT_EQ(legacy.process(rig_->render(kLearn + 20).images, cameras()).status,
            FrameResult::Status::kReconstructed);

  Reconstructor same(skin(), median);
  same.loadBackground(dir.string(), cameras());
  expectSameVolumes(&a, &same);
  fs::remove_all(dir);
}

// A hand sub-volume around the true hand: 3.6 mm voxels, skin class. The centroid of its skin
// voxels near the hand must match the centroid of the true skin there: the tolerance is the
// visual-hull bloat of a hand seen by 8 cameras with one view allowed to disagree (a hull
// thicker by ~1 cm on the side the fewest cameras see), not the voxel size. The resting left
// hand (lying flat on the desk, fingers pressed down) bloats most: its hull spreads over the
// wood next to it, whose tones are close to skin (1.8x the true voxels, centroid 23 mm off).
TEST_F(ReconstructorTest, HandSubVolumeFindsTheHand) {
  Reconstructor r(skin(), params_);
  learn(&r);
  const int f = kLearn + 50;
  const sim::GroundTruth truth = rig_->truth(f);
  ASSERT_TRUE(truth.person_present);
  const FrameResult res =
      r.process(rig_->render(f).images, cameras(), {truth.right_hand, truth.left_hand});
  ASSERT_EQ(res.hands.size(), 2u);
  const auto oracle = rig_->oracle(f);
  for (int h = 0; h < 2; ++h) {
    const Eigen::Vector3d hand = h == 0 ? truth.right_hand : truth.left_hand;
    const ProbabilityVolume& v = res.hands[h];
    EXPECT_LT((v.grid.centre(v.grid.numVoxels() / 2) - hand).cwiseAbs().maxCoeff(),
              v.grid.voxel_size * 1.01);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    size_t n = 0;
    const uint8_t tb = thresholdByte(params_.hand.threshold);
    for (size_t i = 0; i < v.data.size(); ++i) {
      const Eigen::Vector3d p = v.grid.centre(i);
      // The cube also holds the wrist and sleeve; the hand is what lies within 12 cm.
      if (v.data[i] > tb && (p - hand).norm() < 0.12) {
        sum += p;
        ++n;
      }
    }
    std::vector<uint8_t> skin;
    oracle.sampleGrid(v.grid.origin, v.grid.voxel_size, v.grid.dims, nullptr, &skin);
    const double skin_iou = iou(v, tb, skin);
    // The same selection on the true skin: the hand plus whatever wrist skin lies within reach.
    Eigen::Vector3d true_sum = Eigen::Vector3d::Zero();
    size_t true_n = 0;
    for (size_t i = 0; i < skin.size(); ++i) {
      const Eigen::Vector3d p = v.grid.centre(i);
      if (skin[i] && (p - hand).norm() < 0.12) {
        true_sum += p;
        ++true_n;
      }
    }
    ASSERT_GT(n, 100u) << "hand " << h;
    ASSERT_GT(true_n, 100u) << "hand " << h;
    const double err_mm = 1e3 * (sum / double(n) - true_sum / double(true_n)).norm();
    std::printf("[ figures  ] hand %d: %zu skin voxels (true %zu) at %.1f mm, centroid error "
                "%.1f mm, skin IoU %.3f, %.1f ms for both hands\n",
                h, n, true_n, 1e3 * v.grid.voxel_size, err_mm, skin_iou, res.times.hands);
    EXPECT_LT(err_mm, 27.0) << "hand " << h;
  }
}

// Known occlusions instead of the blind tolerance (occluder_depth.h): with the body volume's
// occlusion masks and no tolerated view (k = 0), a view that sees the trunk or the other arm in
// front of a hand gives it no evidence, while every view that sees past the hand still carves.
// Against k = 1 without masks (the default before; the lowest view dropped wherever it is low)
// the hand holds less phantom skin; against k = 0 without masks it keeps the skin the hidden
// views would carve.
TEST_F(ReconstructorTest, HandOcclusionMasksCarveWithoutLosingTheHiddenHand) {
  ReconstructorParams tolerant = params_, blind0 = params_;
  ASSERT_EQ(params_.hand.occluded_views, 0);
  ASSERT_TRUE(params_.hand_occlusion_masks);
  tolerant.hand.occluded_views = 1;
  tolerant.hand_occlusion_masks = false;
  blind0.hand_occlusion_masks = false;
  Reconstructor shipped(skin(), tolerant), strict(skin(), blind0), occl(skin(), params_);
  learn(&shipped);
  learn(&strict);
  learn(&occl);
  const uint8_t tb = thresholdByte(params_.hand.threshold);
  Overlap sums[3];
  double ms[3] = {0, 0, 0};
  int sets = 0;
  for (int f = kLearn + 10; f < kLearn + 100; f += 15) {
    const sim::GroundTruth truth = rig_->truth(f);
    if (!truth.person_present) continue;
    const auto images = rig_->render(f).images;
    const std::vector<Eigen::Vector3d> rois = {truth.right_hand, truth.left_hand};
    const FrameResult res[3] = {shipped.process(images, cameras(), rois),
                                strict.process(images, cameras(), rois),
                                occl.process(images, cameras(), rois)};
    ++sets;
    for (int k = 0; k < 3; ++k) ms[k] += res[k].times.hands;
    const auto oracle = rig_->oracle(f);
    for (int h = 0; h < 2; ++h) {
      std::vector<uint8_t> true_skin;
      const VoxelGrid& g = res[0].hands[h].grid;
      oracle.sampleGrid(g.origin, g.voxel_size, g.dims, nullptr, &true_skin);
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(res[k].hands[h].grid, g);
        const Overlap o = overlap(res[k].hands[h], tb, true_skin);
        sums[k].reconstructed += o.reconstructed;
        sums[k].truth += o.truth;
        sums[k].both += o.both;
      }
    }
  }
  const char* names[3] = {"k = 1 (before)", "k = 0", "k = 0 + occlusion masks (default)"};
  for (int k = 0; k < 3; ++k)
    std::printf("[ figures  ] hand sub-volumes, %s: precision %.3f, recall %.3f, IoU %.3f (%.1f ms "
                "per set for both hands, for information)\n",
                names[k], sums[k].precision(), sums[k].recall(), sums[k].iou(), ms[k] / sets);
  ASSERT_GT(sums[0].truth, 1000u);
  EXPECT_GT(sums[2].precision(), sums[0].precision() + 0.02);
  EXPECT_GT(sums[2].recall(), sums[1].recall());
  EXPECT_GT(sums[2].iou(), sums[0].iou());
}

// The desk top is the workspace's floor (z = 0): over the desk no camera sees below it, yet the
// voxels under a hand resting on it project onto that hand in all of them. A hand cube reaches
// 15 cm under the hand, so without the floor clip it holds phantom skin under the desk where the
// oracle has none; with it (the default) nothing lies below the floor and everything above it
// is unchanged.
TEST_F(ReconstructorTest, HandSubVolumesHoldNothingBelowTheDesk) {
  ReconstructorParams off = params_;
  off.hand_roi_clip_floor = false;
  ASSERT_TRUE(params_.hand_roi_clip_floor);
  const double floor_z = params_.workspace.min_corner.z();
  Reconstructor clipped(skin(), params_), unclipped(skin(), off);
  learn(&clipped);
  learn(&unclipped);
  const int f = kLearn + 50;
  const sim::GroundTruth truth = rig_->truth(f);
  ASSERT_TRUE(truth.person_present);
  const auto images = rig_->render(f).images;
  const std::vector<Eigen::Vector3d> rois = {truth.right_hand, truth.left_hand};
  const FrameResult a = clipped.process(images, cameras(), rois);
  const FrameResult b = unclipped.process(images, cameras(), rois);
  ASSERT_EQ(a.hands.size(), 2u);
  ASSERT_EQ(b.hands.size(), 2u);
  const auto oracle = rig_->oracle(f);
  const uint8_t tb = thresholdByte(params_.hand.threshold);
  for (int h = 0; h < 2; ++h) {
    const ProbabilityVolume &va = a.hands[h], &vb = b.hands[h];
    ASSERT_EQ(va.grid, vb.grid);
    std::vector<uint8_t> true_skin;
    oracle.sampleGrid(va.grid.origin, va.grid.voxel_size, va.grid.dims, nullptr, &true_skin);
    size_t below = 0, true_below = 0, above_differs = 0;
    // The resting hand's footprint: the columns with true skin within 3 cm of the floor.
    std::vector<uint8_t> footprint(size_t(va.grid.dims.x()) * va.grid.dims.y(), 0);
    for (size_t i = 0; i < va.data.size(); ++i) {
      const double z = va.grid.centre(i).z();
      if (z < floor_z) {
        EXPECT_EQ(va.data[i], 0) << "hand " << h << " voxel " << i;
        below += vb.data[i] > tb;
        true_below += true_skin[i];
      } else {
        above_differs += va.data[i] != vb.data[i];
        if (true_skin[i] && z < floor_z + 0.03) footprint[i % footprint.size()] = 1;
      }
    }
    EXPECT_EQ(true_below, 0u) << "hand " << h;  // the simulated person never reaches under it
    EXPECT_EQ(above_differs, 0u) << "hand " << h;
    const size_t true_footprint = size_t(std::count(footprint.begin(), footprint.end(), 1));
    const double iou_a = iou(va, tb, true_skin), iou_b = iou(vb, tb, true_skin);
    std::printf("[ figures  ] hand %d (centre z %.3f m): %zu phantom skin voxels below the desk "
                "without the clip (the hand's footprint on it: %zu columns); skin IoU %.3f "
                "clipped, %.3f not\n",
                h, va.grid.centre(va.data.size() / 2).z(), below, true_footprint, iou_a, iou_b);
    // `wave`'s left hand (the second ROI) rests on the desk at this frame, the right one is
    // raised. Under the resting hand every camera looks through the desk and then through the
    // hand, so the layer just below the floor repeats its footprint (1077 columns), less a rim
    // where the lowest cameras' rays pass beside a hand ~2 cm thick: at least half of it
    // (measured: 832 voxels). The raised hand's cube does not reach the desk.
    if (h == 1) {
      ASSERT_GT(true_footprint, 500u) << "the left hand no longer rests on the desk";
      EXPECT_GE(2 * below, true_footprint);
      EXPECT_GT(iou_a, iou_b);
    } else {
      EXPECT_EQ(below, 0u);
    }
  }
  // The floor stays when the thresholds are tuned live (setFusionThresholds rebuilds the hand
  // fusion): the resting hand's cube is still empty below the desk.
  clipped.setFusionThresholds(params_.body.threshold, params_.skin.threshold, 0.7);
  const FrameResult c = clipped.process(rig_->render(f + 1).images, cameras(), rois);
  ASSERT_EQ(c.hands.size(), 2u);
  size_t nonzero_below = 0, voxels_below = 0;
  const ProbabilityVolume& resting = c.hands[1];
  for (size_t i = 0; i < resting.data.size(); ++i)
    if (resting.grid.centre(i).z() < floor_z) ++voxels_below, nonzero_below += resting.data[i] != 0;
  EXPECT_GT(voxels_below, 0u);
  EXPECT_EQ(nonzero_below, 0u);
}

// The prefilter (image_prefilter.h) acts on every stage alike: a Reconstructor that filters
// gives, set for set, the volumes, likelihoods and clothing colour of one that does not but is
// fed the filtered images, through learning, reconstruction and a set without one camera.
TEST_F(ReconstructorTest, ThePrefilterFeedsEveryStage) {
  ReconstructorParams median = params_;
  median.prefilter = {ImagePrefilter::kMedian, 3};
  ReconstructorParams none = params_;
  none.prefilter = {ImagePrefilter::kNone, 3};
  Reconstructor a(skin(), median), b(skin(), none);
  size_t differing = 0;
  for (int f = 0; f < kLearn + 6; ++f) {
    std::vector<cv::Mat> raw = rig_->render(f).images, filtered;
    if (f == kLearn + 4) raw[3] = cv::Mat();  // camera 3 missing from this set
    prefilterImages(raw, median.prefilter, &filtered);
    const FrameResult ra = a.process(raw, cameras()), rb = b.process(filtered, cameras());
    ASSERT_EQ(ra.status, rb.status) << "set " << f;
    if (ra.status != FrameResult::Status::kReconstructed) continue;
    EXPECT_EQ(ra.body.data, rb.body.data) << "set " << f;
    EXPECT_EQ(ra.skin.data, rb.skin.data) << "set " << f;
    for (size_t c = 0; c < a.lastLikelihoods().size(); ++c) {
      if (a.lastLikelihoods()[c].empty()) continue;
      EXPECT_EQ(cv::norm(a.lastLikelihoods()[c], b.lastLikelihoods()[c], cv::NORM_INF), 0.0);
    }
    EXPECT_EQ(a.clothingColour().valid(), b.clothingColour().valid());
    // Against raw pixels the likelihoods do differ (the filter is not a no-op here).
    if (f == kLearn + 5) {
      Reconstructor c(skin(), none);
      for (int g = 0; g <= f; ++g) c.process(rig_->render(g).images, cameras());
      for (size_t i = 0; i < c.lastLikelihoods().size(); ++i)
        differing += cv::countNonZero(c.lastLikelihoods()[i].reshape(1) !=
                                      a.lastLikelihoods()[i].reshape(1));
    }
  }
  EXPECT_GT(differing, 1000u);
}

TEST(ProbabilityVolume, ClearBelowZeroesTheLayersUnderAHeight) {
  ProbabilityVolume v;
  v.grid.origin = Eigen::Vector3d(0, 0, -0.1);
  v.grid.voxel_size = 0.05;
  v.grid.dims = Eigen::Vector3i(2, 3, 4);  // layer centres at z = -0.075, -0.025, 0.025, 0.075
  v.data.assign(v.grid.numVoxels(), 200);
  EXPECT_EQ(clearBelow(0.0, &v), 2);
  for (size_t i = 0; i < v.data.size(); ++i)
    EXPECT_EQ(v.data[i], v.grid.centre(i).z() < 0.0 ? 0 : 200) << i;
  EXPECT_EQ(clearBelow(-0.025, &v), 1);  // a centre on the height stays
  EXPECT_EQ(clearBelow(-1.0, &v), 0);
  EXPECT_EQ(countAbove(v, 0), 12u);
  EXPECT_EQ(clearBelow(1.0, &v), 4);  // the whole grid below it
  EXPECT_EQ(countAbove(v, 0), 0u);
  ProbabilityVolume empty;
  EXPECT_EQ(clearBelow(0.0, &empty), 0);
  v.data.resize(5);
  EXPECT_THROW(clearBelow(0.0, &v), std::invalid_argument);
}

void expectSameFusion(const PsfsOptions& a, const PsfsOptions& b, const char* what) {
  EXPECT_EQ(a.threshold, b.threshold) << what;
  EXPECT_EQ(a.occluded_views, b.occluded_views) << what;
  EXPECT_EQ(a.drop_threshold, b.drop_threshold) << what;
  EXPECT_EQ(a.min_views, b.min_views) << what;
  EXPECT_EQ(a.multi_projection, b.multi_projection) << what;
  EXPECT_EQ(a.footprint, b.footprint) << what;
  EXPECT_EQ(a.skip_empty_below, b.skip_empty_below) << what;
}

// config/psfs.yaml documents the defaults: it must say what the code does.
TEST(ReconstructorConfig, ShippedFileMatchesTheDefaults) {
  const std::string path = psfs_test::configDir() + "/psfs.yaml";
  if (!psfs_test::fileExists(path)) GTEST_SKIP() << path << " not found";
  const ReconstructorConfig c = loadReconstructorConfig(path);
  const ReconstructorParams d;
  const NodeletOptions n;
  EXPECT_EQ(c.params.workspace.min_corner, d.workspace.min_corner);
  EXPECT_EQ(c.params.workspace.size, d.workspace.size);
  EXPECT_EQ(c.params.dims, d.dims);
  EXPECT_EQ(c.params.hull_occupancy_foreground, d.hull_occupancy_foreground);
  EXPECT_EQ(c.params.hull_occupancy_skin, d.hull_occupancy_skin);
  expectSameFusion(c.params.body, d.body, "body");
  expectSameFusion(c.params.skin, d.skin, "skin");
  expectSameFusion(c.params.hand, d.hand, "hand");
  EXPECT_EQ(c.params.footprint_scale, d.footprint_scale);
  EXPECT_EQ(c.params.hand_roi_edge, d.hand_roi_edge);
  EXPECT_EQ(c.params.hand_roi_voxels, d.hand_roi_voxels);
  EXPECT_EQ(c.params.hand_roi_clip_floor, d.hand_roi_clip_floor);
  EXPECT_EQ(c.params.hand_occlusion_masks, d.hand_occlusion_masks);
  EXPECT_EQ(c.params.hand_occlusion_margin, d.hand_occlusion_margin);
  EXPECT_EQ(c.params.update_background, d.update_background);
  EXPECT_EQ(c.params.mask_margin_px, d.mask_margin_px);
  EXPECT_EQ(c.params.dark_camera_fraction, d.dark_camera_fraction);
  EXPECT_EQ(c.params.saturated_warning_fraction, d.saturated_warning_fraction);
  EXPECT_EQ(c.params.threads, d.threads);
  EXPECT_EQ(c.params.backend, d.backend);
  EXPECT_EQ(c.backend_name, "cpu");
  EXPECT_EQ(c.params.background.learning_frames, d.background.learning_frames);
  EXPECT_EQ(c.params.background.learning_change_sigmas, d.background.learning_change_sigmas);
  EXPECT_EQ(c.params.background.learning_change_fraction, d.background.learning_change_fraction);
  EXPECT_EQ(c.params.background.min_learning_frames, d.background.min_learning_frames);
  EXPECT_EQ(c.params.learning_max_occupied_litres, d.learning_max_occupied_litres);
  EXPECT_EQ(c.params.classifier.shadow_chroma_radius, d.classifier.shadow_chroma_radius);
  EXPECT_EQ(c.params.prefilter.type, d.prefilter.type);
  EXPECT_EQ(c.params.prefilter.size, d.prefilter.size);
  EXPECT_EQ(c.prefilter_name, imagePrefilterName(d.prefilter.type));
  const ClothingColourParams& cc = c.params.clothing;
  const ClothingColourParams& dc = d.clothing;
  EXPECT_EQ(cc.enabled, dc.enabled);
  EXPECT_EQ(cc.weight, dc.weight);
  EXPECT_EQ(cc.band_top, dc.band_top);
  EXPECT_EQ(cc.band_bottom, dc.band_bottom);
  EXPECT_EQ(cc.core_radius, dc.core_radius);
  EXPECT_EQ(cc.hand_exclusion_radius, dc.hand_exclusion_radius);
  EXPECT_EQ(cc.trim_radius, dc.trim_radius);
  EXPECT_EQ(cc.min_inlier_fraction, dc.min_inlier_fraction);
  EXPECT_EQ(cc.min_samples, dc.min_samples);
  EXPECT_EQ(cc.min_sd, dc.min_sd);
  EXPECT_EQ(cc.update_rate, dc.update_rate);
  EXPECT_EQ(c.nodelet.hand_roi_topic, n.hand_roi_topic);
  EXPECT_EQ(c.nodelet.hand_roi_max_age, n.hand_roi_max_age);
  EXPECT_EQ(c.nodelet.max_hand_rois, n.max_hand_rois);
  EXPECT_EQ(c.nodelet.queue_size, n.queue_size);
  EXPECT_EQ(c.nodelet.wait_for_tracker, n.wait_for_tracker);
  EXPECT_EQ(c.nodelet.tracker_timeout, n.tracker_timeout);
  EXPECT_EQ(c.nodelet.load_shedding, n.load_shedding);
  EXPECT_EQ(c.nodelet.shed_drop_fraction, n.shed_drop_fraction);
  EXPECT_EQ(c.nodelet.foreground_mask_topics, n.foreground_mask_topics);
  EXPECT_EQ(c.nodelet.foreground_mask_topic, n.foreground_mask_topic);
  EXPECT_EQ(c.nodelet.foreground_mask_transport, n.foreground_mask_transport);
  EXPECT_EQ(c.nodelet.foreground_mask_max_age, n.foreground_mask_max_age);
  EXPECT_EQ(c.nodelet.background_load_dir, n.background_load_dir);
  EXPECT_EQ(c.nodelet.background_save_dir, n.background_save_dir);
  EXPECT_EQ(c.nodelet.publish_clouds, n.publish_clouds);
  EXPECT_TRUE(psfs_test::fileExists(c.skin_model_path)) << c.skin_model_path;
}

// The aliases the nodelet takes as private parameters (and dynamic_reconfigure writes back).
TEST(ReconstructorConfig, AliasesOverrideTheirKeys) {
  ReconstructorConfig c;
  tabletop_common::ConfigSchema schema;
  addReconstructorKeys(&c, &schema);
  schema.set("skin_threshold", YAML::Node(0.8), "rosparam ~");
  schema.set("threads", YAML::Node(2), "rosparam ~");
  schema.set("fusion/hand/threshold", YAML::Node(0.7), "rosparam ~");
  EXPECT_EQ(c.params.skin.threshold, 0.8);
  EXPECT_EQ(c.params.threads, 2);
  EXPECT_EQ(c.params.hand.threshold, 0.7);
  EXPECT_THROW(schema.set("skin_treshold", YAML::Node(0.8), "rosparam ~"), std::runtime_error);
}

TEST(ReconstructorConfig, BadFilesNameTheFileAndTheKey) {
  const std::string path = (fs::temp_directory_path() / ("psfs_cfg_" + std::to_string(::getpid()) + ".yaml")).string();
  auto expectError = [&](const std::string& text, const std::string& fragment) {
    std::ofstream(path) << text;
    psfs_test::expectThrowContaining<std::runtime_error>([&] { loadReconstructorConfig(path); },
                                                        path + ": ");
    psfs_test::expectThrowContaining<std::runtime_error>([&] { loadReconstructorConfig(path); },
                                                        fragment);
  };
  expectError("volume: {dims: [64, 64]}", "volume/dims");
  expectError("fusion: {body: {treshold: 0.7}}", "fusion/body/treshold: unknown key");
  expectError("fusion: {skin: {threshold: 0.3}}", "threshold");
  expectError("volume: {hull_occupancy_skin: 0.5, hull_occupancy_foreground: 0.1}", "hull_occupancy_skin");
  expectError("nodelet: {threads: many}", "nodelet/threads: wrong type");
  expectError("hand_volumes: {max_age: 0}", "hand_volumes/max_age");
  expectError("compute: {backend: opencl}", "compute/backend: 'opencl' is not cpu or cuda");
  expectError("pixel_classifier: {prefilter: gaussian}",
              "pixel_classifier/prefilter: 'gaussian' is not none, median or box");
  expectError("pixel_classifier: {prefilter: median, prefilter_size: 4}",
              "prefilter_size must be 3, 5 or 7");
  expectError("[1, 2", "cannot read");
  std::ofstream(path) << "volume: {dims: [128, 128, 96]}\n";
  EXPECT_EQ(loadReconstructorConfig(path).params.dims, Eigen::Vector3i(128, 128, 96));
  std::ofstream(path) << "pixel_classifier: {prefilter: none, prefilter_size: 4}\n";  // unused
  EXPECT_EQ(loadReconstructorConfig(path).params.prefilter.type, ImagePrefilter::kNone);
  std::ofstream(path) << "pixel_classifier: {prefilter: median, prefilter_size: 5}\n";
  EXPECT_EQ(loadReconstructorConfig(path).params.prefilter.type, ImagePrefilter::kMedian);
  EXPECT_EQ(loadReconstructorConfig(path).params.prefilter.size, 5);
  fs::remove(path);
  psfs_test::expectThrowContaining<std::runtime_error>([&] { loadReconstructorConfig(path); }, path);
}

}  // namespace
}  // namespace psfs

namespace psfs {
namespace {

// The recording's empty part was partly missed (or is shorter than learning_frames): sets that
// show the person are never learned. After enough empty sets learning ends at the first such
// set, which is reconstructed; before that they are skipped.
TEST_F(ReconstructorTest, SetsThatShowThePersonAreNotLearned) {
  const int person = kLearn + 20;
  {
    Reconstructor r(skin(), params_);
    for (int f = 0; f < 3; ++f) r.process(rig_->render(f).images, cameras());
    const FrameResult res = r.process(rig_->render(person).images, cameras());
    EXPECT_EQ(res.status, FrameResult::Status::kLearningBackground);
    EXPECT_TRUE(res.learning_skipped);
    EXPECT_EQ(res.background_frames, 3);
    ASSERT_FALSE(res.warnings.empty());
    EXPECT_NE(res.warnings.front().find("not learned"), std::string::npos) << res.warnings.front();
    // Empty sets go on being learned.
    const FrameResult next = r.process(rig_->render(3).images, cameras());
    EXPECT_FALSE(next.learning_skipped);
    EXPECT_EQ(next.background_frames, 4);
  }
  {
    const int learned = params_.background.min_learning_frames;
    Reconstructor r(skin(), params_);
    for (int f = 0; f < learned; ++f) r.process(rig_->render(f).images, cameras());
    const FrameResult res = r.process(rig_->render(person).images, cameras());
    ASSERT_EQ(res.status, FrameResult::Status::kReconstructed);
    EXPECT_EQ(res.background_frames, learned);
    ASSERT_FALSE(res.warnings.empty());
    EXPECT_NE(res.warnings.front().find("ended after " + std::to_string(learned)), std::string::npos)
        << res.warnings.front();
    // A model from 10 empty sets is nearly as good as from 25 (the LearnsTheBackground bars).
    const Scores s = score(res, person, params_);
    std::printf("[ figures  ] learning ended after %d sets: body IoU %.3f, skin IoU %.3f\n",
                learned, s.body, s.skin);
    EXPECT_GT(s.body, 0.62);
  }
}

}  // namespace
}  // namespace psfs

namespace psfs {
namespace {

// A relearn with the person in view (a time jump in a live feed, or relearn_background called
// too early): the learning sets keep changing, so after learning_frames of them the model
// learned before is taken back (reported), and the volumes are as good as before the relearn.
TEST_F(ReconstructorTest, ALearningThatNeverSeesAnEmptySceneTakesThePreviousModelBack) {
  Reconstructor r(skin(), params_);
  learn(&r);
  const int f = kLearn + 30;
  const Scores before = score(r.process(rig_->render(f).images, cameras()), f, params_);
  r.resetBackground();
  FrameResult res;
  bool reported = false;
  int sets = 0;
  for (int k = kLearn; k < rig_->scriptFrames() && sets < 3 * params_.background.learning_frames; ++k) {
    res = r.process(rig_->render(k).images, cameras());
    ++sets;
    for (const auto& w : res.warnings) reported = reported || w.find("learned before again") != std::string::npos;
    if (res.status == FrameResult::Status::kReconstructed) break;
  }
  ASSERT_EQ(res.status, FrameResult::Status::kReconstructed) << "after " << sets << " sets";
  EXPECT_TRUE(reported);
  EXPECT_LE(sets, params_.background.learning_frames + 1);
  const Scores after = score(r.process(rig_->render(f).images, cameras()), f, params_);
  std::printf("[ figures  ] previous model back after %d sets: body IoU %.3f (before the relearn "
              "%.3f)\n", sets, after.body, before.body);
  EXPECT_GE(after.body, before.body - 0.05);

  // A relearn with the workspace empty (a bag played again from its empty start) learns every
  // set: the models used before see nothing there.
  r.resetBackground();
  for (int k = 0; k < kLearn; ++k) {
    const FrameResult e = r.process(rig_->render(k).images, cameras());
    EXPECT_FALSE(e.learning_skipped) << "empty set " << k << ": " << (e.warnings.empty() ? "" : e.warnings[0]);
  }
  EXPECT_TRUE(r.backgroundReady());
}

}  // namespace
}  // namespace psfs
