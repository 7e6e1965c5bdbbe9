#include "tabletop_capture/capture_stats.h"

#include <cmath>
#include <stdexcept>

namespace tabletop_capture {

CaptureStats::CaptureStats(double nominal_fps, std::size_t window)
    : period_(nominal_fps > 0 ? 1.0 / nominal_fps : 0.0), max_window_(window) {
  if (!(nominal_fps > 0) || !std::isfinite(nominal_fps))
    throw std::invalid_argument("CaptureStats: nominal fps must be > 0");
  if (window < 1) throw std::invalid_argument("CaptureStats: window must be >= 1");
}

std::uint64_t CaptureStats::missedIn(double interval, double period) {
  if (!(interval > 1.5 * period)) return 0;
  return static_cast<std::uint64_t>(std::llround(interval / period)) - 1;
}

void CaptureStats::add(double stamp) {
  ++frames_;
  if (have_last_ && !(stamp > last_)) {
    ++non_increasing_;
    return;
  }
  if (have_last_) {
    const double dt = stamp - last_;
    window_.push_back(dt);
    if (window_.size() > max_window_) window_.pop_front();
    dropped_total_ += missedIn(dt, period_);
  }
  last_ = stamp;
  have_last_ = true;
}

double CaptureStats::meanIntervalMs() const {
  if (window_.empty()) return 0.0;
  double sum = 0;
  for (double d : window_) sum += d;
  return 1e3 * sum / static_cast<double>(window_.size());
}

double CaptureStats::rate() const {
  const double mean_ms = meanIntervalMs();
  return mean_ms > 0 ? 1e3 / mean_ms : 0.0;
}

double CaptureStats::jitterMs() const {
  if (window_.size() < 2) return 0.0;
  const double mean = meanIntervalMs() / 1e3;
  double ss = 0;
  for (double d : window_) ss += (d - mean) * (d - mean);
  return 1e3 * std::sqrt(ss / static_cast<double>(window_.size() - 1));
}

std::uint64_t CaptureStats::droppedInWindow() const {
  std::uint64_t n = 0;
  for (double d : window_) n += missedIn(d, period_);
  return n;
}

}  // namespace tabletop_capture
