// A synthetic hand that moves and turns over a short sequence, sampled per frame into its own
// sub-volume the way the pipeline does it (a cube around the hand, min corner snapped to the
// voxel lattice, so the cube moves by whole voxels): the codec tests' stream of frames. The
// shape is handVolume's (synthetic_volumes.h): palm ellipsoid, four fingers and a thumb as
// capsules, a 2-voxel probability ramp, +-20 noise re-drawn every frame.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cvephands_bridge/stream/hand_stream_codec.h"
#include "synthetic_volumes.h"

namespace cvephands_test {

// Pose of the hand at `frame`: moving (0-19), at rest (20-34: only the noise changes, so delta
// frames pay off), turning about its long axis while it moves back (35-...).
inline Eigen::Isometry3d syntheticHandPose(int frame, int side) {
  const double t1 = std::min(frame, 20), t2 = std::max(0, frame - 35);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(side ? 0.2 : -0.2, 0.0, 0.12) +
                       0.004 * t1 * Eigen::Vector3d(1.0, 0.5, 0.2) -
                       0.003 * t2 * Eigen::Vector3d(1.0, 0.0, 0.3);
  pose.linear() = (Eigen::AngleAxisd(0.035 * t1, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(0.05 * t2, Eigen::Vector3d::UnitY()))
                      .toRotationMatrix();
  return pose;
}

// The frame of hand `side` (0 left, 1 right: mirrored) in a cube of `edge` metres with n voxels
// per side (the pipeline: 0.30 m, 83). Stamp = frame / 25 s; target id = side.
inline cvephands::HandFrame syntheticHandFrame(int frame, int side, int n = 83, double edge = 0.30,
                                               uint32_t seed = 1) {
  const double voxel = edge / n;
  const Eigen::Isometry3d pose = syntheticHandPose(frame, side);
  const Eigen::Vector3d c = pose.translation();
  Eigen::Vector3d origin = c - Eigen::Vector3d::Constant(edge / 2);
  for (int i = 0; i < 3; ++i) origin[i] = std::round(origin[i] / voxel) * voxel;
  const double s = side ? -1.0 : 1.0;
  // The shape in hand coordinates (palm centre at 0), as handVolume builds it.
  std::vector<Sdf> parts = {
      ellipsoid(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.042, 0.048, 0.014)),
      capsule(Eigen::Vector3d(0, -0.04, 0), Eigen::Vector3d(0, -0.09, -0.01), 0.025)};
  const double spread[4] = {-0.027, -0.009, 0.009, 0.027};
  const double length[4] = {0.070, 0.080, 0.075, 0.060};
  for (int f = 0; f < 4; ++f) {
    const Eigen::Vector3d base(s * spread[f], 0.045, 0.0);
    const Eigen::Vector3d dir =
        Eigen::Vector3d(s * spread[f] * 0.6, 1.0, -0.25 - 0.1 * f).normalized();
    parts.push_back(capsule(base, base + length[f] * dir, 0.0085));
  }
  const Eigen::Vector3d thumb(s * 0.04, -0.01, -0.005);
  parts.push_back(
      capsule(thumb, thumb + 0.06 * Eigen::Vector3d(s * 0.8, 0.55, -0.2).normalized(), 0.010));
  const Sdf local = unite(parts);
  const Eigen::Isometry3d inv = pose.inverse();
  const Sdf world = [local, inv](const Eigen::Vector3d& p) { return local(inv * p); };
  TestVolume v = sampleSdf(Eigen::Vector3i(n, n, n), origin, voxel, world, 2.0 * voxel);
  addNoise(&v, 20, seed * 7919u + uint32_t(frame) * 2u + uint32_t(side));
  cvephands::HandFrame f;
  f.target_id = uint32_t(side);
  f.stamp_sec = uint32_t(frame / 25);
  f.stamp_nsec = uint32_t(frame % 25) * 40000000u;
  f.origin = origin;
  f.voxel_size = voxel;
  f.dims = v.dims;
  f.data = std::move(v.data);
  return f;
}

}  // namespace cvephands_test
