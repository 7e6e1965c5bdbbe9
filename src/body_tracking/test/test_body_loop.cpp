// The closed loop body tracker -> background update (thesis 4.3): the PAPF's silhouettes of
// frame t mask the selective background update of frame t+1, so that a person sitting still is
// not learned into the background and a slowly changing background is still followed.
//
// One stream of the simulated rig ("static" script: the person sits still; it is 3 s long and
// loops, the same pose every frame) is rendered once and fed to several reconstructors in
// lockstep, each with its own background model, masks and (where it needs one) PAPF:
//   still / back-projection  : no masks supplied: the update is masked by the back-projection
//                              of the reconstructor's own body volume (its default);
//   still / PAPF + back-proj : the PAPF's silhouettes (all 9 quadrics, kMarginPx) of the last
//                              frame OR the back-projection of the last frame's body volume
//                              (masks from the previous pose, as a live pipeline has them);
//   drift / ... (both again) : the same on images under a light drift, plus a control
//                              without any background update.
//
// What was measured (this test's setup, default alpha = 0.02, 8 cameras 320x240; recall =
// fraction of the oracle's person voxel centres on the 64x64x48 grid with p > 0.5; "absorbed"
// = rendered person pixels whose P'(F|c) < 0.5, i.e. that the background model explains):
// * Back-projection only: recall stays 1.000 for 300 frames; no in-grid leak. The back-projection
//   is a fixed point: every pixel whose ray meets an occupied voxel is masked, so whatever gets
//   learned cannot carve an occupied voxel. What leaks is the torso OUTSIDE the grid (pelvis at
//   y = -0.48, z = -0.17: the lap below the desk top and the back behind y = -0.5): those
//   person pixels are absorbed within ~20 frames, +3.2 % of all person pixels (7.4 % -> 10.6 %
//   classified background), then the fraction stays flat.
// * PAPF silhouettes ALONE as the masks (not tested here, it is a runaway): they cover 94.8 %
//   of the person's pixels at a 3 px margin (99.2 % at 8 px); the hair, fingers and any arm the
//   estimate misplaces are learned, carved from the volume, the PAPF fits the carved volume and
//   its silhouettes miss more: recall 1.000 -> 0.835 / 0.749 / 0.613 / 0.447 after 50 / 100 /
//   150 / 200 frames (3 px margin; 8 px: 0.999 / 0.998 / 0.920 / 0.913). So the Reconstructor
//   now ORs supplied masks with its own back-projection (reconstructor.h); the loop below also
//   ORs the last frame's back-projection in, as measured.
// * PAPF silhouettes OR back-projection: recall 1.000 for 200 frames (3 px), and the torso
//   outside the grid is kept out of the model: after 100 frames +0.6 % of the person pixels
//   absorbed at 5 px (7.4 -> 8.0 %; +0.8 % at 3 px) against +3.1 % without masks.
// * Light drift (-100 K/s and -1 %/s from 5000 K, so -500 K and -5 % after 100 frames): without
//   any update 34 % of the background outside the masks reads as person and 34850 false voxels
//   appear more than 3 voxels from the person (51 at the start). With the update (either mask)
//   the background outside the masks follows (0.15 % reads as person), but the background
//   inside the masks (the margin and the visual hull's phantom volume around the person, ~35 %
//   of the mask) is frozen and turns "person": 1817 (back-projection) / 1895 (with the
//   silhouettes) far false voxels. That ring depends on the drift accumulated while the person
//   sits there, not on its rate. Recall drops to 0.975 in all three: the person's own colours
//   change under the light, not the model.
// Why the leak needs no larger alpha: an unmasked pixel whose colour jumped by d from the mean
// is absorbed fast, because its variance inflates with it: after n updates its squared
// Mahalanobis distance is (1-a)^(n+1) / (1 - (1-a)^n) (the variance floors are negligible for
// a person's colour), below 4 (2 sigma) once (1-a)^n < 0.8, i.e. n > 0.22 / a = 11 frames at
// a = 0.02. The learning frame count (25) only sets the starting variance, which such a jump
// dwarfs. So 100 frames (4 s) show everything the default alpha does.
// Light drift: SimOptions has no drift of its own (only the scenarios do: "flicker" drifts a
// global gain by 10 %/min, what the classifier's gain compensation is there to divide out; it
// would need a second render pass), so the test multiplies each
// image by the gain of a light whose colour temperature falls from 5000 K at kDriftKelvinPerS
// and whose intensity falls at kDriftGainPerS (applied after the sensor noise, which therefore
// scales by < 10 %; tabletop_sim::colourTemperatureTint gives the tint). A colour drift moves
// normalised rg, which no gain compensation removes.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "body_tracking/body_parts.h"
#include "body_tracking/papf.h"
#include "body_tracking/silhouette_mask.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_sim/lighting.h"
#include "tabletop_sim/simulated_rig.h"

