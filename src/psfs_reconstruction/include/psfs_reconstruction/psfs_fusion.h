// Foreground-class probabilistic shape from silhouette (pSfS, thesis 4.2.2-4.2.3): the default
// volume fusion of the pipeline.
//
// With C cameras, per-view posteriors P(G1[c] | c_c) (the likelihood images) and priors, a voxel
// is in the hull iff (4.7)
//     P(G1) * prod_c P(G1[c] | c_c) / P(G1[c])  >  t^C ,   t > 0.5.
// We store the normalised posterior
//     p = ( P(G1) * prod_c P(G1[c] | c_c) / P(G1[c]) )^(1/C)
// (the per-view geometric mean), so the decision is p > t whatever C is, and the meshing stage's
// iso level is t itself. With the priors of the thesis, P(G1) = P(H) and P(G1[c]) = P(H)^(1/C),
// the priors cancel and p is the geometric mean of the likelihoods.
//
// Which views count, per voxel:
//  * a camera that does not see the voxel (centre behind it or outside its image) gives no
//    evidence: it is left out of the product and of C. A camera's field of view is then not a
//    carving tool (a voxel outside one view is not declared empty), and a grid that sticks out
//    of some views is still reconstructed from the others. A voxel seen by fewer than
//    `min_views` cameras is set to 0 (one view alone only gives its viewing cone);
//  * a pixel switched off by the active mask (known occlusion) also gives no evidence;
//  * occlusion tolerance k (active camera flags used as multiple foreground classes, eq. 4.8):
//    of the k lowest per-view likelihoods of the voxel, those below `drop_threshold` are
//    dropped as if that view were switched off.
// Multi-projection test (needed at 16 mm and coarser): the voxel's 6 face centres (+-1/2
// voxel along x, y, z) are projected per camera, each likelihood bilinearly interpolated, and
// the median of the 6 is the camera's observation. Neighbouring voxels share a face, so each
// face is sampled once (ProjectionTable): 3 lookups per voxel and camera instead of 6, for the
// 64x64x48 volume's 2 ms target on 2 cores (see docs/benchmarks.md (bench_fusion)).
// On the simulated rig the hull quality is unchanged within +-0.01 IoU.
// Footprint-filtered evidence (PsfsOptions::footprint; psfs.yaml fusion/*/footprint):
// the footprint statistic comes from evidence images filtered once per frame (ViewEvidence,
// FootprintFilter) and a table that points each voxel at the window of its projected size
// (ProjectionTableOptions::footprint_levels), so fusion is the single-projection kernel, one
// lookup per voxel and camera; docs/benchmarks.md has its cost and quality.
//
// Implementation: log domain in 1/1024 fixed point, so the product over cameras is an integer
// sum. The uint8 -> log-term table is applied once per pixel and frame (ViewEvidence), so the
// single-projection inner loop is one gather and a few adds per voxel and camera; the
// multi-projection median's log is computed by a short series (cheaper than another gather).
// Parallel over grid rows (OpenMP; with multi-projection over slabs of z layers, each walked by
// one thread carrying the shared faces: a grid only a few layers deep gets fewer threads),
// 16 voxels per AVX-512 step or 8 per AVX2 step, scalar fallback with identical results.
// Costs on the reference rig: bench/bench_fusion.cpp. The same bytes on a CUDA device:
// GpuPsfsFusion (gpu_psfs_fusion.h; bench/bench_gpu_fusion.cpp).
//
// Use (e.g. a nodelet): tables once, evidence and fusion per frame.
//   ProjectionTableOptions mp;  mp.multi_projection = true;
//   ProjectionTable body_table(referenceGrid(Resolution::k16mm), cameras, mp);   // stored, 8.7 MB
//   ProjectionTableOptions fly; fly.storage = TableStorage::kOnTheFly;
//   ProjectionTable hand_table(snappedCubeGrid(hand, 0.30, 83), cameras, fly);
//   PsfsOptions o;  o.multi_projection = true;  PsfsFusion body_fusion(o);
//   per frame:  ViewEvidence body;  body.set(views /* channel 0 */, /*bilinear=*/true);
//               body_fusion.fuse(body_table, body, &body_volume);
//               hand_table.update(snappedCubeGrid(hand_now, 0.30, 83), cameras);  // cheap
//               skin_fusion.fuse(hand_table, skin /* channel 1 */, &hand_volume);
#pragma once

#include <limits>
#include <memory>

#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/view_evidence.h"

