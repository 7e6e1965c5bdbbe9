// The body volume with the tracked model as a prior (issue 15: "less phantom volume: use what
// the hull alone cannot see, e.g. the body model once the PAPF exists").
//
// A visual hull is the largest shape the silhouettes allow: wedges between the arms and the
// trunk, in front of and behind the chest, stay occupied in every view. On the 24 generated
// scenarios the pSfS body volume's precision is ~0.62 at recall ~0.96, and a hull carved from the
// TRUE silhouettes is no better (IoU 0.63, docs/scenario_suite.md). The PAPF's pose says where
// the person is: a voxel well outside every part of the fitted model is phantom unless the
// cameras are sure of it (fingers, loose sleeves, hair, a shoulder the model sits off).
//
// Fusion in log-odds: logit p' = logit p - max(0, (d - offset) / falloff), d the voxel centre's
// signed distance to the model (signedDistance in truncated_quadric.h, < 0 inside). The model
// only lowers probabilities (a prior <= 0.5: it never adds volume the cameras did not see) and
// leaves voxels with d <= offset as they were. With the defaults a voxel on the model's
// surface needs p >= 0.73 to stay at p' >= 0.5, 1 cm out p >= 0.95, 2 cm out p >= 0.993.
// Measured on the scenario suite (docs/benchmarks.md, "body/volume: the tracked model as a
// prior"), median / worst decile of the body IoU: random-1..24 0.571 / 0.315 -> 0.704 / 0.534
// (where offset and falloff were chosen, the middle of a plateau: offsets -10..0 mm and
// falloffs 2.5..10 mm all give 0.685-0.708); random-25..48, not seen before, 0.506 / 0.419 ->
// 0.584 / 0.353: where the PAPF has lost an arm the prior cuts the true arm (a gate on how much
// of the hull the model explains did not tell that from a 4-camera hull's far phantom).
// The model has no neck and its hands stop short of the finger tips; the prior adds both
// (priorSolids): 0.704 / 0.534 -> 0.709 / 0.538 and 0.584 / 0.353 -> 0.589 / 0.370 (recall
// +2.3 points, precision -0.6..-1.0). Of the true voxels the prior still removes (48
// scenarios), the head's (hair, the fit's 15-20 mm error) and the chest's (its girth) are a
// third each; a head grown by 2 cm traded them for phantom (0.695 / 0.528 and 0.594 / 0.382).
#pragma once

#include <vector>

#include "body_tracking/body_parts.h"
#include "body_tracking/model_prior_params.h"
#include "psfs_reconstruction/probability_volume.h"

namespace body_tracking {

// The solids the prior measures distances to: the model's parts (buildParts), beside each hand
// one reaching params.hand_reach further with a round cross-section, and a neck of
// params.neck_radius from the shoulders' height to the head's centre along the head's axis.
// Throws std::invalid_argument for a neck_radius or hand_reach outside [0, 1) m (or NaN).
std::vector<TruncatedQuadric> priorSolids(const BodyProfile& profile, const BodyFrames& frames,
                                          const ModelPriorParams& params);

// `out` = `body` with the prior of the model `solids` (any grid; `out` takes body's). Voxels
// beyond the reach of every solid's box are set to 0 without a distance. Throws
// std::invalid_argument for out == &body or null, a volume whose data does not fill its grid,
// a falloff <= 0 or a non-finite parameter.
void applyModelPrior(const psfs::ProbabilityVolume& body, const std::vector<TruncatedQuadric>& solids,
                     const ModelPriorParams& params, psfs::ProbabilityVolume* out);
// The model's parts alone (no neck, hands as tracked).
void applyModelPrior(const psfs::ProbabilityVolume& body, const BodyParts& parts,
                     const ModelPriorParams& params, psfs::ProbabilityVolume* out);

}  // namespace body_tracking
