// The GPU pixel stage (issue 20) against the CPU path on frames of the simulated rig (8
// distorted 320x240 cameras, sensor noise, shadows, a waving person), plus the edge cases the
// rig does not show by itself: black and near-black pixels, saturated pixels, a global light
// change (the classifier's per-frame gain), switched-off pixels and views, several frames of
// selective background update with and without a mask.
//
// Without a GPU (here, and in CI) the kernels' code is checked through its host emulation
// (pixel_stage_emulation.h): the same per-thread functions in plain loops must give the CPU
// path's bytes exactly. No tolerance is needed or allowed: both sides run the same IEEE float
// operations in the same order (pixel_arithmetic.h), so any difference is a bug. The GpuPixelStage
// tests then compare the device itself with the same CPU path; they skip without a device.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <random>

#include <opencv2/imgproc.hpp>

#include "gpu_test_support.h"
#include "pixel_arithmetic.h"
#include "pixel_stage_emulation.h"
#include "psfs_reconstruction/color_space.h"
#include "psfs_reconstruction/gpu_pixel_stage.h"
#include "psfs_reconstruction/view_evidence.h"
#include "tabletop_sim/simulated_rig.h"
#include "test_data_path.h"

namespace psfs {
namespace {

namespace sim = tabletop_sim;

constexpr int kLearn = 10;  // learning frames (fewer than the default 25: the test's run time)

// The rig, its learned background models and a few frames with the person, rendered once.
struct Rig {
  std::unique_ptr<sim::SimulatedRig> rig;
  std::vector<BackgroundModel> models;
  std::vector<std::vector<cv::Mat>> frames, masks;  // person frames, their person masks
  GaussianMixture2D skin;
  ClassPriors priors = ClassPriors::fromOccupancy(0.08, 0.005, 8);

