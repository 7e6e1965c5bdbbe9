// The hand meshing stage's parameter file (config/hand_mesher.yaml), read through the strict
// loader every stage uses (tabletop_common/config_schema.h). ROS-free, so that a unit test checks
// the shipped file against these defaults.
#pragma once

#include <string>

#include <Eigen/Core>

#include "cvephands_bridge/mesh/marching_cubes.h"
#include "tabletop_common/config_schema.h"

namespace cvephands {

struct HandMesherConfig {
  double iso = 0.6;                     // probability of the iso-surface (thesis: 0.6)
  std::string mode = "probabilistic";   // or "binary" (threshold first: the thesis' comparison)
  bool close_at_border = true;
  int min_component_triangles = 64;     // smaller components (skin-coloured specks) are dropped
  double keep_radius = 0.08;            // m; components farther from the hand are dropped (0: off)
  int threads = 1;
  bool publish_markers = true;
  Eigen::Vector4d marker_color{0.93, 0.72, 0.60, 1.0};  // RGBA
  std::string world_frame = "world";
};

void addHandMesherKeys(HandMesherConfig* c, tabletop_common::ConfigSchema* s);

// The byte iso level of a probability: the half-integer floor(255 iso) + 0.5, so that no uint8
// sample equals it. Throws std::invalid_argument unless iso lies in (0, 1).
float isoByteLevel(double iso);

// The marching cubes options of a config. Throws std::invalid_argument "<key>: <problem>".
MarchingCubesOptions marchingCubesOptions(const HandMesherConfig& c);

// The file alone, checked. Throws std::runtime_error "<path>: <key>: <problem>".
HandMesherConfig loadHandMesherConfig(const std::string& path);

}  // namespace cvephands
