// The body tracker's parameter file (config/papf.yaml): every PapfParams field and the
// nodelet's own options, read through the strict loader every stage uses
// (tabletop_common/config_schema.h). ROS-free, so that a unit test checks the shipped file
// against the code's defaults.
#pragma once

#include <string>

#include "body_tracking/body_profile.h"
#include "body_tracking/model_prior_params.h"
#include "body_tracking/papf_params.h"
#include "tabletop_common/config_schema.h"

namespace body_tracking {

// What only the ROS wrapper uses.
struct PapfNodeletOptions {
  std::string world_frame = "world";
  std::string tf_prefix = "tabletop/body/";  // tf frames <prefix><part>
  std::string body_profile_file;             // "" = config/body_profile.yaml of the package
  bool publish_masks = true;     // cam<i>/body_mask (mono8): the model's silhouettes
  double mask_margin_px = 4.0;   // dilation of those masks (px)
  bool use_skin_volume = true;   // false: the body volume alone (head and hands unweighted)
  // body/volume: psfs/body_volume with the tracked model as a prior (model_prior.h); the input
  // volume unchanged while no pose is tracked.
  bool publish_volume = true;
  ModelPriorParams volume_prior;
  // Volumes waiting for the tracker. Live, a tracker slower than the cameras then drops the
  // oldest instead of lagging; offline (every set counts) launch files set it very large.
  int queue_size = 10;
};

struct PapfConfig {
  PapfParams params;
  PapfNodeletOptions nodelet;
};

void addPapfKeys(PapfConfig* c, tabletop_common::ConfigSchema* s);
// After the file (and any overrides): PapfParams::validate() and the nodelet options' checks.
// Throws std::runtime_error "<where><problem>".
void finishPapfConfig(const std::string& where, PapfConfig* c);
PapfConfig loadPapfConfig(const std::string& path);

}  // namespace body_tracking
