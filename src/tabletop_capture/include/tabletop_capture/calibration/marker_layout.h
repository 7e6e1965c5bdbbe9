// The square fiducial markers lying on the desk for the world-frame step of the rig calibration
// (issue 18 step 3, thesis 3.2.4): their ArUco dictionary, ids, printed sizes and where their
// centres sit on the desk. The world frame (DESIGN.md section 3) is defined by this layout: the
// desk surface is z = 0, every marker's x axis points along world x (the user's right) and its
// y axis along world y (away from the user), and the positions are world coordinates, so the
// default layout puts the reference marker (id 0) at the origin. ROS-free.
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace tabletop_capture {

struct DeskMarker {
  int id = 0;
  double size = 0.15;                          // edge of the black square (m), border included
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // on the desk (world x, y; m)
};

struct MarkerLayout {
  std::string dictionary = "DICT_4X4_50";  // OpenCV's name of the ArUco dictionary
  std::vector<DeskMarker> markers;

  // Index of the marker with this id, or -1.
  int find(int id) const;
  // The 4 corners of marker `index` in world, in ArUco's order: as seen from above with world y
  // up, top-left, top-right, bottom-right, bottom-left (clockwise), z = 0.
  std::array<Eigen::Vector3d, 4> corners(int index) const;
  // Throws std::invalid_argument naming the field: unknown dictionary, id outside it, a
  // repeated id, size <= 0, overlapping markers, no marker.
  void validate() const;
  // The same layout printed at `factor` times its size (positions and sizes scaled).
  MarkerLayout scaled(double factor) const;
};

// Five 150 mm markers of DICT_4X4_50, one per A4 sheet (its 25 mm cells leave the one-cell
// white quiet zone on the sheet): id 0 at the desk centre (the world origin), ids 1-4 at
// (-+0.35, -+0.3) (1 front left, 2 front right, 3 back right, 4 back left). A board spread over
// the desk fixes the world's tilt and the scale from the markers' spacing, not from the edge of
// one small marker (docs/calibration.md has the figures: one 180 mm marker misses the bar).
MarkerLayout defaultMarkerLayout();

// YAML: "dictionary: DICT_4X4_50" and "markers: [{id: 0, size: 0.15, x: 0.0, y: 0.0}, ...]".
// Throws std::runtime_error naming the source and the field.
MarkerLayout parseMarkerLayoutYaml(const std::string& text, const std::string& source);
MarkerLayout loadMarkerLayoutYaml(const std::string& path);
std::string markerLayoutToYaml(const MarkerLayout& layout);

// The names parseMarkerLayoutYaml accepts (DICT_4X4_50 ... DICT_7X7_1000, DICT_ARUCO_ORIGINAL),
// and the number of ids and bits per side of one.
bool markerDictionaryKnown(const std::string& name);
int markerDictionarySize(const std::string& name);
int markerDictionaryBits(const std::string& name);

}  // namespace tabletop_capture
