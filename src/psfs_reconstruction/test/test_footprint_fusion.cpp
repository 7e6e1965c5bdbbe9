// Footprint-filtered evidence (issue 17 prototype): the filters against brute force, the
// table's levels against the projected voxel size, identical bytes from every kernel, the
// rejected combinations, and the hull quality against today's multi-projection on the
// sequences test_fusion_sim and test_reconstructor use.
//
// Quality tolerance: the footprint path must not lose more than 0.01 IoU against the
// multi-projection on the same frames. At 15.6 mm the body hull has ~6000 voxels, ~2500 of
// them in the one-voxel shell at its surface where the two tests disagree; 0.01 IoU is ~60
// voxels, 1/40 of that shell, i.e. the surface moving by ~0.4 mm on average, far below the
// voxel size. The check is one-sided: on the synthetic masks of test_fusion_sim a centre
// lookup beats the face median against the centre-sampled oracle (binary SfS does too: 0.86
// against 0.81 on clean masks), so being better there is expected, not a regression.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <map>
#include <random>

#include "../src/footprint_filter.h"
#include "expect_throw.h"
#include "fusion_test_utils.h"
#include "psfs_reconstruction/binary_sfs.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/reconstructor.h"
#include "psfs_reconstruction/simd_dispatch.h"
#include "tabletop_capture/default_rig.h"
#include "tabletop_sim/simulated_rig.h"
#include "test_data_path.h"

