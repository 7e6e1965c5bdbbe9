// Renders a scripted simulated-rig sequence straight into a bag that follows the camera
// contract (cam<i>/image_raw, cam<i>/camera_info, latched /tf_static) plus ground truth.
#pragma once

#include <functional>
#include <string>

#include "tabletop_sim/simulated_rig.h"

namespace tabletop_sim {

struct SimBagOptions {
  std::string path;                       // output .bag
  std::string ns = "/tabletop";           // topic namespace
  int frames = 100;                       // frame sets, the empty ones included
  double start_time = 1700000000.0;       // stamp of frame 0 (s); fixed so bags are reproducible
  bool lz4 = true;                        // LZ4 chunk compression
};

// progress(frame_done, frames_total) is called after every frame set.
// Throws std::runtime_error (or rosbag::BagException) on I/O errors.
void writeSimBag(const SimulatedRig& rig, const SimBagOptions& options,
                 const std::function<void(int, int)>& progress = nullptr);

}  // namespace tabletop_sim
