// A camera rig: the calibrated cameras and the world frame they are expressed in, loaded from
// and saved to a rig YAML file (format documented in tabletop_sim/config/sim_rig.yaml). ROS-free.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "tabletop_capture/camera_model.h"

namespace tabletop_capture {

// Thrown for any invalid rig file. what() names the file, the camera and the field, e.g.
// "rig.yaml: camera 'cam2' (index 2): field 'rotation': not a rotation matrix (det = -1)".
class RigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RigDescription {
  std::string name = "rig";
  std::string world_frame = "world";
  std::vector<CameraModel> cameras;

  // Index of the camera with this name, or -1.
  int findCamera(const std::string& camera_name) const;
};

// Loads and validates a rig YAML file. Throws RigError.
RigDescription loadRigYaml(const std::string& path);
// Parses rig YAML text; `source` is the name used in error messages. Throws RigError.
RigDescription parseRigYaml(const std::string& yaml_text, const std::string& source);
// Serialises a rig (exact round trip through parseRigYaml to 1e-12).
std::string rigToYaml(const RigDescription& rig);
// Writes rigToYaml to a file. Throws RigError if the file cannot be written.
void saveRigYaml(const RigDescription& rig, const std::string& path);
// Checks a camera in memory with the same rules as the loader (finite values, positive focal
// lengths and sizes, orthonormal right-handed rotation). Throws RigError naming `source`.
void validateCamera(const CameraModel& camera, const std::string& source, int index);

}  // namespace tabletop_capture