namespace psfs {
namespace {

namespace sim = tabletop_sim;

cv::Mat randomImage(int w, int h, uint32_t seed) {
  cv::Mat m(h, w, CV_8UC1);
  cv::randu(m, cv::Scalar(0), cv::Scalar(256));
  (void)seed;
  return m;
}

TEST(FootprintFilter, MatchesTheBruteForce) {
  cv::setRNGSeed(3);
  std::vector<int16_t> lut(256);
  for (int b = 0; b < 256; ++b) lut[b] = ViewEvidence::logTerm(b);
  for (const cv::Size sz : {cv::Size(1, 1), cv::Size(2, 7), cv::Size(5, 3), cv::Size(37, 11), cv::Size(320, 240)}) {
    const cv::Mat img = randomImage(sz.width, sz.height, 0);
    const int W = sz.width, H = sz.height;
    std::vector<int16_t> terms(size_t(W) * H);
    for (int i = 0; i < W * H; ++i) terms[i] = lut[img.data[i]];
    for (int R : {1, 2}) {
      detail::FootprintScratch s;
      std::vector<int16_t> med(terms.size()), mean(terms.size());
      detail::medianFilterTerms(terms.data(), W, H, R, med.data(), &s);
      detail::meanFilterTerms(img.data, W, H, R, lut.data(), mean.data(), &s);
      for (int v = 0; v < H; ++v)
        for (int u = 0; u < W; ++u) {
          ASSERT_EQ(med[size_t(v) * W + u], detail::separableMedianAt(terms.data(), W, H, R, u, v))
              << W << "x" << H << " R " << R << " at " << u << "," << v;
          ASSERT_EQ(mean[size_t(v) * W + u], lut[detail::boxMeanAt(img.data, W, H, R, u, v)])
              << W << "x" << H << " R " << R << " at " << u << "," << v;
        }
    }
  }
  // The median commutes with the monotone byte -> term map: filtering terms is filtering bytes.
  const cv::Mat img = randomImage(9, 9, 0);
  std::vector<int16_t> terms(81);
  for (int i = 0; i < 81; ++i) terms[i] = lut[img.data[i]];
  std::vector<int16_t> bytes(img.data, img.data + 81);
  EXPECT_EQ(lut[detail::separableMedianAt(bytes.data(), 9, 9, 2, 4, 4)],
            detail::separableMedianAt(terms.data(), 9, 9, 2, 4, 4));
}

TEST(FootprintFilter, EvidenceStacksTheLevelsWithGuardsAndMasks) {
  cv::setRNGSeed(5);
  const int W = 64, H = 48;
  std::vector<ViewImage> views(2);
  for (auto& v : views) v.likelihood = randomImage(W, H, 0);
  views[1].active = cv::Mat(H, W, CV_8UC1, cv::Scalar(1));
  views[1].active(cv::Rect(10, 5, 20, 12)).setTo(0);
  for (FootprintStatistic stat : {FootprintStatistic::kMedian, FootprintStatistic::kMean}) {
    ViewEvidence plain, fp;
    plain.set(views, false);
    fp.set(views, true, 1, FootprintFilter{3, stat});
    EXPECT_EQ(fp.footprint().levels, 3);
    for (int c = 0; c < 2; ++c) {
      // Level 0 (with its guard pixel) is the plain evidence.
      ASSERT_EQ(0, std::memcmp(plain.terms(c), fp.terms(c), (size_t(W) * H + 1) * sizeof(int16_t)));
      std::vector<int16_t> raw(size_t(W) * H);
      for (int i = 0; i < W * H; ++i) raw[i] = ViewEvidence::logTerm(views[c].likelihood.data[i]);
      for (int l = 1; l < 3; ++l) {
        const int16_t* level = fp.terms(c) + size_t(l) * W * (H + 1);
        for (int v = 0; v < H; ++v)
          for (int u = 0; u < W; ++u) {
            const bool off = !views[c].active.empty() && views[c].active.at<uint8_t>(v, u) == 0;
            const int16_t want =
                off ? ViewEvidence::kNoEvidence
                    : stat == FootprintStatistic::kMedian
                          ? detail::separableMedianAt(raw.data(), W, H, l, u, v)
                          : ViewEvidence::logTerm(detail::boxMeanAt(views[c].likelihood.data, W, H, l, u, v));
            ASSERT_EQ(level[size_t(v) * W + u], want) << "view " << c << " level " << l << " at " << u << "," << v;
          }
        // A guard row after each level; after the last only the guard pixel and 2 more.
        for (int u = 0; u < (l < 2 ? W : 3); ++u) ASSERT_EQ(level[size_t(H) * W + u], ViewEvidence::kNoEvidence);
      }
      for (int u = 0; u < W; ++u) ASSERT_EQ(fp.terms(c)[size_t(H) * W + u], ViewEvidence::kNoEvidence);
    }
  }
}

TEST(FootprintTable, LevelsFollowTheProjectedVoxelSize) {
  const auto rig = tabletop_capture::makeDefaultRig();
  const VoxelGrid grid = referenceGrid(Resolution::k16mm);
  ProjectionTableOptions plain_o, fo;
  plain_o.storage = fo.storage = TableStorage::kPrecomputed;
  fo.footprint_levels = 3;
  const ProjectionTable plain(grid, rig.cameras, plain_o), fp(grid, rig.cameras, fo);
  fo.storage = TableStorage::kOnTheFly;
  const ProjectionTable fly(grid, rig.cameras, fo);
  std::vector<uint32_t> scratch(fly.centreScratchSize());
  size_t hist[3] = {0, 0, 0}, near_tie = 0, mismatches = 0;
  for (size_t r = 0; r < grid.numRows(); ++r) {
    const uint32_t* a = fp.rowCentres(r, nullptr);
    ASSERT_EQ(0, std::memcmp(a, fly.rowCentres(r, scratch.data()), fp.centreScratchSize() * 4)) << "row " << r;
    const int y = static_cast<int>(r % grid.dims.y()), z = static_cast<int>(r / grid.dims.y());
    for (int c = 0; c < fp.numCameras(); ++c) {
      const auto& cam = rig.cameras[c];
      for (int x = 0; x < grid.dims.x(); ++x) {
        const uint32_t p = a[c * fp.paddedRowLength() + x];
        // The same image position as the plain table, in the level's rows.
        ASSERT_EQ(fp.withoutLevel(c, p), plain.rowCentres(r, nullptr)[c * plain.paddedRowLength() + x]);
        if (p == PackedUV::notObserved(cam.height)) continue;
        const int level = fp.footprintLevelOf(c, p);
        ++hist[level];
        const double depth = (cam.world_T_camera.inverse() * grid.centre(x, y, z)).z();
        const double w = fo.footprint_scale * std::sqrt(cam.fx * cam.fy) * grid.voxel_size / depth;
        const int want = std::min(2, static_cast<int>(std::floor(w + 0.5)));
        const bool tie = std::abs(w + 0.5 - std::round(w + 0.5)) < 1e-6;
        near_tie += tie;
        mismatches += !tie && level != want;
      }
    }
  }
  std::printf("16 mm grid, 8 cameras: voxels at level 0 / 1 / 2 (1, 3x3, 5x5 px): %zu / %zu / %zu\n",
              hist[0], hist[1], hist[2]);
  EXPECT_EQ(mismatches, 0u);
  EXPECT_LT(near_tie, 10u);
  EXPECT_GT(hist[1], 0u);
  EXPECT_GT(hist[2], 0u);
  if (avx2Available()) {
    // The levels come from integer x ranges: every projection copy gives the same ones.
    ProjectionTableOptions o = fo;
    o.storage = TableStorage::kPrecomputed;
    forceAvx2Kernels(true);
    const ProjectionTable avx2(grid, rig.cameras, o);
    forceAvx2Kernels(false);
    forceScalarKernels(true);
    const ProjectionTable scalar(grid, rig.cameras, o);
    forceScalarKernels(false);
    for (size_t r = 0; r < grid.numRows(); ++r)
      for (int c = 0; c < fp.numCameras(); ++c)
        for (int x = 0; x < grid.dims.x(); ++x) {
          const size_t i = size_t(c) * fp.paddedRowLength() + x;
          const uint32_t p = fp.rowCentres(r, nullptr)[i];
          ASSERT_EQ(p, avx2.rowCentres(r, nullptr)[i]) << "row " << r;
          ASSERT_EQ(fp.footprintLevelOf(c, p), scalar.footprintLevelOf(c, scalar.rowCentres(r, nullptr)[i]));
        }
  }
}

TEST(FootprintFusion, ScalarAndVectorKernelsGiveIdenticalBytes) {
  if (!avx2Available()) GTEST_SKIP() << "no AVX2 on this CPU: the AVX2 and AVX-512 targets cannot run here";
  const auto rig = tabletop_capture::makeDefaultRig();
  std::vector<ViewImage> views = test::twoSpheresWithMaskedView(rig.cameras);
  const VoxelGrid grids[2] = {referenceGrid(Resolution::k16mm), cubeGrid(Eigen::Vector3d(0.0, 0.0, 0.3), 0.6, 37)};
  for (const VoxelGrid& grid : grids)
    for (FootprintStatistic stat : {FootprintStatistic::kMedian, FootprintStatistic::kMean})
      for (int k : {0, 1}) {
        ProjectionTableOptions to;
        to.footprint_levels = 3;
        const ProjectionTable table(grid, rig.cameras, to);
        ViewEvidence ev;
        ev.set(views, false, 0, FootprintFilter{3, stat});
        PsfsOptions o;
        o.footprint = true;
        o.occluded_views = k;
        ProbabilityVolume vec, avx2, sca;
        PsfsFusion(o).fuse(table, ev, &vec);
        forceAvx2Kernels(true);
        PsfsFusion(o).fuse(table, ev, &avx2);
        forceAvx2Kernels(false);
        forceScalarKernels(true);
        PsfsFusion(o).fuse(table, ev, &sca);
        forceScalarKernels(false);
        ASSERT_EQ(vec.data, sca.data) << grid.describe() << " k " << k;
        ASSERT_EQ(avx2.data, sca.data) << grid.describe() << " k " << k;
        for (int threads : {1, 3}) {
          o.threads = threads;
          ProbabilityVolume t;
          PsfsFusion(o).fuse(table, ev, &t);
          ASSERT_EQ(t.data, vec.data) << threads << " threads";
        }
        EXPECT_GT(countAbove(vec, thresholdByte(o.threshold)), 100u);
      }
}

TEST(FootprintFusion, BadCombinationsAreRejected) {
  const auto rig = tabletop_capture::makeDefaultRig();
  const VoxelGrid grid = cubeGrid(Eigen::Vector3d(0.0, 0.0, 0.3), 0.4, 16);
  std::vector<ViewImage> views(rig.cameras.size());
  for (auto& v : views) v.likelihood = cv::Mat(240, 320, CV_8UC1, cv::Scalar(200));
  PsfsOptions both;
  both.footprint = both.multi_projection = true;
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { PsfsFusion f{both}; (void)f; }, "exclusive");
  ProjectionTableOptions to;
  to.footprint_levels = 3;
  to.multi_projection = true;
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { ProjectionTable(grid, rig.cameras, to); }, "exclusive");
  to.multi_projection = false;
  for (int bad : {1, 4, -1}) {
    to.footprint_levels = bad;
    psfs_test::expectThrowContaining<std::invalid_argument>([&] { ProjectionTable(grid, rig.cameras, to); }, "footprint_levels");
    ViewEvidence ev;
    psfs_test::expectThrowContaining<std::invalid_argument>([&] { ev.set(views, false, 0, FootprintFilter{bad, FootprintStatistic::kMedian}); }, "footprint levels");
  }
  to.footprint_levels = 3;
  const ProjectionTable fp(grid, rig.cameras, to), plain(grid, rig.cameras);
  ViewEvidence ev2, ev3, ev0;
  ev2.set(views, false, 0, FootprintFilter{2, FootprintStatistic::kMedian});
  ev3.set(views, false, 0, FootprintFilter{3, FootprintStatistic::kMedian});
  ev0.set(views, false);
  PsfsOptions o;
  o.footprint = true;
  ProbabilityVolume out;
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { PsfsFusion(o).fuse(plain, ev3, &out); }, "footprint_levels");
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { PsfsFusion(o).fuse(fp, ev2, &out); }, "3 footprint levels");
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { PsfsFusion(o).fuse(fp, ev0, &out); }, "3 footprint levels");
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { PsfsFusion().fuse(fp, ev3, &out); }, "PsfsOptions::footprint");
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { BinarySfs().fuse(fp, ev3, &out); }, "footprint levels");
  PsfsFusion(o).fuse(fp, ev3, &out);  // the right combination
  PsfsFusion().fuse(plain, ev3, &out);  // plain tables read level 0 of footprint evidence
  std::vector<ViewImage> tall(rig.cameras.size());
  for (auto& v : tall) v.likelihood = cv::Mat(1400, 16, CV_8UC1, cv::Scalar(200));
  ViewEvidence ev;
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { ev.set(tall, false, 0, FootprintFilter{3, FootprintStatistic::kMedian}); }, "too high");
  ReconstructorParams p;
  p.body.footprint = true;
  p.body.multi_projection = false;
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { p.validate(); }, "must agree");
}

