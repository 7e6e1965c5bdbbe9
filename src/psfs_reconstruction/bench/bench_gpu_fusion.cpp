// GPU against CPU pSfS on the reference workload of bench_fusion (the default rig's 8 distorted
// 320x240 cameras, a person-like cluster of spheres, classifier-like noise): 64x64x48 with the
// multi-projection test (the CPU default there), 128x128x96 and 256x256x192 with single
// projection (the last projected on the fly: a stored table would take 400 MB), and two 83^3
// hand sub-volumes that move every frame. Per case, in one run: the CPU's PsfsFusion, the GPU's
// wall time per frame with evidence upload and readback included, its stages (CUDA events),
// whether the bytes agree, and the bandwidth the volume kernel achieves on what it must stream
// (the table, the evidence, the volume) against the device's peak (DeviceInfo).
//
//   bench_gpu_fusion [frames=30]      (says why and exits 0 without a usable device)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <omp.h>
#include <string>
#include <vector>

#include "../test/fusion_test_utils.h"
#include "psfs_reconstruction/cuda_device.h"
#include "psfs_reconstruction/gpu_psfs_fusion.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/simd_dispatch.h"
#include "tabletop_capture/default_rig.h"

namespace psfs {
namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Median wall time (ms) of `frames` calls of fn(frame) after one warm-up call.
double timeMs(int frames, const std::function<void(int)>& fn) {
  fn(0);
  std::vector<double> t;
  for (int f = 1; f <= frames; ++f) {
    const auto a = std::chrono::steady_clock::now();
    fn(f);
    t.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
  }
  return median(t);
}

// Bytes the volume kernel must move at least: each (voxel, camera) centre and chunk offsets
// once, each camera's evidence once, each voxel's byte once.
double streamedBytes(const ProjectionTable& t, const ViewEvidence& ev, bool multi) {
  double b = double(t.grid().numRows()) * t.centreScratchSize() * 4.0 + double(t.grid().numVoxels());
  if (multi) b += double(t.grid().numRows()) * t.offsetScratchSize() * 4.0;
  for (int c = 0; c < ev.numViews(); ++c) {
    b += 2.0 * ev.width(c) * ev.height(c);
    if (multi) b += 2.0 * ev.quadStride(c) * (ev.height(c) + 2 * ViewEvidence::kQuadPad);
  }
  return b;
}

int run(int frames) {
  const cuda::DeviceInfo& dev = cuda::device();
  std::printf("%s\n", dev.describe().c_str());
  if (!dev.usable) {
    std::printf("bench_gpu_fusion: nothing to time without a usable CUDA device\n");
    return 0;
  }
  const auto rig = tabletop_capture::makeDefaultRig();
  const std::vector<test::Sphere> person = {
      {Eigen::Vector3d(0.0, -0.35, 0.35), 0.17},   {Eigen::Vector3d(0.0, -0.35, 0.62), 0.10},
      {Eigen::Vector3d(-0.2, -0.15, 0.25), 0.06},  {Eigen::Vector3d(0.2, -0.15, 0.25), 0.06},
      {Eigen::Vector3d(-0.15, 0.05, 0.15), 0.045}, {Eigen::Vector3d(0.18, 0.08, 0.2), 0.045}};
  std::vector<ViewImage> views;
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    ViewImage v;
    v.likelihood = test::classifierLikelihood(test::sphereLikelihood(rig.cameras[c], person, 255, 0), true, 17 + c);
    views.push_back(v);
  }
  ViewEvidence single, bilinear;
  single.set(views, false);
  bilinear.set(views, true);
  std::printf("CPU: %d OpenMP threads, %s kernels; %d frames per case, median\n", omp_get_max_threads(),
              avx512KernelsActive() ? "AVX-512"
              : avx2Available()     ? "AVX2"
              : scalarKernelsForced() ? "scalar"
                                      : "no AVX2: Highway SSE4/NEON",
              frames);
  std::printf("%-44s %9s %9s %8s | %7s %7s %7s %7s | %9s %6s %s\n", "volume", "CPU ms", "GPU ms", "speedup",
              "upload", "project", "fuse", "readbk", "kernel GB/s", "%peak", "bytes");

