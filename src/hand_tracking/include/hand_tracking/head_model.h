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
//   4. the centre: at a weighted mean of that height (vertex_weight) and the top
//      less top_above_centre (the vertex alone where the top is cut off by the workspace's
//      ceiling; the top alone where the profile has no plausible vertex), horizontally
//      between the axis and the face estimate (face_weight: hair pulls the axis back).
// On generated scenarios the hull's cross-section is not an ellipse's: cameras looking down
// leave phantom volume around the head's upper half, and the chin, neck and long hair bend
// the profile, so the vertex scatters: -15..+65 mm from the centre on the pSfS hull, -6..+50
// mm on the TRUE occupancy (the oracle's voxels; 48 scenarios, docs/benchmarks.md "MPF: the
// head's centre where the profile has no vertex"); the top less top_above_centre -35..+10 mm
// (bald or hair, the hull's cap). The top is read to a fraction of a level (the top level's
// area against the one below), or the estimate would step by 8 mm.
// Anything implausible (no top found, a column that does not end, fewer than 3 levels, a top
// at the workspace's ceiling without a vertex) leaves the face estimate as it was, flagged in
// the result; a profile without a plausible vertex (convex, flat, or its vertex outside the
// fitted levels: long or background-coloured hair, a hand beside the head) gives the
// top-based estimate. Before, such frames reported the face, 40-60 mm low: on random-25..48
// (100 frames) the head's worst decile 28.2 -> 24.2 mm (random-38, 32, 47, 28 moved).
#pragma once

#include <limits>

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
  // Weight of the profile's vertex in the centre's height (the top-based estimate has the
  // rest). The vertex scatters further (see above), but its errors come from different
  // things than the top's (the hull's shape below the widest level; hair and cap above). On
  // 48 scenarios 0.25 with top_above_centre 0.13 looked better (head 12.8 -> 11.1 mm median),
  // but on 24 held-out ones it was not (11.4 -> 11.6 mm; docs/benchmarks.md): kept at 0.5.
  double vertex_weight = 0.5;
  // Weight of the face estimate's horizontal position in the centre's (the blob's axis has the
  // rest), in [0, 1]. Hair lies on top of and behind the head, so the axis (the centroid of
  // the blob's upper part) sits behind the centre: 19 mm for the simulator's short hair on the
  // exact hull, a median of 6 mm back (world y) over 96 generated scenarios on the pSfS hull
  // (3.5 mm forward for the bald ones). The face estimate (the skin the MPF follows) lies in
  // front of the centre, by much more where hair covers the rest of the head and by little on
  // a bald one, so a blend pulls a haired head forward and leaves a bald one nearly as it was.
  // 0.25 halves the median bias (6.0 -> 3.0 mm back); 0.5 removes it but scatters more
  // (docs/benchmarks.md, "MPF: the head's centre between the axis and the face"). 0: the axis.
  double face_weight = 0.25;

  // Throws std::invalid_argument naming the field.
  void validate() const;
};

struct HeadFit {
  bool ok = false;                  // false: centre = the face estimate given
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double top = 0.0;                 // z of the head's top (m, world)
  int levels = 0;                   // levels fitted
  bool clipped = false;             // the head reaches the grid's top (vertex only); set
                                    // whether or not the fit succeeds
  bool from_top = false;            // no plausible vertex: the centre from the top alone
  double vertex = std::numeric_limits<double>::quiet_NaN();  // z of the profile's vertex (m)
};

// Fits the head's centre in the body volume, starting from `face` (world, m).
HeadFit fitHeadCentre(const psfs::ProbabilityVolume& body, const Eigen::Vector3d& face,
                      const HeadModelParams& params);

}  // namespace hand_tracking
