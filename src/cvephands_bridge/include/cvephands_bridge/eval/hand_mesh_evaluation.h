// Hand-mesh accuracy on the simulated rig (issue "hand meshes", tool 4): renders the simulated
// rig, reconstructs with psfs::Reconstructor, meshes each hand's high-resolution sub-volume with
// marching cubes (probabilistic and binary, the thesis' figure 6.6 comparison) and measures both
// against the true skin surface in that sub-volume (mesh_accuracy.h, surface_samples.h).
//
// The sub-volumes are centred on the TRUE hand centroids: this scores meshing (and the
// reconstruction under it), not tracking (track_eval does that; a 30 cm cube holds the hand
// either way). The truth is the visible skin surface plus the face where skin meets the sleeve
// (the skin hull ends there too). The cube's faces cut the forearm and the meshes are closed
// there by caps: mesh vertices within `border_voxels` of a face and truth samples in that band
// are left out of the statistics.
//
// Used by the mesh_eval tool and by test_hand_meshes_sim. Not a ROS library: it needs the
// simulator (tabletop_capture) and the reconstruction (psfs_reconstruction) cores only.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "cvephands_bridge/mesh/marching_cubes.h"
#include "cvephands_bridge/mesh/mesh_accuracy.h"
#include "cvephands_bridge/mesh/triangle_mesh.h"
#include "psfs_reconstruction/probability_volume.h"
#include "tabletop_common/running_stats.h"
#include "tabletop_sim/primitives.h"

namespace cvephands {

struct HandMeshEvalOptions {
  std::string scenario = "default";      // simulated rig scenario (tabletop_sim::SimOptions)
  std::string script = "reach_targets";  // simulated rig motion script
  int frames = 0;             // script frames to run after the background (0 = the whole script)
  int every = 5;              // score every n-th frame (surface sampling costs ~0.2 s per hand)
  int seed = 1;               // sensor noise seed of the simulated rig
  int cameras = 8;
  std::string skin_model;     // path of skin_gmm.yaml (psfs_reconstruction/config)
  double iso = 0.6;           // probability of the iso-surface (byte level floor(255 iso) + 0.5)
  double spacing = 0.001;     // truth sample spacing (m)
  double border_voxels = 2.0; // band along the cube faces left out (caps)
  int min_component_triangles = 64;  // specks below this are dropped, as the HandMesher does
  double keep_radius = 0.08;  // m; components no nearer to the cube's centre are dropped (as the
                              // HandMesher does; 0 keeps them)
  double hand_edge = 0.30;    // hand cube edge (m) and voxels per side: the pipeline's defaults
  int hand_voxels = 83;
  bool clip_floor = true;     // hand cubes hold nothing below the desk top (psfs.yaml default)
  // Called once per scored frame (progress output).
  std::function<void(int frame, int total)> progress;
};

// One scored hand in one frame.
struct HandMeshSample {
  int frame = 0;
  int side = 0;  // 0 left, 1 right
  MeshAccuracy probabilistic, binary;
  size_t triangles_probabilistic = 0, triangles_binary = 0;
  double mesh_ms_probabilistic = 0, mesh_ms_binary = 0;
  double truth_area_m2 = 0;
};

struct HandMeshEvalResult {
  std::vector<HandMeshSample> samples;
  int frames_scored = 0;
  int frames_both_hands = 0;          // scored frames with both hands in the workspace
  int frames_both_meshed = 0;         // ... where both probabilistic meshes are non-empty
  // Means over samples of the per-hand means / p95s (mm), for the summary table.
  tabletop_common::RunningStats prob_mesh_to_truth, prob_truth_to_mesh, prob_p95_mesh_to_truth,
      prob_p95_truth_to_mesh, bin_mesh_to_truth, bin_truth_to_mesh, bin_p95_mesh_to_truth,
      bin_p95_truth_to_mesh, prob_triangles, bin_triangles, prob_ms, bin_ms;
  // The meshes of the scored frame with both hands nearest the middle of the run (for a
  // picture): [0] probabilistic left, right; [1] binary left, right.
  int picture_frame = -1;
  TriangleMesh picture[2][2];

  std::string summary() const;  // the table the tool prints
};

// Throws std::invalid_argument for bad options, std::runtime_error if the skin model cannot be
// read.
HandMeshEvalResult evaluateHandMeshes(const HandMeshEvalOptions& options);

// The per-hand step of evaluateHandMeshes, for loops that make their own hand sub-volumes (the
// scenario evaluation): meshes one sub-volume (probabilistic and, if asked, binary marching
// cubes; specks and components away from the hand removed) and scores the meshes against the
// true skin surface inside the cube, with the options' iso, spacing, border_voxels,
// min_component_triangles, keep_radius and seed (the other fields are not used). Throws
// std::invalid_argument for bad options.
class HandMeshScorer {
 public:
  explicit HandMeshScorer(const HandMeshEvalOptions& options);
  // `person`: the frame's primitives (SimulatedRig::person). The meshes are returned through
  // the pointers when given; binary = false leaves the binary fields of the sample empty.
  HandMeshSample score(const psfs::ProbabilityVolume& volume,
                       const std::vector<tabletop_sim::Primitive>& person, int frame, int side,
                       bool binary = true, TriangleMesh* probabilistic_mesh = nullptr,
                       TriangleMesh* binary_mesh = nullptr);

 private:
  HandMeshEvalOptions options_;
  MarchingCubes probabilistic_, binary_;
};

}  // namespace cvephands
