// Local coordinates of the body state around a reference pose: positions and scalar joints as
// differences, the torso's rotation as a rotation vector (the quaternion log at the reference),
// and each 2-DOF joint as the log map of its bone direction on the sphere at the reference
// direction (the tangent plane of thesis 5.2.1, the QuTEM idea). The PAPF averages particles,
// estimates their covariance and diffuses them in these coordinates, so nothing depends on the
// Euler-like angles of the message: no wrap-around, no singularity where an arm is straight
// or points sideways.
#pragma once

#include <Eigen/Core>

#include "body_tracking/body_state.h"

namespace body_tracking {

constexpr int kTangentDim = dof::COUNT;  // same count: the 2-DOF joints stay 2-D
using Tangent = Eigen::Matrix<double, kTangentDim, 1>;

// Layout: 0-2 torso position (m), 3-5 torso rotation vector in the reference pelvis frame
// (rad), 6 spine bend, 7 head yaw, then per arm (left from 8, right from 13): 2 shoulder
// direction, 1 shift (m), 2 forearm direction in the upper arm's frame.
Tangent toTangent(const BodyState& at, const BodyState& s);
// Only the blocks that coordinates [first, first + count) belong to (the rest is zero): what a
// partition's covariance needs.
Tangent toTangent(const BodyState& at, const BodyState& s, int first, int count);
BodyState fromTangent(const BodyState& at, const Tangent& t);
// The same for a step in coordinates [first, first + count) only (the rest of t is ignored):
// the joints outside the range keep their values bit for bit (a full fromTangent sends them
// through their log / exp round trip, which moves them by rounding). What a partition's
// diffusion needs, at a fraction of the cost.
BodyState fromTangent(const BodyState& at, const Tangent& t, int first, int count);

// Weighted mean of states (weights >= 0, not all zero), computed in the tangent space at
// `start` and refined by re-centring `iterations` times. threads: OpenMP threads for the
// per-state tangents (the sum stays in order, so the result does not depend on it).
BodyState weightedMean(const BodyState* states, const double* weights, int n,
                       const BodyState& start, int iterations = 2, int threads = 1);

}  // namespace body_tracking
