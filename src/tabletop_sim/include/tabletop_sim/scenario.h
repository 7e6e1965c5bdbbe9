// Scenarios of the simulated rig: who sits there, how the room is lit, which cameras watch and
// what is on the desk. The default scenario is DESIGN.md's office, person and 8-camera ring;
// the generator draws the others from a seed (DESIGN.md section 5), so the accuracy bars are
// checked over many worlds and never tuned to one.
//
// Names: "default", the presets of scenarioPresets(), and "random-<seed>" (any unsigned
// 64-bit seed; the same seed gives the same scenario on every machine: the generator uses its
// own SplitMix64 stream, not std:: distributions, whose output is implementation-defined).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "tabletop_capture/rig_description.h"
#include "tabletop_sim/body_model.h"
#include "tabletop_sim/camera_effects.h"
#include "tabletop_sim/lighting.h"
#include "tabletop_sim/primitives.h"
#include "tabletop_sim/scene.h"

namespace tabletop_sim {

struct Scenario {
  std::string name = "default";
  uint64_t seed = 0;  // 0 for default and presets

  // The person: shape, sleeves and hair (BodyOptions) and the albedo of each material
  // (indexed by Material; skin tone, clothing and hair colours).
  BodyOptions body;
  std::array<Eigen::Vector3d, kNumMaterials> albedo;

  // The light: the scene's sun-like light and its changes over time (lighting.h).
  LightingScript lighting;

  // The cameras: the rig (empty = the default ring) and what their optics and electronics do
  // to the pictures (camera_effects.h). noise_sigma: sensor noise (grey levels).
  tabletop_capture::RigDescription rig;
  CameraEffects effects;
  double noise_sigma = 2.0;

  // The room: objects added to the default office (clutter, skin-coloured things, occluders
  // in front of the torso); the office's own objects stay.
  std::vector<SceneObject> extra_objects;

  // One line per aspect, for reports and the demo's log.
  std::string describe() const;
};

// The default scenario (the one every older test and figure used).
Scenario defaultScenario();
// Seeded random scenario "random-<seed>".
Scenario randomScenario(uint64_t seed);
// Presets: each the default with one aspect pushed to a hard case (dark_skin, pale_skin,
// skin_sleeves, cuffs, short_sleeves, four_cameras, vga, lights_on, flicker, clutter,
// occluder, low_light).
const std::vector<std::string>& scenarioPresets();
// By name (see above). Throws std::invalid_argument listing the valid forms otherwise.
Scenario scenarioByName(const std::string& name);

// The default albedos (linear R, G, B in [0, 1]) of the person's materials.
std::array<Eigen::Vector3d, kNumMaterials> defaultAlbedo();
// Skin albedo of Fitzpatrick type 1..6 (interpolated for fractional types).
Eigen::Vector3d fitzpatrickSkin(double type);

}  // namespace tabletop_sim
