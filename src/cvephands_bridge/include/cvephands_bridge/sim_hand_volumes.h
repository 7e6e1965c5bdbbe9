// Real hand sub-volumes from the simulated rig (render -> psfs::Reconstructor -> one 83^3 skin
// volume per hand in the workspace, on psfs' snapped world lattice), as the codec's tests and
// benchmark feed them to the encoder. The sub-volumes are centred on the TRUE hand centroids (as
// in hand_mesh_evaluation.h): this is about the data the pipeline streams, not about tracking.
// Part of cvephands_eval (needs the simulator and reconstruction cores; no ROS).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace cvephands {

struct SimHandVolumeOptions {
  std::string script = "wave";  // simulated rig motion script (MotionScript::names())
  int first_frame = 0;          // script frames skipped after the background frames
  int frames = 50;              // consecutive script frames recorded after those
  int seed = 1;                 // sensor noise seed
  int cameras = 8;
  bool short_sleeves = false;  // forearm skin inside the cube too: more surface to send
  std::string skin_model;      // path of psfs_reconstruction/config/skin_gmm.yaml
  double hand_edge = 0.30;     // cube edge (m) and voxels per side: the pipeline's defaults
  int hand_voxels = 83;
};

struct SimHandVolume {
  int frame = 0;    // script frame (0 = first frame after the background)
  int side = 0;     // 0 left, 1 right (a stable id per hand, like a tracker's target id)
  double time = 0;  // s since the rig started
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // min corner (world, m)
  double voxel_size = 0;
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();
  std::vector<uint8_t> data;  // p = value / 255, x fastest then y then z
};

// Learns the background on the rig's empty frames, then records every hand in the workspace in
// each requested frame (in frame order, left before right). Throws std::invalid_argument for bad
// options, std::runtime_error if the skin model cannot be read.
std::vector<SimHandVolume> recordSimHandVolumes(const SimHandVolumeOptions& options);

}  // namespace cvephands
