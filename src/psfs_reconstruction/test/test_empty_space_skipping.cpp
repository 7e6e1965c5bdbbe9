// Empty-space skipping in the multi-projection pSfS (PsfsOptions::skip_empty_below, issue 17):
// every skipped voxel is one whose posterior without skipping lies below the level, every
// other voxel is the same byte, on the simulated rig's frames (synthetic classifier-like
// likelihoods and the real pipeline), with occlusion tolerance, masked views, on-the-fly tables
// and any thread count. The figures printed are the skipped share of the grid's voxels.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>

#include "../src/empty_space_bound.h"
#include "../src/psfs_kernels.h"
#include "expect_throw.h"
#include "gpu_fusion_cases.h"
#include "pipeline_frames.h"
#include "fusion_test_utils.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/reconstructor.h"
#include "psfs_reconstruction/simd_dispatch.h"
#include "tabletop_sim/simulated_rig.h"
#include "test_data_path.h"

namespace psfs {
namespace {

namespace sim = tabletop_sim;

// The chunks a skipping fusion with options o leaves out on this evidence, with the bound's
// cache (its fill) as the fusion derives them.
std::vector<uint8_t> skippedFlags(const ProjectionTable& table, const ViewEvidence& ev, const PsfsOptions& o,
                                  detail::EmptySkipCache* cache) {
  detail::tileMaxImages(ev, 1, &cache->tiles);
  std::vector<uint8_t> flags;
  detail::skippedChunks(o, table, cache, &flags);
  return flags;
}

// The rule, exactly: the chunks (8 voxels of a row) the bound skips hold its fill (0 where a
// voxel has fewer than min_views cameras), and each of their voxels was at most the level's
// byte without skipping (the bound's soundness); every other voxel is the full fusion's byte.
// Returns the voxels that differ from the full fusion.
size_t expectSkippingRule(const ProjectionTable& table, const ViewEvidence& ev, const PsfsOptions& skipping,
                          const ProbabilityVolume& full, const ProbabilityVolume& skipped, const std::string& what) {
  EXPECT_EQ(full.data.size(), skipped.data.size()) << what;
  if (full.data.size() != skipped.data.size()) return 0;
  detail::EmptySkipCache cache;
  const std::vector<uint8_t> flags = skippedFlags(table, ev, skipping, &cache);
  const size_t nx = size_t(table.grid().dims.x()), chunks = size_t(table.chunksPerRow());
  // A posterior below the level rounds to at most this byte (the exp table rounds to nearest).
  const int level_byte = int(skipping.skip_empty_below * 255.0 + 0.5);
  std::vector<uint8_t> fill_row(nx);
  size_t changed = 0, bad_computed = 0, bad_fill = 0, unsound = 0;
  for (size_t r = 0; r < table.grid().numRows(); ++r) {
    const uint8_t* a = full.data.data() + r * nx;
    const uint8_t* b = skipped.data.data() + r * nx;
    const uint8_t* f = &flags[r * chunks];
    std::fill(fill_row.begin(), fill_row.end(), uint8_t(0));
    cache.bound.fillChunks(r, f, cache.fill, skipping.min_views, cache.absent, fill_row.data());
    for (size_t x = 0; x < nx; ++x) {
      changed += a[x] != b[x];
      if (!f[x / ProjectionTable::kChunk]) {
        if (a[x] != b[x] && ++bad_computed <= 3)
          ADD_FAILURE() << what << ": computed voxel " << x << " of row " << r << " differs";
        continue;
      }
      if (fill_row[x] != b[x] && ++bad_fill <= 3)
        ADD_FAILURE() << what << ": skipped voxel " << x << " of row " << r << " is not the fill " << int(cache.fill);
      if (a[x] > level_byte && ++unsound <= 3)
        ADD_FAILURE() << what << ": skipped voxel " << r * nx + x << " was " << int(a[x]) << " (level byte "
                      << level_byte << ")";
    }
  }
  EXPECT_EQ(bad_computed, 0u) << what;
  EXPECT_EQ(bad_fill, 0u) << what;
  EXPECT_EQ(unsound, 0u) << what;
  return changed;
}

struct SimViews {
  std::vector<std::vector<ViewImage>> frames[2];  // [class][frame]
  std::vector<tabletop_capture::CameraModel> cameras;
};

// Three frames of 'wave' with short sleeves as the GPU fusion tests have them (gpu_fusion_cases.h:
// the renderer's masks as classifier-like likelihoods with noise and outliers, CV_8UC2 with
// channel 0 body and 1 skin).
const SimViews& simViews() {
  static const SimViews v = [] {
    SimViews s;
    const int n = gpu_test::simRig().scriptFrames();
    for (int f : {n / 5, n / 2, 4 * n / 5}) {
      const gpu_test::SimScene scene = gpu_test::simScene(f, /*inactive=*/false);
      s.cameras = scene.cameras;
      for (int cls = 0; cls < 2; ++cls) s.frames[cls].push_back(scene.views(cls));
    }
    return s;
  }();
  return v;
}

TEST(EmptySpaceSkipping, SkipsOnlyVoxelsBelowTheLevelAndLeavesTheRestByteForByte) {
  const SimViews& s = simViews();
  ProjectionTableOptions to;
  to.multi_projection = true;
  const ProjectionTable table(referenceGrid(Resolution::k16mm), s.cameras, to);
  ProjectionTableOptions fly = to;
  fly.storage = TableStorage::kOnTheFly;
  const ProjectionTable fly_table(referenceGrid(Resolution::k16mm), s.cameras, fly);
  for (int cls = 0; cls < 2; ++cls)
    for (double level : {0.1, 0.3, 0.5})
      for (int threads : {1, 2, 3}) {
        PsfsOptions o;
        o.multi_projection = true;
        o.occluded_views = cls;  // skin tolerates a view, as the pipeline's
        o.threads = threads;
        PsfsOptions os = o;
        os.skip_empty_below = level;
        const PsfsFusion full(o), skipping(os);
        double skipped = 0;
        for (size_t f = 0; f < s.frames[cls].size(); ++f) {
          ViewEvidence ev;
          ev.set(s.frames[cls][f], true);
          ProbabilityVolume a, b, c;
          full.fuse(table, ev, &a);
          skipping.fuse(table, ev, &b);
          skipped += skipping.lastSkippedFraction() / s.frames[cls].size();
          const std::string what = std::string(cls ? "skin" : "body") + " level " + std::to_string(level) +
                                   " threads " + std::to_string(threads) + " frame " + std::to_string(f);
          expectSkippingRule(table, ev, os, a, b, what);
          skipping.fuse(fly_table, ev, &c);  // the on-the-fly table: the same bytes
          EXPECT_EQ(b.data, c.data) << what << " (on-the-fly table)";
        }
        if (threads == 1)
          std::printf("[ figures  ] %s, level %.1f: %.0f %% of the voxels skipped\n", cls ? "skin" : "body", level,
                      100.0 * skipped);
        // The bound is not vacuous: most of the workspace is empty in the default rig's views
        // (these likelihoods' background is 0.1-0.2, above the lower levels).
        if (level == 0.5) {
          EXPECT_GT(skipped, 0.3) << (cls ? "skin" : "body");
        }
      }
}

// The shapes of the spans the fusion computes (forEachFaceRow): rows partly skipped, spans that
// start inside a row (x carried from plusXFaces), spans of an odd number of chunks that end
// inside a row (the 16-lane kernels' half step away from the padding).
struct SpanShapes {
  size_t partial_rows = 0, inner_starts = 0, odd_inner_ends = 0;
};
SpanShapes spanShapes(const ProjectionTable& table, const PsfsOptions& skipping, const ViewEvidence& ev) {
  detail::EmptySkipCache cache;
  const std::vector<uint8_t> flags = skippedFlags(table, ev, skipping, &cache);
  const size_t chunks = size_t(table.chunksPerRow());
  SpanShapes n;
  for (size_t r = 0; r < table.grid().numRows(); ++r) {
    const uint8_t* f = &flags[r * chunks];
    const size_t flagged = size_t(std::count(f, f + chunks, uint8_t(1)));
    if (flagged == 0 || flagged == chunks) continue;
    ++n.partial_rows;
    for (size_t a = 0; a < chunks;) {
      if (f[a]) { ++a; continue; }
      size_t b = a + 1;
      while (b < chunks && !f[b]) ++b;
      n.inner_starts += a > 0;
      n.odd_inner_ends += b < chunks && (b - a) % 2 == 1;
      a = b;
    }
  }
  return n;
}

// Every face kernel (the reference, every Highway target this CPU runs, the default selection)
// computes spans of a row and re-samples the carried faces the same way after a skipped chunk
// (plusFacesOfRow's Highway and portable branches through the switches); a grid whose
// sides are not multiples of the cell or the kernels' vectors; the layers under a floor (0
// whatever is skipped); stored and on-the-fly tables.
TEST(EmptySpaceSkipping, EveryKernelOddGridsAndAFloor) {
  const SimViews& s = simViews();
  VoxelGrid odd = referenceGrid(Resolution::k16mm);
  odd.dims = Eigen::Vector3i(61, 59, 45);
  ProjectionTableOptions to;
  to.multi_projection = true;
  ProjectionTableOptions fly = to;
  fly.storage = TableStorage::kOnTheFly;
  // -1: the reference, -2: the default selection, > 0: a Highway target.
  std::vector<int64_t> kernels = {-1, -2};
  for (int64_t t : detail::hwyRowTargets()) kernels.push_back(t);
  for (const VoxelGrid& g : {referenceGrid(Resolution::k16mm), odd}) {
    const ProjectionTable table(g, s.cameras, to), fly_table(g, s.cameras, fly);
    ViewEvidence ev;
    ev.set(s.frames[0][1], true);
    PsfsOptions os;
    os.multi_projection = true;
    os.skip_empty_below = 0.5;
    // The rule below is only worth as much as the shapes it meets.
    const SpanShapes n = spanShapes(table, os, ev);
    std::printf("[ figures  ] %s: %zu rows partly skipped, %zu spans start inside a row, %zu odd spans end inside one\n",
                g.describe().c_str(), n.partial_rows, n.inner_starts, n.odd_inner_ends);
    EXPECT_GT(n.partial_rows, 100u) << g.describe();
    EXPECT_GT(n.inner_starts, 100u) << g.describe();
    EXPECT_GT(n.odd_inner_ends, 10u) << g.describe();
    // The reference's skipping bytes (faceRowScalar, plusFacesOfRow's portable branch) per floor.
    std::vector<ProbabilityVolume> ref(2);
    for (int f = 0; f < 2; ++f) {
      detail::forceFaceRowKernelForTest(-1);
      forceScalarKernels(true);
      PsfsOptions osf = os;
      osf.floor_z = f == 0 ? -std::numeric_limits<double>::infinity() : 0.1;
      osf.threads = 2;
      PsfsFusion(osf).fuse(table, ev, &ref[size_t(f)]);
      forceScalarKernels(false);
      detail::forceFaceRowKernelForTest(0);
    }
    for (int64_t kernel : kernels)
      for (int mode : {0, 1, 2}) {  // the CPU's best, the AVX2 switch, the scalar switch
        const bool avx2 = mode == 1, scalar = mode == 2;
        if (avx2 && kernel != -2) continue;  // the switch changes the default selection only
        if (scalar && kernel != -1) continue;  // the reference with plusFacesOfRow's portable branch
        for (double floor_z : {-std::numeric_limits<double>::infinity(), 0.1}) {
          detail::forceFaceRowKernelForTest(kernel);
          forceAvx2Kernels(avx2);
          forceScalarKernels(scalar);
          PsfsOptions o;
          o.multi_projection = true;
          o.floor_z = floor_z;
          o.threads = 2;
          PsfsOptions osf = os;
          osf.floor_z = floor_z;
          osf.threads = 2;
          ProbabilityVolume a, b, c;
          PsfsFusion(o).fuse(table, ev, &a);
          PsfsFusion(osf).fuse(table, ev, &b);
          const std::string what = g.describe() + " kernel " + std::to_string(kernel) + (avx2 ? " (AVX2)" : "") +
                                   (scalar ? " (scalar)" : "") +
                                   " floor " + std::to_string(floor_z);
          expectSkippingRule(table, ev, osf, a, b, what);
          EXPECT_EQ(b.data, ref[floor_z > 0.0 ? 1 : 0].data) << what << " (against the reference's)";
          if (kernel == -1 || avx2) {
            PsfsFusion(osf).fuse(fly_table, ev, &c);
            EXPECT_EQ(b.data, c.data) << what << " (on-the-fly table)";
          }
        }
      }
    forceAvx2Kernels(false);
    forceScalarKernels(false);
    detail::forceFaceRowKernelForTest(0);
  }
}

// A camera switched off as a whole (dark, missing) observes nothing: it neither blocks the
// skipping nor counts as a view.
TEST(EmptySpaceSkipping, AViewSwitchedOffAsAWholeIsLeftOut) {
  const SimViews& s = simViews();
  ProjectionTableOptions to;
  to.multi_projection = true;
  const ProjectionTable table(referenceGrid(Resolution::k16mm), s.cameras, to);
  std::vector<ViewImage> views = s.frames[0][1];
  views[2].active = cv::Mat::zeros(views[2].likelihood.size(), CV_8UC1);
  ViewEvidence ev;
  ev.set(views, true);
  PsfsOptions o;
  o.multi_projection = true;
  PsfsOptions os = o;
  os.skip_empty_below = 0.5;
  const PsfsFusion skipping(os);
  ProbabilityVolume a, b;
  PsfsFusion(o).fuse(table, ev, &a);
  skipping.fuse(table, ev, &b);
  expectSkippingRule(table, ev, os, a, b, "camera 2 off");
  EXPECT_GT(skipping.lastSkippedFraction(), 0.3);
}

// The GPU paths fuse every voxel and then fill the chunks PsfsFusion skips, with the bounds taken
// from the host's views (likelihood channel and masks) instead of the evidence: the same bytes.
TEST(EmptySpaceSkipping, FillingAFullFusionGivesTheSkippingFusionsBytes) {
  const SimViews& s = simViews();
  ProjectionTableOptions to;
  to.multi_projection = true;
  const ProjectionTable table(referenceGrid(Resolution::k16mm), s.cameras, to);
  for (int cls = 0; cls < 2; ++cls) {
    std::vector<ViewImage> views = s.frames[cls][2];
    views[1].active = cv::Mat(views[1].likelihood.size(), CV_8UC1, cv::Scalar(1));
    views[1].active(cv::Rect(10, 20, 60, 50)).setTo(0);  // part of a view masked
    views[4].active = cv::Mat::zeros(views[4].likelihood.size(), CV_8UC1);  // a view off
    ViewEvidence ev;
    ev.set(views, true);
    PsfsOptions o;
    o.multi_projection = true;
    o.occluded_views = cls;
    PsfsOptions os = o;
    os.skip_empty_below = 0.5;
    ProbabilityVolume full, skipped;
    PsfsFusion(o).fuse(table, ev, &full);
    PsfsFusion(os).fuse(table, ev, &skipped);
    detail::EmptySkipCache cache;
    detail::tileMaxImages(views, 1, &cache.tiles);  // the classifier's two-channel images
    detail::fillSkipped(os, table, &cache, &full);
    EXPECT_EQ(full.data, skipped.data) << (cls ? "skin" : "body");
    EXPECT_GT(cache.last_fraction, 0.2) << (cls ? "skin" : "body");
  }
}

// The tiles against brute force: per 8x8 tile the bound of the largest 2x2 minimum (the right
// and lower neighbours replicated at the border), the squares of 2 and 4 tiles, inactive tiles
// and the commonest byte (every 4th row), on images whose sides are not multiples of a tile or
// a vector, with and without a mask; and the largest bound over every rectangle of tiles.
TEST(EmptySpaceSkipping, TileMaxImagesMatchBruteForce) {
  // The bound of byte b: a constant image's only tile.
  std::vector<int32_t> term(256);
  for (int b = 0; b < 256; ++b) {
    const std::vector<uint8_t> flat(64, uint8_t(b));
    detail::TileMaxImage t;
    t.set(flat.data(), 8, 8, 8, cv::Mat());
    term[size_t(b)] = t.bound[0][0];
  }
  EXPECT_LT(term[10], term[200]);
  cv::RNG rng(17);
  for (const cv::Size size : {cv::Size(320, 240), cv::Size(37, 29), cv::Size(41, 9), cv::Size(8, 8), cv::Size(3, 2)})
    for (bool masked : {false, true}) {
      const int w = size.width, h = size.height;
      const size_t stride = size_t(w) + 5;
      std::vector<uint8_t> img(stride * h);
      for (int v = 0; v < h; ++v)
        for (int u = 0; u < w; ++u)  // a background byte with bright blobs and noise
          img[size_t(v) * stride + u] = uint8_t(rng.uniform(0, 8) == 0 ? rng.uniform(0, 256) : 40 + rng.uniform(0, 3));
      cv::Mat active;
      std::vector<int16_t> terms;  // the evidence's form of the same switched-off pixel
      if (masked) {
        active = cv::Mat(h, w, CV_8UC1, cv::Scalar(255));
        active.at<uint8_t>(h / 2, w / 3) = 0;
        terms.assign(size_t(w) * h, int16_t(-5));
        terms[size_t(h / 2) * w + w / 3] = 1;
      }
      detail::TileMaxImage t, by_terms;
      t.set(img.data(), w, h, stride, active);
      if (masked) {  // terms index rows of width w: the same bytes without the stride's gap
        std::vector<uint8_t> packed(size_t(w) * h);
        for (int v = 0; v < h; ++v) std::copy_n(&img[size_t(v) * stride], w, &packed[size_t(v) * w]);
        by_terms.set(packed.data(), w, h, size_t(w), cv::Mat(), terms.data());
      }
      const std::string what = std::to_string(w) + "x" + std::to_string(h) + (masked ? " masked" : "");
      ASSERT_EQ(t.tiles_x, (w + 7) / 8) << what;
      ASSERT_EQ(t.tiles_y, (h + 7) / 8) << what;
      auto px = [&](int u, int v) { return img[size_t(std::min(v, h - 1)) * stride + std::min(u, w - 1)]; };
      std::vector<int32_t> expect(size_t(t.tiles_x) * t.tiles_y);
      for (int ty = 0; ty < t.tiles_y; ++ty)
        for (int tx = 0; tx < t.tiles_x; ++tx) {
          int m = 0;
          bool off = false;
          for (int v = ty * 8; v < std::min(h, ty * 8 + 8); ++v)
            for (int u = tx * 8; u < std::min(w, tx * 8 + 8); ++u) {
              m = std::max<int>(m, std::min({px(u, v), px(u + 1, v), px(u, v + 1), px(u + 1, v + 1)}));
              off |= masked && active.at<uint8_t>(v, u) == 0;
            }
          expect[size_t(ty) * t.tiles_x + tx] = off ? detail::TileMaxImage::kInactive : term[size_t(m)];
        }
      EXPECT_EQ(t.bound[0], expect) << what;
      if (masked) {
        for (int l = 0; l < detail::TileMaxImage::kLevels; ++l)
          EXPECT_EQ(by_terms.bound[l], t.bound[l]) << what << " through the terms, level " << l;
        EXPECT_EQ(by_terms.mode, t.mode) << what;
      }
      for (int l = 1; l < detail::TileMaxImage::kLevels; ++l)
        for (int ty = 0; ty < t.tiles_y; ++ty)
          for (int tx = 0; tx < t.tiles_x; ++tx) {
            const int s = 1 << l;
            int32_t m = std::numeric_limits<int32_t>::min();
            for (int y = ty; y < std::min(t.tiles_y, ty + s); ++y)
              for (int x = tx; x < std::min(t.tiles_x, tx + s); ++x) m = std::max(m, expect[size_t(y) * t.tiles_x + x]);
            ASSERT_EQ(t.bound[l][size_t(ty) * t.tiles_x + tx], m) << what << " level " << l << " tile " << tx << "," << ty;
          }
      // Every rectangle of tiles (tile_squares.h's walk over the squares): the largest bound of
      // the tiles it covers.
      for (int ty0 = 0; ty0 < t.tiles_y; ++ty0)
        for (int ty1 = ty0; ty1 < t.tiles_y; ++ty1)
          for (int tx0 = 0; tx0 < t.tiles_x; ++tx0)
            for (int tx1 = tx0; tx1 < t.tiles_x; ++tx1) {
              int32_t m = std::numeric_limits<int32_t>::min();
              for (int y = ty0; y <= ty1; ++y)
                for (int x = tx0; x <= tx1; ++x) m = std::max(m, expect[size_t(y) * t.tiles_x + x]);
              ASSERT_EQ(t.rectMax(tx0, ty0, tx1, ty1), m)
                  << what << " tiles " << tx0 << ".." << tx1 << " x " << ty0 << ".." << ty1;
            }
      std::vector<int> histogram(256, 0);
      for (int v = 0; v < h; v += 4)
        for (int u = 0; u < w; ++u) ++histogram[px(u, v)];
      EXPECT_EQ(int(t.mode), int(std::max_element(histogram.begin(), histogram.end()) - histogram.begin())) << what;
      EXPECT_FALSE(t.absent) << what;
    }
}

// boundBelow against the rule it implements, by brute force: for every count j of the cameras
// that see only part of a cell (their j largest bounds), every voxel with n = all + j >= min_views
// views keeps its n - min(k, n - 1) largest bounds, and their sum must stay below kept * limit.
TEST(EmptySpaceSkipping, BoundBelowMatchesBruteForce) {
  cv::RNG rng(5);
  size_t below = 0, cases = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const int n_all = rng.uniform(0, 9), n_some = rng.uniform(0, 5);
    std::vector<int32_t> all(size_t(n_all) + 1), some(size_t(n_some) + 1);
    for (int32_t& b : all) b = -rng.uniform(0, 4000);
    for (int32_t& b : some) b = -rng.uniform(0, 4000);
    detail::PsfsRowParams p;
    p.min_views = rng.uniform(1, 4);
    const int k = rng.uniform(0, 5);
    const int32_t limit = -rng.uniform(0, 2500);
    bool expect = true;
    std::vector<int32_t> sorted_some(some.begin(), some.begin() + n_some);
    std::sort(sorted_some.begin(), sorted_some.end(), std::greater<int32_t>());
    for (int j = 0; j <= n_some; ++j) {
      const int n = n_all + j;
      if (n < p.min_views) continue;
      std::vector<int32_t> v(all.begin(), all.begin() + n_all);
      v.insert(v.end(), sorted_some.begin(), sorted_some.begin() + j);
      std::sort(v.begin(), v.end(), std::greater<int32_t>());
      const int kept = n - std::min(k, n - 1);
      int64_t sum = 0;
      for (int i = 0; i < kept; ++i) sum += v[size_t(i)];
      if (sum >= int64_t(kept) * limit) expect = false;
    }
    const bool got = detail::boundBelow(all.data(), n_all, some.data(), n_some, p, k, limit);
    ASSERT_EQ(got, expect) << "trial " << trial << ": " << n_all << " all, " << n_some << " some, k " << k
                           << ", min_views " << p.min_views << ", limit " << limit;
    below += got;
    ++cases;
  }
  // Both answers occur often enough for the comparison to mean something.
  EXPECT_GT(below, cases / 10);
  EXPECT_LT(below, cases - cases / 10);
}

TEST(EmptySpaceSkipping, RejectsLevelsThatCouldTouchTheHull) {
  PsfsOptions o;
  o.multi_projection = true;
  for (double bad : {-0.1, 0.75, 0.9, std::nan("")}) {
    o.skip_empty_below = bad;
    psfs_test::expectThrowContaining<std::invalid_argument>([&] { PsfsFusion f(o); }, "skip_empty_below");
  }
  // The single-projection path takes it too (its own bound: test_hand_space_skipping).
  o.multi_projection = false;
  o.skip_empty_below = 0.3;
  EXPECT_NO_THROW(PsfsFusion f(o));
  // The hand sub-volumes refuse this bound (it is derived once per table, and their cube moves
  // every frame).
  ReconstructorParams p;
  p.hand.multi_projection = true;
  p.hand.skip_empty_below = 0.3;
  psfs_test::expectThrowContaining<std::invalid_argument>([&] { p.validate(); }, "hand.skip_empty_below");
}

// The real pipeline (classifier, background learned from 25 sets), 4 frames of 'wave': body
// and skin with the skipping of `level` against none.
TEST(EmptySpaceSkipping, PipelineVolumesKeepEveryVoxelAboveTheLevel) {
  const double level = 0.5;
  std::vector<FrameResult> results[2];
  for (int skip : {0, 1}) {
    ReconstructorParams params;
    params.threads = 2;
    params.body.skip_empty_below = params.skin.skip_empty_below = skip ? level : 0.0;  // the default skips
    results[skip] = psfs_test::pipelineFrames(params, false);
    ASSERT_EQ(results[skip].size(), 4u);
  }
  // The Reconstructor's evidence is its own: here the rule's weaker half, voxel by voxel.
  const int level_byte = int(level * 255.0 + 0.5);
  size_t changed = 0, voxels = 0, bad = 0;
  for (size_t i = 0; i < results[0].size(); ++i)
    for (int kind = 0; kind < 2; ++kind) {
      const ProbabilityVolume& a = kind ? results[0][i].skin : results[0][i].body;
      const ProbabilityVolume& b = kind ? results[1][i].skin : results[1][i].body;
      ASSERT_EQ(a.data.size(), b.data.size());
      for (size_t v = 0; v < a.data.size(); ++v) {
        if (a.data[v] == b.data[v]) continue;
        ++changed;
        if ((a.data[v] > level_byte || b.data[v] > level_byte) && ++bad <= 5)
          ADD_FAILURE() << (kind ? "skin" : "body") << " frame " << i << " voxel " << v << ": " << int(a.data[v])
                        << " -> " << int(b.data[v]);
      }
      voxels += a.data.size();
    }
  EXPECT_EQ(bad, 0u);
  std::printf("[ figures  ] pipeline, 4 frames, level %.2f: %.1f %% of the voxels changed (to the fill)\n", level,
              100.0 * double(changed) / double(voxels));
}

}  // namespace
}  // namespace psfs
