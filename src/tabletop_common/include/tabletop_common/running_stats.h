// Mean / max / count of a stream of samples (latencies, rates) for diagnostics and summaries.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace tabletop_common {

class RunningStats {
 public:
  void add(double x) {
    ++n_;
    const double d = x - mean_;
    mean_ += d / n_;
    m2_ += d * (x - mean_);
    max_ = std::max(max_, x);
    min_ = std::min(min_, x);
  }
  uint64_t count() const { return n_; }
  double mean() const { return n_ ? mean_ : 0.0; }
  double max() const { return n_ ? max_ : 0.0; }
  double min() const { return n_ ? min_ : 0.0; }
  double stddev() const { return n_ > 1 ? std::sqrt(m2_ / (n_ - 1)) : 0.0; }
  void reset() { *this = RunningStats(); }

 private:
  uint64_t n_ = 0;
  double mean_ = 0, m2_ = 0;
  double max_ = -std::numeric_limits<double>::infinity();
  double min_ = std::numeric_limits<double>::infinity();
};

}  // namespace tabletop_common
