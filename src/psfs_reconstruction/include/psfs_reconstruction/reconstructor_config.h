// The pSfS stage's parameter file (config/psfs.yaml): every parameter of the classifier, the
// background models, the volumes and the nodelet, with the file documenting each one. ROS-free
// so the shipped file can be checked against the code's defaults in a unit test.
//
// Keys are optional (missing = the default in the structs); unknown keys and values of the
// wrong type or range are errors that name the file and the key, so a typo never silently
// falls back to a default (tabletop_common/config_schema.h, the loader of every stage).
#pragma once

#include <string>

#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_common/config_schema.h"

namespace psfs {

// What only the ROS wrapper uses (topics, queues, files).
struct NodeletOptions {
  std::string hand_roi_topic = "hands/targets";  // TrackedTargets; active HAND targets -> ROIs
  double hand_roi_max_age = 0.5;  // s: ROIs older than this (vs the frame stamp) are ignored
  int max_hand_rois = 2;
  // Mask the background update with per-camera masks from <camera>/<foreground_mask_topic>
  // (mono8, nonzero = person), OR-ed with the volume's back-projection: the body tracker's
  // silhouettes (body_mask), which also cover the person outside the grid (the torso leak of
  // thesis 4.3). A set takes each camera's newest mask not newer than its stamp and at most
  // foreground_mask_max_age older (the tracker's masks are of the previous set). Off by
  // default: nothing waits for the masks, so offline runs would depend on timing.
  bool foreground_mask_topics = false;
  std::string foreground_mask_topic = "body_mask";
  std::string foreground_mask_transport = "raw";  // image_transport plugin
  double foreground_mask_max_age = 0.2;  // s
  // Frame sets waiting in the stage's gate (tabletop_common/pipeline_gate.h): beyond it the
  // oldest waiting set is dropped (the pipeline's one drop point). Live: 2 (a source in
  // lockstep with up to 2 sets in flight then never loses one to thread timing); offline
  // evaluation: larger than the recording, so that every set is processed at any speed.
  int queue_size = 2;
  // Closed loop: after publishing a set's volumes, wait for the tracker's targets with that
  // stamp (on hand_roi_topic) before the next set, so its hand ROIs never depend on timing.
  // Only while the topic has a publisher; at most tracker_timeout seconds per set.
  bool wait_for_tracker = true;
  double tracker_timeout = 1.0;
  // Live load shedding: while more than shed_drop_fraction of the recent sets were dropped,
  // hand volumes are computed on 1 of every 2, then 3, then 4 sets (reported on /diagnostics),
  // and a step back after a window without drops. Off for offline evaluation.
  bool load_shedding = true;
  double shed_drop_fraction = 0.1;
  std::string background_load_dir;  // load <dir>/<camera>.bgm instead of learning ("" = learn)
  std::string background_save_dir;  // save the model there once learned ("" = don't)
  bool publish_clouds = true;       // psfs/*_cloud, only while someone subscribes
};

struct ReconstructorConfig {
  ReconstructorParams params;
  // As written in the file until finishReconstructorConfig() resolves it against the file's
  // directory.
  std::string skin_model_path = "skin_gmm.yaml";
  // compute/backend: "cpu" or "cuda" (ReconstructorParams::backend).
  std::string backend_name = "cpu";
  // pixel_classifier/prefilter: "none", "median" or "box" (ReconstructorParams::prefilter).
  std::string prefilter_name = "none";
  NodeletOptions nodelet;
};

// Binds every key of config/psfs.yaml to `c`, with the aliases the nodelet takes as private
// parameters (~threads for nodelet/threads, ~body_threshold for fusion/body/threshold, ...).
void addReconstructorKeys(ReconstructorConfig* c, tabletop_common::ConfigSchema* s);

// After the file (and any overrides) were read: the range checks of the parameter structs, and
// the skin model's path resolved. Throws std::runtime_error "<path>: <key>: <problem>".
void finishReconstructorConfig(const std::string& path, ReconstructorConfig* c);

// Both of the above around the file alone. Throws std::runtime_error "<path>: <key>: <problem>"
// for unreadable files, unknown keys, wrong types and values the parameter structs reject.
ReconstructorConfig loadReconstructorConfig(const std::string& path);

}  // namespace psfs
