// Frame sets of a bag (tabletop_msgs/MultiViewFrame, normally /tabletop/frames recorded from the
// synchroniser) to per-camera PNG sequences, the input of the rig calibration tools
// (calibrate_intrinsics, calibrate_extrinsics, align_rig_to_marker):
//
//   OUT/<camera name>/NNNNN.png   NNNNN = the set's index among the sets read from the topic
//                                 (0-based, 5 digits), so the same file name in every camera
//                                 folder is the same set, i.e. the same instant
//   OUT/stamps.csv                index,stamp,cameras: one row per set written, the stamp in
//                                 seconds with 9 decimals, the cameras with a file (space separated)
//
// A camera missing from a degraded set (empty image) gets no file: the calibration tools read a
// missing file as "not seen". Images are converted with convertToRgb8 (rgb8, bgr8, mono8,
// bayer_*8) and written as 8-bit colour PNGs; an image that fails conversion is a warning and no
// file. Used by the export_frame_sets tool.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace tabletop_capture {

struct FrameSetExportOptions {
  std::string topic = "/tabletop/frames";
  int every = 1;                     // write every Nth set (index % every == 0); >= 1
  int max_sets = 0;                  // stop after this many sets written; 0 = no limit
  std::vector<std::string> cameras;  // only these cameras; empty = every camera of the sets
};

struct CameraExportCount {
  std::string name;
  int written = 0;  // PNGs written
  int missing = 0;  // sets written in which this camera's slot was empty (degraded set)
  int failed = 0;   // images that failed conversion (warned, no file)
};

struct FrameSetExportResult {
  int sets_read = 0;     // sets read from the topic (up to the last one written with max_sets)
  int sets_written = 0;  // sets selected by every / max_sets (a row of stamps.csv each)
  std::vector<CameraExportCount> cameras;  // in the order of the sets' camera_names
  int conversion_failures = 0;
  std::vector<std::string> warnings;  // also passed to `log` as "WARNING: ..." when they happen
};

// Throws std::runtime_error with a message for the user when the bag cannot be read, the topic
// is absent or not of type tabletop_msgs/MultiViewFrame (the message lists the bag's topics with
// their types), the topic holds no frame set, a camera of options.cameras is not in the sets, or
// the output folder or a file in it cannot be written. `log` (optional) receives a progress
// line every 50 sets written and the warnings.
FrameSetExportResult exportFrameSets(const std::string& bag, const std::string& out_dir,
                                     const FrameSetExportOptions& options,
                                     const std::function<void(const std::string&)>& log = {});

}  // namespace tabletop_capture