namespace body_tracking {
namespace {

namespace sim = tabletop_sim;

constexpr int kFrames = 100;            // reconstructed frames after the 25 learning ones (4 s)
constexpr int kPrintEvery = 25;
// Margin of the silhouettes (px, 320x240 images). The quadrics are a model, not the person:
// alone they cover 94.8 % of the person's pixels at 3 px, 99.2 % at 8 px (hair, fingers,
// shoulders). OR-ed with the back-projection the margin only has to cover the torso outside
// the grid, which the abdomen cylinder models well: person pixels absorbed over 100 frames
// +0.8 / +0.6 / +0.3 points at 3 / 5 / 8 px, but a wider mask also freezes a wider ring of
// background: under the drift below, false voxels far from the person 1842 / 1895 / 2185.
// 5 px is the middle; the thesis gives no value.
constexpr double kMarginPx = 5.0;
constexpr double kDriftKelvinPerS = -100.0;
constexpr double kDriftGainPerS = -0.01;

struct Loop {
  std::string name;
  bool drift = false, update = true, silhouettes = false;
  std::unique_ptr<psfs::Reconstructor> rec;
  std::unique_ptr<Papf> papf;
  std::vector<cv::Mat> next_masks;  // for the next frame's update (empty: the default)
  // Measurements.
  double recall_min = 1.0, recall_last = 0;
  double absorbed_first = -1, absorbed_last = 0;  // person pixels classified background
  double outside_fg_last = 0;    // non-person pixels outside the update mask classified person
  size_t far_false_first = 0, far_false_last = 0;  // false voxels > 3 voxels from the person
  int tracked = 0;
};

// Oracle voxels dilated by r voxels (26-neighbourhood).
std::vector<uint8_t> dilateVoxels(const std::vector<uint8_t>& in, const psfs::VoxelGrid& g, int r) {
  std::vector<uint8_t> cur = in;
  const Eigen::Vector3i& d = g.dims;
  for (int it = 0; it < r; ++it) {
    std::vector<uint8_t> next = cur;
    for (int z = 0; z < d.z(); ++z)
      for (int y = 0; y < d.y(); ++y)
        for (int x = 0; x < d.x(); ++x) {
          if (!cur[g.index(x, y, z)]) continue;
          for (int dz = std::max(0, z - 1); dz <= std::min(d.z() - 1, z + 1); ++dz)
            for (int dy = std::max(0, y - 1); dy <= std::min(d.y() - 1, y + 1); ++dy)
              for (int dx = std::max(0, x - 1); dx <= std::min(d.x() - 1, x + 1); ++dx)
                next[g.index(dx, dy, dz)] = 1;
        }
    cur.swap(next);
  }
  return cur;
}

TEST(BodyLoop, StillPersonAndLightDriftWithAndWithoutBodyMasks) {
  const auto t0 = std::chrono::steady_clock::now();
  sim::SimOptions o;
  o.script = "static";
  o.empty_frames = 25;
  o.render_masks = true;
  sim::SimulatedRig rig(o);
  const auto& cams = rig.rig().cameras;
  const int nc = static_cast<int>(cams.size());
  const psfs::GaussianMixture2D skin = psfs::GaussianMixture2D::load(BODY_TRACKING_SKIN_MODEL);
  std::vector<SilhouetteProjector> projectors;
  for (const auto& c : cams) projectors.emplace_back(c);

  std::vector<Loop> loops;
  auto add = [&](const std::string& name, bool drift, bool update, bool silhouettes) {
    Loop l;
    l.name = name;
    l.drift = drift;
    l.update = update;
    l.silhouettes = silhouettes;
    psfs::ReconstructorParams rp;
    rp.threads = 2;
    rp.update_background = update;
    l.rec = std::make_unique<psfs::Reconstructor>(skin, rp);
    if (silhouettes) {
      PapfParams pp;
      pp.seed = 3;
      pp.threads = 2;
      l.papf = std::make_unique<Papf>(BodyProfile(), pp);
    }
    loops.push_back(std::move(l));
  };
  add("still, back-projection", false, true, false);
  add("still, PAPF + back-proj", false, true, true);
  add("drift, back-projection", true, true, false);
  add("drift, PAPF + back-proj", true, true, true);
  add("drift, no update", true, false, false);
  Loop& still_bp = loops[0];
  Loop& still_papf = loops[1];
  Loop& drift_bp = loops[2];
  Loop& drift_papf = loops[3];
  Loop& drift_none = loops[4];

  std::vector<uint8_t> truth, near;
  size_t n_truth = 0;
  int k = 0;
  for (int i = 0; k < kFrames; ++i) {
    const sim::SimFrame f = rig.render(i);
    const Eigen::Vector3d g = sim::colourTemperatureTint(5000.0 + kDriftKelvinPerS * f.time) *
                              (1.0 + kDriftGainPerS * f.time);
    std::vector<cv::Mat> drifted(nc);
    for (int c = 0; c < nc; ++c) cv::multiply(f.images[c], cv::Scalar(g.x(), g.y(), g.z()), drifted[c]);
    bool reconstructed = false;
    for (Loop& l : loops) {
      const psfs::FrameResult r =
          l.rec->process(l.drift ? drifted : f.images, cams, {}, l.next_masks);
      if (r.status != psfs::FrameResult::Status::kReconstructed) continue;
      reconstructed = true;
      const psfs::VoxelGrid& grid = r.body.grid;
      if (truth.empty()) {  // the person does not move: one oracle for the whole stream
        ASSERT_TRUE(f.truth.person_present);
        rig.oracle(i).sampleGrid(grid.origin, grid.voxel_size, grid.dims, &truth, nullptr, 2);
        for (uint8_t v : truth) n_truth += v;
        near = dilateVoxels(truth, grid, 3);
        ASSERT_GT(n_truth, 1000u);
      }
      size_t hit = 0, false_voxels = 0, far_false = 0;
      for (size_t v = 0; v < truth.size(); ++v) {
        if (r.body.data[v] <= 127) continue;  // p <= 0.5
        if (truth[v]) ++hit;
        else ++false_voxels;
        if (!near[v]) ++far_false;
      }
      l.recall_last = static_cast<double>(hit) / n_truth;
      l.recall_min = std::min(l.recall_min, l.recall_last);
      l.far_false_last = far_false;
      if (k == 0) l.far_false_first = far_false;

      // The masks for the next frame's update.
      const std::vector<cv::Mat> used_masks = std::move(l.next_masks);
      l.next_masks.clear();
      std::vector<cv::Mat> back_projection;
      if (l.silhouettes || k % kPrintEvery == 0 || k == kFrames - 1)
        back_projection = l.rec->backProject(r.body, psfs::thresholdByte(l.rec->params().body.threshold),
                                             l.rec->params().mask_margin_px);
      if (l.silhouettes) {
        const BodyEstimate& e = l.papf->update(r.body, &r.skin);
        if (e.tracking) {
          ++l.tracked;
          const BodyParts parts = buildParts(l.papf->profile(), e.state);
          l.next_masks.resize(nc);
          for (int c = 0; c < nc; ++c) {
            projectors[c].draw(parts, kMarginPx, &l.next_masks[c]);
            cv::bitwise_or(l.next_masks[c], back_projection[c], l.next_masks[c]);
          }
        }
      }
      if (k % kPrintEvery != 0 && k != kFrames - 1) continue;
      // Pixel statistics against the rendered person masks. The mask this frame's update used:
      // the one supplied (made last frame), else this frame's back-projection (which is what
      // the reconstructor drew itself).
      size_t person = 0, absorbed = 0, outside = 0, outside_fg = 0;
      for (int c = 0; c < nc; ++c) {
        const cv::Mat& used = used_masks.empty() ? back_projection[c] : used_masks[c];
        const cv::Mat& pm = f.person_masks[c];
        const cv::Mat& lk = l.rec->lastLikelihoods()[c];
        for (int y = 0; y < pm.rows; ++y)
          for (int x = 0; x < pm.cols; ++x) {
            const bool fg = lk.at<cv::Vec2b>(y, x)[0] >= 128;  // P'(F|c) >= 0.5
            if (pm.at<uint8_t>(y, x)) {
              ++person;
              absorbed += !fg;
            } else if (!used.at<uint8_t>(y, x)) {
              ++outside;
              outside_fg += fg;
            }
          }
      }
      l.absorbed_last = static_cast<double>(absorbed) / person;
      if (l.absorbed_first < 0) l.absorbed_first = l.absorbed_last;
      l.outside_fg_last = static_cast<double>(outside_fg) / outside;
      std::printf("[ loop     ] %-24s frame %3d: recall %.3f, false voxels %5zu (%4zu far), person "
                  "pixels absorbed %.3f, background outside the mask seen as person %.4f\n",
                  l.name.c_str(), k, l.recall_last, false_voxels, far_false, l.absorbed_last,
                  l.outside_fg_last);
    }
    if (reconstructed) ++k;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[ loop     ] %d frames after 25 learning ones, 5 loops, in %.1f s\n", k, seconds);
  for (const Loop& l : loops)
    std::printf("[ loop     ] %-24s recall min %.3f last %.3f; absorbed %.3f -> %.3f; far false voxels "
                "%zu -> %zu; outside fg %.4f; tracked %d\n", l.name.c_str(), l.recall_min,
                l.recall_last, l.absorbed_first, l.absorbed_last, l.far_false_first,
                l.far_false_last, l.outside_fg_last, l.tracked);
  std::printf("[ loop     ] not run: the PAPF silhouettes alone as the masks (a runaway: recall "
              "0.749 after 100 frames at 3 px, see the comment at the top)\n");
  ASSERT_EQ(k, kFrames);

  // A person sitting still, without masks: the in-grid volume does not leak (the
  // back-projection is a fixed point), but the torso outside the grid is learned.
  EXPECT_GE(still_bp.recall_min, 0.98);                                   // measured 0.999
  const double torso_leak = still_bp.absorbed_last - still_bp.absorbed_first;
  EXPECT_GE(torso_leak, 0.02) << "no torso leak without masks any more: revisit this test";  // 0.031
  EXPECT_LE(still_bp.far_false_last, still_bp.far_false_first + 50);     // 50 -> 50
  // With the PAPF's silhouettes: the same recall, and most of the torso kept out of the model.
  EXPECT_EQ(still_papf.tracked, kFrames);
  EXPECT_GE(still_papf.recall_min, 0.98);                                 // 0.999
  EXPECT_LE(still_papf.absorbed_last - still_papf.absorbed_first, 0.5 * torso_leak);  // 0.006
  EXPECT_LE(still_papf.far_false_last, still_papf.far_false_first + 50);  // 50 -> 50

  // The drift is strong enough to matter: without updates a third of the background reads as
  // person after 5 s (-500 K, -5 %) and phantom voxels fill the workspace.
  EXPECT_GE(drift_none.outside_fg_last, 0.1);                             // 0.336
  EXPECT_GE(drift_none.far_false_last, 10000u);                           // 34850
  // With the update, with and without masks, the background outside the masks follows the
  // light. Inside the masks it cannot (the ring of background around the person is frozen
  // while the person sits there, however slow the drift), and that ring does leak into the
  // volume: far false voxels 51 -> ~1850, 5 % of the no-update count.
  for (const Loop* l : {&drift_bp, &drift_papf}) {
    EXPECT_LE(l->outside_fg_last, 0.005) << l->name;                      // 0.0015
    EXPECT_LE(static_cast<double>(l->far_false_last), 0.15 * drift_none.far_false_last)
        << l->name;                                                       // 0.052, 0.054
    EXPECT_GE(l->recall_min, 0.95) << l->name;                            // 0.975
  }
  EXPECT_EQ(drift_papf.tracked, kFrames);
}

}  // namespace
}  // namespace body_tracking
