#include "hand_tracking/resampling.h"

#include <cmath>
#include <stdexcept>

namespace hand_tracking {

void systematicResample(const double* weights, size_t m, size_t n, double u,
                        std::vector<int>* out) {
  if (m == 0) throw std::invalid_argument("systematicResample: no weights");
  double total = 0.0;
  for (size_t i = 0; i < m; ++i) total += weights[i];
  if (!std::isfinite(total) || !(total > 0.0))
    throw std::invalid_argument("systematicResample: weights must have a positive finite sum");
  out->resize(n);
  const double step = total / static_cast<double>(n);
  double target = u * step;
  double cumulative = weights[0];
  size_t i = 0;
  for (size_t k = 0; k < n; ++k) {
    while (cumulative <= target && i + 1 < m) cumulative += weights[++i];
    (*out)[k] = static_cast<int>(i);
    target += step;
  }
}

}  // namespace hand_tracking