// The frames and likelihoods of test_fusion_sim, 16 mm: multi-projection vs footprint levels
// (body median, skin mean, as ReconstructorParams has them).
TEST(FootprintFusion, SimRigIoUWithinTheMultiProjection) {
  sim::SimOptions so;
  so.script = "wave";
  so.empty_frames = 0;
  so.render_masks = true;
  so.short_sleeves = true;
  sim::SimulatedRig rig(so);
  const int n = rig.scriptFrames();
  const std::vector<int> frames = {n / 5, n / 2, 4 * n / 5};
  ProjectionTableOptions mo, fo;
  mo.multi_projection = true;
  fo.footprint_levels = 3;
  const ProjectionTable multi_table(referenceGrid(Resolution::k16mm), rig.rig().cameras, mo);
  const ProjectionTable fp_table(referenceGrid(Resolution::k16mm), rig.rig().cameras, fo);
  const ReconstructorParams defaults;
  std::map<std::string, double> sum;
  for (int f : frames) {
    const sim::SimFrame fr = rig.render(f);
    const sim::Oracle oracle = rig.oracle(f);
    std::vector<uint8_t> person, skin;
    const VoxelGrid& g = multi_table.grid();
    oracle.sampleGrid(g.origin, g.voxel_size, g.dims, &person, &skin);
    for (bool noise : {false, true})
      for (int cls = 0; cls < 2; ++cls) {
        std::vector<ViewImage> views;
        for (size_t c = 0; c < fr.person_masks.size(); ++c)
          views.push_back(ViewImage{test::classifierLikelihood(cls ? fr.skin_masks[c] : fr.person_masks[c], noise,
                                                               1000 * f + c + (cls ? 7919 : 0)),
                                    0, cv::Mat()});
        PsfsOptions o;
        o.occluded_views = cls;  // skin tolerates one occluded view, as in test_fusion_sim
        const std::string key = std::string(cls ? "skin" : "body") + (noise ? " noisy" : " clean");
        ViewEvidence mev, fev;
        mev.set(views, true);
        fev.set(views, false, 0, cls ? defaults.skin_footprint : defaults.body_footprint);
        PsfsOptions om = o, of = o;
        om.multi_projection = true;
        of.footprint = true;
        ProbabilityVolume m, p;
        PsfsFusion(om).fuse(multi_table, mev, &m);
        PsfsFusion(of).fuse(fp_table, fev, &p);
        sum[key + " multi"] += test::occupancyIoU(m, thresholdByte(o.threshold), cls ? skin : person) / frames.size();
        sum[key + " footprint"] += test::occupancyIoU(p, thresholdByte(o.threshold), cls ? skin : person) / frames.size();
      }
  }
  std::printf("simulated rig, 'wave' frames %d %d %d, 16 mm, mean IoU vs oracle (multi-projection | footprint levels):\n",
              frames[0], frames[1], frames[2]);
  for (const char* key : {"body clean", "body noisy", "skin clean", "skin noisy"}) {
    const double m = sum[std::string(key) + " multi"], p = sum[std::string(key) + " footprint"];
    std::printf("  %s: %.4f | %.4f (%+.4f)\n", key, m, p, p - m);
    EXPECT_GE(p, m - 0.01) << key;
  }
}

