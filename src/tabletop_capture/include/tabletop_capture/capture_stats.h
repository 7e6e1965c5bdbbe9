// Timing of one camera's frames from their capture stamps: measured rate, inter-frame jitter
// and dropped frames over a sliding window of the latest intervals, plus totals. ROS-free.
//
// Dropped frames: an interval longer than 1.5 nominal periods means frames were missed; it
// counts round(interval / period) - 1 of them (a 3-period gap = 2 missed frames).
// Jitter: the standard deviation (ms) of the window's intervals, gaps included (a drop is
// jitter too). Rate: the window's intervals divided into their count.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>

namespace tabletop_capture {

class CaptureStats {
 public:
  // nominal_fps > 0; window: the number of latest intervals measured (>= 1).
  explicit CaptureStats(double nominal_fps, std::size_t window = 50);

  // A frame captured at `stamp` (s). A stamp not after the previous one is counted in
  // nonIncreasing() and measures nothing.
  void add(double stamp);
  // The source was re-opened: the gap to the next frame is not an interval (neither rate nor
  // drops); window and totals are kept.
  void restart() { have_last_ = false; }

  double rate() const;      // Hz over the window; 0 without an interval
  double jitterMs() const;  // std dev of the window's intervals (ms); 0 with < 2 intervals
  double meanIntervalMs() const;
  std::uint64_t droppedInWindow() const;  // frames missed within the window's intervals
  std::uint64_t droppedTotal() const { return dropped_total_; }
  std::uint64_t frames() const { return frames_; }
  std::uint64_t nonIncreasing() const { return non_increasing_; }
  std::size_t intervals() const { return window_.size(); }
  double nominalFps() const { return 1.0 / period_; }

  // Frames missed in one interval (s) at this nominal period.
  static std::uint64_t missedIn(double interval, double period);

 private:
  double period_;
  std::size_t max_window_;
  std::deque<double> window_;  // intervals (s)
  double last_ = 0.0;
  bool have_last_ = false;
  std::uint64_t frames_ = 0, dropped_total_ = 0, non_increasing_ = 0;
};

}  // namespace tabletop_capture
