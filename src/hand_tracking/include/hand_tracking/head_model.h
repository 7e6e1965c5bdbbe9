// The head's centre from the body volume (DESIGN.md section 5: the head target is the head's
// centre, not its face). The MPF follows the face: skin is what the head observation sees,
// and the skin centroid sits in front of and below the centre (the face, chin and neck are
// skin; the crown is hair). Measured on generated scenarios it was 30-50 mm low, while the
// aligned error was 2-10 mm: a bias that depends on the hair and the neck, not noise.
//
// The model: the head with its hair is an ellipsoid-like blob on top of the body hull, so its
// horizontal cross-section area A(z) is quadratic in z, A(z) = pi a b (1 - (z - c)^2 / h^2),
// with its maximum at the centre's height c whatever the hair adds on top or the hull adds
// around it (a halo of constant width adds a near-constant term). The fit, starting from the
// face:
//   1. the head's axis: the centroid of the body voxels in a vertical cylinder around the
//      estimate, over the upper part of the blob (the neck and shoulders left out), iterated;
//   2. the top: going up from the face, the last level with a head's worth of area in that
//      cylinder;
//   3. the centre's height: the vertex of a least-squares parabola through A(z) over the levels
//      from the top down to fit_depth below it (the neck's narrowing is below that);
//   4. the centre: the axis at the mean of that height and the top less top_above_centre
//      (the vertex alone only where the top is cut off by the workspace's ceiling).
// On generated scenarios the hull's cross-section is not an ellipse's: cameras looking down
// leave phantom volume around the head's upper half (vertex up to +30 mm), and hair or the
// hull lift the top (top-based estimate -18..+27 mm). The top is read to a fraction of a
// level (the top level's area against the one below), or the estimate would step by 8 mm.
// Over the 24 generated scenarios of docs/scenario_suite.md: 14.8 mm median, 43.7 mm worst
// decile (the face's skin centroid: 43.7 / 73.0 mm on the first 12 of them).
// Anything implausible (no top found, a convex or flat profile, a vertex outside the fitted
// levels) leaves the face estimate as it was, flagged in the result.
#pragma once

#include <Eigen/Core>

#include "psfs_reconstruction/probability_volume.h"

namespace hand_tracking {

struct HeadModelParams {
  // Radius (m) of the vertical cylinder around the head's axis. A head is 15-19 cm wide and
  // 19-23 cm deep (the simulator's 0.075 x 0.095 m semi-axes, up to x1.06, plus hair): 0.13 m
  // holds it with the hull's halo, and stays clear of the shoulders' outer parts.
  double radius = 0.13;
  // Search for the top of the head up to this far above the face estimate (m).
  double max_above = 0.30;
  // Levels fitted: from the top down this far (m). The head with hair is 23-28 cm tall; its
  // lower 5 cm are the chin and the neck's narrowing, which a parabola does not model.
  double fit_depth = 0.20;
  // Body voxels above this probability count (the tracker's body volume, p = byte/255).
  double threshold = 0.5;
  // The top is the last level, going up, whose area in the cylinder reaches this (m^2; 4
  // voxels at 16 mm): a lone voxel of noise above the head is not its top.
  double min_top_area = 0.001;
  // Axis iterations (each re-centres the cylinder on the blob's upper part).
  int iterations = 3;
  // Height of the blob's top above the head's centre (m): 0.115 m for a bald head of the
  // simulator's size, 0.14 m with hair, x0.94-1.06 with the person's size; the hull adds
  // 0-2 cm. 0.135 m splits these.
  double top_above_centre = 0.135;

  // Throws std::invalid_argument naming the field.
  void validate() const;
};

struct HeadFit {
  bool ok = false;                  // false: centre = the face estimate given
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double top = 0.0;                 // z of the head's top (m, world)
  int levels = 0;                   // levels fitted
  bool clipped = false;             // the head reaches the grid's top (vertex only)
};

// Fits the head's centre in the body volume, starting from `face` (world, m).
HeadFit fitHeadCentre(const psfs::ProbabilityVolume& body, const Eigen::Vector3d& face,
                      const HeadModelParams& params);

}  // namespace hand_tracking
