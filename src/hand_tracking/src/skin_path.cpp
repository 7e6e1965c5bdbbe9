#include "hand_tracking/skin_path.h"

#include <algorithm>
#include <cmath>

namespace hand_tracking {

double skinPathFraction(const IntegralVolume& skin, const Eigen::Vector3d& a,
                        const Eigen::Vector3d& b, double half, double min_mean) {
  if (skin.empty() || !(skin.grid().voxel_size > 0.0) || !a.allFinite() || !b.allFinite())
    return 0.0;
  const double step = 0.5 * skin.grid().voxel_size;
  const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
  const Eigen::Vector3d h = Eigen::Vector3d::Constant(half);
  int on = 0;
  for (int i = 0; i <= steps; ++i) {
    const Eigen::Vector3d p = a + (b - a) * (double(i) / steps);
    if (skin.boxMeanSmooth(p - h, p + h) >= min_mean) ++on;
  }
  return double(on) / (steps + 1);
}

}  // namespace hand_tracking
