// Simulated-rig rendering speed: one frame set of the default rig (8 cameras, 320x240, person
// present mid-script), 1 thread vs all threads, against two baselines measured in the same
// run: the same renderer without screen-space culling (every primitive ray tested at every
// pixel), and the static part alone (background + noise, no person).
// Target (DESIGN.md: the simulated rig must keep up with 25 fps): <= 40 ms per frame set.
#include <benchmark/benchmark.h>
#include <omp.h>

#include "tabletop_sim/simulated_rig.h"

using namespace tabletop_sim;

namespace {

const SimulatedRig& rig() {
  static const SimulatedRig r([] {
    SimOptions o;
    o.threads = 0;
    return o;
  }());
  return r;
}

int midFrame() { return rig().scriptFrames() / 2; }

// Renderers with a given thread count share the rig's cameras and options.
const Renderer& renderer(int threads) {
  static std::unique_ptr<Renderer> r1, rn;
  std::unique_ptr<Renderer>& r = threads == 1 ? r1 : rn;
  if (!r) {
    RenderOptions o;
    o.threads = threads;
    r.reset(new Renderer(rig().rig(), o));
  }
  return *r;
}

void setCounters(benchmark::State& state, int threads) {
  state.counters["threads"] = threads == 0 ? omp_get_max_threads() : threads;
  state.counters["cameras"] = static_cast<double>(rig().rig().cameras.size());
  state.counters["frame_sets/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// Arg: thread count (0 = all).
void BM_RenderFrameSet(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const std::vector<Primitive> person = rig().person(midFrame());
  const Renderer& r = renderer(threads);  // built outside the timed loop
  RenderOutput out;
  uint64_t frame = midFrame();
  for (auto _ : state) {
    r.render(person, frame++, false, &out);
    benchmark::DoNotOptimize(out.images[0].data);
  }
  state.counters["primitives"] = static_cast<double>(person.size());
  setCounters(state, threads);
}
BENCHMARK(BM_RenderFrameSet)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RenderFrameSetWithMasks(benchmark::State& state) {
  const std::vector<Primitive> person = rig().person(midFrame());
  const Renderer& r = renderer(0);
  RenderOutput out;
  uint64_t frame = midFrame();
  for (auto _ : state) {
    r.render(person, frame++, true, &out);
    benchmark::DoNotOptimize(out.images[0].data);
  }
  setCounters(state, 0);
}
BENCHMARK(BM_RenderFrameSetWithMasks)->Unit(benchmark::kMillisecond)->UseRealTime();

// Baseline 1: no culling (every primitive at every pixel).
void BM_BaselineNoCulling(benchmark::State& state) {
  const std::vector<Primitive> person = rig().person(midFrame());
  const Renderer& r = renderer(0);
  RenderOutput out;
  uint64_t frame = midFrame();
  for (auto _ : state) {
    r.renderWithoutCulling(person, frame++, false, &out);
    benchmark::DoNotOptimize(out.images[0].data);
  }
  setCounters(state, 0);
}
BENCHMARK(BM_BaselineNoCulling)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// Baseline 2: the static part alone (precomputed background + sensor noise).
void BM_BaselineBackgroundOnly(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const std::vector<Primitive> nobody;
  const Renderer& r = renderer(threads);
  RenderOutput out;
  uint64_t frame = 0;
  for (auto _ : state) {
    r.render(nobody, frame++, false, &out);
    benchmark::DoNotOptimize(out.images[0].data);
  }
  setCounters(state, threads);
}
BENCHMARK(BM_BaselineBackgroundOnly)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

// The facade as the nodelet uses it: pose (IK), primitives, ground truth, render.
void BM_SimulatedRigRender(benchmark::State& state) {
  int frame = midFrame();
  for (auto _ : state) {
    SimFrame f = rig().render(frame++);
    benchmark::DoNotOptimize(f.images[0].data);
  }
  setCounters(state, 0);
}
BENCHMARK(BM_SimulatedRigRender)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_GroundTruthOnly(benchmark::State& state) {
  int frame = midFrame();
  for (auto _ : state) benchmark::DoNotOptimize(rig().truth(frame++));
}
BENCHMARK(BM_GroundTruthOnly)->Unit(benchmark::kMicrosecond);

void BM_RigConstruction(benchmark::State& state) {
  for (auto _ : state) {
    SimOptions o;
    SimulatedRig r(o);
    benchmark::DoNotOptimize(&r);
  }
}
BENCHMARK(BM_RigConstruction)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

}  // namespace

BENCHMARK_MAIN();
