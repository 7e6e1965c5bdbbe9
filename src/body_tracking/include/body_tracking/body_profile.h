// The person's measurements: bone lengths and part radii of the quadric body model. Loaded from
// a YAML body profile (config/body_profile.yaml documents every field); the defaults are the
// medium-sized adult of the simulated rig (tabletop_sim/body_model.h). The tracker reads the
// arms' length online (arm_length.h, on by default) and the trunk's girth when asked
// (trunk_girth.h, off by default); nothing else: give a user of another build their own profile.
#pragma once

#include <string>

namespace YAML {
class Node;
}

namespace body_tracking {

struct BodyProfile {
  // Skeleton (m), in the frames of tabletop_msgs/BodyPose.
  double spine_height = 0.25;          // pelvis origin -> upper-spine joint
  double shoulder_half_width = 0.17;   // chest centre line -> shoulder joint (at shift 0)
  double shoulder_height = 0.29;       // shoulder joints above the spine joint
  double neck_height = 0.34;           // neck pivot above the spine joint
  double upper_arm = 0.29;             // shoulder -> elbow
  double forearm = 0.26;               // elbow -> wrist
  double wrist_to_hand = 0.05;         // wrist -> hand centre, along the forearm
  // Parts (m). Trunk parts are elliptic cylinders: half width (x) and half depth (y).
  double abdomen_half_width = 0.155, abdomen_half_depth = 0.11;  // pelvis up to the spine joint
  double chest_half_width = 0.165, chest_half_depth = 0.105;     // spine joint up to the shoulders
  double head_centre_height = 0.15;  // head centre above the neck pivot
  double head_centre_forward = 0.025;
  double head_half_width = 0.08, head_half_depth = 0.10, head_half_height = 0.12;
  double upper_arm_radius = 0.05;
  double forearm_radius = 0.04;
  double hand_half_length = 0.07, hand_half_width = 0.045, hand_half_thickness = 0.025;

  // Throws std::invalid_argument naming the field for a non-finite or non-positive value.
  void validate() const;
  // Fields missing from the node keep their current values; unknown keys throw
  // std::invalid_argument (a misspelt key must not pass silently).
  void merge(const YAML::Node& node);
  static BodyProfile fromYamlFile(const std::string& path);
};

}  // namespace body_tracking
