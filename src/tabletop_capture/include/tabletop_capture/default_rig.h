// The simulated rig's default cameras: N cameras on a ring around and above the desk, all
// looking at the workspace (as in thesis figure 4.2: every camera sees the whole user space).
#pragma once

#include <Eigen/Geometry>

#include "tabletop_capture/rig_description.h"

namespace tabletop_capture {

struct DefaultRigOptions {
  int num_cameras = 8;     // 1..16
  int width = 320;         // pixels
  int height = 240;
  bool distortion = true;  // mild barrel distortion (plumb_bob) as on the thesis' webcams
};

// Camera i sits on a ring of radius ~1.4 m around the desk, alternately 1.05 m and 1.4 m above
// it, skipping the sector straight behind the user (their back would hide the hands), and is
// zoomed so that the whole workspace box just fits its image.
RigDescription makeDefaultRig(const DefaultRigOptions& options = DefaultRigOptions());

// A camera at `center` looking at `target` (REP 103 optical frame, world z up).
Eigen::Isometry3d lookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target);

// The largest focal length fx (fy = fx * aspect) that keeps every corner of `box` (world)
// `margin` pixels inside the image of `cam` (its pose, size and principal point; barrel
// distortion only pulls corners in, so it is ignored). Every corner must be in front.
double focalToFit(const CameraModel& cam, const Eigen::AlignedBox3d& box, double margin,
                  double aspect = 1.002);

}  // namespace tabletop_capture