  struct Case {
    Resolution res;
    bool multi;
  };
  for (const Case& c : {Case{Resolution::k16mm, true}, Case{Resolution::k8mm, false}, Case{Resolution::k4mm, false}}) {
    PsfsOptions o;
    o.multi_projection = c.multi;
    ProjectionTableOptions to;
    to.multi_projection = c.multi;
    const ProjectionTable table(referenceGrid(c.res), rig.cameras, to);
    const ViewEvidence& ev = c.multi ? bilinear : single;
    const PsfsFusion cpu(o);
    GpuPsfsFusion gpu(o);
    ProbabilityVolume vc, vg;
    const double cpu_ms = timeMs(c.res == Resolution::k4mm ? std::max(3, frames / 5) : frames,
                                 [&](int) { cpu.fuse(table, ev, &vc); });
    std::vector<double> up, pr, fu, rb;
    gpu.fuse(table, ev, &vg);  // the table reaches the device (upload or projection)
    const GpuFusionTimings first = gpu.lastTimings();
    const double gpu_ms = timeMs(frames, [&](int) {
      gpu.fuse(table, ev, &vg);
      const GpuFusionTimings& t = gpu.lastTimings();
      up.push_back(t.upload_ms), pr.push_back(t.project_ms), fu.push_back(t.fuse_ms), rb.push_back(t.readback_ms);
    });
    const double gbs = streamedBytes(table, ev, c.multi) / (median(fu) * 1e-3) / 1e9;
    const std::string name = table.grid().describe().substr(0, table.grid().describe().find(',')) +
                             (c.multi ? ", multi-projection" : ", single") +
                             (table.precomputed() ? ", stored" : ", on the fly");
    std::printf("%-44s %9.3f %9.3f %7.1fx | %7.3f %7.3f %7.3f %7.3f | %9.1f %5.1f%% %s\n", name.c_str(), cpu_ms,
                gpu_ms, cpu_ms / gpu_ms, median(up), median(pr), median(fu), median(rb), gbs,
                100.0 * gbs / dev.memory_bandwidth_gbs, vc.data == vg.data ? "equal" : "DIFFER");
    std::printf("%-44s first frame: upload %.3f ms, projection %.3f ms (table %.1f MB)\n", "",
                first.upload_ms, first.project_ms, double(ProjectionTable::precomputedBytes(
                                                       table.grid(), table.numCameras(), c.multi)) / 1e6);
  }

  // Two hand sub-volumes following the hands: a new on-the-fly table per frame and hand.
  {
    PsfsOptions o;
    o.occluded_views = 1;
    ProjectionTableOptions to;
    to.storage = TableStorage::kOnTheFly;
    const Eigen::Vector3d hands[2] = {person[4].centre, person[5].centre};
    ProjectionTable tables[2] = {ProjectionTable(snappedCubeGrid(hands[0], 0.3, 83), rig.cameras, to),
                                 ProjectionTable(snappedCubeGrid(hands[1], 0.3, 83), rig.cameras, to)};
    auto move = [&](int frame) {
      const Eigen::Vector3d step(0.003 * (frame % 5), 0.002 * (frame % 3), 0.0);
      for (int h = 0; h < 2; ++h) tables[h].update(snappedCubeGrid(hands[h] + step, 0.3, 83), rig.cameras);
    };
    const PsfsFusion cpu(o);
    GpuPsfsFusion gpu[2] = {GpuPsfsFusion(o), GpuPsfsFusion(o)};
    GpuEvidenceBuffer on_device;
    ProbabilityVolume vc[2], vg[2];
    bool equal = true;
    const double cpu_ms = timeMs(frames, [&](int f) {
      move(f);
      for (int h = 0; h < 2; ++h) cpu.fuse(tables[h], single, &vc[h]);
    });
    std::vector<double> pr, fu;
    const double gpu_ms = timeMs(frames, [&](int f) {
      move(f);
      on_device.upload(single);  // one upload for both sub-volumes
      for (int h = 0; h < 2; ++h) {
        gpu[h].fuse(tables[h], on_device.views(), &vg[h]);
        pr.push_back(gpu[h].lastTimings().project_ms), fu.push_back(gpu[h].lastTimings().fuse_ms);
      }
    });
    for (int h = 0; h < 2; ++h) {
      cpu.fuse(tables[h], single, &vc[h]);
      equal = equal && vc[h].data == vg[h].data;
    }
    std::printf("%-44s %9.3f %9.3f %7.1fx | %7s %7.3f %7.3f %7s | %9s %6s %s\n",
                "2 x 83^3 hands, moving, on the fly", cpu_ms, gpu_ms, cpu_ms / gpu_ms, "-", median(pr), median(fu),
                "-", "-", "-", equal ? "equal" : "DIFFER");
  }
  return 0;
}

}  // namespace
}  // namespace psfs

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::max(1, std::atoi(argv[1])) : 30;
  try {
    return psfs::run(frames);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_gpu_fusion: %s\n", e.what());
    return 1;
  }
}
