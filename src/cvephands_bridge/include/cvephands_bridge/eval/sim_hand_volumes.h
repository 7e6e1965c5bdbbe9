// Real hand sub-volumes from the simulated rig (render -> psfs::Reconstructor -> one 83^3 skin
// volume per hand in the workspace, on psfs' snapped world lattice), as the codec's tests and
// benchmark feed them to the encoder. The sub-volumes are centred on the TRUE hand centroids (as
// in hand_mesh_evaluation.h): this is about the data the pipeline streams, not about tracking.
// Part of cvephands_eval (needs the simulator and reconstruction cores; no ROS).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cvephands_bridge/stream/hand_stream_codec.h"
#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_sim/simulated_rig.h"

namespace cvephands {

struct SimHandVolumeOptions {
  std::string scenario = "default";  // simulated rig scenario (tabletop_sim::SimOptions)
  std::string script = "wave";  // simulated rig motion script (MotionScript::names())
  int first_frame = 0;          // script frames skipped after the background frames
  int frames = 50;              // script frames after those (0 = to the end of the script)
  int every = 1;                // of those, every n-th is reconstructed (the others skipped)
  int seed = 1;                 // sensor noise seed
  int cameras = 8;
  bool short_sleeves = false;  // forearm skin inside the cube too: more surface to send
  std::string skin_model;      // path of psfs_reconstruction/config/skin_gmm.yaml
  double hand_edge = 0.30;     // cube edge (m) and voxels per side: the pipeline's defaults
  int hand_voxels = 83;
  bool clip_floor = true;      // ReconstructorParams::hand_roi_clip_floor (the desk top)
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

// One reconstructed frame set: result.hands[i] is the sub-volume of hand sides[i] (0 left,
// 1 right; left before right), centred on that hand's true centroid.
struct SimHandFrame {
  const tabletop_sim::SimulatedRig* rig = nullptr;  // e.g. rig->person(rig_frame)
  const tabletop_sim::SimFrame* sim = nullptr;      // the rendered frame set
  int rig_frame = 0;  // index in the rig's frames (the background frames included)
  int index = 0;      // 0, 1, ... over the visited frames
  int count = 0;      // frames that will be visited in all (for progress output)
  const psfs::FrameResult* result = nullptr;
  std::vector<int> sides;
};

// Learns the background on the rig's empty frames, then renders and reconstructs each requested
// frame (first_frame, frames, every) and calls visit() with it. Shared by the recorder below and
// the mesh accuracy evaluation (hand_mesh_evaluation.h). Throws std::invalid_argument for bad
// options, std::runtime_error if the skin model cannot be read.
void visitSimHandFrames(const SimHandVolumeOptions& options,
                        const std::function<void(const SimHandFrame&)>& visit);

// Records every hand in the workspace in each requested frame (in frame order, left before
// right): visitSimHandFrames with the volumes copied out.
std::vector<SimHandVolume> recordSimHandVolumes(const SimHandVolumeOptions& options);

// The volume as one frame of a hand stream (target id = side, stamp = simulated time), moving
// the voxels out of `v`.
HandFrame toHandFrame(SimHandVolume&& v);

}  // namespace cvephands
