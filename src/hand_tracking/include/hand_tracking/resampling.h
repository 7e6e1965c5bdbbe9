// Systematic resampling (thesis 3.4.3): n draws from a discrete distribution with a single
// uniform offset, O(m + n), lowest variance of the standard schemes.
#pragma once

#include <cstddef>
#include <vector>

namespace hand_tracking {

// weights: m non-negative values with a positive sum (need not be normalised); u in [0, 1).
// Writes n indices into [0, m) to *out (resized), non-decreasing. Throws std::invalid_argument
// for m == 0 or a non-positive or non-finite sum.
void systematicResample(const double* weights, size_t m, size_t n, double u,
                        std::vector<int>* out);

}  // namespace hand_tracking
