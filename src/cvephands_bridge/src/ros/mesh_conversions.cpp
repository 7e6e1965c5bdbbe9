#include "cvephands_bridge/ros/mesh_conversions.h"

#include <cmath>
#include <stdexcept>

namespace cvephands {

ProbabilityGridView gridView(const tabletop_msgs::VoxelVolume& msg) {
  ProbabilityGridView g;
  const uint64_t n = uint64_t(msg.size_x) * msg.size_y * msg.size_z;
  if (n != msg.data.size())
    throw std::invalid_argument("volume is " + std::to_string(msg.size_x) + "x" +
                                std::to_string(msg.size_y) + "x" + std::to_string(msg.size_z) +
                                " but carries " + std::to_string(msg.data.size()) + " bytes");
  if (msg.size_x > 4096 || msg.size_y > 4096 || msg.size_z > 4096)
    throw std::invalid_argument("volume side above 4096 voxels");
  g.dims = Eigen::Vector3i(int(msg.size_x), int(msg.size_y), int(msg.size_z));
  g.data = msg.data.empty() ? nullptr : msg.data.data();
  g.origin = Eigen::Vector3d(msg.origin.x, msg.origin.y, msg.origin.z);
  g.voxel_size = msg.voxel_size;
  g.validate();
  return g;
}

void toMessage(const TriangleMesh& mesh, tabletop_msgs::HandMesh* out) {
  out->vertices.resize(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    out->vertices[i].x = mesh.vertices[i].x();
    out->vertices[i].y = mesh.vertices[i].y();
    out->vertices[i].z = mesh.vertices[i].z();
  }
  out->normals.resize(mesh.normals.size());
  for (size_t i = 0; i < mesh.normals.size(); ++i) {
    out->normals[i].x = mesh.normals[i].x();
    out->normals[i].y = mesh.normals[i].y();
    out->normals[i].z = mesh.normals[i].z();
  }
  out->triangles = mesh.triangles;
}

void toMarker(const TriangleMesh& mesh, const std::string& ns, int id,
              const std_msgs::ColorRGBA& color, visualization_msgs::Marker* out) {
  out->ns = ns;
  out->id = id;
  out->type = visualization_msgs::Marker::TRIANGLE_LIST;
  out->action = visualization_msgs::Marker::ADD;
  out->pose.orientation.w = 1.0;
  out->scale.x = out->scale.y = out->scale.z = 1.0;
  out->color = color;
  out->points.resize(mesh.triangles.size());
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Eigen::Vector3f& v = mesh.vertices[mesh.triangles[i]];
    out->points[i].x = v.x();
    out->points[i].y = v.y();
    out->points[i].z = v.z();
  }
}

}  // namespace cvephands
