// All-classes pSfS (thesis 4.2.2, eq. 4.4-4.6, 4.8): the reference the foreground-class variant
// is checked against. Every voxel is assigned the most probable of the 2^C super classes G_n
// (each camera either sees class phi or background beta):
//     G_m = arg max_n P(G_n) * prod_c P(G_n[c] | c_c) / P(G_n[c]),
// with P(G_n) = prod_c P(G_n[c]) (phi: P(H)^(1/C), beta: 1 - P(H)^(1/C)) and P(G_n[c]) the
// per-view prior the likelihood images were computed with. The voxel is in the hull iff the
// winner is a hull class: at most `occluded_views` cameras see beta (eq. 4.8 with k = 1), and,
// if `threshold` > 0, the normalised hull posterior P(H | c_1..c_C)^(1/C) exceeds it (the
// threshold the thesis added for its comparison, 7.3).
//
// Exponential cost (2^C per voxel, explicit enumeration on purpose): fine for C <= 8 on small
// grids; limited to 16 observing cameras. Same view rules as PsfsFusion (unobserved voxels and
// switched-off pixels give no evidence; min_views).
#pragma once

#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/view_evidence.h"

namespace psfs {

struct AllClassesOptions {
  double hull_prior = 0.0;   // P(H); 0 = consistent with view_prior (priors cancel)
  double view_prior = 0.0;   // P(G1[c]) of the likelihood images; 0 = P(H)^(1/C)
  int occluded_views = 0;    // hull classes have at most this many beta views
  double threshold = 0.0;    // 0 = pure arg max; else also P(H|obs)^(1/C) > threshold
  int min_views = 2;
  bool multi_projection = false;
  int threads = 0;
};

class AllClassesFusion {
 public:
  explicit AllClassesFusion(const AllClassesOptions& options = AllClassesOptions());
  const AllClassesOptions& options() const { return options_; }
  // Decision volume: 255 in the hull, 0 outside. Throws std::invalid_argument as PsfsFusion,
  // and for more than 16 cameras.
  void fuse(const ProjectionTable& table, const ViewEvidence& evidence, ProbabilityVolume* out) const;

 private:
  AllClassesOptions options_;
};

}  // namespace psfs
