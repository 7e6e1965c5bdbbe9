// PAPF timings (DESIGN.md section 6: "PAPF 256 particles x 4 layers <= 10 ms" on 2 cores; the
// thesis: 25.8 ms on a GTX 280). Input (sim_frames.h): 40 consecutive frames of the simulated rig's
// reach_targets script in short sleeves, rendered and reconstructed by psfs::Reconstructor
// (64x64x48 body and skin volumes), prepared once (~3 s). A tracker is warmed up on them, then
// each iteration is one full update (downsampling, three partitions x L layers, hands) on the
// next frame, going back and forth over the 40 so that no step is a jump. Same-run baseline:
// the MPF hand/head tracker with 1000 particles on the same volumes (its bar: 1 ms).
//
//   bench_papf --benchmark_repetitions=3 [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include "body_tracking/arm_length.h"
#include "body_tracking/model_prior.h"
#include "body_tracking/papf.h"
#include "body_tracking/silhouette_mask.h"
#include "hand_tracking/mpf_tracker.h"
#include "sim_frames.h"

namespace body_tracking {
namespace {

// Arguments: particles, layers, observation downsample (2: 32x32x24, 1: 64x64x48), threads.
void BM_PapfUpdate(benchmark::State& st) {
  const Frames& f = frames();
  PapfParams p;
  p.particles = static_cast<int>(st.range(0));
  p.layers = static_cast<int>(st.range(1));
  p.observation.downsample = static_cast<int>(st.range(2));
  p.threads = static_cast<int>(st.range(3));
  p.arm_length.frames = 0;  // the steady state: the arms' votes (BM_ArmLengthVote) end after ~2 s
  Papf papf(BodyProfile(), p);
  const size_t n = f.body.size();
  for (size_t i = 0; i < n; ++i) papf.update(f.body[i], &f.skin[i]);  // start and warm up
  size_t i = n - 1;
  double obs = 0, score = 0;
  int frames_run = 0;
  for (auto _ : st) {
    const size_t k = f.at(i++);
    const BodyEstimate& e = papf.update(f.body[k], &f.skin[k]);
    benchmark::DoNotOptimize(e.state.data());
    obs += papf.lastTimes().observation_ms;
    score += e.score;
    ++frames_run;
  }
  st.counters["observation_ms"] = obs / frames_run;
  st.counters["fit"] = score / frames_run;
}
BENCHMARK(BM_PapfUpdate)
    ->ArgNames({"particles", "layers", "downsample", "threads"})
    ->Args({256, 4, 2, 2})
    ->Args({256, 4, 2, 1})
    ->Args({256, 4, 1, 2})
    ->Args({128, 4, 2, 2})
    ->Args({512, 4, 2, 2})
    ->Args({1024, 4, 2, 2})
    ->Args({2048, 4, 2, 2})
    ->Args({256, 2, 2, 2})
    ->Args({256, 8, 2, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The same-run baseline: the MPF (1000 particles: head 200, hands 400 each) on the same frames.
void BM_MpfBaseline(benchmark::State& st) {
  const Frames& f = frames();
  hand_tracking::MpfParams p;
  p.hand_particles = 400;
  p.head_particles = 200;
  p.threads = static_cast<int>(st.range(0));
  hand_tracking::MpfTracker mpf(p, 1);
  const size_t n = f.body.size();
  for (size_t i = 0; i < n; ++i) mpf.update(f.skin[i], f.body[i], 0.04);
  size_t i = n - 1;
  for (auto _ : st) {
    const size_t k = f.at(i++);
    benchmark::DoNotOptimize(mpf.update(f.skin[k], f.body[k], 0.04).data());
  }
}
BENCHMARK(BM_MpfBaseline)->ArgName("threads")->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// Silhouette masks of a tracked pose for all 8 cameras (argument: margin in px).
void BM_Masks8Cameras(benchmark::State& st) {
  const Frames& f = frames();
  PapfParams p;
  Papf papf(BodyProfile(), p);
  for (size_t i = 0; i < f.body.size(); ++i) papf.update(f.body[i], &f.skin[i]);
  const BodyParts parts = buildParts(papf.profile(), papf.estimate().frames);
  std::vector<SilhouetteProjector> projectors;
  for (const auto& c : f.cameras) projectors.emplace_back(c);
  std::vector<cv::Mat> masks(projectors.size());
  for (auto _ : st) {
    for (size_t c = 0; c < projectors.size(); ++c)
      projectors[c].draw(parts, static_cast<double>(st.range(0)), &masks[c]);
    benchmark::DoNotOptimize(masks[0].data);
  }
}
BENCHMARK(BM_Masks8Cameras)->ArgName("margin_px")->Arg(0)->Arg(4)->Unit(benchmark::kMillisecond)->UseRealTime();

// One frame's vote of the arms' length refinement (arm_length.h), which runs on top of the
// update over a track's first shape/arm_frames frames only: both arms, 13 factors x 6 hand
// targets each, on the estimate after the 40 frames.
void BM_ArmLengthVote(benchmark::State& st) {
  const Frames& f = frames();
  Papf papf(BodyProfile{}, PapfParams{});
  for (size_t i = 0; i < f.body.size(); ++i) papf.update(f.body[i], &f.skin[i]);
  const BodyEstimate& e = papf.estimate();
  ArmLengthParams ap;
  ap.frames = 1 << 30;
  ArmLength arms(ap);
  for (auto _ : st) arms.add(papf.observation(), BodyProfile{}, e.state, e.hands);
  st.counters["voting_arms"] = e.hands.from_skin[0] + e.hands.from_skin[1];
  st.counters["factor"] = arms.factor();
}
BENCHMARK(BM_ArmLengthVote)->Unit(benchmark::kMillisecond)->UseRealTime();

// body/volume (model_prior.h): the tracked model as a prior on one 64x64x48 body volume, what
// the nodelet adds per frame while body/volume has a subscriber.
void BM_ModelPrior(benchmark::State& st) {
  const Frames& f = frames();
  Papf papf(BodyProfile{}, PapfParams{});
  for (size_t i = 0; i < f.body.size(); ++i) papf.update(f.body[i], &f.skin[i]);
  const psfs::ProbabilityVolume& body = f.body.back();
  psfs::ProbabilityVolume out;
  for (auto _ : st) {  // the nodelet's per-frame work: the solids (neck, reaching hands) as well
    applyModelPrior(body, priorSolids(papf.profile(), papf.estimate().frames, ModelPriorParams()),
                    ModelPriorParams(), &out);
    benchmark::DoNotOptimize(out.data.data());
  }
  st.counters["hull_voxels"] = static_cast<double>(psfs::countAbove(body, 127));
  st.counters["volume_voxels"] = static_cast<double>(psfs::countAbove(out, 127));
}
BENCHMARK(BM_ModelPrior)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace body_tracking

BENCHMARK_MAIN();
