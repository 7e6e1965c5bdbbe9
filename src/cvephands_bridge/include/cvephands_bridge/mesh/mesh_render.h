// A small software rasteriser for pictures of hand meshes (the demo's and the accuracy tool's
// output images): perspective camera, z-buffer, Gouraud shading of the per-vertex normals with a
// head light. Offscreen and dependency-free beyond OpenCV's cv::Mat, so it works headless in CI
// where an OpenGL context (rviz under Xvfb) would be slow and fragile. Not for live display:
// rviz shows the meshes live from cve/hand_meshes.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "cvephands_bridge/mesh/triangle_mesh.h"

namespace cvephands {

struct RenderCamera {
  Eigen::Vector3d eye{0.0, -1.0, 0.6};     // camera centre (world, m)
  Eigen::Vector3d target{0.0, 0.0, 0.0};   // looked-at point
  Eigen::Vector3d up{0.0, 0.0, 1.0};       // world direction shown upwards
  double vertical_fov_deg = 30.0;
  int width = 640, height = 480;
};

struct RenderItem {
  const TriangleMesh* mesh = nullptr;    // not owned; normals used if present, else face normals
  Eigen::Vector3f color{0.93f, 0.72f, 0.60f};  // RGB in [0, 1]
};

// BGR CV_8UC3 image of the meshes on `background` (BGR). Triangles behind the near plane
// (5 cm) are skipped. Throws std::invalid_argument for a degenerate camera (eye == target, up
// parallel to the view, size < 1, fov outside (0, 180)).
cv::Mat renderMeshes(const std::vector<RenderItem>& items, const RenderCamera& camera,
                     const cv::Vec3b& background = cv::Vec3b(255, 255, 255));

// A camera looking along `direction` (world, need not be unit) at the centre of the meshes'
// bounding box, far enough that the whole box fits with a margin. Meshes without vertices are
// ignored; with none at all the camera looks at the origin.
RenderCamera framingCamera(const std::vector<RenderItem>& items, const Eigen::Vector3d& direction,
                           int width = 640, int height = 480);

}  // namespace cvephands
