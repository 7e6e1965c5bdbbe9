// Metric scale and world frame for a rig known up to a similarity (issue 18 step 3, thesis
// 3.2.4): the point-light step gives camera poses with an arbitrary origin, rotation and scale.
// The desk markers' corners, seen by >= 2 cameras, are triangulated in that frame, the
// similarity that maps them onto their known desk positions (MarkerLayout) is fitted (Umeyama,
// with scale), and it is applied to every camera pose: the rig in the metric world frame of
// DESIGN.md section 3. Intrinsics are unchanged. ROS-free.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "tabletop_capture/calibration/marker_detection.h"
#include "tabletop_capture/calibration/marker_layout.h"
#include "tabletop_capture/rig_description.h"

namespace tabletop_capture {

// Input that cannot give a world frame: fewer than 2 cameras saw a marker of the layout, or no
// marker corner was seen by 2 cameras.
class MarkerAlignmentError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MarkerAlignmentOptions {
  int refine_iterations = 10;        // Gauss-Newton steps per corner
  double max_fit_rms = 0.002;        // m: above it the layout does not match what was seen
  double square_tolerance = 0.02;    // relative: sides and diagonals of each marker
  double planar_tolerance = 0.003;   // m: corners off the desk plane
  double max_reprojection_px = 1.0;  // per corner RMS over its cameras
};

struct AlignedCorner {
  int marker_id = 0, corner = 0;            // corner 0..3 in ArUco's order
  std::vector<std::string> cameras;         // that saw it
  Eigen::Vector3d triangulated = Eigen::Vector3d::Zero();  // in the input rig's frame
  Eigen::Vector3d world = Eigen::Vector3d::Zero();         // triangulated, mapped into world
  Eigen::Vector3d layout = Eigen::Vector3d::Zero();        // where the layout says it is
  std::vector<double> residuals_px;         // reprojection, per camera in `cameras`
  double rms_px = 0;
  double rms_mm = 0;                        // the pixel residuals at the corner's distance
};

struct CameraPoseChange {
  std::string camera;
  Eigen::Vector3d centre_before, centre_after;  // input frame; world
  int markers_seen = 0;
};

struct MarkerAlignment {
  RigDescription rig;  // every camera's pose in world (intrinsics as given)
  // world = scale * rotation * input + translation.
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  std::vector<AlignedCorner> corners;
  std::vector<CameraPoseChange> cameras;
  std::vector<int> markers_used;            // ids triangulated (all 4 corners, >= 2 cameras)
  int cameras_with_marker = 0;
  double fit_rms = 0, fit_max = 0;          // m: world corners against the layout
  double reprojection_rms_px = 0;
  std::vector<std::string> warnings;
};

// sightings[i]: what rig.cameras[i] saw (mean corners per marker id); ids not in the layout are
// ignored. Throws MarkerAlignmentError (see above) and std::invalid_argument for a sightings
// vector of the wrong length or a bad layout. Warnings (nothing thrown): the layout's fit residual
// above max_fit_rms (wrong ids, positions or sizes of some markers), a marker that is not square
// or not flat (a wrong size for one marker, a bent sheet), a marker seen by one camera only, a
// poorly reprojected corner, a camera below the desk after the alignment (z < 0: the rig looks
// at the desk from underneath, e.g. a mirrored input rig; the result is not flipped: a proper
// similarity cannot undo a reflection).
MarkerAlignment alignRigToMarkers(const RigDescription& rig, const std::vector<MarkerSightings>& sightings,
                                  const MarkerLayout& layout, const MarkerAlignmentOptions& options = {});

// The same similarity applied to a rig: world_T_camera' = S * world_T_camera with the rotation
// part rotating the camera and the translation scaled. Also for other points (e.g. the point
// light's path): world = scale * rotation * p + translation.
RigDescription transformRig(const RigDescription& rig, double scale, const Eigen::Matrix3d& rotation,
                            const Eigen::Vector3d& translation);

}  // namespace tabletop_capture
