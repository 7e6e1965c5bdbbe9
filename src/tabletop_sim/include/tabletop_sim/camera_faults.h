// Faults injected into the simulated rig's camera streams while it runs (issue 19's fault
// matrix): a camera stops, switches encoding or size, publishes NaN calibration, or the light
// gets brighter. Commands are plain text (the SimRig nodelet's ~fault topic, std_msgs/String):
//   stop <camera> <seconds>                 publish nothing from that camera
//   encoding <camera> <encoding> <seconds>  e.g. bgr8, mono8 (converted from the rendered rgb8)
//   size <camera> <width> <height> <seconds>  the image resized (camera_info unchanged)
//   nan_info <camera> <seconds>             camera_info with NaN intrinsics
//   brightness <gain> <seconds>             every camera's pixels x gain (saturating)
//   clear                                   end every fault now
// <camera> is an index (0-based) or "all"; <seconds> 0 means until `clear`.
#pragma once

#include <string>
#include <vector>

namespace tabletop_sim {

struct CameraFaultEffect {
  bool drop = false;
  std::string encoding;        // empty: as rendered
  int width = 0, height = 0;   // 0: as rendered
  bool nan_info = false;
  double gain = 1.0;
  bool any() const { return drop || !encoding.empty() || width > 0 || nan_info || gain != 1.0; }
};

class CameraFaults {
 public:
  explicit CameraFaults(int num_cameras) : num_cameras_(num_cameras) {}
  // Parses and schedules one command from `now` (s, any clock). Throws std::invalid_argument
  // naming what is wrong (unknown command, camera out of range, bad number, unknown encoding).
  void command(const std::string& text, double now);
  // What applies to `camera` at `now` (later commands of a kind override earlier ones).
  CameraFaultEffect effect(int camera, double now) const;
  // A short text of the faults active at `now` (diagnostics), "" if none.
  std::string describe(double now) const;

 private:
  struct Fault {
    std::string kind;
    int camera = -1;  // -1: all
    std::string encoding;
    int width = 0, height = 0;
    double gain = 1.0;
    double start = 0.0, end = 0.0;  // end <= start: until clear
    bool activeAt(double t) const { return t >= start && (end <= start || t < end); }
  };
  int num_cameras_;
  std::vector<Fault> faults_;
};

}  // namespace tabletop_sim
