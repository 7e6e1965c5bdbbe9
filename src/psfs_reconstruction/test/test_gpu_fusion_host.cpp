// The GPU pSfS path's per-thread code run on the host (hostEmulateFusion, volume_fusion.h)
// against the CPU's PsfsFusion on simulated-rig frames: identical bytes in every case of
// gpu_fusion_cases.h, with the stored tables read as they are and projected again by the
// projection kernel's code. And the pieces on their own: the PSFS_HD projection against the
// table build (stored and on the fly, every kernel path), and one voxel's face rule against the
// CPU's walk with carried faces. Runs in every build: no device needed.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "../src/fusion_common.h"
#include "../src/volume_fusion.h"
#include "expect_throw.h"
#include "gpu_fusion_cases.h"
#include "psfs_reconstruction/gpu_psfs_fusion.h"
#include "psfs_reconstruction/simd_dispatch.h"

namespace psfs {
namespace {

using gpu_test::FusionCase;
using gpu_test::SimScene;

TEST(GpuPsfsEmulation, HostEmulationGivesPsfsFusionBytes) {
  for (int frame : {40, 120}) {
    const SimScene scene = gpu_test::simScene(frame, true);
    for (const FusionCase& fc : gpu_test::fusionCases(scene)) {
      const auto table = fc.table(scene);
      const ViewEvidence ev = fc.evidence(scene);
      ProbabilityVolume cpu, emulated, projected;
      PsfsFusion(fc.options).fuse(*table, ev, &cpu);
      detail::hostEmulateFusion(fc.options, *table, ev, &emulated, false);
      ASSERT_EQ(emulated.grid, cpu.grid) << fc.name;
      ASSERT_TRUE(emulated.data == cpu.data) << fc.name << ", frame " << frame;
      if (table->precomputed()) {  // the device projects only on-the-fly tables; check it here too
        detail::hostEmulateFusion(fc.options, *table, ev, &projected, true);
        ASSERT_TRUE(projected.data == cpu.data) << fc.name << ", frame " << frame << ", projected";
      }
      const size_t in = countAbove(cpu, thresholdByte(fc.options.threshold));
      std::printf("[ figures  ] frame %d, %-70s %7zu voxels in the hull\n", frame, fc.name.c_str(), in);
      EXPECT_GT(in, 20u) << fc.name << ": the person must be in the volume";
    }
  }
}

// The projection kernel's code (hostEmulateProjection) writes the table build's values, for
// stored and on-the-fly tables and whichever CPU kernel built them (AVX-512, AVX2, scalar):
// the scalar build is the PSFS_HD code itself, the vector builds do its steps lane by lane.
TEST(GpuPsfsEmulation, ProjectionGivesTheTableBuildsValues) {
  const SimScene scene = gpu_test::simScene(40, false);
  auto zoomed = scene.cameras;
  zoomed[1].fx *= 2.5;
  zoomed[1].fy *= 2.5;
  struct Case {
    const char* name;
    VoxelGrid grid;
    bool multi;
    int levels;
    const std::vector<tabletop_capture::CameraModel>* cams;
  };
  const Case cases[] = {
      {"64x64x48 multi", referenceGrid(Resolution::k16mm), true, 0, &scene.cameras},
      {"128x128x96", referenceGrid(Resolution::k8mm), false, 0, &scene.cameras},
      {"hand 83^3 multi", snappedCubeGrid(scene.right_hand, 0.30, 83), true, 0, &scene.cameras},
      {"64x64x48 footprint 3", referenceGrid(Resolution::k16mm), false, 3, &scene.cameras},
      {"40^3 beyond the views, zoomed, multi", cubeGrid(Eigen::Vector3d(0.1, 0, 0.4), 1.8, 40), true, 0, &zoomed},
      {"37^3 footprint 2, zoomed", cubeGrid(Eigen::Vector3d(0, -0.2, 0.4), 0.7, 37), false, 2, &zoomed}};
  size_t compared = 0, unobserved = 0;
  for (const Case& c : cases)
    for (TableStorage storage : {TableStorage::kPrecomputed, TableStorage::kOnTheFly})
      for (int path = 0; path < 3; ++path) {  // CPU build: best, AVX2, scalar
        forceAvx2Kernels(path == 1);
        forceScalarKernels(path == 2);
        ProjectionTableOptions to;
        to.multi_projection = c.multi;
        to.footprint_levels = c.levels;
        to.storage = storage;
        const ProjectionTable table(c.grid, *c.cams, to);
        forceAvx2Kernels(false);
        forceScalarKernels(false);
        const size_t rows = table.grid().numRows();
        std::vector<uint32_t> centres(rows * table.centreScratchSize());
        std::vector<uint32_t> offsets(c.multi ? rows * table.offsetScratchSize() : 0);
        detail::hostEmulateProjection(table, centres.data(), offsets.data());
        std::vector<uint32_t> cs(table.centreScratchSize()), os(c.multi ? table.offsetScratchSize() : 0);
        const std::string what = std::string(c.name) + (table.precomputed() ? ", stored" : ", on the fly") +
                                 ", CPU path " + std::to_string(path);
        for (size_t r = 0; r < rows; ++r) {
          ASSERT_EQ(0, std::memcmp(table.rowCentres(r, cs.data()), &centres[r * cs.size()], cs.size() * 4))
              << what << ": centres of row " << r;
          if (c.multi) {
            ASSERT_EQ(0, std::memcmp(table.rowOffsets(r, os.data()), &offsets[r * os.size()], os.size() * 4))
                << what << ": offsets of row " << r;
          }
        }
        // The scalar accessor, per voxel, against projectVoxel (levels removed).
        const ProjectionGrid g = table.projectionGrid();
        for (int z = 0; z < g.nz; z += 5)
          for (int y = 0; y < g.ny; y += 3)
            for (int cam = 0; cam < table.numCameras(); ++cam) {
              const ProjectionCamera& pc = table.projectionCamera(cam);
              const detail::ProjectionRow row = detail::projectionRow(pc, g, y, z);
              for (int x = 0; x < g.nx; ++x) {
                const uint32_t p = detail::projectVoxel(pc, row, x);
                ASSERT_EQ(table.centre(cam, x, y, z), table.withoutLevel(cam, p))
                    << what << ": voxel (" << x << ", " << y << ", " << z << ") camera " << cam;
                unobserved += p == pc.not_observed;
                ++compared;
              }
            }
      }
  std::printf("[ figures  ] %zu voxel projections compared, %zu of them outside a view\n", compared, unobserved);
  EXPECT_GT(unobserved, 0u) << "the cases must include voxels outside some view";
}

// One voxel's face samples on their own (voxelMedianPair, the GPU thread's view) equal the CPU
// walk's, which carries faces along rows, rows of a layer and layers, and restarts at the slab
// borders of each thread split.
TEST(GpuPsfsEmulation, OneVoxelsFacesEqualTheCarriedFaceWalk) {
  const SimScene scene = gpu_test::simScene(120, true);
  auto zoomed = scene.cameras;
  zoomed[1].fx *= 2.5;
  zoomed[1].fy *= 2.5;
  const VoxelGrid grids[] = {referenceGrid(Resolution::k16mm), snappedCubeGrid(scene.left_hand, 0.30, 83),
                             cubeGrid(Eigen::Vector3d(0.1, 0, 0.4), 1.8, 37)};
  size_t checked = 0, from_upper = 0;
  for (const VoxelGrid& grid : grids) {
    ProjectionTableOptions to;
    to.multi_projection = true;
    to.storage = TableStorage::kPrecomputed;
    const ProjectionTable table(grid, zoomed, to);
    ViewEvidence ev;
    ev.set(scene.views(0), true);
    const std::vector<detail::KernelView> kv = detail::kernelViews(ev);
    const int C = table.numCameras(), nx = grid.dims.x(), ny = grid.dims.y();
    const int nxp = table.paddedRowLength(), chunks = table.chunksPerRow();
    const uint32_t* all_centres = table.rowCentres(0, nullptr);
    const uint32_t* all_offsets = table.rowOffsets(0, nullptr);
    auto centre = [&](int c, int x, int y, int z) {
      return all_centres[((size_t(y) + size_t(ny) * z) * C + c) * nxp + x];
    };
    auto offset = [&](int c, int x, int y, int z, int axis) {
      return all_offsets[(((size_t(y) + size_t(ny) * z) * C + c) * chunks + x / ProjectionTable::kChunk) * 3 + axis];
    };
    for (int threads : {1, 3}) {
      std::vector<int32_t> walk(grid.numVoxels() * C);
      detail::forEachFaceRow(table, kv, threads, [&](size_t r, const uint32_t* cen, const uint32_t* off,
                                                     uint16_t* yface, uint16_t* zface) {
        std::vector<int32_t> pairs(size_t(C) * nxp);
        detail::medianPairsOfRow(kv.data(), C, nxp, cen, off, yface, zface, pairs.data());
        for (int c = 0; c < C; ++c)
          for (int x = 0; x < nx; ++x) walk[(r * nx + x) * C + c] = pairs[size_t(c) * nxp + x];
      });
      for (int z = 0; z < grid.dims.z(); ++z)
        for (int y = 0; y < ny; ++y)
          for (int x = 0; x < nx; ++x)
            for (int c = 0; c < C; ++c) {
              const detail::KernelView& v = kv[c];
              const uint32_t uv = centre(c, x, y, z);
              if (uv == v.not_observed) continue;  // its pair is never used
              const uint32_t off[3] = {offset(c, x, y, z, 0), offset(c, x, y, z, 1), offset(c, x, y, z, 2)};
              uint32_t lower_uv[3] = {v.not_observed, v.not_observed, v.not_observed}, lower_off[3] = {0, 0, 0};
              if (x > 0) lower_uv[0] = centre(c, x - 1, y, z), lower_off[0] = offset(c, x - 1, y, z, 0);
              if (y > 0) lower_uv[1] = centre(c, x, y - 1, z), lower_off[1] = offset(c, x, y - 1, z, 1);
              if (z > 0) lower_uv[2] = centre(c, x, y, z - 1), lower_off[2] = offset(c, x, y, z - 1, 2);
              for (int a = 0; a < 3; ++a) from_upper += lower_uv[a] == v.not_observed;
              ASSERT_EQ(detail::voxelMedianPair(v, uv, off, lower_uv, lower_off), walk[grid.index(x, y, z) * C + c])
                  << grid.describe() << ", voxel (" << x << ", " << y << ", " << z << ") camera " << c << ", "
                  << threads << " threads";
              ++checked;
            }
    }
  }
  std::printf("[ figures  ] %zu voxel-camera median pairs equal the walk's (%zu faces from the upper voxel)\n",
              checked, from_upper);
  EXPECT_GT(from_upper, 0u);
}

// Without a device the GPU class still validates like PsfsFusion, says why it is not usable
// and throws std::runtime_error (the caller's cue to fall back); it allocates nothing.
TEST(GpuPsfsFusion, ChecksLikePsfsFusionAndThrowsWithoutDevice) {
  PsfsOptions bad;
  bad.threshold = 0.4;
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { GpuPsfsFusion g(bad); }, "threshold");
  const SimScene scene = gpu_test::simScene(40, false);
  PsfsOptions o;
  o.multi_projection = true;
  GpuPsfsFusion gpu(o);
  ProjectionTableOptions to;
  to.multi_projection = true;
  const ProjectionTable table(referenceGrid(Resolution::k16mm), scene.cameras, to);
  ViewEvidence single;
  single.set(scene.views(0), false);
  ProbabilityVolume out;
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { gpu.fuse(table, single, &out); }, "bilinear");
  GpuEvidence two(2);
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { gpu.fuse(table, two, &out); }, "2 views for 8 cameras");
  if (gpu.usable()) GTEST_SKIP() << "a device is usable here: the no-device behaviour is not reachable";
  EXPECT_FALSE(gpu.reason().empty());
  ViewEvidence ev;
  ev.set(scene.views(0), true);
  psfs_test::expectThrowContaining<std::runtime_error>([&] { gpu.fuse(table, ev, &out); }, "no usable CUDA device");
  EXPECT_EQ(gpu.deviceAllocations(), 0u);
  GpuEvidenceBuffer buffer;
  psfs_test::expectThrowContaining<std::runtime_error>([&] { buffer.upload(ev); }, "no usable CUDA device");
  EXPECT_TRUE(buffer.views().empty());
}

}  // namespace
}  // namespace psfs
