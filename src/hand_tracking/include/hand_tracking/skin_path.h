// Whether two points lie on one skin blob along the straight line between them. With bare
// forearms a hand and its own forearm or elbow are one blob: the elbow fills a palm box better
// than a flat hand does, and a second hand track was born there while the other hand rested
// unseen (generated scenarios, short sleeves). A hand track is not born where skin joins it to
// an existing hand track; the other hand is joined to it only through the body, which is no
// straight skin line, unless the two touch (clasped hands are one target anyway).
// Each point of the line counts when the skin fills enough of a small cube around it, not
// only its own voxel: the strongest particles of a box likelihood lie on an arm's surface or
// beside it (a 9 cm box half over a 7 cm arm), and a line from there starts off the skin.
#pragma once

#include <Eigen/Core>

#include "hand_tracking/integral_volume.h"

namespace hand_tracking {

// Fraction (0..1) of the points sampled every half voxel on the segment [a, b] around which the
// mean skin probability in the cube of half edge `half` (m) reaches `min_mean`; the outside of
// the grid counts as no skin. 0 for an empty volume or a non-finite end.
double skinPathFraction(const IntegralVolume& skin, const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b, double half, double min_mean);

}  // namespace hand_tracking
