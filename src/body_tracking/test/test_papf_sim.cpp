// The PAPF on the real pipeline: the simulated rig renders 8 cameras, psfs::Reconstructor
// learns the background and fuses the 64x64x48 body and skin volumes, the tracker runs on them
// (at 32x32x24 after its 2x downsampling, as in the thesis), and the result is scored against
// the rig's ground truth: hands (centroid of palm + fingers), head centre, elbows.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <vector>
#include <chrono>
#include <cstdlib>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

#include "body_tracking/papf.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_sim/simulated_rig.h"

namespace body_tracking {
namespace {

namespace sim = tabletop_sim;

struct Frame {
  int k = 0;
  const sim::SimulatedRig* rig = nullptr;
  int rig_frame = 0;
  const sim::GroundTruth* truth = nullptr;
  const psfs::ProbabilityVolume* body = nullptr;
  const psfs::ProbabilityVolume* skin = nullptr;
};

// Renders and reconstructs `script` after 25 empty frames for the background (plus extra_empty
// empty frames that are reconstructed and streamed) and calls fn for each reconstructed frame,
// at most max_frames (< 0: all).
int stream(const std::string& script, bool short_sleeves, int max_frames,
           const std::function<void(const Frame&)>& fn, int extra_empty = 0) {
  const auto t0 = std::chrono::steady_clock::now();
  sim::SimOptions o;
  o.script = script;
  o.short_sleeves = short_sleeves;
  o.empty_frames = 25 + extra_empty;
  sim::SimulatedRig rig(o);
  psfs::ReconstructorParams rp;
  rp.threads = 2;
  psfs::Reconstructor rec(psfs::GaussianMixture2D::load(BODY_TRACKING_SKIN_MODEL), rp);
  Frame f;
  f.rig = &rig;
  for (int i = 0; i < rig.scriptFrames() && (max_frames < 0 || f.k < max_frames); ++i) {
    const sim::SimFrame frame = rig.render(i);
    const psfs::FrameResult r = rec.process(frame.images, rig.rig().cameras);
    if (r.status != psfs::FrameResult::Status::kReconstructed) continue;
    f.rig_frame = i;
    f.truth = &frame.truth;
    f.body = &r.body;
    f.skin = &r.skin;
    fn(f);
    ++f.k;
  }
  std::printf("[ sim      ] %s%s: %d frames in %.1f s\n", script.c_str(),
              short_sleeves ? " (short sleeves)" : "", f.k,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return f.k;
}

struct Stats {
  double sum = 0, max = 0;
  int n = 0;
  void add(double v) {
    sum += v;
    max = std::max(max, v);
    ++n;
  }
  double mean() const { return n ? sum / n : NAN; }
};

// Bars: the issue's, 16 mm (hands), 15 mm (head) and 25 mm (elbows); the thesis measured 32.1
// mm for the hands on real data. What the defaults measure on this sequence, seeds 1-5: hands
// 12.7 / 11.2 / 11.2 / 11.1 / 11.7 mm (median 11.2), head 9.5, elbows 19.4, shoulders 19.0 mm
// (medians). History: before the trunk parts' shell (volume_observation.h) the trunk wandered
// inside the blob of trunk, arms and halo and the median read hands 21.5, head 13.0, elbows
// 37.2 mm, two seeds losing an arm for seconds; with the shell, 20.5 / 11.5 / 33.5; with the arm
// partitions reseeded from the propagated particles (PapfParams::reseed_arms) instead of the
// trunk layers' survivors, 13.3 / 9.7 / 19.0; with the arms' length read online
// (arm_length.h), today's. Any change upstream moves every later particle (the fusion
// and observation kernels give the same bytes on every instruction set: TABLETOP_SIMD=avx2
// prints the same figures), so the bars judge the median of five seeds, and every seed only for
// a lost arm (kHandSeedBar: such runs read 50-80 mm).
constexpr double kHandMeanBar = 0.016, kHeadMeanBar = 0.015, kElbowMeanBar = 0.025;
constexpr double kHandSeedBar = 0.025;

bool sameState(const BodyState& a, const BodyState& b) {
  for (int i = 0; i < dof::COUNT; ++i)
    if (a[i] != b[i]) return false;
  return true;
}

TEST(PapfSim, ReachTargetsShortSleevesAccuracyAndDeterminism) {
  // Five seeds on the same volumes: one seed's run is one draw of a chaotic search (a change
  // anywhere moves every later particle; a run that loses an arm for a few seconds reads 50-80
  // mm), so the accuracy bars judge the median run and every run only for a lost arm.
  constexpr int kSeeds = 5;
  std::vector<std::unique_ptr<Papf>> papfs;
  for (int k = 0; k < kSeeds; ++k) {
    PapfParams p;
    p.seed = 1 + k;
    p.threads = 2;
    papfs.push_back(std::make_unique<Papf>(BodyProfile(), p));
  }
  PapfParams p1 = papfs[0]->params();
  p1.threads = 1;
  Papf single(BodyProfile(), p1);  // the first seed on one thread: must agree exactly
  Stats hands[kSeeds], head[kSeeds], elbows[kSeeds], shoulders[kSeeds];
  int tracked[kSeeds] = {}, starts[kSeeds] = {}, person_frames = 0, differing = 0;
  double ms = 0, obs_ms = 0;
  stream("reach_targets", true, -1, [&](const Frame& f) {
    if (f.truth->person_present) ++person_frames;
    const sim::BodyFrames t = f.rig->body().forward(f.rig->pose(f.rig_frame));
    for (int k = 0; k < kSeeds; ++k) {
      Papf& papf = *papfs[k];
      const BodyEstimate& e = papf.update(*f.body, f.skin);
      if (k == 0) {
        if (!sameState(single.update(*f.body, f.skin).state, e.state)) ++differing;
        ms += papf.lastTimes().total_ms;
        obs_ms += papf.lastTimes().observation_ms;
      }
      if (e.started) ++starts[k];
      if (!f.truth->person_present || !e.tracking) continue;
      ++tracked[k];
      hands[k].add((e.hands.position[0] - f.truth->left_hand).norm());
      hands[k].add((e.hands.position[1] - f.truth->right_hand).norm());
      head[k].add((e.frames.head_centre - f.truth->head).norm());
      for (int i = 0; i < 2; ++i) {
        elbows[k].add((e.frames.elbow[i] - t.elbow[i]).norm());
        shoulders[k].add((e.frames.shoulder[i] - t.shoulder[i]).norm());
      }
    }
  });
  std::vector<double> hand_means, head_means, elbow_means;
  for (int k = 0; k < kSeeds; ++k) {
    std::printf("[ papf     ] seed %d: tracked %d/%d frames, %d start(s); hands %.1f mm mean (max %.1f), "
                "head %.1f (max %.1f), elbows %.1f (max %.1f), shoulders %.1f\n",
                1 + k, tracked[k], person_frames, starts[k], 1000 * hands[k].mean(), 1000 * hands[k].max,
                1000 * head[k].mean(), 1000 * head[k].max, 1000 * elbows[k].mean(), 1000 * elbows[k].max,
                1000 * shoulders[k].mean());
    hand_means.push_back(hands[k].mean());
    head_means.push_back(head[k].mean());
    elbow_means.push_back(elbows[k].mean());
    EXPECT_EQ(tracked[k], person_frames) << "seed " << 1 + k << ": the track was lost";
    EXPECT_LT(hands[k].mean(), kHandSeedBar) << "seed " << 1 + k << ": an arm was lost for a while";
    EXPECT_EQ(starts[k], 1) << "seed " << 1 + k;
  }
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  std::printf("[ papf     ] median of %d seeds: hands %.1f mm, head %.1f, elbows %.1f; %.1f ms/frame "
              "(observation %.1f)\n",
              kSeeds, 1000 * median(hand_means), 1000 * median(head_means), 1000 * median(elbow_means),
              ms / std::max(1, tracked[0]), obs_ms / std::max(1, tracked[0]));
  ASSERT_GT(person_frames, 400);
  EXPECT_LT(median(hand_means), kHandMeanBar);
  EXPECT_LT(median(head_means), kHeadMeanBar);
  EXPECT_LT(median(elbow_means), kElbowMeanBar);
  EXPECT_EQ(differing, 0) << "1 and 2 threads disagree";
}

TEST(PapfSim, NoStartOnEmptyScenesRestartsWhenThePersonComesBack) {
  // The stream starts with 10 empty reconstructed frames; the person then sits there. Frames
  // 60-79 are replaced by an empty frame's volumes (the person has left), then the real frames
  // go on (the person is back).
  PapfParams p;
  p.seed = 5;
  Papf papf(BodyProfile(), p);
  psfs::ProbabilityVolume empty_body, empty_skin;
  int false_starts = 0, lost_at = -1, back_at = -1, starts = 0;
  Stats head_after;
  stream("reach_targets", true, 150, [&](const Frame& f) {
    const bool present = f.truth->person_present;
    if (!present && empty_body.data.empty()) {
      empty_body = *f.body;
      empty_skin = *f.skin;
    }
    const bool away = f.k >= 60 && f.k < 80;
    const BodyEstimate& e = away ? papf.update(empty_body, &empty_skin) : papf.update(*f.body, f.skin);
    if (e.started) ++starts;
    if (!present && e.tracking) ++false_starts;
    if (away && !e.tracking && lost_at < 0) lost_at = f.k;
    if (f.k >= 80 && e.tracking && back_at < 0) back_at = f.k;
    if (f.k >= 90 && e.tracking) head_after.add((e.frames.head_centre - f.truth->head).norm());
  }, 10);
  std::printf("[ papf     ] lost at frame %d (left at 60), restarted at %d (back at 80), head after "
              "the restart %.1f mm mean\n", lost_at, back_at, 1000 * head_after.mean());
  EXPECT_FALSE(empty_body.data.empty()) << "the stream had no empty frame";
  EXPECT_EQ(false_starts, 0);
  ASSERT_GE(lost_at, 60) << "the track was not dropped while nobody was there";
  EXPECT_LE(lost_at, 60 + p.lost_frames);
  EXPECT_EQ(back_at, 80) << "no restart on the first frame with the person back";
  EXPECT_EQ(starts, 2);
  EXPECT_LT(head_after.mean(), 2 * kHeadMeanBar);
}

}  // namespace
}  // namespace body_tracking
