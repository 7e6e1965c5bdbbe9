#include "hand_tracking/reclustering.h"

#include <limits>

namespace hand_tracking {

KMeansResult typedKMeans(const std::vector<ClusterPoint>& points, std::vector<ClusterMean>* means,
                         int max_iterations, std::vector<int>* assignment) {
  KMeansResult result;
  const size_t n = points.size();
  const int k = static_cast<int>(means->size());
  assignment->assign(n, -1);
  if (k == 0 || max_iterations < 1) return result;
  std::vector<Eigen::Vector3f> centres(k);
  std::vector<Eigen::Vector3d> sums(k);
  std::vector<double> mass(k);
  for (int it = 0; it < max_iterations; ++it) {
    for (int c = 0; c < k; ++c) centres[c] = (*means)[c].position.cast<float>();
    bool changed = false;
    for (size_t i = 0; i < n; ++i) {
      if (!points[i].active) continue;
      int best = 0;
      float best_d = std::numeric_limits<float>::infinity();
      for (int c = 0; c < k; ++c) {
        const float d = (points[i].position - centres[c]).squaredNorm();
        if (d < best_d) {
          best_d = d;
          best = c;
        }
      }
      if ((*assignment)[i] != best) {
        (*assignment)[i] = best;
        changed = true;
      }
    }
    ++result.iterations;
    if (!changed && it > 0) {
      result.converged = true;
      break;
    }
    // Update step: weighted centre of the same-type points.
    for (int c = 0; c < k; ++c) {
      sums[c].setZero();
      mass[c] = 0.0;
    }
    for (size_t i = 0; i < n; ++i) {
      const int c = (*assignment)[i];
      if (c < 0 || points[i].type != (*means)[c].type) continue;
      sums[c] += static_cast<double>(points[i].weight) * points[i].position.cast<double>();
      mass[c] += points[i].weight;
    }
    bool moved = false;
    for (int c = 0; c < k; ++c) {
      if (!(mass[c] > 0.0)) continue;
      const Eigen::Vector3d p = sums[c] / mass[c];
      moved |= (p.cast<float>() - centres[c]).squaredNorm() > 0.f;
      (*means)[c].position = p;
    }
    if (!moved) {  // means did not move: the next pass cannot change the assignment
      result.converged = true;
      break;
    }
  }
  return result;
}

}  // namespace hand_tracking
