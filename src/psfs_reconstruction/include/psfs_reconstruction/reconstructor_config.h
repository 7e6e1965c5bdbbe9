// The pSfS stage's parameter file (config/psfs.yaml): every parameter of the classifier, the
// background models, the volumes and the nodelet, with the file documenting each one. ROS-free
// so the shipped file can be checked against the code's defaults in a unit test.
//
// Keys are optional (missing = the default in the structs); unknown keys and values of the
// wrong type or range are errors that name the file and the key, so a typo never silently
// falls back to a default.
#pragma once

#include <string>

#include "psfs_reconstruction/reconstructor.h"

namespace psfs {

// What only the ROS wrapper uses (topics, queues, files).
struct NodeletOptions {
  std::string hand_roi_topic = "hands/targets";  // TrackedTargets; active HAND targets -> ROIs
  double hand_roi_max_age = 0.5;  // s: ROIs older than this (vs the frame stamp) are ignored
  int max_hand_rois = 2;
  // Subscribe cam<i>/foreground_mask (mono8, same stamp as the frame set) for the selective
  // background update instead of the volume's back-projection.
  bool foreground_mask_topics = false;
  int queue_size = 2;  // frame sets waiting; older ones are dropped when fusion falls behind
  std::string background_load_dir;  // load <dir>/<camera>.bgm instead of learning ("" = learn)
  std::string background_save_dir;  // save the model there once learned ("" = don't)
  bool publish_clouds = true;       // psfs/*_cloud, only while someone subscribes
};

struct ReconstructorConfig {
  ReconstructorParams params;
  std::string skin_model_path;  // resolved against the config file's directory
  NodeletOptions nodelet;
};

// Throws std::runtime_error "<path>: <key>: <problem>" for unreadable files, unknown keys, wrong
// types and values the parameter structs reject.
ReconstructorConfig loadReconstructorConfig(const std::string& path);

}  // namespace psfs
