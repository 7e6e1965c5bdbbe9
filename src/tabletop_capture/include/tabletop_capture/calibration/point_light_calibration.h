// Extrinsic calibration of a multi-camera rig from a moving point light (issue 18 step 2,
// thesis 3.2.4 after Svoboda et al. 2005): the light waved through the workspace is one 3D
// point per frame, seen by several cameras at once; the camera poses and those points are
// found together from the pixels alone, the intrinsics being known (calibrate_intrinsics).
//
//  1. Initialisation, incremental: the pair of cameras with the most light positions in common
//     gives a relative pose from their essential matrix (RANSAC on undistorted points); their
//     points are triangulated; then the camera that sees most of the triangulated points is
//     added by PnP (RANSAC), its points triangulated, and so on. Each camera is placed against
//     all cameras placed before it, so a ring of cameras that overlap only partially, or that see
//     the light from opposite sides, needs no chain of pairwise scales.
//  2. Bundle adjustment (Ceres): all poses and points, the pixel error through each camera's own
//     distortion, a Huber loss; then the observations whose error exceeds max(outlier_min_px,
//     outlier_sigmas x the robust sigma (1.4826 x median)) are dropped and it is solved again.
//  3. Gauge: a moving light fixes neither the world's origin nor its scale (thesis 3.2.4). If
//     the input rig has approximate poses (camera centres not all at one point or on a line),
//     the result is mapped onto them by the similarity of the camera centres (Umeyama); if not,
//     camera 0 is the world origin (world_T_camera = identity) and the distance between cameras
//     0 and 1 is `reference_distance` (1 unit: the scale is arbitrary until the desk-marker
//     step).
// Deterministic: the random steps take options.seed. ROS-free.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tabletop_capture/calibration/light_track.h"
#include "tabletop_capture/rig_description.h"

namespace tabletop_capture {

// Input the calibration cannot work with: fewer than 3 cameras, detections of other cameras
// than the rig's, no frame seen by 3 cameras, a camera that never saw the light together with
// two others, a camera that cannot be placed (too few light positions shared with the cameras
// placed before it). what() says which camera and why. A camera is never left out silently:
// a rig with one camera's pose missing or wrong would mislead every later stage.
class PointLightCalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct PointLightCalibrationOptions {
  int min_cameras_per_frame = 3;  // frames seen by fewer are not used (Svoboda: >= 3)
  int min_shared_points = 12;     // a camera pair or a camera added by PnP needs this many
  int few_points_warning = 40;    // a camera with fewer inlier points gets a warning
  // ... and one whose inlier points' convex hull covers less of its image than this. (The
  // workspace box, which each camera of the default rig just sees whole, covers 40-60 % of its
  // image; a light waved through it at random for 20 s covers 15-25 %: its corners are rarely
  // reached.)
  double coverage_warning = 0.10;
  double ransac_threshold_px = 2.0;   // essential matrix, PnP and triangulation inliers
  double huber_px = 1.0;              // robust loss of the bundle adjustment
  double outlier_min_px = 1.0;        // never drop an observation closer than this
  double outlier_sigmas = 4.0;        // ... or closer than this many robust sigmas
  int outlier_rounds = 3;             // drop-and-resolve rounds at most
  int max_iterations = 100;           // per bundle adjustment
  bool refine_intrinsics = false;     // also fx, fy, cx, cy (distortion stays fixed)
  bool align_to_input_poses = true;   // see the gauge above
  double reference_distance = 1.0;    // |c1 - c0| without input poses
  unsigned seed = 1;
};

struct PointLightCameraStats {
  int observations = 0;  // frames used in which this camera saw the light
  int inliers = 0;
  int outliers = 0;
  double rms_px = 0;     // reprojection error over its inliers
  double coverage = 0;   // area of the inliers' convex hull / image area
};

struct PointLightCalibration {
  RigDescription rig;                   // the input intrinsics (refined if asked), the new poses
  std::vector<Eigen::Vector3d> points;  // reconstructed light positions (world)...
  std::vector<int> point_frames;        // ... and their frame numbers
  std::vector<PointLightCameraStats> cameras;
  int frames_used = 0;         // frames seen by >= min_cameras_per_frame cameras
  double mean_error_px = 0;    // over all inlier observations
  double rms_px = 0;
  int iterations = 0;          // of all bundle adjustments together
  std::string gauge;           // how the world frame and its scale were chosen
  std::vector<std::string> warnings;
};

// Progress lines ("init: cam0-cam3 ...", "bundle adjustment: ...") for a tool to print.
using PointLightProgress = std::function<void(const std::string&)>;

// `intrinsics`: the rig whose cameras' intrinsics are known (poses: approximate or identity),
// in the order of track.cameras (names must match). Throws PointLightCalibrationError.
PointLightCalibration calibrateFromPointLight(const RigDescription& intrinsics, const LightTrack& track,
                                              const PointLightCalibrationOptions& options = {},
                                              const PointLightProgress& progress = {});

}  // namespace tabletop_capture
