// Volume fusion timings on the reference workload (DESIGN.md section 6): the default rig's 8
// distorted 320x240 cameras, synthetic likelihood images of a person-like cluster of spheres
// with classifier-like noise. In the same run: foreground-class pSfS at the three reference
// resolutions (multi-projection at 16 mm), two 83^3 hand sub-volumes that move every frame
// (projected on the fly), the binary SfS baseline on the same projection tables, 1 and 2
// threads, the scalar kernels, the per-frame image preparation and the table builds. Issue 17
// prototype: the footprint-filtered evidence (one lookup per voxel and camera) beside them,
// with and without its per-frame filtering in the timed loop.
//
//   bench_fusion --benchmark_filter=... --benchmark_repetitions=5
#include <benchmark/benchmark.h>

#include <algorithm>
#include <memory>

#include <hwy/targets.h>  // HWY_SSE4

#include "../src/psfs_kernels.h"  // private: the face kernel switch (BM_PsfsFace)
#include "../test/fusion_test_utils.h"
#include "psfs_reconstruction/binary_sfs.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/simd_dispatch.h"
#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_capture/default_rig.h"
#include "tabletop_sim/simulated_rig.h"

namespace psfs {
namespace {

struct Workload {
  tabletop_capture::RigDescription rig = tabletop_capture::makeDefaultRig();
  std::vector<test::Sphere> person = {
      {Eigen::Vector3d(0.0, -0.35, 0.35), 0.17},   // torso
      {Eigen::Vector3d(0.0, -0.35, 0.62), 0.10},   // head
      {Eigen::Vector3d(-0.2, -0.15, 0.25), 0.06},  // arms
      {Eigen::Vector3d(0.2, -0.15, 0.25), 0.06},
      {Eigen::Vector3d(-0.15, 0.05, 0.15), 0.045},  // hands
      {Eigen::Vector3d(0.18, 0.08, 0.2), 0.045}};
  std::vector<ViewImage> views;
  ViewEvidence single, bilinear, footprint;
  static FootprintFilter filter() { return FootprintFilter{3, FootprintStatistic::kMedian}; }
  Workload() {
    for (size_t c = 0; c < rig.cameras.size(); ++c) {
      const cv::Mat mask = test::sphereLikelihood(rig.cameras[c], person, 255, 0);
      ViewImage v;
      v.likelihood = test::classifierLikelihood(mask, true, 17 + c);
      views.push_back(v);
    }
    single.set(views, false);
    bilinear.set(views, true);
    footprint.set(views, false, 0, filter());
  }
};

Workload& workload() {
  static Workload w;
  return w;
}

VoxelGrid gridFor(int res) {
  return referenceGrid(res == 16 ? Resolution::k16mm : res == 8 ? Resolution::k8mm : Resolution::k4mm);
}

// ---- per-frame image part -----------------------------------------------------------------
void BM_Evidence(benchmark::State& st) {
  Workload& w = workload();
  const bool bil = st.range(0) != 0;
  ViewEvidence ev;
  for (auto _ : st) {
    ev.set(w.views, bil, static_cast<int>(st.range(1)));
    benchmark::DoNotOptimize(ev.terms(0));
  }
  st.SetLabel(bil ? "8 views, terms + pairs" : "8 views, terms");
}
BENCHMARK(BM_Evidence)->ArgsProduct({{0, 1}, {1, 2}})->ArgNames({"bilinear", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

// Footprint levels: range(0) 0 = median, 1 = mean.
void BM_EvidenceFootprint(benchmark::State& st) {
  Workload& w = workload();
  FootprintFilter f = Workload::filter();
  f.statistic = st.range(0) ? FootprintStatistic::kMean : FootprintStatistic::kMedian;
  ViewEvidence ev;
  for (auto _ : st) {
    ev.set(w.views, false, static_cast<int>(st.range(1)), f);
    benchmark::DoNotOptimize(ev.terms(0));
  }
  st.SetLabel(std::string("8 views, terms + 2 footprint levels, ") + (st.range(0) ? "mean" : "median"));
}
BENCHMARK(BM_EvidenceFootprint)->ArgsProduct({{0, 1}, {1, 2}})->ArgNames({"mean", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

// ---- table builds -------------------------------------------------------------------------
void BM_TableBuild(benchmark::State& st) {
  Workload& w = workload();
  const int res = static_cast<int>(st.range(0));
  ProjectionTableOptions o;
  o.multi_projection = res == 16;
  o.storage = TableStorage::kPrecomputed;
  o.threads = static_cast<int>(st.range(1));
  size_t bytes = 0;
  for (auto _ : st) {
    ProjectionTable t(gridFor(res), w.rig.cameras, o);
    bytes = t.memoryBytes();
    benchmark::DoNotOptimize(bytes);
  }
  st.counters["MB"] = bytes / 1e6;
  st.SetLabel(gridFor(res).describe());
}
BENCHMARK(BM_TableBuild)->ArgsProduct({{16, 8}, {1, 2}})->ArgNames({"mm", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

// ---- full volumes -------------------------------------------------------------------------
// range(0): resolution in mm; range(1): threads; range(2): 1 = scalar kernels.
void BM_Psfs(benchmark::State& st) {
  Workload& w = workload();
  const int res = static_cast<int>(st.range(0));
  const bool multi = res == 16;
  ProjectionTableOptions to;
  to.multi_projection = multi;
  const ProjectionTable table(gridFor(res), w.rig.cameras, to);
  PsfsOptions o;
  o.multi_projection = multi;
  o.threads = static_cast<int>(st.range(1));
  const PsfsFusion fusion(o);
  forceScalarKernels(st.range(2) != 0);
  ProbabilityVolume out;
  for (auto _ : st) {
    fusion.fuse(table, multi ? w.bilinear : w.single, &out);
    benchmark::DoNotOptimize(out.data.data());
  }
  forceScalarKernels(false);
  st.counters["voxels_in"] = static_cast<double>(countAbove(out, thresholdByte(o.threshold)));
  st.counters["table_MB"] = table.memoryBytes() / 1e6;
  st.SetLabel(table.grid().describe() + (multi ? ", multi-projection" : "") +
              (table.precomputed() ? ", stored table" : ", projected on the fly") +
              (st.range(2) ? ", scalar"
                           : avx512KernelsActive() ? ", AVX-512"
                                                   : (avx2Available() ? ", AVX2" : ", no AVX2: Highway's best target")));
}
BENCHMARK(BM_Psfs)
    ->ArgsProduct({{16, 8}, {1, 2}, {0}})
    ->Args({16, 1, 1})->Args({8, 1, 1})
    ->Args({4, 1, 0})->Args({4, 2, 0})
    ->ArgNames({"mm", "threads", "scalar"})->UseRealTime()->Unit(benchmark::kMillisecond);

// The default multi-projection volume (16 mm): its table, and the fusion options on `threads`.
ProjectionTable multiTable16(const Workload& w) {
  ProjectionTableOptions to;
  to.multi_projection = true;
  return ProjectionTable(gridFor(16), w.rig.cameras, to);
}
PsfsOptions multiOptions(int threads) {
  PsfsOptions o;
  o.multi_projection = true;
  o.threads = threads;
  return o;
}

// The multi-projection volume (16 mm) by face kernel (issue 17). range(0): threads; range(1):
// kernel, 0 = the default selection (Highway's best target: AVX3, or AVX2 under
// TABLETOP_SIMD=avx2), 1 = Highway's best target chosen here (the same kernel: a check of the
// selection), 2 = faceRowScalar (the plain C++ reference), 3 = Highway's portable target
// (SCALAR), 4 = Highway's SSE4 target (x86; skipped where it is not compiled or supported).
// The hand-written AVX-512 / AVX2 kernels that kernel 0 ran before 2026-12-07 are gone
// (docs/benchmarks.md has their figures beside Highway's).
void BM_PsfsFace(benchmark::State& st) {
  Workload& w = workload();
  const ProjectionTable table = multiTable16(w);
  const PsfsFusion fusion(multiOptions(static_cast<int>(st.range(0))));
  const int kernel = static_cast<int>(st.range(1));
  int64_t hwy_target = detail::hwyRowTarget(kernel == 1, avx512KernelsActive());
  if (kernel == 4) {
    const std::vector<int64_t> t = detail::hwyRowTargets();
    if (std::find(t.begin(), t.end(), int64_t{HWY_SSE4}) == t.end()) {
      st.SkipWithError("no SSE4 target");
      return;
    }
    hwy_target = HWY_SSE4;
  }
  detail::forceFaceRowKernelForTest(kernel == 0 ? -2 : kernel == 2 ? -1 : hwy_target);
  ProbabilityVolume out;
  for (auto _ : st) {
    fusion.fuse(table, w.bilinear, &out);
    benchmark::DoNotOptimize(out.data.data());
  }
  detail::forceFaceRowKernelForTest(0);
  st.counters["voxels_in"] = static_cast<double>(countAbove(out, thresholdByte(fusion.options().threshold)));
  st.SetLabel(kernel == 0 ? std::string("default, Highway ") + detail::hwyTargetName(detail::hwyRowTarget(
                                                                   !scalarKernelsForced(), avx512KernelsActive()))
              : kernel == 2 ? std::string("faceRowScalar")
                            : std::string("Highway ") + detail::hwyTargetName(hwy_target));
}
BENCHMARK(BM_PsfsFace)->ArgsProduct({{1, 2}, {0, 1, 2, 3, 4}})->ArgNames({"threads", "kernel"})
    ->UseRealTime()->Unit(benchmark::kMillisecond);

// pSfS at 16 mm without the multi-projection test: the like-for-like partner of binary SfS.
void BM_PsfsSingle16(benchmark::State& st) {
  Workload& w = workload();
  const ProjectionTable table(gridFor(16), w.rig.cameras);
  PsfsOptions o;
  o.threads = static_cast<int>(st.range(0));
  const PsfsFusion fusion(o);
  ProbabilityVolume out;
  for (auto _ : st) {
    fusion.fuse(table, w.single, &out);
    benchmark::DoNotOptimize(out.data.data());
  }
  st.SetLabel(table.grid().describe() + ", single projection");
}
BENCHMARK(BM_PsfsSingle16)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);

// Footprint-filtered evidence (issue 17 prototype): the single-projection kernel on a table
// with footprint levels. range(0): mm; range(1): threads; range(2): 1 = the per-frame evidence
// (terms and the 2 median-filtered levels, ViewEvidence::set) inside the timed loop;
// range(3): 1 = scalar kernels.
void BM_PsfsFootprint(benchmark::State& st) {
  Workload& w = workload();
  const int res = static_cast<int>(st.range(0));
  ProjectionTableOptions to;
  to.footprint_levels = 3;
  const ProjectionTable table(gridFor(res), w.rig.cameras, to);
  PsfsOptions o;
  o.footprint = true;
  o.threads = static_cast<int>(st.range(1));
  const PsfsFusion fusion(o);
  const bool with_evidence = st.range(2) != 0;
  forceScalarKernels(st.range(3) != 0);
  ViewEvidence ev;
  ev.set(w.views, false, o.threads, Workload::filter());
  ProbabilityVolume out;
  for (auto _ : st) {
    if (with_evidence) ev.set(w.views, false, o.threads, Workload::filter());
    fusion.fuse(table, ev, &out);
    benchmark::DoNotOptimize(out.data.data());
  }
  forceScalarKernels(false);
  st.counters["voxels_in"] = static_cast<double>(countAbove(out, thresholdByte(o.threshold)));
  st.SetLabel(table.grid().describe() + ", footprint levels" + (with_evidence ? " + evidence" : "") +
              (table.precomputed() ? ", stored table" : ", projected on the fly") +
              (st.range(3) ? ", scalar" : avx512KernelsActive() ? ", AVX-512" : ", AVX2"));
}
BENCHMARK(BM_PsfsFootprint)
    ->ArgsProduct({{16, 8}, {1, 2}, {0, 1}, {0}})
    ->Args({16, 1, 0, 1})
    ->ArgNames({"mm", "threads", "evidence", "scalar"})->UseRealTime()->Unit(benchmark::kMillisecond);

// The multi-projection with its per-frame evidence (terms + pair images) in the loop: the
// like-for-like partner of BM_PsfsFootprint/evidence:1.
void BM_PsfsMultiWithEvidence(benchmark::State& st) {
  Workload& w = workload();
  const ProjectionTable table = multiTable16(w);
  const PsfsFusion fusion(multiOptions(static_cast<int>(st.range(0))));
  ViewEvidence ev;
  ProbabilityVolume out;
  for (auto _ : st) {
    ev.set(w.views, true, fusion.options().threads);
    fusion.fuse(table, ev, &out);
    benchmark::DoNotOptimize(out.data.data());
  }
  st.SetLabel(table.grid().describe() + ", multi-projection + evidence");
}
BENCHMARK(BM_PsfsMultiWithEvidence)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);

// The multi-projection with empty-space skipping (PsfsOptions::skip_empty_below = range(1), in
// percent; issue 17), the bound's per-frame tiles included; range(2) = 1 also sets the
// evidence in the loop (the partner of BM_PsfsMultiWithEvidence).
void BM_PsfsSkipEmpty(benchmark::State& st) {
  Workload& w = workload();
  const ProjectionTable table = multiTable16(w);
  PsfsOptions o = multiOptions(static_cast<int>(st.range(0)));
  o.skip_empty_below = double(st.range(1)) / 100.0;
  const PsfsFusion fusion(o);
  ViewEvidence ev;
  ev.set(w.views, true, o.threads);
  ProbabilityVolume out;
  fusion.fuse(table, ev, &out);  // the bound's cells: once per table, not per frame
  for (auto _ : st) {
    if (st.range(2)) ev.set(w.views, true, o.threads);
    fusion.fuse(table, ev, &out);
    benchmark::DoNotOptimize(out.data.data());
  }
  st.counters["voxels_skipped"] = fusion.lastSkippedFraction();
  st.counters["voxels_in"] = static_cast<double>(countAbove(out, thresholdByte(o.threshold)));
  st.SetLabel(table.grid().describe() + ", multi-projection, empty space skipped" +
              (st.range(2) ? " + evidence" : "") + (avx512KernelsActive() ? ", AVX-512" : ", AVX2"));
}
BENCHMARK(BM_PsfsSkipEmpty)
    ->ArgsProduct({{1, 2}, {50}, {0, 1}})
    ->ArgNames({"threads", "below_pct", "evidence"})->UseRealTime()->Unit(benchmark::kMillisecond);

// The real pipeline's likelihoods (the simulated rig's default scenario, 'wave', the background
// learned from 25 sets, the classifier as shipped): frame 60, body (channel 0) and skin
// (channel 1). range(0): 0 body, 1 skin; range(1): skip_empty_below in percent (0 = off), with
// the body and skin options as ReconstructorParams has them otherwise; range(2): threads.
struct PipelineFrame {
  std::vector<tabletop_capture::CameraModel> cameras;
  std::vector<ViewImage> views[2];
  ViewEvidence evidence[2], single, single_skin;
  Eigen::Vector3d hands[2];  // the true hands (left, right)
  PipelineFrame() {
    tabletop_sim::SimOptions so;
    so.script = "wave";
    so.empty_frames = 25;
    const tabletop_sim::SimulatedRig rig(so);
    cameras = rig.rig().cameras;
    ReconstructorParams params;
    Reconstructor r(GaussianMixture2D::load(PSFS_BENCH_CONFIG_DIR "/skin_gmm.yaml"), params);
    for (int f = 0; f < 25; ++f) r.process(rig.render(f).images, cameras);
    const tabletop_sim::SimFrame frame = rig.render(60);
    hands[0] = frame.truth.left_hand, hands[1] = frame.truth.right_hand;
    r.process(frame.images, cameras);
    for (int k = 0; k < 2; ++k) {
      for (const cv::Mat& l : r.lastLikelihoods()) views[k].push_back(ViewImage{l.clone(), k, cv::Mat()});
      evidence[k].set(views[k], true);
    }
    single.set(views[0], false);
    single_skin.set(views[1], false);
  }
};
PipelineFrame& pipelineFrame() {
  static PipelineFrame f;
  return f;
}

void BM_PsfsPipelineFrame(benchmark::State& st) {
  PipelineFrame& w = pipelineFrame();
  const int kind = static_cast<int>(st.range(0));
  ProjectionTableOptions to;
  to.multi_projection = true;
  const ProjectionTable table(referenceGrid(Resolution::k16mm), w.cameras, to);
  PsfsOptions o = kind ? ReconstructorParams::defaultSkin() : ReconstructorParams::defaultBody();
  o.skip_empty_below = double(st.range(1)) / 100.0;
  o.threads = static_cast<int>(st.range(2));
  const PsfsFusion fusion(o);
  ProbabilityVolume out;
  fusion.fuse(table, w.evidence[kind], &out);  // the bound's cells: once per table
  for (auto _ : st) {
    fusion.fuse(table, w.evidence[kind], &out);
    benchmark::DoNotOptimize(out.data.data());
  }
  st.counters["voxels_skipped"] = fusion.lastSkippedFraction();
  // What no sound skipping at 0.5 can skip: the voxels at or above it.
  st.counters["voxels_from_half"] = double(countAbove(out, 127)) / double(out.data.size());
  st.SetLabel(std::string(kind ? "skin" : "body") + ", default scenario frame 60, multi-projection" +
              (avx512KernelsActive() ? ", AVX-512" : ", AVX2"));
}
BENCHMARK(BM_PsfsPipelineFrame)
    ->ArgsProduct({{0, 1}, {0, 50}, {1, 2}})
    ->ArgNames({"skin", "below_pct", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

// The 128x128x96 grid (7.8 mm) on the same frame: the single projection (its default, one pixel
// per voxel and camera; range(0): 0 body, 1 skin) with the strict bound's skipping below
// range(1) percent (0 = off; src/centre_space_bound.h), range(2): threads. Baseline:
// BM_BinaryPipelineFrame8.
void BM_PsfsPipelineFrame8(benchmark::State& st) {
  PipelineFrame& w = pipelineFrame();
  const int kind = static_cast<int>(st.range(0));
  const ProjectionTable table(referenceGrid(Resolution::k8mm), w.cameras);
  PsfsOptions o = kind ? ReconstructorParams::defaultSkin() : ReconstructorParams::defaultBody();
  o.multi_projection = false;
  o.skip_empty_below = double(st.range(1)) / 100.0;
  o.threads = static_cast<int>(st.range(2));
  const PsfsFusion fusion(o);
  ProbabilityVolume out;
  for (auto _ : st) {
    fusion.fuse(table, kind ? w.single_skin : w.single, &out);
    benchmark::DoNotOptimize(out.data.data());
  }
  st.counters["voxels_skipped"] = fusion.lastSkippedFraction();
  st.counters["voxels_from_half"] = double(countAbove(out, 127)) / double(out.data.size());
  st.SetLabel(std::string(kind ? "skin" : "body") + ", default scenario frame 60, 128x128x96 single projection" +
              (avx512KernelsActive() ? ", AVX-512" : ", AVX2"));
}
BENCHMARK(BM_PsfsPipelineFrame8)
    ->ArgsProduct({{0, 1}, {0, 50}, {1, 2}})
    ->ArgNames({"skin", "below_pct", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

// Binary SfS baseline on the same tables (carving only; silhouettes set once: thresholding
// the 8 images is the image part, timed in BM_BinarySilhouettes).
void carveLoop(benchmark::State& st, const ProjectionTable& table, const ViewEvidence& single, int threads) {
  BinarySfsOptions o;
  o.threads = threads;
  BinarySfs bin(o);
  bin.setSilhouettes(single);
  ProbabilityVolume out;
  for (auto _ : st) {
    bin.carve(table, &out);
    benchmark::DoNotOptimize(out.data.data());
  }
  st.counters["voxels_in"] = static_cast<double>(countAbove(out, 0));
}

void BM_Binary(benchmark::State& st) {
  Workload& w = workload();
  const int res = static_cast<int>(st.range(0));
  const ProjectionTable table(gridFor(res), w.rig.cameras);
  carveLoop(st, table, w.single, static_cast<int>(st.range(1)));
  st.SetLabel(table.grid().describe() + (table.precomputed() ? ", stored table" : ", projected on the fly"));
}
BENCHMARK(BM_Binary)
    ->ArgsProduct({{16, 8}, {1, 2}})->Args({4, 1})->Args({4, 2})
    ->ArgNames({"mm", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

// Binary SfS on the same frame's body likelihoods (carving stops at the first camera that sees
// background, so its cost depends on the scene too).
void BM_BinaryPipelineFrame(benchmark::State& st) {
  PipelineFrame& w = pipelineFrame();
  carveLoop(st, ProjectionTable(referenceGrid(Resolution::k16mm), w.cameras), w.single,
            static_cast<int>(st.range(0)));
  st.SetLabel("body, default scenario frame 60");
}
BENCHMARK(BM_BinaryPipelineFrame)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_BinaryPipelineFrame8(benchmark::State& st) {
  PipelineFrame& w = pipelineFrame();
  carveLoop(st, ProjectionTable(referenceGrid(Resolution::k8mm), w.cameras), w.single, static_cast<int>(st.range(0)));
  st.SetLabel("body, default scenario frame 60, 128x128x96");
}
BENCHMARK(BM_BinaryPipelineFrame8)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_BinarySilhouettes(benchmark::State& st) {
  Workload& w = workload();
  BinarySfs bin;
  for (auto _ : st) bin.setSilhouettes(w.single);
}
BENCHMARK(BM_BinarySilhouettes)->UseRealTime()->Unit(benchmark::kMillisecond);

// ---- hand sub-volumes ---------------------------------------------------------------------
// Two 30 cm cubes at 83^3 around the hands, moving by a few millimetres every frame, so the
// tables are re-derived each frame (cheap: on the fly) and every voxel is projected.
// range(1) = 1: PsfsOptions::floor_z 3 cm below each hand's centre, as for a hand resting on the
// desk (the Reconstructor's hand_roi_clip_floor): the 12 cm of the cube below it are skipped.
void BM_HandSubVolumes(benchmark::State& st) {
  Workload& w = workload();
  const Eigen::Vector3d hands[2] = {w.person[4].centre, w.person[5].centre};
  const bool with_floor = st.range(1) != 0;
  std::vector<PsfsFusion> fusions;
  for (int h = 0; h < 2; ++h) {
    PsfsOptions o;
    o.threads = static_cast<int>(st.range(0));
    if (with_floor) o.floor_z = hands[h].z() - 0.03;
    fusions.emplace_back(o);
  }
  ProjectionTableOptions to;
  to.storage = TableStorage::kOnTheFly;
  ProjectionTable tables[2] = {ProjectionTable(cubeGrid(hands[0], 0.3, 83), w.rig.cameras, to),
                               ProjectionTable(cubeGrid(hands[1], 0.3, 83), w.rig.cameras, to)};
  ProbabilityVolume out[2];
  int frame = 0;
  for (auto _ : st) {
    const Eigen::Vector3d step(0.003 * (frame % 5), 0.002 * (frame % 3), 0.0);
    for (int h = 0; h < 2; ++h) {
      tables[h].update(snappedCubeGrid(hands[h] + step, 0.3, 83), w.rig.cameras);
      fusions[h].fuse(tables[h], w.single, &out[h]);
    }
    ++frame;
    benchmark::DoNotOptimize(out[1].data.data());
  }
  st.SetLabel("2 x " + out[0].grid.describe().substr(0, out[0].grid.describe().find(',')) +
              ", projected on the fly" + (with_floor ? ", floor 3 cm below the hands" : ""));
}
BENCHMARK(BM_HandSubVolumes)
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->ArgNames({"threads", "floor"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// The same with footprint levels (3.6 mm voxels are ~1 px wide: mostly the 3x3 level).
// range(1): 1 = the footprint evidence (ViewEvidence::set) inside the timed loop.
void BM_HandSubVolumesFootprint(benchmark::State& st) {
  Workload& w = workload();
  PsfsOptions o;
  o.threads = static_cast<int>(st.range(0));
  o.footprint = true;
  const PsfsFusion fusion(o);
  ProjectionTableOptions to;
  to.storage = TableStorage::kOnTheFly;
  to.footprint_levels = 3;
  const Eigen::Vector3d hands[2] = {w.person[4].centre, w.person[5].centre};
  ProjectionTable tables[2] = {ProjectionTable(cubeGrid(hands[0], 0.3, 83), w.rig.cameras, to),
                               ProjectionTable(cubeGrid(hands[1], 0.3, 83), w.rig.cameras, to)};
  const bool with_evidence = st.range(1) != 0;
  ViewEvidence ev;
  ev.set(w.views, false, o.threads, Workload::filter());
  ProbabilityVolume out[2];
  int frame = 0;
  for (auto _ : st) {
    if (with_evidence) ev.set(w.views, false, o.threads, Workload::filter());
    const Eigen::Vector3d step(0.003 * (frame % 5), 0.002 * (frame % 3), 0.0);
    for (int h = 0; h < 2; ++h) {
      tables[h].update(snappedCubeGrid(hands[h] + step, 0.3, 83), w.rig.cameras);
      fusion.fuse(tables[h], ev, &out[h]);
    }
    ++frame;
    benchmark::DoNotOptimize(out[1].data.data());
  }
  st.SetLabel(std::string("2 x 83^3, projected on the fly, footprint levels") + (with_evidence ? " + evidence" : ""));
}
BENCHMARK(BM_HandSubVolumesFootprint)->ArgsProduct({{1, 2}, {0, 1}})->ArgNames({"threads", "evidence"})->UseRealTime()->Unit(benchmark::kMillisecond);

// The two hand cubes on the real classifier's skin likelihoods of the default scenario's frame
// 60 (at the true hands, moved a few mm per iteration, the desk top as their floor as the
// Reconstructor has it; fusion only, no known occlusions): single projection with skipping below
// range(1) percent (0 = off), range(0) threads; range(2) = 1: binary SfS on the same silhouettes
// and tables instead (the same-frame baseline).
void BM_HandsPipelineFrame(benchmark::State& st) {
  PipelineFrame& w = pipelineFrame();
  const int threads = static_cast<int>(st.range(0));
  const bool binary = st.range(2) != 0;
  PsfsOptions o = ReconstructorParams::defaultHand();
  o.skip_empty_below = double(st.range(1)) / 100.0;
  o.threads = threads;
  o.floor_z = ReconstructorParams().workspace.min_corner.z();
  const PsfsFusion fusion(o);
  BinarySfsOptions bo;
  bo.threads = threads;
  BinarySfs bin(bo);
  bin.setSilhouettes(w.single_skin);
  ProjectionTableOptions to;
  to.storage = TableStorage::kOnTheFly;
  ProjectionTable tables[2] = {ProjectionTable(snappedCubeGrid(w.hands[0], 0.3, 83), w.cameras, to),
                               ProjectionTable(snappedCubeGrid(w.hands[1], 0.3, 83), w.cameras, to)};
  ProbabilityVolume out[2];
  int frame = 0;
  double skipped = 0;
  for (auto _ : st) {
    const Eigen::Vector3d step(0.003 * (frame % 5), 0.002 * (frame % 3), 0.0);
    for (int h = 0; h < 2; ++h) {
      tables[h].update(snappedCubeGrid(w.hands[h] + step, 0.3, 83), w.cameras);
      if (binary) {
        bin.carve(tables[h], &out[h]);
      } else {
        fusion.fuse(tables[h], w.single_skin, &out[h]);
        skipped += fusion.lastSkippedFraction() / 2.0;
      }
    }
    ++frame;
    benchmark::DoNotOptimize(out[1].data.data());
  }
  st.counters["voxels_skipped"] = skipped / std::max(frame, 1);
  st.SetLabel(std::string(binary ? "binary SfS" : "pSfS") + ", 2 x 83^3 at the hands of the default scenario's frame 60");
}
BENCHMARK(BM_HandsPipelineFrame)
    ->Args({1, 0, 0})->Args({1, 50, 0})->Args({1, 0, 1})->Args({2, 0, 0})->Args({2, 50, 0})->Args({2, 0, 1})
    ->ArgNames({"threads", "below_pct", "binary"})->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_HandSubVolumesBinary(benchmark::State& st) {
  Workload& w = workload();
  BinarySfsOptions o;
  o.threads = static_cast<int>(st.range(0));
  BinarySfs bin(o);
  bin.setSilhouettes(w.single);
  ProjectionTableOptions to;
  to.storage = TableStorage::kOnTheFly;
  const Eigen::Vector3d hands[2] = {w.person[4].centre, w.person[5].centre};
  ProjectionTable tables[2] = {ProjectionTable(cubeGrid(hands[0], 0.3, 83), w.rig.cameras, to),
                               ProjectionTable(cubeGrid(hands[1], 0.3, 83), w.rig.cameras, to)};
  ProbabilityVolume out[2];
  for (auto _ : st)
    for (int h = 0; h < 2; ++h) bin.carve(tables[h], &out[h]);
  st.SetLabel("2 x 83^3, projected on the fly");
}
BENCHMARK(BM_HandSubVolumesBinary)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);

// The hand stage as the pipeline runs it (Reconstructor::process with two hand ROIs at the true
// hands of the default scenario's frame 60, known occlusions on): the occluders' depths, each
// hand's masks and evidence and its fusion. range(0): threads (every stage's), range(1): the
// hands' skip_empty_below in percent (0 = off; the default is 50). Counters: the hand stage's
// mean wall time (ms), the whole process() call's, and the share of the hands' voxels skipped.
void BM_ReconstructorHands(benchmark::State& st) {
  tabletop_sim::SimOptions so;
  so.script = "wave";
  so.empty_frames = 25;
  const tabletop_sim::SimulatedRig rig(so);
  const auto cameras = rig.rig().cameras;
  ReconstructorParams params;
  params.threads = static_cast<int>(st.range(0));
  params.hand.threads = params.threads;
  params.hand.skip_empty_below = double(st.range(1)) / 100.0;
  params.update_background = false;  // the same set every iteration
  Reconstructor r(GaussianMixture2D::load(PSFS_BENCH_CONFIG_DIR "/skin_gmm.yaml"), params);
  for (int f = 0; f < 25; ++f) r.process(rig.render(f).images, cameras);
  const tabletop_sim::SimFrame frame = rig.render(60);
  double hands = 0, total = 0, skipped = 0;
  int n = 0;
  for (auto _ : st) {
    // The cubes move by a few millimetres, as a hand does from frame to frame: their tables are
    // derived anew.
    const Eigen::Vector3d step(0.003 * (n % 5), 0.002 * (n % 3), 0.0);
    const FrameResult res = r.process(frame.images, cameras, {frame.truth.left_hand + step, frame.truth.right_hand + step});
    hands += res.times.hands;
    skipped += res.hands_skipped;
    total += res.times.total;
    ++n;
  }
  st.counters["hands_ms"] = hands / std::max(n, 1);
  st.counters["process_ms"] = total / std::max(n, 1);
  st.counters["hand_voxels_skipped"] = skipped / std::max(n, 1);
  st.SetLabel("default scenario frame 60, 2 hands, known occlusions");
}
BENCHMARK(BM_ReconstructorHands)
    ->ArgsProduct({{1, 2}, {0, 50}})
    ->ArgNames({"threads", "below_pct"})->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace psfs

BENCHMARK_MAIN();
