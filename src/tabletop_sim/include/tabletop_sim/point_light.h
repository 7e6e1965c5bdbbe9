// A simulated point-light calibration sequence (issue 18 step 4; thesis 3.2.4): a light waved
// through the workspace along a smooth random path, each camera's view of it as a small bright
// spot on a dim background (the room darkened), with the faults a real sequence has: the light
// hidden from a camera for a while (behind the user's hand or body), a camera that sees it only
// now and then, and a reflection detected instead of the light. The truth is the rig and the
// path. ROS-free.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "tabletop_capture/rig_description.h"

namespace tabletop_sim {

// Positions per frame: Catmull-Rom through random waypoints in `box` (kept `margin` inside it),
// `step` metres per frame (0.02 m at 30 fps: a calm wave of 0.6 m/s).
std::vector<Eigen::Vector3d> randomLightPath(const Eigen::AlignedBox3d& box, int frames, std::uint64_t seed,
                                             double step = 0.02, double margin = 0.05);

struct LightSequenceFaults {
  double occlusion = 0;       // fraction of the frames the light is hidden from each camera
  double outliers = 0;        // fraction of a camera's views showing a reflection instead
  int sparse_camera = -1;     // this camera sees the light in only sparse_fraction of the frames
  double sparse_fraction = 1;
  int mean_hidden_frames = 20;  // occlusions come in runs of about this length
  // An LED shines into a cone about its axis (180: a diffuser all round). The axis turns slowly
  // as the hand waves, so cameras on opposite sides see the light at different times.
  double emission_half_angle_deg = 180;
};

// What one camera shows at one instant.
struct LightView {
  bool light = false;  // the light is in view and not hidden
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();       // its true (distorted) pixel
  bool reflection = false;                               // a distractor spot instead
  Eigen::Vector2d reflection_pixel = Eigen::Vector2d::Zero();
};

// views[frame][camera]. The light is in view if it projects in front of the camera and at least
// 3 px inside the image.
std::vector<std::vector<LightView>> planLightSequence(const tabletop_capture::RigDescription& rig,
                                                      const std::vector<Eigen::Vector3d>& path,
                                                      const LightSequenceFaults& faults, std::uint64_t seed);

struct LightImageOptions {
  double spot_sigma = 1.2;   // px: an LED with a diffuser, slightly out of focus
  double peak = 230;         // grey levels above the background at the spot's centre
  double background = 18;    // the darkened room
  double noise_sigma = 2.0;  // sensor noise (grey levels), as the rig's default
};

// rgb8 image of one camera's view: the spot (light or reflection) integrated over each pixel,
// a dim background and noise. `seed` makes the noise reproducible.
cv::Mat renderLightView(const tabletop_capture::CameraModel& camera, const LightView& view,
                        const LightImageOptions& options, std::uint64_t seed);

}  // namespace tabletop_sim
