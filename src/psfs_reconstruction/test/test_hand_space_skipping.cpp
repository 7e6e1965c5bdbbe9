// Empty-space skipping in the single-projection pSfS (PsfsOptions::skip_empty_below without
// multi_projection: the hand sub-volumes, src/centre_space_bound.h). The bound is strict and
// keeps a margin of two voxels, so on the simulated rig's frames (synthetic classifier-like
// likelihoods with known occlusions, and the real pipeline) every voxel at or above the level,
// and every voxel within 2 of one (what marching cubes above the level reads), is the full
// fusion's byte; every other voxel is that byte or 0. Every row kernel, thread count, table
// storage, a floor, occlusion tolerance, cubes that leave some views and a view switched off.
// The figures printed are the skipped share of the cubes' voxels.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <random>
#include <string>

#include <opencv2/imgproc.hpp>

#include "../src/centre_space_bound.h"
#include "../src/psfs_kernels.h"
#include "../src/volume_fusion.h"
#include "expect_throw.h"
#include "fusion_test_utils.h"
#include "gpu_fusion_cases.h"
#include "pipeline_frames.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/reconstructor.h"
#include "psfs_reconstruction/simd_dispatch.h"
#include "tabletop_sim/simulated_rig.h"
#include "test_data_path.h"

namespace psfs {
namespace {

namespace sim = tabletop_sim;

// The voxels of `full` at or above level_byte and those within 2 of them along each axis (all
// that marching cubes near such a voxel reads, the central differences of its normals included).
std::vector<uint8_t> keptByTheRule(const ProbabilityVolume& full, int level_byte) {
  const VoxelGrid& g = full.grid;
  const int nx = g.dims.x(), ny = g.dims.y(), nz = g.dims.z();
  std::vector<uint8_t> keep(full.data.size(), 0);
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        if (full.data[g.index(x, y, z)] < level_byte) continue;
        for (int dz = -2; dz <= 2; ++dz)
          for (int dy = -2; dy <= 2; ++dy)
            for (int dx = -2; dx <= 2; ++dx) {
              const int X = x + dx, Y = y + dy, Z = z + dz;
              if (X >= 0 && Y >= 0 && Z >= 0 && X < nx && Y < ny && Z < nz) keep[g.index(X, Y, Z)] = 1;
            }
      }
  return keep;
}

// The rule: a voxel the rule keeps is the full fusion's byte; any other is that byte or 0, and
// is 0 exactly in the chunks the bound flags. Returns the share of the voxels that differ.
double expectHandSkippingRule(const ProbabilityVolume& full, const ProbabilityVolume& skipped, double level,
                              const std::string& what) {
  EXPECT_EQ(full.data.size(), skipped.data.size()) << what;
  if (full.data.size() != skipped.data.size() || full.data.empty()) return 0.0;
  // A byte above 255 level + 1 is certainly a posterior at or above the level (the bound proves
  // posterior < level, which the exp table may round up to the byte above 255 level).
  const int level_byte = int(std::ceil(level * 255.0)) + 1;
  const std::vector<uint8_t> keep = keptByTheRule(full, level_byte);
  size_t changed = 0, bad_kept = 0, bad_other = 0;
  for (size_t i = 0; i < full.data.size(); ++i) {
    if (full.data[i] == skipped.data[i]) continue;
    ++changed;
    if (keep[i] && ++bad_kept <= 3)
      ADD_FAILURE() << what << ": voxel " << i << " at or near the level changed " << int(full.data[i]) << " -> "
                    << int(skipped.data[i]);
    if (!keep[i] && skipped.data[i] != 0 && ++bad_other <= 3)
      ADD_FAILURE() << what << ": voxel " << i << " changed to " << int(skipped.data[i]) << ", not to 0";
  }
  EXPECT_EQ(bad_kept, 0u) << what;
  EXPECT_EQ(bad_other, 0u) << what;
  return double(changed) / double(full.data.size());
}

// Fuses with options o and with o skipping below `level`, expects the rule; returns the share skipped.
double fuseAndExpectTheRule(const ProjectionTable& table, const ViewEvidence& ev, const PsfsOptions& o, double level,
                            const std::string& what) {
  PsfsOptions os = o;
  os.skip_empty_below = level;
  ProbabilityVolume a, b;
  PsfsFusion(o).fuse(table, ev, &a);
  const PsfsFusion skipping(os);
  skipping.fuse(table, ev, &b);
  expectHandSkippingRule(a, b, level, what);
  return skipping.lastSkippedFraction();
}

// Three frames of 'wave' with short sleeves (gpu_fusion_cases.h), with the known-occlusion
// patches, and the hands' centres: [0] the classifier-like likelihoods with noise and 2 %
// outliers (a bright pixel under nearly every cell of every view: little to skip), [1] the same
// without noise.
struct HandFrames {
  std::vector<gpu_test::SimScene> scenes[2];
};
const HandFrames& handFrames() {
  static const HandFrames h = [] {
    HandFrames f;
    const int n = gpu_test::simRig().scriptFrames();
    for (int frame : {n / 5, n / 2, 4 * n / 5}) {
      gpu_test::SimScene s = gpu_test::simScene(frame, /*inactive=*/true);
      f.scenes[0].push_back(s);
      const sim::SimFrame fr = gpu_test::simRig().render(frame);
      for (size_t c = 0; c < s.likelihoods.size(); ++c) {
        s.likelihoods[c] = cv::Mat();  // (the noisy scene holds the old pixels)
        cv::merge(std::vector<cv::Mat>{test::classifierLikelihood(fr.person_masks[c], false, 0),
                                       test::classifierLikelihood(fr.skin_masks[c], false, 0)},
                  s.likelihoods[c]);
      }
      f.scenes[1].push_back(s);
    }
    return f;
  }();
  return h;
}

ProjectionTable handTable(const gpu_test::SimScene& s, const Eigen::Vector3d& centre, TableStorage storage) {
  ProjectionTableOptions o;
  o.storage = storage;
  return ProjectionTable(snappedCubeGrid(centre, 0.30, 83), s.cameras, o);
}

TEST(HandSpaceSkipping, KeepsEveryVoxelAtTheLevelAndItsNeighboursByteForByte) {
  const HandFrames& h = handFrames();
  for (int clean : {0, 1})
    for (int k : {0, 1})
      for (double level : {0.3, 0.5}) {
        double skipped = 0, changed = 0;
        int n = 0;
        for (size_t f = 0; f < h.scenes[clean].size(); ++f) {
          const gpu_test::SimScene& s = h.scenes[clean][f];
          ViewEvidence ev;
          ev.set(s.views(1), false);
          for (const Eigen::Vector3d& hand : {s.right_hand, s.left_hand}) {
            const ProjectionTable table = handTable(s, hand, TableStorage::kOnTheFly);
            for (bool floor : {false, true}) {
              PsfsOptions o;
              o.occluded_views = k;
              o.threads = 2;
              if (floor) o.floor_z = hand.z() - 0.03;  // a hand resting on the desk
              PsfsOptions os = o;
              os.skip_empty_below = level;
              const PsfsFusion full(o), skipping(os);
              ProbabilityVolume a, b;
              full.fuse(table, ev, &a);
              skipping.fuse(table, ev, &b);
              const std::string what = std::string(clean ? "clean" : "noisy") + " k " + std::to_string(k) + " level " +
                                       std::to_string(level) + " frame " + std::to_string(f) + (floor ? " floor" : "");
              changed += expectHandSkippingRule(a, b, level, what);
              skipped += skipping.lastSkippedFraction();
              ++n;
            }
          }
        }
        std::printf("[ figures  ] %s likelihoods, k %d, level %.1f: %.0f %% of the voxels skipped, %.1f %% changed\n",
                    clean ? "clean" : "noisy", k, level, 100.0 * skipped / n, 100.0 * changed / n);
        // Not vacuous: a hand fills a few per cent of its cube.
        if (clean && level == 0.5 && k == 0) {
          EXPECT_GT(skipped / n, 0.3);
        }
      }
}

// Threads, the table's storage and every row kernel (each Highway target this CPU runs, and
// the plain C++ reference) give the same bytes with skipping: the kernels' spans.
TEST(HandSpaceSkipping, EveryKernelThreadCountAndStorageGivesTheSameBytes) {
  const gpu_test::SimScene& s = handFrames().scenes[1][1];
  ViewEvidence ev;
  ev.set(s.views(1), false);
  const ProjectionTable fly = handTable(s, s.right_hand, TableStorage::kOnTheFly);
  const ProjectionTable stored = handTable(s, s.right_hand, TableStorage::kPrecomputed);
  PsfsOptions o;
  o.skip_empty_below = 0.5;
  o.threads = 1;
  ProbabilityVolume reference;
  PsfsFusion(o).fuse(fly, ev, &reference);
  std::vector<int64_t> targets = detail::hwyRowTargets();
  targets.push_back(-1);  // the plain C++ reference kernel
  for (int64_t target : targets) {
    detail::forceRowKernelForTest(target);
    for (int threads : {1, 2, 3})
      for (const ProjectionTable* table : {&fly, &stored}) {
        PsfsOptions ot = o;
        ot.threads = threads;
        ProbabilityVolume out;
        PsfsFusion(ot).fuse(*table, ev, &out);
        EXPECT_EQ(out.data, reference.data) << (target < 0 ? "reference" : detail::hwyTargetName(target)) << ", "
                                            << threads << " threads, " << (table == &fly ? "on the fly" : "stored");
      }
  }
  detail::forceRowKernelForTest(0);
}

// A grid that stays (the workspace's, or a hand that holds still) keeps its cells' boxes and its
// cameras' windows from the second frame on: the same bytes as a fusion that derives them
// afresh, frame after frame and on new evidence.
TEST(HandSpaceSkipping, AGridThatStaysKeepsItsBoxes) {
  const HandFrames& h = handFrames();
  const ProjectionTable tables[2] = {
      handTable(h.scenes[1][0], h.scenes[1][0].right_hand, TableStorage::kPrecomputed),
      handTable(h.scenes[1][0], h.scenes[1][0].left_hand, TableStorage::kOnTheFly)};
  PsfsOptions o;
  o.skip_empty_below = 0.5;
  const PsfsFusion kept(o);
  // Table A three times (boxes kept from the second), B once (a moving cube), A twice again.
  for (int frame = 0; frame < 6; ++frame) {
    const ProjectionTable& table = tables[frame == 3 ? 1 : 0];
    ViewEvidence ev;
    ev.set(h.scenes[1][size_t(frame % 3)].views(1), false);
    ProbabilityVolume a, b;
    kept.fuse(table, ev, &a);
    PsfsFusion(o).fuse(table, ev, &b);  // a fresh fusion: boxes on demand
    EXPECT_EQ(a.data, b.data) << "frame " << frame;
    EXPECT_GT(kept.lastSkippedFraction(), 0.3) << "frame " << frame;
  }
}

// A cube half outside the views (at the workspace's corner, beyond some cameras' images), and
// one view switched off as a whole: the cells those cameras see in part or not at all.
TEST(HandSpaceSkipping, CubesLeavingTheViewsAndAViewSwitchedOff) {
  const gpu_test::SimScene& s = handFrames().scenes[1][1];
  // Camera 1 zoomed in 5x: most cubes lie wholly or partly outside its image.
  std::vector<tabletop_capture::CameraModel> zoomed = s.cameras;
  zoomed[1].fx *= 5.0, zoomed[1].fy *= 5.0;
  for (int zoom : {0, 1})
    for (int off : {-1, 3})
      for (const Eigen::Vector3d& centre :
           {Eigen::Vector3d(-0.55, -0.55, 0.05), Eigen::Vector3d(0.6, 0.1, 0.6), s.right_hand}) {
        std::vector<ViewImage> views = s.views(1);
        if (off >= 0) views[size_t(off)].active = cv::Mat::zeros(views[size_t(off)].likelihood.size(), CV_8UC1);
        ViewEvidence ev;
        ev.set(views, false);
        ProjectionTableOptions o;
        o.storage = TableStorage::kOnTheFly;
        const ProjectionTable table(snappedCubeGrid(centre, 0.30, 83), zoom ? zoomed : s.cameras, o);
        fuseAndExpectTheRule(table, ev, PsfsOptions(), 0.5,
                             "zoom " + std::to_string(zoom) + " view off " + std::to_string(off));
      }
}

// The real pipeline (classifier, background learned from 25 sets, known occlusions), 4 frames
// of 'wave' with hand cubes at the true hands: the default hand options against none.
TEST(HandSpaceSkipping, PipelineHandVolumesKeepTheirSurface) {
  std::vector<FrameResult> results[2];
  for (int skip : {0, 1}) {
    ReconstructorParams params;
    params.threads = 2;
    if (!skip) params.hand.skip_empty_below = 0.0;  // the default skips
    results[skip] = psfs_test::pipelineFrames(params, true);
    ASSERT_EQ(results[skip].size(), 4u);
  }
  const double level = ReconstructorParams::defaultHand().skip_empty_below;
  ASSERT_GT(level, 0.0);
  double changed = 0;
  for (size_t i = 0; i < results[0].size(); ++i)
    for (int h = 0; h < 2; ++h)
      changed += expectHandSkippingRule(results[0][i].hands[size_t(h)], results[1][i].hands[size_t(h)], level,
                                        "frame " + std::to_string(i) + " hand " + std::to_string(h));
  double skipped = 0;
  for (const FrameResult& r : results[1]) skipped += r.hands_skipped / double(results[1].size());
  for (const FrameResult& r : results[0]) EXPECT_EQ(r.hands_skipped, 0.0);
  std::printf("[ figures  ] pipeline, 4 frames, 2 hands, level %.2f: %.1f %% of the voxels skipped, %.1f %% changed (to 0)\n",
              level, 100.0 * skipped, 100.0 * changed / 8.0);
  EXPECT_GT(skipped, 0.3);  // not vacuous: the real classifier's views are quiet away from the person
  EXPECT_LE(changed / 8.0, skipped);  // only skipped voxels change
}

// Other fusion parameters: min_views 1, occlusion tolerance 2, a drop threshold, hull and view
// priors (an offset that changes the limit per view).
TEST(HandSpaceSkipping, OtherFusionParametersKeepTheRule) {
  const gpu_test::SimScene& s = handFrames().scenes[1][2];
  ViewEvidence ev;
  ev.set(s.views(1), false);
  const ProjectionTable table = handTable(s, s.left_hand, TableStorage::kOnTheFly);
  for (int variant = 0; variant < 4; ++variant) {
    PsfsOptions o;
    if (variant == 0) o.min_views = 1;
    if (variant == 1) o.occluded_views = 2;
    if (variant == 2) o.occluded_views = 1, o.drop_threshold = 0.3;
    if (variant == 3) o.hull_prior = 0.005, o.view_prior = skinViewPrior(0.005, 0.08, int(s.cameras.size()));
    const double skipped = fuseAndExpectTheRule(table, ev, o, 0.5, "variant " + std::to_string(variant));
    std::printf("[ figures  ] variant %d: %.0f %% of the voxels skipped\n", variant, 100.0 * skipped);
  }
}

// The geometry the bound rests on: every voxel centre's pixel (the table's own projection) lies in
// its cell's and its block's box, for high-resolution cameras with strong lens distortion close
// to the cube (where a box spans tens of pixels and the distortion bends it most), and for the
// simulated rig.
TEST(HandSpaceSkipping, EveryVoxelCentreLiesInItsCellsBox) {
  const Eigen::Vector3d target(0.05, -0.02, 0.1);
  std::vector<tabletop_capture::CameraModel> strong = test::ringCameras(6, target, 0.45, 1280, 960, 900.0);
  for (size_t c = 0; c < strong.size(); ++c)
    strong[c].distortion = {c % 2 ? -0.35 : 0.25, c % 2 ? 0.12 : -0.08, 0.002, -0.0015, c % 3 ? 0.0 : -0.02};
  const std::vector<tabletop_capture::CameraModel> rigs[2] = {strong, handFrames().scenes[1][0].cameras};
  for (int rig = 0; rig < 2; ++rig) {
    const auto& cams = rigs[rig];
    std::vector<ViewImage> views;
    for (const auto& cam : cams) views.push_back(ViewImage{cv::Mat(cam.height, cam.width, CV_8UC1, cv::Scalar(200)), 0, cv::Mat()});
    ViewEvidence ev;
    ev.set(views, false);
    for (const Eigen::Vector3d& centre : {target, Eigen::Vector3d(target + Eigen::Vector3d(0.12, 0.1, 0.05))}) {
      ProjectionTableOptions to;
      to.storage = TableStorage::kOnTheFly;
      const ProjectionTable table(snappedCubeGrid(centre, 0.30, 83), cams, to);
      detail::PsfsRowParams p = detail::psfsRowParams(PsfsOptions(), table);
      detail::CentreSpaceBound bound;
      std::vector<uint8_t> flags;
      bound.skippableChunks(table, ev, p, 0, 0.5, 2, &flags);  // derives the boxes
      const VoxelGrid& g = table.grid();
      const int nxp = table.paddedRowLength(), C = table.numCameras(), k = detail::CentreSpaceBound::kCell;
      const int cx = (g.dims.x() + k - 1) / k, cy = (g.dims.y() + k - 1) / k, cz = (g.dims.z() + k - 1) / k;
      std::vector<uint32_t> scratch(table.centreScratchSize());
      size_t checked = 0, outside = 0;
      for (int z = 0; z < g.dims.z(); ++z)
        for (int y = 0; y < g.dims.y(); ++y) {
          const uint32_t* row = table.rowCentres(size_t(y) + size_t(g.dims.y()) * z, scratch.data());
          for (int c = 0; c < C; ++c) {
            const uint32_t none = PackedUV::notObserved(cams[size_t(c)].height);
            for (int x = 0; x < g.dims.x(); ++x) {
              const uint32_t q = row[size_t(c) * nxp + x];
              if (q == none) continue;
              const int u = int(q & 0xFFFFu) >> 4, v = int(q >> 20);
              const int X = x / k, Y = y / k, Z = z / k, BX = X & ~1, BY = Y & ~1, BZ = Z & ~1;
              const detail::CentreSpaceBound::PixelBox boxes[2] = {
                  bound.boxPixels(c, X, Y, Z, X + 1, Y + 1, Z + 1),
                  bound.boxPixels(c, BX, BY, BZ, std::min(cx, BX + 2), std::min(cy, BY + 2), std::min(cz, BZ + 2))};
              for (const auto& b : boxes) {
                if (b.unknown) continue;
                ++checked;
                if ((u < b.u0 || u > b.u1 || v < b.v0 || v > b.v1) && ++outside <= 3)
                  ADD_FAILURE() << "rig " << rig << " camera " << c << " voxel (" << x << ", " << y << ", " << z
                                << ") at pixel (" << u << ", " << v << ") outside [" << b.u0 << ", " << b.u1 << "] x ["
                                << b.v0 << ", " << b.v1 << "]";
              }
            }
          }
        }
      EXPECT_EQ(outside, 0u) << "rig " << rig;
      EXPECT_GT(checked, size_t(1000000)) << "rig " << rig;
    }
  }
}

// TermTiles::rectMax against the pixels of the tiles a rectangle touches, on random windows,
// bytes and switched-off pixels (through both the terms and a mask; every other trial none,
// which takes the one-byte levels of a window whose every pixel gives evidence).
TEST(HandSpaceSkipping, TileMaximaAreThoseOfTheTilesARectangleTouches) {
  std::mt19937 rng(7);
  const int W = 97, H = 71;
  cv::Mat bytes(H, W, CV_8UC1), active(H, W, CV_8UC1);
  std::vector<int16_t> terms(size_t(W) * H + 1);
  for (int trial = 0; trial < 40; ++trial) {
    cv::randu(bytes, 0, 256);
    for (int v = 0; v < H; ++v)
      for (int u = 0; u < W; ++u) {
        const bool off = trial % 2 == 0 && rng() % 23 == 0;
        active.at<uint8_t>(v, u) = off ? 0 : 255;
        terms[size_t(v) * W + u] = off ? 1 : -5;
      }
    const int u0 = int(rng() % W), v0 = int(rng() % H);
    const int u1 = u0 + int(rng() % (W - u0)), v1 = v0 + int(rng() % (H - v0));
    detail::TermTiles by_mask, by_terms;
    by_mask.set(bytes.data, size_t(W), 1, W, H, active, nullptr, u0, v0, u1, v1);
    by_terms.set(bytes.data, size_t(W), 1, W, H, cv::Mat(), terms.data(), u0, v0, u1, v1);
    constexpr int kT = detail::TermTiles::kTile;
    for (int q = 0; q < 50; ++q) {
      const int a0 = u0 + int(rng() % (u1 - u0 + 1)), b0 = v0 + int(rng() % (v1 - v0 + 1));
      const int a1 = a0 + int(rng() % (u1 - a0 + 1)), b1 = b0 + int(rng() % (v1 - b0 + 1));
      int want = -1;
      bool want_off = false;
      for (int v = b0 / kT * kT; v <= std::min(H - 1, b1 / kT * kT + kT - 1); ++v)
        for (int u = a0 / kT * kT; u <= std::min(W - 1, a1 / kT * kT + kT - 1); ++u) {
          if (active.at<uint8_t>(v, u) == 0)
            want_off = true;
          else
            want = std::max(want, int(bytes.at<uint8_t>(v, u)));
        }
      for (const detail::TermTiles* t : {&by_mask, &by_terms}) {
        int m;
        bool off;
        t->rectMax(a0, b0, a1, b1, &m, &off);
        ASSERT_EQ(m, want) << "trial " << trial << " rect " << a0 << "," << b0 << "-" << a1 << "," << b1;
        ASSERT_EQ(off, want_off) << "trial " << trial;
      }
    }
  }
}

// The bound from the images the evidence is made of (the GPU paths') flags what the bound from
// the evidence flags, masks and the 2-channel likelihood included; a view of the wrong size is refused.
TEST(HandSpaceSkipping, TheViewsAndTheEvidenceGiveTheSameChunks) {
  const gpu_test::SimScene& s = handFrames().scenes[1][1];
  const std::vector<ViewImage> views = s.views(1);
  ViewEvidence ev;
  ev.set(views, false);
  const ProjectionTable table = handTable(s, s.right_hand, TableStorage::kOnTheFly);
  const detail::PsfsRowParams p = detail::psfsRowParams(PsfsOptions(), table);
  detail::CentreSpaceBound a, b;
  std::vector<uint8_t> fa, fb;
  const double sa = a.skippableChunks(table, ev, p, 0, 0.5, 1, &fa);
  const double sb = b.skippableChunks(table, views, p, 0, 0.5, 2, &fb);
  EXPECT_EQ(fa, fb);
  EXPECT_EQ(sa, sb);
  EXPECT_GT(sa, 0.3);
  std::vector<ViewImage> bad = views;
  cv::resize(bad[3].likelihood, bad[3].likelihood, cv::Size(100, 80));
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { b.skippableChunks(table, bad, p, 0, 0.5, 1, &fb); },
                                                         "view 3");
}

