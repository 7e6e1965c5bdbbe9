// The point light found in a recorded sequence: DIR/<camera name>/*.png, one directory per
// camera, the same file name in every directory = the same instant (the frames of a
// synchronised capture). The instants are numbered by the sorted union of the file names, so a
// camera that dropped a frame only misses that frame. ROS-free.
#pragma once

#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "tabletop_capture/calibration/light_blob.h"
#include "tabletop_capture/calibration/light_track.h"

namespace tabletop_capture {

struct LightImagesCamera {
  int images = 0, found = 0;
  std::map<std::string, int> rejected;  // why the light was not found ("too dark": 12, ...)
};

struct LightImages {
  LightTrack track;
  std::vector<std::string> instants;       // file names; frame i = instants[i]
  std::vector<LightImagesCamera> cameras;  // per camera (the order of camera_names)
};

// progress(camera index, its statistics) after each camera's directory. Throws
// std::runtime_error if no camera has an image or an image cannot be read.
LightImages detectLightInImages(const std::vector<std::string>& camera_names, const std::string& dir,
                                const LightBlobOptions& options = {},
                                const std::function<void(int, const LightImagesCamera&)>& progress = {});

}  // namespace tabletop_capture
