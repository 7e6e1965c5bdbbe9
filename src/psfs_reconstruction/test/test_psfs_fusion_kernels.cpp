// The kernel paths give the same bytes: scalar, AVX2 and AVX-512 fusion kernels, every
// Highway target of the row and face kernels, and thread splits; the shared multi-projection
// face samples against a brute force; the AVX-512 and AVX2 row projections. Part of
// test_psfs_fusion.
#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "../src/fusion_common.h"  // private: the face walk, checked against a brute force below
#include "../src/log_term_table.h"
#include "../src/psfs_kernels.h"
#include "fusion_test_utils.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/simd_dispatch.h"
#include "tabletop_capture/default_rig.h"

namespace psfs {
namespace {

using test::Sphere;

// The kernel tests' cameras: the default rig with camera 1 zoomed in, so it sees only part of
// the grid and rows, columns and layers switch between observed and unobserved voxels (the face
// kernels' fallbacks).
std::vector<tabletop_capture::CameraModel> partlyObservingCameras() {
  auto cams = tabletop_capture::makeDefaultRig().cameras;
  cams[1].fx *= 2.5;
  cams[1].fy *= 2.5;
  return cams;
}

// 37 voxels wide: rows padded to 40, so the AVX-512 kernels' last step per row has a single
// chunk of 8 (5 voxels and 3 of padding).
VoxelGrid oddWidthGrid() { return cubeGrid(Eigen::Vector3d(0.0, 0.0, 0.3), 0.6, 37); }

TEST(PsfsFusion, ScalarAndVectorKernelsGiveIdenticalBytes) {
  if (!avx2Available()) {
    GTEST_SKIP() << "no AVX2 on this CPU: the AVX2 and AVX-512 targets cannot run here (every target it has is "
                    "compared with the reference in EveryHighway*TargetMatchesTheReference)";
  }
  const auto rig = tabletop_capture::makeDefaultRig();
  const std::vector<ViewImage> all_views = test::twoSpheresWithMaskedView(rig.cameras);
  const auto all_cams = partlyObservingCameras();
  const VoxelGrid grids[2] = {referenceGrid(Resolution::k16mm), oddWidthGrid()};
  // The face kernels take the cameras in groups (4 then 1 on AVX2; 2 then 1 on AVX-512): 7 and 3
  // cameras take every tail.
  for (const size_t num_cameras : {size_t(8), size_t(7), size_t(3)})
  for (const VoxelGrid& grid : grids)
  for (bool multi : {false, true})
    for (int k : {0, 1, 2, 4}) {
      if (num_cameras < 8 && !multi) continue;
      const std::vector<tabletop_capture::CameraModel> cams(all_cams.begin(), all_cams.begin() + num_cameras);
      const std::vector<ViewImage> views(all_views.begin(), all_views.begin() + num_cameras);
      PsfsOptions o;
      o.multi_projection = multi;
      o.occluded_views = k;
      ProjectionTableOptions to;
      to.multi_projection = multi;
      ProjectionTable table(grid, cams, to);
      ViewEvidence ev;
      ev.set(views, multi);
      ProbabilityVolume vec, sca, vec2;
      PsfsFusion(o).fuse(table, ev, &vec);  // AVX-512 where the CPU has it, else AVX2
      forceAvx2Kernels(true);
      PsfsFusion(o).fuse(table, ev, &vec2);
      {  // layers split over 3 threads: slabs that start inside the grid (plusFacesOfRow's vector path)
        PsfsOptions o3 = o;
        o3.threads = 3;
        ProbabilityVolume vec2_3;
        PsfsFusion(o3).fuse(table, ev, &vec2_3);
        ASSERT_EQ(vec2_3.data, vec2.data) << grid.describe() << " multi " << multi << " k " << k << ", "
                                          << num_cameras << " cameras (AVX2, 3 threads)";
      }
      forceAvx2Kernels(false);
      forceScalarKernels(true);
      PsfsFusion(o).fuse(table, ev, &sca);
      forceScalarKernels(false);
      ASSERT_EQ(vec.data, sca.data) << grid.describe() << " multi " << multi << " k " << k << ", " << num_cameras
                                    << " cameras" << (avx512KernelsActive() ? " (AVX-512)" : " (AVX2)");
      ASSERT_EQ(vec2.data, sca.data) << grid.describe() << " multi " << multi << " k " << k << ", " << num_cameras
                                     << " cameras (AVX2)";
      // Each thread walks its own range of layers: the split must not show in the bytes.
      for (int threads : {1, 3, 5}) {
        o.threads = threads;
        ProbabilityVolume t;
        PsfsFusion(o).fuse(table, ev, &t);
        ASSERT_EQ(t.data, vec.data) << grid.describe() << " multi " << multi << " k " << k << ", "
                                    << threads << " threads";
      }
    }
}

// The single-projection row kernel has one Highway source: every target compiled for this
// CPU (AVX-512, AVX2, SSE4, SSSE3 and SCALAR on x86 with GCC 12; NEON on ARM) writes the bytes of the plain
// C++ reference, on plain and footprint tables, for every occlusion tolerance, with a masked
// view, an odd row length and zero_outside_hull.
TEST(PsfsFusion, EveryHighwayRowTargetMatchesTheReference) {
  const auto rig = tabletop_capture::makeDefaultRig();
  std::vector<ViewImage> views = test::twoSpheresWithMaskedView(rig.cameras);
  auto cams = partlyObservingCameras();
  // The portable (SCALAR) kernel works on blocks of 64 voxels and groups of 8, 4 and 1
  // cameras: a 70-wide grid and 7 cameras take every tail.
  const VoxelGrid grids[3] = {referenceGrid(Resolution::k16mm), oddWidthGrid(),
                              cubeGrid(Eigen::Vector3d(0.0, 0.0, 0.3), 0.6, 70)};
  const std::vector<int64_t> targets = detail::hwyRowTargets();
  ASSERT_FALSE(targets.empty());
  std::string names;
  for (int64_t t : targets) names += std::string(" ") + detail::hwyTargetName(t);
  std::printf("[ figures  ] Highway row targets on this CPU:%s\n", names.c_str());
  for (const int num_cameras : {8, 7})
  for (const VoxelGrid& grid : grids)
    for (bool footprint : {false, true}) {
      cams.resize(num_cameras);
      views.resize(num_cameras);
      ProjectionTableOptions to;
      to.footprint_levels = footprint ? 3 : 0;
      const ProjectionTable table(grid, cams, to);
      ViewEvidence ev;
      ev.set(views, false, 0, footprint ? FootprintFilter{3, FootprintStatistic::kMedian} : FootprintFilter());
      for (int k : {0, 1, 2, 4})
        for (bool zero_outside : {false, true}) {
          PsfsOptions o;
          o.footprint = footprint;
          o.occluded_views = k;
          o.zero_outside_hull = zero_outside;
          ProbabilityVolume ref;
          detail::forceRowKernelForTest(-1);
          PsfsFusion(o).fuse(table, ev, &ref);
          for (int64_t t : targets) {
            detail::forceRowKernelForTest(t);
            ProbabilityVolume out;
            PsfsFusion(o).fuse(table, ev, &out);
            detail::forceRowKernelForTest(0);
            ASSERT_EQ(out.data, ref.data) << detail::hwyTargetName(t) << ", " << grid.describe()
                                          << ", " << num_cameras << " cameras"
                                          << ", footprint " << footprint << ", k " << k
                                          << ", zero outside " << zero_outside;
          }
          detail::forceRowKernelForTest(0);
          EXPECT_GT(countAbove(ref, thresholdByte(o.threshold)), 100u) << "the spheres are in the hull";
        }
    }
}

// On a CPU without AVX2 (an older x86, ARM) the callers' `vector` is false; the Highway kernels
// must still take the CPU's best target there (SSE4, NEON), and only a forced scalar run the
// portable one.
// With it, both kernels are Highway's best target the switches allow.
TEST(PsfsFusion, WithoutAvx2TheHighwayKernelsTakeTheBestTarget) {
  const bool was_forced = scalarKernelsForced();  // TABLETOP_SIMD=scalar
  forceScalarKernels(false);
  const int64_t best = detail::hwyRowTarget(true, avx512KernelsActive());
  const int64_t portable = detail::hwyRowTarget(false, false);
  EXPECT_EQ(detail::selectPsfsRow(1, false), detail::hwyRowKernel(best, 1));
  EXPECT_EQ(detail::selectPsfsFaceRow(1, false), detail::hwyFaceRowKernel(best, 1));
  EXPECT_EQ(detail::selectPsfsFaceRow(1, true), detail::hwyFaceRowKernel(best, 1));
  forceScalarKernels(true);
  EXPECT_EQ(detail::selectPsfsRow(1, false), detail::hwyRowKernel(portable, 1));
  EXPECT_EQ(detail::selectPsfsFaceRow(1, false), detail::hwyFaceRowKernel(portable, 1));
  forceScalarKernels(was_forced);
}

// The multi-projection (face) kernel has one Highway source too: every compiled target writes
// the bytes of faceRowScalar on the cases the default kernels are checked on above (a
// masked view, a camera that sees part of the grid, a row whose last 16-lane step holds one
// chunk), for every occlusion tolerance, with zero_outside_hull, and with thread splits whose
// slabs start inside the grid (their first faces come from plusFacesOfRow).
TEST(PsfsFusion, EveryHighwayFaceTargetMatchesTheReference) {
  const auto rig = tabletop_capture::makeDefaultRig();
  const std::vector<ViewImage> all_views = test::twoSpheresWithMaskedView(rig.cameras);
  const auto all_cams = partlyObservingCameras();
  const VoxelGrid grids[2] = {referenceGrid(Resolution::k16mm), oddWidthGrid()};
  const std::vector<int64_t> targets = detail::hwyRowTargets();
  ASSERT_FALSE(targets.empty());
  // What this CPU runs (the AVX-512 steps only where it has AVX-512): said, so a log shows it.
  std::string names;
  for (int64_t t : targets) names += std::string(" ") + detail::hwyTargetName(t);
  std::printf("[ targets  ]%s\n", names.c_str());
  // Cameras in groups of 4 or 2 and a tail of single ones: 8, 7 and 3 cameras.
  for (const size_t num_cameras : {size_t(8), size_t(7), size_t(3)})
  for (const VoxelGrid& grid : grids) {
    const std::vector<tabletop_capture::CameraModel> cams(all_cams.begin(), all_cams.begin() + num_cameras);
    const std::vector<ViewImage> views(all_views.begin(), all_views.begin() + num_cameras);
    ProjectionTableOptions to;
    to.multi_projection = true;
    const ProjectionTable table(grid, cams, to);
    ViewEvidence ev;
    ev.set(views, true);
    for (int k : {0, 1, 2, 4})
      for (bool zero_outside : {false, true}) {
        PsfsOptions o;
        o.multi_projection = true;
        o.occluded_views = k;
        o.zero_outside_hull = zero_outside;
        ProbabilityVolume ref;
        detail::forceFaceRowKernelForTest(-1);
        PsfsFusion(o).fuse(table, ev, &ref);
        for (int64_t t : targets)
          for (int threads : {1, 3}) {
            o.threads = threads;
            detail::forceFaceRowKernelForTest(t);
            ProbabilityVolume out;
            PsfsFusion(o).fuse(table, ev, &out);
            detail::forceFaceRowKernelForTest(0);
            ASSERT_EQ(out.data, ref.data) << detail::hwyTargetName(t) << ", " << grid.describe() << ", k " << k
                                          << ", zero outside " << zero_outside << ", " << threads << " threads, "
                                          << num_cameras << " cameras";
          }
        detail::forceFaceRowKernelForTest(0);
        EXPECT_GT(countAbove(ref, thresholdByte(o.threshold)), 100u) << "the spheres are in the hull";
      }
  }
}

// plusFacesOfRow's vector path is Highway's PlusFacesRow at the CPU's best target: every target
// this CPU runs (those a CPU without AVX2 would run too) writes the reference loop's bytes (the
// scalar switch's path) and nothing outside the range, for every axis, on rows of 5 chunks
// (a 16-lane step over one chunk) with a camera that sees only part of the grid, over ranges
// that start and end at odd chunks.
TEST(PsfsFusion, EveryHighwayPlusFacesTargetMatchesTheReference) {
  const auto cams = partlyObservingCameras();
  const std::vector<ViewImage> views = test::twoSpheresWithMaskedView(tabletop_capture::makeDefaultRig().cameras);
  ProjectionTableOptions to;
  to.multi_projection = true;
  const ProjectionTable table(oddWidthGrid(), cams, to);
  ViewEvidence ev;
  ev.set(views, true);
  const std::vector<detail::KernelView> kv = detail::kernelViews(ev);
  const int C = table.numCameras(), nxp = table.paddedRowLength(), chunks = table.chunksPerRow();
  ASSERT_EQ(chunks % 2, 1) << "the grid's rows must hold an odd number of chunks";
  const size_t rows = size_t(table.grid().dims.y()) * table.grid().dims.z();
  const bool was_forced = scalarKernelsForced();
  std::vector<uint32_t> cs(table.centreScratchSize()), os(table.offsetScratchSize());
  size_t observed = 0, unobserved = 0;
  const int ranges[5][2] = {{0, chunks}, {1, chunks}, {0, chunks - 1}, {1, 2}, {3, chunks}};
  for (size_t row = 0; row < rows; row += 5) {
    const uint32_t* cen = table.rowCentres(row, cs.data());
    const uint32_t* off = table.rowOffsets(row, os.data());
    for (int axis = 0; axis < 3; ++axis)
      for (const auto& r : ranges) {
        const int x0 = r[0] * ProjectionTable::kChunk, x1 = r[1] * ProjectionTable::kChunk;
        std::vector<uint16_t> ref(size_t(C) * nxp + 16, uint16_t(0x1234));
        forceScalarKernels(true);
        detail::plusFacesOfRow(kv.data(), C, nxp, cen, off, axis, ref.data(), x0, x1);
        forceScalarKernels(false);
        for (int64_t t : detail::hwyRowTargets()) {
          std::vector<uint16_t> out(ref.size(), uint16_t(0x1234));
          detail::hwyPlusFacesKernel(t)(kv.data(), C, nxp, cen, off, axis, out.data(), x0, x1);
          ASSERT_EQ(out, ref) << detail::hwyTargetName(t) << ", row " << row << ", axis " << axis << ", voxels "
                              << x0 << ".." << x1;
        }
        for (int c = 0; c < C; ++c)
          for (int x = x0; x < x1; ++x) (ref[size_t(c) * nxp + x] == detail::kNoFace ? unobserved : observed) += 1;
      }
  }
  forceScalarKernels(was_forced);
  EXPECT_GT(observed, 10000u) << "faces sampled";
  EXPECT_GT(unobserved, 1000u) << "voxels a camera does not see (and the rows' padding)";
}

// The targets without a fused multiply-add (SSE4, EMU128, SCALAR) take the log term of a median
// pair from a table (log_term_table.h): it must hold logTermOfPair's own value for every pair a
// kernel can make, and entry 0 the value of every negative one. The function is
// round(1024 ln(max(m, 256) / 130560)) in float: ln x near 12 carries a few ulps (2^-20 each)
// and 1024 times that is a few thousandths of a step, so it may differ from the
// double-precision value by one only where that lies within 0.01 of a half.
TEST(PsfsFusion, LogTermTableHoldsTheFunctionsOwnValues) {
  const int16_t* table = detail::logTermTable();
  ASSERT_EQ(detail::logTermTable(), table) << "built once";
  int off_by_one = 0;
  for (int32_t m = 0; m <= detail::kMaxMedianPair; ++m) {
    ASSERT_EQ(table[m], detail::logTermOfPair(m)) << "m " << m;
    const double exact = 1024.0 * std::log(std::max(m, 256) / 130560.0);
    const long nearest = std::lround(exact);
    if (table[m] != nearest) {
      ++off_by_one;
      ASSERT_EQ(std::abs(table[m] - nearest), 1) << "m " << m;
      ASSERT_LT(std::abs(std::abs(exact - std::floor(exact)) - 0.5), 0.01) << "m " << m << ": not at a half";
    }
  }
  EXPECT_EQ(table[0], table[256]) << "pairs below 256 are floored at half a byte step";
  EXPECT_EQ(table[detail::kMaxMedianPair], 0);
  EXPECT_LT(off_by_one, (detail::kMaxMedianPair + 1) / 100) << "of " << detail::kMaxMedianPair + 1;
  // The kernels clamp pairs below 0 to 0 (log_term_table.h): the function's value there too.
  for (int32_t m : {-1, -65280, INT32_MIN}) EXPECT_EQ(table[0], detail::logTermOfPair(m)) << "m " << m;
}

// The shared face samples follow the rule of psfs_kernels.h whatever the walk: a brute force
// per voxel (each face from the table and the likelihood bytes directly) against the walk the
// reference variants use, on a rig where one camera sees only part of the grid.
TEST(PsfsFusion, FaceSamplesFollowTheSharingRule) {
  const auto cams = partlyObservingCameras();
  const std::vector<Sphere> spheres = {{Eigen::Vector3d(0.0, 0.0, 0.3), 0.2}};
  std::vector<ViewImage> views;
  std::vector<cv::Mat> images;
  for (size_t c = 0; c < cams.size(); ++c) {
    images.push_back(test::noisy(test::sphereLikelihood(cams[c], spheres), 40, 0.05, 31 + c));
    views.push_back(ViewImage{images.back(), 0, cv::Mat()});
  }
  // A switched-off patch: it takes evidence away, but which samples a face uses must not change.
  views[2].active = cv::Mat(240, 320, CV_8UC1, cv::Scalar(1));
  views[2].active(cv::Rect(100, 50, 80, 120)).setTo(0);
  const VoxelGrid grid = cubeGrid(Eigen::Vector3d(0.0, 0.0, 0.3), 0.6, 20);  // 20^3, 30 mm
  ProjectionTableOptions to;
  to.multi_projection = true;
  const ProjectionTable table(grid, cams, to);
  ViewEvidence ev;
  ev.set(views, true);
  const std::vector<detail::KernelView> kv = detail::kernelViews(ev);
  const int C = table.numCameras(), nx = grid.dims.x(), ny = grid.dims.y(), nz = grid.dims.z();
  const int nxp = table.paddedRowLength(), chunks = table.chunksPerRow();

  // Bilinear sample of camera c at packed centre uv + sign * packed offset, straight from the
  // bytes with clamped coordinates (1/16 px weights).
  auto sample = [&](int c, uint32_t uv, uint32_t off, int sign) {
    const int U = int(uv & 0xFFFF) + sign * int(int16_t(off & 0xFFFF)) - 8;  // 16 * (u - pixel 0)
    const int V = int(uv >> 16) + sign * (int32_t(off) >> 16) - 8;
    const int u0 = U >> 4, v0 = V >> 4, fu = U & 15, fv = V & 15;  // floor for negatives too
    auto at = [&](int u, int v) {
      return int(images[c].at<uint8_t>(std::clamp(v, 0, images[c].rows - 1), std::clamp(u, 0, images[c].cols - 1)));
    };
    return (at(u0, v0) * (16 - fv) + at(u0, v0 + 1) * fv) * (16 - fu) +
           (at(u0 + 1, v0) * (16 - fv) + at(u0 + 1, v0 + 1) * fv) * fu;
  };
  std::vector<uint32_t> scratch(table.offsetScratchSize());
  auto offset = [&](int c, int x, int y, int z, int axis) {
    return table.rowOffsets(size_t(y) + size_t(ny) * z, scratch.data())[(c * chunks + x / ProjectionTable::kChunk) * 3 + axis];
  };
  size_t checked = 0, unobserved = 0, fallbacks = 0;
  std::vector<int32_t> walk(grid.numVoxels() * C);
  for (int threads : {1, 2, 3}) {
    detail::forEachFaceRow(table, kv, threads, [&](size_t r, const uint32_t* centres, const uint32_t* offsets,
                                                   uint16_t* yface, uint16_t* zface) {
      std::vector<int32_t> pairs(size_t(C) * nxp);
      detail::medianPairsOfRow(kv.data(), C, nxp, centres, offsets, yface, zface, pairs.data());
      for (int c = 0; c < C; ++c)
        for (int x = 0; x < nx; ++x) walk[(r * nx + x) * C + c] = pairs[size_t(c) * nxp + x];
    });
    for (int z = 0; z < nz; ++z)
      for (int y = 0; y < ny; ++y)
        for (int x = 0; x < nx; ++x)
          for (int c = 0; c < C; ++c) {
            const uint32_t no = PackedUV::notObserved(cams[c].height);
            const uint32_t p = table.centre(c, x, y, z);
            if (p == no) {
              ++unobserved;
              continue;
            }
            const int lower[3][3] = {{x - 1, y, z}, {x, y - 1, z}, {x, y, z - 1}};
            int32_t f[6];
            for (int a = 0; a < 3; ++a) {
              f[2 * a + 1] = sample(c, p, offset(c, x, y, z, a), 1);
              const int* l = lower[a];
              const bool has = l[0] >= 0 && l[1] >= 0 && l[2] >= 0;
              const uint32_t q = has ? table.centre(c, l[0], l[1], l[2]) : no;
              fallbacks += has && q == no;
              f[2 * a] = q != no ? sample(c, q, offset(c, l[0], l[1], l[2], a), 1)
                                 : sample(c, p, offset(c, x, y, z, a), -1);
            }
            std::sort(f, f + 6);
            ASSERT_EQ(walk[(grid.index(x, y, z)) * C + c], f[2] + f[3])
                << "voxel (" << x << ", " << y << ", " << z << ") camera " << c << ", " << threads << " threads";
            ++checked;
          }
  }
  std::printf("face samples: %zu voxel-camera medians match the brute force (%zu unobserved, %zu "
              "faces sampled from the upper voxel because the lower one is unobserved)\n",
              checked, unobserved, fallbacks);
  EXPECT_GT(unobserved, 0u);
  EXPECT_GT(fallbacks, 0u);
}

// The AVX-512 and AVX2 row projections do the same float operations per lane: their tables
// must be identical to the bit (volumes then agree across CPUs with either extension).
TEST(ProjectionTable, Avx512AndAvx2ProjectionsAreIdentical) {
  if (!avx512Available()) GTEST_SKIP() << "no AVX-512 on this CPU: only the AVX2 projection runs";
  const auto rig = tabletop_capture::makeDefaultRig();
  ProjectionTableOptions o;
  o.multi_projection = true;
  o.storage = TableStorage::kPrecomputed;
  const ProjectionTable wide(referenceGrid(Resolution::k16mm), rig.cameras, o);
  forceAvx2Kernels(true);
  const ProjectionTable narrow(referenceGrid(Resolution::k16mm), rig.cameras, o);
  forceAvx2Kernels(false);
  for (size_t r = 0; r < wide.grid().numRows(); ++r) {
    const uint32_t* a = wide.rowCentres(r, nullptr);
    const uint32_t* b = narrow.rowCentres(r, nullptr);
    ASSERT_EQ(0, std::memcmp(a, b, wide.centreScratchSize() * sizeof(uint32_t))) << "row " << r;
  }
}

}  // namespace
}  // namespace psfs
