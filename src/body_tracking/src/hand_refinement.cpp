#include "body_tracking/hand_refinement.h"

#include <algorithm>
#include <cmath>

namespace body_tracking {

using Eigen::Vector3d;

RefinedHands refineHands(const psfs::ProbabilityVolume& skin, const BodyFrames& f,
                         const HandRefinementParams& p) {
  RefinedHands out;
  out.position = f.hand;
  if (!p.enabled || skin.data.size() != skin.grid.numVoxels()) return out;
  const psfs::VoxelGrid& g = skin.grid;
  const double h = g.voxel_size, cell = h * h * h;
  const float floor_p = static_cast<float>(p.min_probability);
  for (int side = 0; side < 2; ++side) {
    const Vector3d axis = (f.wrist[side] - f.elbow[side]).normalized();
    const Vector3d cut = f.wrist[side] + p.wrist_offset * axis;
    Vector3d centre = f.hand[side];
    for (int it = 0; it < std::max(1, p.iterations); ++it) {
      const Vector3d lo = (centre - Vector3d::Constant(p.radius) - g.origin) / h;
      const Vector3d hi = (centre + Vector3d::Constant(p.radius) - g.origin) / h;
      Vector3d sum = Vector3d::Zero();
      double mass = 0;
      for (int z = std::max(0, static_cast<int>(lo.z())); z <= std::min(g.dims.z() - 1, static_cast<int>(hi.z())); ++z)
        for (int y = std::max(0, static_cast<int>(lo.y())); y <= std::min(g.dims.y() - 1, static_cast<int>(hi.y())); ++y)
          for (int x = std::max(0, static_cast<int>(lo.x())); x <= std::min(g.dims.x() - 1, static_cast<int>(hi.x())); ++x) {
            const float v = skin.data[g.index(x, y, z)] / 255.0f;
            if (v <= floor_p) continue;
            const Vector3d c = g.centre(x, y, z);
            if ((c - centre).squaredNorm() > p.radius * p.radius) continue;
            if ((c - cut).dot(axis) < 0) continue;
            // Folded hands: each voxel goes to the nearer model hand.
            if ((c - f.hand[side]).squaredNorm() > (c - f.hand[1 - side]).squaredNorm()) continue;
            const double w = v - floor_p;
            sum += w * c;
            mass += w;
          }
      if (mass * cell / (1.0 - p.min_probability) < p.min_volume) break;
      centre = sum / mass;
      out.position[side] = centre;
      out.from_skin[side] = true;
    }
  }
  return out;
}

}  // namespace body_tracking
