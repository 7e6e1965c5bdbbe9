// How far a calibrated rig's camera poses are from a reference rig's (the truth of a simulated
// sequence): per camera the position (m) and orientation (deg) error, after mapping the
// calibrated rig by a similarity when its frame is not the reference's (a point-light rig is
// known up to one). One formula for the calibration tools' --truth reports and the calibration
// tests. ROS-free.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "tabletop_capture/rig_description.h"

namespace tabletop_capture {

struct CameraPoseError {
  std::string camera;
  double position_m = 0;    // |camera centre - reference centre|
  double rotation_deg = 0;  // angle of the rotation between the two orientations
};

// Per camera of `rig`, in its order, against the reference camera of the same name, after
// mapping `rig` by `similarity` (s R | t as Eigen::umeyama returns it: p -> s R p + t; the
// cameras are rotated by R). Throws std::invalid_argument naming a camera the reference lacks.
std::vector<CameraPoseError> cameraPoseErrors(const RigDescription& rig, const RigDescription& reference,
                                              const Eigen::Matrix4d& similarity = Eigen::Matrix4d::Identity());

// The similarity (Umeyama, with scale) of rig's camera centres onto those of the reference's
// cameras of the same names. Throws std::invalid_argument as above.
Eigen::Matrix4d cameraCentreSimilarity(const RigDescription& rig, const RigDescription& reference);

// The largest position and rotation errors.
CameraPoseError worstPoseError(const std::vector<CameraPoseError>& errors);

}  // namespace tabletop_capture
