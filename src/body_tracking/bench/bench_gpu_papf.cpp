// The PAPF's particle weights on the GPU against the CPU, in the same run, on the frames of
// bench_papf (sim_frames.h). Thesis 7.4, GTX 280 with 256 particles: 0.61 ms part poses +
// 3.24 ms weights per annealing layer.
//  BM_Weights     one annealing layer's scoring: each of the three partitions once, on 256 or
//                 4096 particles spread around the tracked pose; CPU = Papf's OpenMP loop over
//                 scoreState (2 threads), GPU = GpuParticleWeights (part poses on 2 threads,
//                 counters poses_ms and device_ms per layer).
//  BM_PapfUpdate  one full update (three partitions x 4 layers, hands) with 256 and 4096
//                 particles, gpu_weights off and on.
// Without a usable device the GPU runs are skipped with the reason (printed first).
//
//   bench_gpu_papf [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <cstdio>
#include <random>

#include "body_tracking/gpu_particle_weights.h"
#include "body_tracking/papf.h"
#include "sim_frames.h"

namespace body_tracking {
namespace {

constexpr int kThreads = 2;

const std::string& gpuMissing() {
  static const std::string reason = [] {
    const GpuParticleWeights probe;
    return probe.usable() ? std::string() : probe.reason();
  }();
  return reason;
}

// A tracker on the frames, and `n` particles spread around its estimate as a layer's are.
struct Tracked {
  std::unique_ptr<Papf> papf;
  std::vector<BodyState> particles;
  explicit Tracked(int n) {
    const Frames& f = frames();
    papf = std::make_unique<Papf>(BodyProfile(), PapfParams());
    for (size_t i = 0; i < 5; ++i) papf->update(f.body[i], &f.skin[i]);
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    particles.assign(n, papf->estimate().state);
    for (BodyState& s : particles) {
      for (int j = 0; j < dof::COUNT; ++j) s[j] += (j < dof::TORSO_ROLL ? 0.02 : 0.15) * u(rng);
      papf->limits().enforce(&s);
    }
  }
};

// Arguments: particles, backend (0 CPU, 1 GPU).
void BM_Weights(benchmark::State& st) {
  const int n = static_cast<int>(st.range(0));
  const bool gpu = st.range(1) != 0;
  if (gpu && !gpuMissing().empty()) {
    st.SkipWithError(("no GPU: " + gpuMissing()).c_str());
    return;
  }
  const Tracked t(n);
  const Papf& papf = *t.papf;
  GpuParticleWeights w;
  if (gpu) w.setObservation(papf.observation());
  std::vector<double> scores(n);
  double poses = 0, device = 0;
  int layers = 0;
  for (auto _ : st) {
    for (int k = 0; k < Papf::kPartitions; ++k) {
      if (gpu) {
        w.score(papf.profile(), t.particles, k, kThreads, &scores);
        poses += w.lastTimes().poses_ms;
        device += w.lastTimes().device_ms;
      } else {
#pragma omp parallel for num_threads(kThreads) schedule(dynamic, 8)
        for (int i = 0; i < n; ++i) scores[i] = papf.scoreState(t.particles[i], k);
      }
    }
    benchmark::DoNotOptimize(scores.data());
    ++layers;
  }
  if (gpu) {
    st.counters["poses_ms"] = poses / layers;
    st.counters["device_ms"] = device / layers;
  }
}
BENCHMARK(BM_Weights)
    ->ArgNames({"particles", "gpu"})
    ->Args({256, 0})
    ->Args({256, 1})
    ->Args({4096, 0})
    ->Args({4096, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Arguments: particles, layers, gpu_weights.
void BM_PapfUpdate(benchmark::State& st) {
  const bool gpu = st.range(2) != 0;
  if (gpu && !gpuMissing().empty()) {
    st.SkipWithError(("no GPU: " + gpuMissing()).c_str());
    return;
  }
  const Frames& f = frames();
  PapfParams p;
  p.particles = static_cast<int>(st.range(0));
  p.layers = static_cast<int>(st.range(1));
  p.threads = kThreads;
  p.gpu_weights = gpu;
  Papf papf(BodyProfile(), p);
  for (size_t i = 0; i < 5; ++i) papf.update(f.body[i], &f.skin[i]);  // start and warm up
  size_t i = 4;
  double obs = 0;
  int frames_run = 0;
  for (auto _ : st) {
    const size_t k = f.at(i++);
    benchmark::DoNotOptimize(papf.update(f.body[k], &f.skin[k]).state.data());
    obs += papf.lastTimes().observation_ms;
    ++frames_run;
  }
  st.counters["observation_ms"] = obs / frames_run;
}
BENCHMARK(BM_PapfUpdate)
    ->ArgNames({"particles", "layers", "gpu"})
    ->Args({256, 4, 0})
    ->Args({256, 4, 1})
    ->Args({4096, 4, 0})
    ->Args({4096, 4, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace body_tracking

int main(int argc, char** argv) {
  const std::string& missing = body_tracking::gpuMissing();
  if (missing.empty())
    std::printf("bench_gpu_papf: GPU particle weights on the device below\n");
  else
    std::printf("bench_gpu_papf: the GPU runs are skipped: %s\n", missing.c_str());
  std::fflush(stdout);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