// A moved grid with the same cameras (a hand's cube, frame after frame) rebuilds to a fresh
// table's projections, stored or on the fly.
TEST(HandSpaceSkipping, AMovedTableIsAFreshTable) {
  const gpu_test::SimScene& s = handFrames().scenes[0][0];
  for (TableStorage storage : {TableStorage::kOnTheFly, TableStorage::kPrecomputed}) {
    ProjectionTable moved = handTable(s, s.right_hand, storage);
    const uint64_t before = moved.revision();
    const VoxelGrid g = snappedCubeGrid(s.right_hand + Eigen::Vector3d(0.011, -0.007, 0.004), 0.30, 83);
    ASSERT_TRUE(moved.update(g, s.cameras));
    EXPECT_NE(moved.revision(), before);
    ProjectionTableOptions o;
    o.storage = storage;
    const ProjectionTable fresh(g, s.cameras, o);
    std::vector<uint32_t> sa(moved.centreScratchSize()), sb(fresh.centreScratchSize());
    for (size_t row = 0; row < g.numRows(); row += 97)
      ASSERT_EQ(0, std::memcmp(moved.rowCentres(row, sa.data()), fresh.rowCentres(row, sb.data()),
                               moved.centreScratchSize() * sizeof(uint32_t)))
          << "row " << row;
  }
}

