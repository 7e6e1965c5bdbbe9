// Faults injected into the simulated rig's camera streams while it runs (issue 19's fault
// matrix): a camera stops, switches encoding or size, publishes NaN calibration, or the light
// gets brighter. Commands are plain text (the SimRig nodelet's ~fault topic, std_msgs/String):
//   stop <camera> <seconds>                 publish nothing from that camera
//   encoding <camera> <encoding> <seconds>  e.g. bgr8, mono8 (converted from the rendered rgb8)
//   size <camera> <width> <height> <seconds>  the image resized (camera_info unchanged)
//   nan_info <camera> <seconds>             camera_info with NaN intrinsics
//   brightness <gain> <seconds>             every camera's pixels x gain (saturating)
//   frame <camera> <frame_id> <seconds>     images and camera_info name another optical frame,
//                                           one without a tf (the camera's tf is missing)
//   tf <camera> <dx> <dy> <dz> <seconds>    the camera's static tf re-broadcast shifted by
//                                           (dx, dy, dz) m in world; the camera did not move
//                                           (a wrong recalibration); the true tf again after
//   clock <offset> <seconds>                every stamp shifted by offset s (negative: the
//                                           clock jumped back, as a bag played in a loop)
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
  std::string frame_id;              // empty: the camera's own
  double tf_shift[3] = {0, 0, 0};    // m, world
  // Image faults only (the tf and the clock are the nodelet's, not the image's).
  bool any() const { return drop || !encoding.empty() || width > 0 || nan_info || gain != 1.0; }
  bool tfShifted() const { return tf_shift[0] != 0 || tf_shift[1] != 0 || tf_shift[2] != 0; }
};

class CameraFaults {
 public:
  explicit CameraFaults(int num_cameras) : num_cameras_(num_cameras) {}
  // Parses and schedules one command from `now` (s, any clock). Throws std::invalid_argument
  // naming what is wrong (unknown command, camera out of range, bad number, unknown encoding).
  void command(const std::string& text, double now);
  // What applies to `camera` at `now` (later commands of a kind override earlier ones).
  CameraFaultEffect effect(int camera, double now) const;
  // The stamp offset (s) of a clock fault at `now` (0 without one).
  double clockOffset(double now) const;
  // A short text of the faults active at `now` (diagnostics), "" if none.
  std::string describe(double now) const;

 private:
  struct Fault {
    std::string kind;
    int camera = -1;  // -1: all
    std::string encoding;  // or the frame_id of a frame fault
    int width = 0, height = 0;
    double shift[3] = {0, 0, 0};  // tf shift, or the clock offset in shift[0]
    double gain = 1.0;
    double start = 0.0, end = 0.0;  // end <= start: until clear
    bool activeAt(double t) const { return t >= start && (end <= start || t < end); }
  };
  int num_cameras_;
  std::vector<Fault> faults_;
};

}  // namespace tabletop_sim