  Rig() {
    sim::SimOptions o;
    o.script = "wave";
    o.empty_frames = kLearn;
    o.render_masks = true;
    rig = std::make_unique<sim::SimulatedRig>(o);
    skin = GaussianMixture2D::load(psfs_test::configDir() + "/skin_gmm.yaml");
    BackgroundModelParams bp;
    bp.learning_frames = kLearn;
    for (int f = 0; f < kLearn; ++f) {
      const sim::SimFrame frame = rig->render(f);
      if (models.empty())
        for (const cv::Mat& im : frame.images) models.emplace_back(im.cols, im.rows, bp);
      for (size_t c = 0; c < models.size(); ++c) models[c].addLearningFrame(frame.images[c]);
    }
    const int n = rig->scriptFrames();
    for (int f : {kLearn + 8, kLearn + (n - kLearn) / 2, n - 5}) {
      const sim::SimFrame frame = rig->render(f);
      frames.push_back(frame.images);
      std::vector<cv::Mat> m;
      for (const cv::Mat& pm : frame.person_masks) {
        cv::Mat d;
        cv::dilate(pm, d, cv::Mat::ones(5, 5, CV_8U));  // as the pipeline's mask margin
        m.push_back(d);
      }
      masks.push_back(m);
    }
  }
  int cameras() const { return int(models.size()); }
  std::vector<const BackgroundModel*> modelPointers(const std::vector<BackgroundModel>& m) const {
    std::vector<const BackgroundModel*> p;
    for (const auto& b : m) p.push_back(&b);
    return p;
  }
};

const Rig& rig() {
  static const Rig r;
  return r;
}

// The edge cases, painted into a copy of a rig frame: black and near-black (dark: no chroma),
// saturated white and a saturated skin tone (one channel at 255), and, on camera 1, the whole
// image 25 % brighter (a global light change: the classifier divides out a gain).
std::vector<cv::Mat> withEdgeCases(const std::vector<cv::Mat>& images) {
  std::vector<cv::Mat> out;
  for (size_t c = 0; c < images.size(); ++c) {
    cv::Mat im = images[c].clone();
    if (c == 1) im.convertTo(im, -1, 1.25);
    im(cv::Rect(0, 0, 24, 16)).setTo(cv::Scalar(0, 0, 0));
    for (int v = 1; v < 8; ++v) im(cv::Rect(24 + 3 * v, 0, 3, 16)).setTo(cv::Scalar(v, v - 1, v));
    im(cv::Rect(60, 0, 24, 16)).setTo(cv::Scalar(255, 255, 255));
    im(cv::Rect(84, 0, 24, 16)).setTo(cv::Scalar(255, 200, 170));
    out.push_back(im);
  }
  return out;
}

bool sameBytes(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && a.isContinuous() && b.isContinuous() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

template <typename T>
int differing(const std::vector<T>& a, const T* b, size_t n) {
  int d = 0;
  for (size_t i = 0; i < n; ++i) d += a[i] != b[i];
  return d + int(a.size() != n) * 1000000;
}

void expectSameStats(const ClassificationStats& a, const ClassificationStats& b,
                     const std::string& what) {
  EXPECT_EQ(a.pixels, b.pixels) << what;
  EXPECT_EQ(a.dark_pixels, b.dark_pixels) << what;
  EXPECT_EQ(a.saturated_pixels, b.saturated_pixels) << what;
  EXPECT_EQ(a.shadow_pixels, b.shadow_pixels) << what;
  EXPECT_EQ(a.mean_foreground, b.mean_foreground) << what;
  EXPECT_EQ(a.gain, b.gain) << what;
}

// Every plane of two models, bit for bit (the scales included).
int differingPlaneValues(const BackgroundModel& a, const BackgroundModel& b) {
  const auto pa = planeList(a.planes()), qa = planeList(b.planes());
  const size_t n = size_t(a.width()) * a.height();
  int d = 0;
  for (size_t k = 0; k < pa.size(); ++k) d += std::memcmp(pa[k], qa[k], n * sizeof(float)) != 0;
  return d;
}

std::vector<PixelClassifierParams> paramVariants() {
  std::vector<PixelClassifierParams> v(4);
  v[1].intensity_model = false;  // the thesis' rg model (dark pixels get the priors)
  v[2].shadow_suppression = false;
  v[3].gain_compensation = false;
  return v;
}

}  // namespace

// ---- per-pixel functions ----------------------------------------------------------------

TEST(PixelArithmetic, ColourConversionIsColorSpaceForEveryColour) {
  int bad = 0;
  for (int R = 0; R < 256; ++R)
    for (int G = 0; G < 256; ++G)
      for (int B = 0; B < 256; ++B) {
        const NormalizedRgI a = toNormalizedRgI(R, G, B);
        const pixel::RgI b = pixel::rgbToRgI(R, G, B);
        bad += a.r != b.r || a.g != b.g || a.intensity != b.intensity;
      }
  EXPECT_EQ(bad, 0);
}

// ---- host emulation of the kernels vs. the CPU path ---------------------------------------

TEST(PixelStageEmulation, ClassificationIsTheClassifiersBytesOnTheRig) {
  const Rig& r = rig();
  int gains_not_one = 0, dark = 0, saturated = 0, shadow = 0;
  // With and without a clothing colour in p(c|notS) (a skin-like tan, clothing_colour.h).
  ColourGaussian tan;
  tan.mean = Eigen::Vector2d(0.46, 0.32);
  tan.covariance << 1.2e-4, 1e-5, 1e-5, 9e-5;
  int clothing_changed = 0;  // skin bytes the clothing colour changed (it must be exercised)
  for (const PixelClassifierParams& params : paramVariants()) {
    for (const bool clothing : {false, true}) {
      PixelClassifier cls(r.skin, params, r.priors);
      if (clothing) cls.setClothingColour(&tan, 0.5);
      const PixelClassifier plain(r.skin, params, r.priors);
      for (size_t f = 0; f < r.frames.size(); ++f) {
        for (const std::vector<cv::Mat>& images : {r.frames[f], withEdgeCases(r.frames[f])}) {
          std::vector<cv::Mat> cpu, without;
          const auto cpu_stats = cls.classify(images, r.modelPointers(r.models), cpu, 2);
          if (clothing) plain.classify(images, r.modelPointers(r.models), without, 2);
          for (int c = 0; c < r.cameras(); ++c) {
            cv::Mat emu;
            const ClassificationStats s = emulation::classify(cls, images[c], r.models[c], emu);
            const std::string what = "frame " + std::to_string(f) + " cam " + std::to_string(c);
            EXPECT_TRUE(sameBytes(emu, cpu[c])) << what << ": " << cv::norm(emu, cpu[c], cv::NORM_INF);
            expectSameStats(s, cpu_stats[c], what);
            if (clothing) clothing_changed += cv::norm(cpu[c], without[c], cv::NORM_L1) > 0;
            gains_not_one += s.gain != 1.0;
            dark += s.dark_pixels;
            saturated += s.saturated_pixels;
            shadow += s.shadow_pixels;
          }
        }
      }
    }
  }
  EXPECT_GT(clothing_changed, 0) << "the clothing colour changed no pixel of the rig's frames";
  std::printf("[ figures  ] over all frames: %d gains != 1, %d dark, %d saturated, %d shadow px\n",
              gains_not_one, dark, saturated, shadow);
  // The cases were exercised, not just present.
  EXPECT_GT(gains_not_one, 0);
  EXPECT_GT(dark, 0);
  EXPECT_GT(saturated, 0);
  EXPECT_GT(shadow, 0);
}

TEST(PixelStageEmulation, GainIsEstimateGain) {
  const Rig& r = rig();
  const PixelClassifier cls(r.skin, {}, r.priors);
  const std::vector<cv::Mat>& images = r.frames[0];
  int checked = 0;
  for (int c = 0; c < r.cameras(); ++c)
    // 0.05: below the gain's range (clamped to 0.25); 0.01: too dark to sample (gain 1).
    for (double scale : {1.0, 0.8, 1.2, 0.05, 0.01}) {
      cv::Mat im;
      images[c].convertTo(im, -1, scale);
      if (c == 2) im(cv::Rect(0, 0, im.cols / 2, im.rows)).convertTo(
          im(cv::Rect(0, 0, im.cols / 2, im.rows)), -1, 0.5);  // half the view in shadow
      cv::Mat lik;
      const double expected = cls.estimateGain(im, r.models[c]);
      const ClassificationStats s = emulation::classify(cls, im, r.models[c], lik);
      EXPECT_EQ(s.gain, expected) << "cam " << c << " scale " << scale;
      if (scale == 0.05) {
        EXPECT_EQ(s.gain, 0.25);
      } else if (scale == 0.01) {
        EXPECT_EQ(s.gain, 1.0);
      }
      ++checked;
    }
  EXPECT_EQ(checked, 5 * r.cameras());
}

TEST(PixelStageEmulation, EvidenceIsViewEvidence) {
  const Rig& r = rig();
  const PixelClassifier cls(r.skin, {}, r.priors);
  std::vector<cv::Mat> lik;
  cls.classify(r.frames[1], r.modelPointers(r.models), lik, 2);
  const int n = r.cameras();
  // Masks: none, the person switched off (a partial mask), the whole view off.
  std::vector<cv::Mat> active(n);
  for (int c = 0; c < n; ++c) {
    if (c % 3 == 1) active[c] = r.masks[1][c] == 0;
    if (c % 3 == 2) active[c] = cv::Mat::zeros(lik[c].size(), CV_8UC1);
  }
  for (int cls_channel : {0, 1})
    for (bool bilinear : {true, false}) {
      std::vector<ViewImage> views(n);
      for (int c = 0; c < n; ++c) {
        views[c].likelihood = lik[c];
        views[c].channel = cls_channel;
        views[c].active = active[c];
      }
      ViewEvidence ev;
      ev.set(views, bilinear, 2);
      for (int c = 0; c < n; ++c) {
        std::vector<int16_t> terms;
        std::vector<uint16_t> pairs;
        emulation::evidence(lik[c], cls_channel, active[c], bilinear, &terms, &pairs);
        const size_t np = size_t(lik[c].total());
        EXPECT_EQ(differing(terms, ev.terms(c), np + 3), 0) << "cam " << c;
        EXPECT_EQ(ev.hasInactivePixels(c), c % 3 != 0);
        if (bilinear) {
          const size_t pc = size_t(ev.quadStride(c)) * (lik[c].rows + 2 * ViewEvidence::kQuadPad) + 2;
          EXPECT_EQ(differing(pairs, ev.pairs(c), pc), 0) << "cam " << c;
        } else {
          EXPECT_TRUE(pairs.empty());
        }
      }
    }
}

TEST(PixelStageEmulation, BackgroundUpdateIsTheModelsOverSeveralFrames) {
  const Rig& r = rig();
  std::vector<BackgroundModel> cpu = r.models, emu = r.models;
  for (auto& m : cpu) {  // a faster rate so six frames move the models visibly
    BackgroundModelParams p = m.params();
    p.learning_rate = 0.1f;
    m.setParams(p);
  }
  for (size_t c = 0; c < emu.size(); ++c) emu[c].setParams(cpu[c].params());
  const PixelClassifier cls(r.skin, {}, r.priors);
  for (int step = 0; step < 6; ++step) {
    const size_t f = size_t(step) % r.frames.size();
    const std::vector<cv::Mat> images = step == 4 ? withEdgeCases(r.frames[f]) : r.frames[f];
    for (size_t c = 0; c < cpu.size(); ++c) {
      const cv::Mat mask = step == 3 ? cv::Mat() : r.masks[f][c];  // step 3: no mask at all
      cpu[c].update(images[c], mask, 2);
      emulation::updateBackground(emu[c], images[c], mask);
      EXPECT_EQ(differingPlaneValues(cpu[c], emu[c]), 0) << "step " << step << " cam " << c;
    }
  }
  // The models did change (and masked pixels did not), and classify alike afterwards.
  EXPECT_GT(cv::norm(cpu[0].meanR(), r.models[0].meanR(), cv::NORM_INF), 0.0);
  std::vector<cv::Mat> a, b;
  cls.classify(r.frames[0], r.modelPointers(cpu), a, 2);
  cls.classify(r.frames[0], r.modelPointers(emu), b, 2);
  for (size_t c = 0; c < a.size(); ++c) EXPECT_TRUE(sameBytes(a[c], b[c]));
}

// ---- the GPU stage itself ------------------------------------------------------------------

TEST(GpuPixelStage, SaysWhyItIsNotUsable) {
  const Rig& r = rig();
  GpuPixelStage stage(r.skin, {}, r.priors);
  EXPECT_EQ(stage.deviceAllocations(), 0u);
  if (cuda::device().usable) {
    EXPECT_TRUE(stage.usable()) << stage.reason();
    return;
  }
  EXPECT_FALSE(stage.usable());
  EXPECT_NE(stage.reason().find(cuda::device().reason), std::string::npos) << stage.reason();
  EXPECT_THROW(stage.uploadBackgrounds(r.modelPointers(r.models)), std::runtime_error);
  EXPECT_THROW(stage.classify(r.frames[0]), std::runtime_error);
  EXPECT_THROW(stage.updateBackground({}), std::runtime_error);
  EXPECT_TRUE(stage.bodyEvidence().empty());
  // The CPU fallback is there with the same settings.
  EXPECT_EQ(stage.classifier().priors().foreground, r.priors.foreground);
}

// Ten frames as the pipeline runs them: classify, evidence (one view off, one with the person
// switched off), selective update; every output compared with the CPU path's.
TEST(GpuPixelStage, TenFramesAreTheCpuPathsBytes) {
  PSFS_REQUIRE_GPU();
  const Rig& r = rig();
  const int n = r.cameras();
  std::vector<BackgroundModel> cpu_models = r.models, gpu_models = r.models;
  for (auto* ms : {&cpu_models, &gpu_models})
    for (auto& m : *ms) {
      BackgroundModelParams p = m.params();
      p.learning_rate = 0.1f;
      m.setParams(p);
    }
  PixelClassifier cls(r.skin, {}, r.priors);
  GpuPixelStage stage(r.skin, {}, r.priors);
  ASSERT_TRUE(stage.usable()) << stage.reason();
  stage.uploadBackgrounds(r.modelPointers(gpu_models));
  size_t allocations_after_first = 0;
  ColourGaussian tan;  // a clothing colour in p(c|notS) from step 5 on (clothing_colour.h)
  tan.mean = Eigen::Vector2d(0.46, 0.32);
  tan.covariance << 1.2e-4, 1e-5, 1e-5, 9e-5;
  for (int step = 0; step < 10; ++step) {
    if (step == 5) {
      cls.setClothingColour(&tan, 0.5);
      stage.setClothingColour(&tan, 0.5);
    }
    const size_t f = size_t(step) % r.frames.size();
    const std::vector<cv::Mat> images = step % 2 ? withEdgeCases(r.frames[f]) : r.frames[f];
    const std::string what = "step " + std::to_string(step);
    // classification
    std::vector<cv::Mat> cpu_lik, gpu_lik;
    const auto cpu_stats = cls.classify(images, r.modelPointers(cpu_models), cpu_lik, 2);
    const auto gpu_stats = stage.classify(images, &gpu_lik);
    ASSERT_EQ(gpu_lik.size(), size_t(n));
    for (int c = 0; c < n; ++c) {
      EXPECT_TRUE(sameBytes(gpu_lik[c], cpu_lik[c]))
          << what << " cam " << c << ": " << cv::norm(gpu_lik[c], cpu_lik[c], cv::NORM_INF);
      expectSameStats(gpu_stats[c], cpu_stats[c], what);
    }
    // evidence
    std::vector<cv::Mat> active(n);
    active[1] = r.masks[f][1] == 0;
    active[2] = cv::Mat::zeros(cpu_lik[2].size(), CV_8UC1);
    stage.buildEvidence(active, true, step % 3 != 0);
    for (int ch : {0, 1}) {
      std::vector<ViewImage> views(n);
      for (int c = 0; c < n; ++c) views[c] = {cpu_lik[c], ch, active[c]};
      ViewEvidence ev;
      const bool bilinear = ch == 0 || step % 3 != 0;
      ev.set(views, bilinear, 2);
      const GpuEvidence& g = ch ? stage.skinEvidence() : stage.bodyEvidence();
      ASSERT_EQ(g.size(), size_t(n));
      for (int c = 0; c < n; ++c) {
        std::vector<int16_t> terms;
        std::vector<uint16_t> pairs;
        stage.readEvidence(c, ch == 1, &terms, &pairs);
        EXPECT_EQ(differing(terms, ev.terms(c), cpu_lik[c].total() + 3), 0) << what;
        EXPECT_EQ(g[c].has_inactive_pixels, ev.hasInactivePixels(c));
        EXPECT_EQ(g[c].quad_stride, ev.quadStride(c));
        EXPECT_EQ(g[c].pairs != nullptr, bilinear);
        if (bilinear) {
          const size_t pc = size_t(ev.quadStride(c)) * (cpu_lik[c].rows + 16) + 2;
          EXPECT_EQ(differing(pairs, ev.pairs(c), pc), 0) << what;
        }
      }
    }
    // selective update (step 3: no masks)
    const std::vector<cv::Mat> masks = step == 3 ? std::vector<cv::Mat>() : r.masks[f];
    for (int c = 0; c < n; ++c) cpu_models[c].update(images[c], masks.empty() ? cv::Mat() : masks[c], 2);
    stage.updateBackground(masks);
    std::vector<BackgroundModel*> out;
    for (auto& m : gpu_models) out.push_back(&m);
    stage.downloadBackgrounds(out);
    for (int c = 0; c < n; ++c)
      EXPECT_EQ(differingPlaneValues(cpu_models[c], gpu_models[c]), 0) << what << " cam " << c;
    if (step == 0) allocations_after_first = stage.deviceAllocations();
    EXPECT_EQ(stage.deviceAllocations(), allocations_after_first) << what;
  }
  EXPECT_EQ(allocations_after_first, size_t(2 * n));  // one device, one pinned block per camera
}

TEST(GpuPixelStage, MissingCameraHasNoLikelihoodAndIsNotUpdated) {
  PSFS_REQUIRE_GPU();
  const Rig& r = rig();
  GpuPixelStage stage(r.skin, {}, r.priors);
  ASSERT_TRUE(stage.usable()) << stage.reason();
  stage.uploadBackgrounds(r.modelPointers(r.models));
  std::vector<cv::Mat> images = r.frames[0];
  images[3] = cv::Mat();
  std::vector<cv::Mat> lik;
  const auto stats = stage.classify(images, &lik);
  EXPECT_EQ(stats[3].pixels, 0);
  EXPECT_EQ(cv::countNonZero(lik[3].reshape(1)), 0);
  EXPECT_THROW(stage.updateBackground({}, std::vector<bool>(r.cameras(), true)), std::logic_error);
  stage.updateBackground({});  // every camera with an image
  std::vector<BackgroundModel> back = r.models;
  std::vector<BackgroundModel*> out;
  for (auto& m : back) out.push_back(&m);
  stage.downloadBackgrounds(out);
  EXPECT_EQ(differingPlaneValues(back[3], r.models[3]), 0);
  EXPECT_GT(differingPlaneValues(back[0], r.models[0]), 0);
  EXPECT_THROW(stage.classify(std::vector<cv::Mat>(2)), std::invalid_argument);
}

}  // namespace psfs