TEST(HandSpaceSkipping, PartialRowProjectionsAreTheWholeRowsEntries) {
  const gpu_test::SimScene& s = handFrames().scenes[0][0];
  const ProjectionTable fly = handTable(s, s.right_hand, TableStorage::kOnTheFly);
  const ProjectionTable stored = handTable(s, s.right_hand, TableStorage::kPrecomputed);
  const int nxp = fly.paddedRowLength(), C = fly.numCameras();
  std::vector<uint32_t> scratch(fly.centreScratchSize(), 0u);
  for (size_t row : {size_t(0), size_t(1234), fly.grid().numRows() - 1})
    for (auto span : {std::make_pair(0, nxp), std::make_pair(8, 24), std::make_pair(nxp - 8, nxp)}) {
      const uint32_t* part = fly.rowCentres(row, scratch.data(), span.first, span.second);
      const uint32_t* whole = stored.rowCentres(row, nullptr);
      for (int c = 0; c < C; ++c)
        for (int x = span.first; x < span.second; ++x)
          ASSERT_EQ(part[size_t(c) * nxp + x], whole[size_t(c) * nxp + x]) << "row " << row << " camera " << c << " x " << x;
    }
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { fly.rowCentres(0, scratch.data(), 3, 16); },
                                                         "whole chunks");
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { fly.rowCentres(0, scratch.data(), 0, nxp + 8); },
                                                         "whole chunks");
}

TEST(HandSpaceSkipping, TheReconstructorTakesItOnlyWithTheSingleProjection) {
  ReconstructorParams p;
  EXPECT_GT(p.hand.skip_empty_below, 0.0);  // the default
  p.validate();
  p.hand.multi_projection = true;
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { p.validate(); },
                                                         "hand.skip_empty_below needs the single projection");
  p.hand.skip_empty_below = 0.0;
  p.validate();
}

}  // namespace
}  // namespace psfs
