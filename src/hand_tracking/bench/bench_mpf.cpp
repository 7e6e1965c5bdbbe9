// MPF timings on the reference workload (DESIGN.md section 6: "MPF with 1000 particles <= 1 ms"
// on 2 cores; the thesis: ~5 ms on a 2008 desktop). Input: 40 consecutive frames of the
// simulated rig's reach_targets script, rendered and reconstructed by psfs::Reconstructor
// (64x64x48 skin and body volumes), prepared once (~2 s). A tracker is warmed up on them (head
// and both hands tracked), then each iteration is one full update (both integral volumes,
// prediction, weights, births, reconfiguration, estimates) on the next frame.
//
//   bench_mpf --benchmark_repetitions=3 [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <cstdio>
#include <random>
#include <string>

#include "hand_tracking/box_observation.h"
#include "hand_tracking/integral_volume.h"
#include "hand_tracking/mpf_tracker.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_sim/simulated_rig.h"

namespace hand_tracking {
namespace {

namespace sim = tabletop_sim;

struct Frames {
  std::vector<psfs::ProbabilityVolume> skin, body;
  explicit Frames(const std::string& scenario = "default") {
    constexpr int kLearn = 25, kFrames = 40, kSkip = 60;  // start mid-reach
    sim::SimOptions o;
    o.scenario = scenario;
    o.script = "reach_targets";
    o.empty_frames = kLearn;
    sim::SimulatedRig rig(o);
    psfs::ReconstructorParams rp;
    psfs::Reconstructor rec(psfs::GaussianMixture2D::load(HAND_TRACKING_SKIN_MODEL), rp);
    for (int f = 0; f < kLearn; ++f) rec.process(rig.render(f).images, rig.rig().cameras);
    for (int f = kLearn + kSkip; f < kLearn + kSkip + kFrames; ++f) {
      psfs::FrameResult r = rec.process(rig.render(f).images, rig.rig().cameras);
      skin.push_back(std::move(r.skin));
      body.push_back(std::move(r.body));
    }
  }
};

const Frames& frames() {
  static const Frames f;
  return f;
}
// The same person in short sleeves: bare forearms and elbows, where the reported hand is found
// by the walk along the skin (arm_geodesic.h) wherever the box around it sees an arm.
const Frames& bareArmFrames() {
  static const Frames f("short_sleeves");
  return f;
}

MpfParams paramsFor(int total, int threads) {
  MpfParams p;
  p.hand_particles = std::max(3, static_cast<int>(0.4 * total));
  p.head_particles = std::max(1, total - 2 * p.hand_particles);
  p.threads = threads;
  return p;
}

// Full updates on `f`'s frames, after one warm-up pass, with the stages' times as counters.
void runUpdates(benchmark::State& st, const Frames& f, int particles, int threads) {
  MpfTracker tracker(paramsFor(particles, threads), 1);
  const size_t n = f.skin.size();
  for (size_t i = 0; i < n; ++i) tracker.update(f.skin[i], f.body[i], 0.04);  // warm-up
  size_t i = 0;
  double integral = 0, weights = 0, reconfigure = 0, active = 0;
  for (auto _ : st) {
    const auto& t = tracker.update(f.skin[i % n], f.body[i % n], 0.04);
    benchmark::DoNotOptimize(t.data());
    const MpfTracker::Times& tm = tracker.lastTimes();
    integral += tm.integral_ms;
    weights += tm.weights_ms;
    reconfigure += tm.reconfigure_ms;
    for (const Target& x : t) active += x.active;
    ++i;
  }
  st.counters["integral_ms"] = integral / i;
  st.counters["weights_ms"] = weights / i;
  st.counters["reconf_ms"] = reconfigure / i;
  st.counters["targets"] = active / i;
  st.counters["particles"] = static_cast<double>(tracker.particles().size());
}

// Arguments: total particles (head 20 %, each hand 40 %, the thesis' 200/400/400 ratio),
// OpenMP threads.
void BM_MpfUpdate(benchmark::State& st) {
  runUpdates(st, frames(), static_cast<int>(st.range(0)), static_cast<int>(st.range(1)));
}
BENCHMARK(BM_MpfUpdate)
    ->ArgNames({"particles", "threads"})
    ->Args({1000, 2})
    ->Args({1000, 1})
    ->Args({250, 2})
    ->Args({500, 2})
    ->Args({2000, 2})
    ->Args({4000, 2})
    ->Args({8000, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Bare forearms (1000 particles, 2 threads): the hands' ends found along the skin.
void BM_MpfUpdateBareArms(benchmark::State& st) { runUpdates(st, bareArmFrames(), 1000, 2); }
BENCHMARK(BM_MpfUpdateBareArms)->Unit(benchmark::kMillisecond)->UseRealTime();

// The thesis' observation: voxel-centre box means (8 reads per box) instead of the smooth ones.
void BM_MpfUpdateVoxelBoxes(benchmark::State& st) {
  const Frames& f = frames();
  MpfParams p = paramsFor(1000, 2);
  p.smooth_boxes = false;
  MpfTracker tracker(p, 1);
  const size_t n = f.skin.size();
  for (size_t i = 0; i < n; ++i) tracker.update(f.skin[i], f.body[i], 0.04);
  size_t i = 0;
  for (auto _ : st) benchmark::DoNotOptimize(tracker.update(f.skin[i % n], f.body[i % n], 0.04).data()), ++i;
}
BENCHMARK(BM_MpfUpdateVoxelBoxes)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_IntegralVolumeBuild(benchmark::State& st) {
  const Frames& f = frames();
  IntegralVolume iv;
  for (auto _ : st) {
    iv.build(f.skin[0]);
    benchmark::DoNotOptimize(iv.boxSum({0, 0, 0}, {1, 1, 1}));
  }
  st.counters["voxels"] = static_cast<double>(f.skin[0].grid.numVoxels());
}
BENCHMARK(BM_IntegralVolumeBuild)->Unit(benchmark::kMicrosecond);

// One box mean at random positions: voxel-centre (8 reads) and smooth (64 reads).
void BM_BoxMean(benchmark::State& st) {
  const Frames& f = frames();
  const IntegralVolume iv(f.skin[0]);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.45, 0.45);
  std::vector<Eigen::Vector3d> c(1024);
  for (auto& x : c) x = Eigen::Vector3d(u(rng), u(rng), 0.35 + 0.8 * u(rng));
  const Eigen::Vector3d half(0.045, 0.045, 0.045);
  const bool smooth = st.range(0) != 0;
  size_t i = 0;
  for (auto _ : st) {
    const Eigen::Vector3d& x = c[i++ & 1023];
    benchmark::DoNotOptimize(smooth ? iv.boxMeanSmooth(x - half, x + half)
                                    : iv.boxMean(x - half, x + half));
  }
}
BENCHMARK(BM_BoxMean)->ArgName("smooth")->Arg(0)->Arg(1);

}  // namespace
}  // namespace hand_tracking

BENCHMARK_MAIN();