// The whole pipeline of test_reconstructor (real classifier, background learned from 25 sets,
// 4 frames of the wave script): body and skin IoU, multi-projection vs footprint levels.
TEST(FootprintFusion, PipelineIoUWithinTheMultiProjection) {
  double body[2] = {0, 0}, skin[2] = {0, 0};
  for (int footprint : {0, 1}) {
    sim::SimOptions so;
    so.script = "wave";
    so.empty_frames = 25;
    so.render_masks = true;
    sim::SimulatedRig rig(so);
    ReconstructorParams params;
    params.threads = 2;
    if (footprint) {
      params.body.multi_projection = params.skin.multi_projection = false;
      params.body.footprint = params.skin.footprint = true;
    }
    Reconstructor r(GaussianMixture2D::load(psfs_test::configDir() + "/skin_gmm.yaml"), params);
    for (int f = 0; f < 25; ++f) r.process(rig.render(f).images, rig.rig().cameras);
    ASSERT_TRUE(r.backgroundReady());
    const int n = rig.scriptFrames();
    const std::vector<int> frames = {25 + 5, 25 + (n - 25) / 3, 25 + 2 * (n - 25) / 3, n - 3};
    for (int f : frames) {
      const FrameResult res = r.process(rig.render(f).images, rig.rig().cameras);
      ASSERT_EQ(res.status, FrameResult::Status::kReconstructed);
      std::vector<uint8_t> person, sk;
      const VoxelGrid& g = res.body.grid;
      rig.oracle(f).sampleGrid(g.origin, g.voxel_size, g.dims, &person, &sk);
      body[footprint] += test::occupancyIoU(res.body, thresholdByte(params.body.threshold), person) / frames.size();
      skin[footprint] += test::occupancyIoU(res.skin, thresholdByte(params.skin.threshold), sk) / frames.size();
    }
  }
  std::printf("[ figures  ] pipeline, 4 frames: body IoU %.4f multi-projection | %.4f footprint (%+.4f), "
              "skin IoU %.4f | %.4f (%+.4f)\n",
              body[0], body[1], body[1] - body[0], skin[0], skin[1], skin[1] - skin[0]);
  EXPECT_GE(body[1], body[0] - 0.01);
  EXPECT_GE(skin[1], skin[0] - 0.01);
}

}  // namespace
}  // namespace psfs
