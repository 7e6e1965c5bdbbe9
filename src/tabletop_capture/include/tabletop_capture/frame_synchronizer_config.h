// The frame synchroniser's parameter file (config/frame_synchronizer.yaml, which documents each
// key), read through the strict loader every stage uses (tabletop_common/config_schema.h).
// ROS-free, so that a unit test checks the shipped file against these defaults.
#pragma once

#include <string>

#include "tabletop_capture/frame_set_assembler.h"
#include "tabletop_common/config_schema.h"

namespace tabletop_capture {

struct FrameSynchronizerConfig {
  int num_cameras = 8;
  std::string camera_prefix = "cam";
  std::string image_transport = "raw";  // image_transport plugin the images come through
  double tolerance = 0.0;  // s; 0 = hardware sync (identical stamps)
  double timeout = 0.2;    // s
  int max_pending = 10;
  int max_missing_cameras = 2;  // clamped to num_cameras - 2
  int absent_after = 3;
  double time_jump_threshold = 1.0;  // s
  std::string world_frame = "world";
  double tf_timeout = 0.05;  // s
  int queue_size = 4;
  int image_queue_size = 10;
  int hold_until_subscribers = 1;
  int max_held = 100;

  // The assembler's part. Throws std::invalid_argument "<key>: <problem>" for values out of
  // range (checked here, so that a bad file is reported with its key).
  FrameSetAssemblerConfig assembler() const;
};

void addFrameSynchronizerKeys(FrameSynchronizerConfig* c, tabletop_common::ConfigSchema* s);

// The file alone, checked. Throws std::runtime_error "<path>: <key>: <problem>".
FrameSynchronizerConfig loadFrameSynchronizerConfig(const std::string& path);

}  // namespace tabletop_capture
