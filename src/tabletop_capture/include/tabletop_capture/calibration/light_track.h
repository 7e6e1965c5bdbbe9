// The correspondences of the point-light calibration: at each instant (frame) the pixel where
// each camera saw the light, or nothing. The same frame number across cameras is the same
// instant (the cameras are synchronised), so a frame seen by several cameras is one 3D point.
// Saved as CSV ("frame,camera,u,v", camera by name) so that a solve can be re-run without
// reading the images again. ROS-free.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace tabletop_capture {

struct LightFrame {
  int frame = 0;
  std::vector<std::optional<Eigen::Vector2d>> pixels;  // per camera (rig order)
  int seenBy() const;
};

struct LightTrack {
  std::vector<std::string> cameras;  // names in rig order
  std::vector<LightFrame> frames;    // ascending frame numbers, each at most once

  explicit LightTrack(std::vector<std::string> camera_names = {}) : cameras(std::move(camera_names)) {}
  int numCameras() const { return static_cast<int>(cameras.size()); }
  // Records camera's detection in frame (creating the frame; frames may come in any order).
  // Throws std::out_of_range for a bad camera index.
  void add(int frame, int camera, const Eigen::Vector2d& pixel);
  // Detections per camera, and frames seen by at least `min_cameras`.
  std::vector<int> detectionsPerCamera() const;
  int framesSeenBy(int min_cameras) const;
};

// Thrown for a malformed detections file; what() names the file and the line.
class LightTrackError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string lightTrackToCsv(const LightTrack& track);
// Parses CSV text; cameras not in `camera_names` are an error (the rig decides the order).
LightTrack parseLightTrackCsv(const std::string& text, const std::vector<std::string>& camera_names,
                              const std::string& source);
void saveLightTrackCsv(const LightTrack& track, const std::string& path);
LightTrack loadLightTrackCsv(const std::string& path, const std::vector<std::string>& camera_names);

}  // namespace tabletop_capture
