#include "body_tracking/body_profile.h"

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace body_tracking {

namespace {

std::vector<std::pair<const char*, double*>> fields(BodyProfile* p) {
  return {{"spine_height", &p->spine_height},
          {"shoulder_half_width", &p->shoulder_half_width},
          {"shoulder_height", &p->shoulder_height},
          {"neck_height", &p->neck_height},
          {"upper_arm", &p->upper_arm},
          {"forearm", &p->forearm},
          {"wrist_to_hand", &p->wrist_to_hand},
          {"abdomen_half_width", &p->abdomen_half_width},
          {"abdomen_half_depth", &p->abdomen_half_depth},
          {"chest_half_width", &p->chest_half_width},
          {"chest_half_depth", &p->chest_half_depth},
          {"head_centre_height", &p->head_centre_height},
          {"head_centre_forward", &p->head_centre_forward},
          {"head_half_width", &p->head_half_width},
          {"head_half_depth", &p->head_half_depth},
          {"head_half_height", &p->head_half_height},
          {"upper_arm_radius", &p->upper_arm_radius},
          {"forearm_radius", &p->forearm_radius},
          {"hand_half_length", &p->hand_half_length},
          {"hand_half_width", &p->hand_half_width},
          {"hand_half_thickness", &p->hand_half_thickness}};
}

}  // namespace

void BodyProfile::validate() const {
  BodyProfile copy = *this;
  for (const auto& f : fields(&copy)) {
    // head_centre_forward may be zero or negative (a face set back); all others are sizes.
    const bool signed_ok = std::string(f.first) == "head_centre_forward";
    if (!std::isfinite(*f.second) || (!signed_ok && *f.second <= 0.0))
      throw std::invalid_argument(std::string("body profile: ") + f.first +
                                  " must be a finite length > 0 (m)");
  }
}

void BodyProfile::merge(const YAML::Node& node) {
  if (!node) return;
  if (!node.IsMap()) throw std::invalid_argument("body profile: expected a map of lengths (m)");
  auto list = fields(this);
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    bool known = false;
    for (auto& f : list)
      if (key == f.first) {
        *f.second = kv.second.as<double>();
        known = true;
      }
    if (!known) throw std::invalid_argument("body profile: unknown key '" + key + "'");
  }
  validate();
}

BodyProfile BodyProfile::fromYamlFile(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("body profile: cannot read " + path + ": " + e.what());
  }
  BodyProfile p;
  p.merge(root["body_profile"] ? root["body_profile"] : root);
  return p;
}

}  // namespace body_tracking
