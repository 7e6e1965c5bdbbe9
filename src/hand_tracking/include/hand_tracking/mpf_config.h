// The MPF stage's parameter file (config/mpf.yaml): every MpfParams field and the nodelet's
// own options, read through the strict loader every stage uses (tabletop_common/config_schema.h).
// ROS-free, so that a unit test checks the shipped file against the code's defaults.
#pragma once

#include <cstdint>
#include <string>

#include "hand_tracking/mpf_params.h"
#include "tabletop_common/config_schema.h"

namespace hand_tracking {

// What only the ROS wrapper uses.
struct MpfNodeletOptions {
  int seed = 1;                     // random generator seed (same bag + seed = same output)
  bool publish_particles = false;   // particle cloud in hands/markers (costly in rviz)
  std::string world_frame = "world";
  std::string tf_prefix = "tabletop/";  // tf frames <prefix>head, <prefix>hand_<id>
};

struct MpfConfig {
  MpfParams params;
  MpfNodeletOptions nodelet;
};

// Binds every key of config/mpf.yaml (flat names, as in the file) to `c`.
void addMpfKeys(MpfConfig* c, tabletop_common::ConfigSchema* s);

// After the file (and any overrides): MpfParams::validate() and the nodelet options' checks.
// Throws std::runtime_error "<where><problem>".
void finishMpfConfig(const std::string& where, MpfConfig* c);

// Both around the file alone. Throws std::runtime_error "<path>: <key>: <problem>".
MpfConfig loadMpfConfig(const std::string& path);

}  // namespace hand_tracking
