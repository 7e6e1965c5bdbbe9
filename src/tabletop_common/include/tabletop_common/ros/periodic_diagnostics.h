// Diagnostics of a nodelet on /diagnostics, published once a second from a wall timer
// (force_update): the status keeps coming while the nodelet's callbacks stall or no input
// arrives, which is exactly when someone looks. Plus RateMeter, the per-second rate of a
// counter between two diagnostics calls, and GrowthMeter, whether a counter grew since the
// previous call. Shared by every nodelet of the workspace.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <utility>

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

namespace tabletop_common {

class PeriodicDiagnostics {
 public:
  using Task = std::function<void(diagnostic_updater::DiagnosticStatusWrapper&)>;

  // node_name: the nodelet's getName(); task runs on the timer thread once a second.
  PeriodicDiagnostics(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& node_name,
                      const std::string& hardware_id, const std::string& task_name, Task task)
      : updater_(nh, pnh, node_name) {
    updater_.setHardwareID(hardware_id);
    updater_.add(task_name, diagnostic_updater::TaskFunction(std::move(task)));
    boost::function<void(const ros::WallTimerEvent&)> tick = [this](const ros::WallTimerEvent&) {
      updater_.force_update();
    };
    timer_ = nh.createWallTimer(ros::WallDuration(1.0), tick);
  }
  PeriodicDiagnostics(const PeriodicDiagnostics&) = delete;
  PeriodicDiagnostics& operator=(const PeriodicDiagnostics&) = delete;

 private:
  diagnostic_updater::Updater updater_;
  ros::WallTimer timer_;
};

// Events per second of a monotonically increasing counter since the previous call (0 on the
// first call), on the wall clock.
class RateMeter {
 public:
  double rate(uint64_t count) {
    const ros::WallTime now = ros::WallTime::now();
    const double dt = last_.isZero() ? 0.0 : (now - last_).toSec();
    const double r = dt > 0 ? static_cast<double>(count - last_count_) / dt : 0.0;
    last_ = now;
    last_count_ = count;
    return r;
  }

 private:
  ros::WallTime last_;
  uint64_t last_count_ = 0;
};

// Whether a monotonically increasing counter (e.g. rejected inputs) grew since the previous
// call (false on the first call for 0).
class GrowthMeter {
 public:
  bool grew(uint64_t count) {
    const bool g = count > last_;
    last_ = count;
    return g;
  }

 private:
  uint64_t last_ = 0;
};

}  // namespace tabletop_common
