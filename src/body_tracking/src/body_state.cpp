#include "body_tracking/body_state.h"

namespace body_tracking {

const char* dofName(int i) {
  static const char* const kNames[dof::COUNT] = {
      "torso_x",          "torso_y",          "torso_z",         "torso_roll",
      "torso_pitch",      "torso_yaw",        "spine_bend",      "head_yaw",
      "l_shoulder_swing_1", "l_shoulder_swing_2", "l_shoulder_shift", "l_elbow_flex",
      "l_elbow_twist",    "r_shoulder_swing_1", "r_shoulder_swing_2", "r_shoulder_shift",
      "r_elbow_flex",     "r_elbow_twist"};
  return i >= 0 && i < dof::COUNT ? kNames[i] : "?";
}

}  // namespace body_tracking