namespace psfs {

// Priors from expected occupancy (thesis 4.2.2). hull_occupancy = P(H_F), the expected fraction
// of the user space inside the foreground hull. Returns P(F) = P(H_F)^(1/C).
double foregroundViewPrior(double hull_occupancy_foreground, int num_cameras);
// P(S) = P(H)^(1/C) / P(F), with P(H) the expected skin-hull occupancy (<= P(H_F)), so that the
// skin-coloured-foreground view prior P(F) P(S) is P(H)^(1/C).
double skinViewPrior(double hull_occupancy_skin, double hull_occupancy_foreground, int num_cameras);

struct PsfsOptions {
  // t, in (0.5, 1): in hull iff normalised posterior > t. The default separates "all views
  // agree" from "one view confidently disagrees" for 6-8 views whose likelihoods the outlier
  // model bounds to about [0.03, 0.95] (4.2.1): one such dissent gives
  // exp((7 ln 0.95 + ln 0.03) / 8) = 0.62 < 0.75 < 0.95, while a view at 0.3 among views at
  // 0.95 still gives 0.82. A lower t (0.6) keeps voxels that one view rejects (a fatter,
  // occlusion-tolerant hull); use occluded_views for that on purpose. Mesh at the same level
  // (byte iso thresholdByte(t) + 0.5) to get the hull's surface.
  double threshold = 0.75;
  // Priors. hull_prior = P(G1) = P(H) (expected occupancy of this class's hull),
  // view_prior = P(G1[c]), the per-view prior the likelihood images were computed with.
  // Leave both 0 when the classifier used view_prior = P(H)^(1/C) (the design): they cancel.
  // Otherwise each observing view multiplies the posterior by P(H)^(1/C) / view_prior.
  double hull_prior = 0.0;
  double view_prior = 0.0;
  int occluded_views = 0;       // k in [0, 4]
  double drop_threshold = 0.0;  // 0 = threshold
  int min_views = 2;            // >= 1
  bool multi_projection = false;   // needs a table and evidence built for it
  // Footprint-filtered evidence (exclusive with multi_projection): the
  // single-projection kernel reads, per voxel and camera, the evidence filtered over a window
  // matched to the voxel's projected size. Needs a table built with footprint_levels and
  // evidence set with a FootprintFilter of at least as many levels.
  bool footprint = false;
  bool zero_outside_hull = false;  // store 0 instead of the posterior where p <= t
  // Voxels whose centre lies below this height (world z, m) are 0 and not computed. The hand
  // sub-volumes use it for the desk top, which no camera sees below
  // (ReconstructorParams::hand_roi_clip_floor); a hand resting on the desk has 40 % of its
  // cube below it. -infinity: none. On the CPU the single-projection (and footprint) fusion
  // skips those layers, projection included; the multi-projection kernel computes and clears
  // them (it carries the faces from layer to layer). On a GPU no thread below fuses, but an
  // on-the-fly table is still projected whole.
  double floor_z = -std::numeric_limits<double>::infinity();
  // Empty-space skipping (0 = off), in [0, threshold); the footprint path ignores it.
  // Multi-projection test: runs of 8 voxels along x whose
  // voxels a bound of the posterior (from the largest 2x2 minimum of the likelihood in the 8x8
  // pixel tiles around their footprints) puts below this level are not fused but set to the
  // background's posterior (every camera's commonest likelihood, fused: what empty space far
  // from the person is). Every voxel at or above the level (the hull included) keeps its byte;
  // only a structure under 2 px wide in a view could be lost. src/empty_space_bound.h
  // explains the bound; docs/benchmarks.md has the cost and the trackers' figures.
  // Single projection (the hand sub-volumes): a strict bound (the largest likelihood under
  // each 4x4x4 cell in every view) with a margin of two voxels; runs of 8 voxels it puts below
  // the level are set to 0 and not projected. Every voxel at or above the level and every
  // voxel within 2 of one keeps its byte, so a mesh at an iso above the level is the same
  // (src/centre_space_bound.h). Workspace volumes on this path skip the same way (0, not the
  // background's posterior).
  double skip_empty_below = 0.0;
  int threads = 0;                 // OpenMP threads (0 = OpenMP default)
};

namespace detail {
struct EmptySkipCache;
}

class PsfsFusion {
 public:
  // Throws std::invalid_argument for options out of range or not finite.
  explicit PsfsFusion(const PsfsOptions& options = PsfsOptions());
  const PsfsOptions& options() const { return options_; }

  // Fuses one frame into `out` (grid = table.grid(); buffer reused when the size matches).
  // Throws std::invalid_argument if the evidence does not match the table (number of views,
  // image sizes) or lacks what the options need (multi-projection).
  void fuse(const ProjectionTable& table, const ViewEvidence& evidence, ProbabilityVolume* out) const;
  // Fraction of the grid's voxels the last fuse skipped (PsfsOptions::skip_empty_below; 0 without).
  double lastSkippedFraction() const;

 private:
  PsfsOptions options_;
  // The empty-space bound's per-table cells and the last frame's figure (shared by copies,
  // guarded by its mutex: fuse is const and may run on several threads).
  std::shared_ptr<detail::EmptySkipCache> skip_;
};

}  // namespace psfs
