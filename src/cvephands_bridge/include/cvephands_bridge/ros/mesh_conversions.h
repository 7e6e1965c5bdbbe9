// Conversions between the meshing core and the ROS messages: the hand volume of a VoxelVolume
// message as a grid view (no copy), and a TriangleMesh as a HandMesh message and as an rviz
// TRIANGLE_LIST marker. The only header of this package's ROS layer (src/ros/).
#pragma once

#include <string>

#include <tabletop_msgs/HandMesh.h>
#include <tabletop_msgs/VoxelVolume.h>
#include <visualization_msgs/Marker.h>

#include "cvephands_bridge/mesh/probability_grid.h"
#include "cvephands_bridge/mesh/triangle_mesh.h"

namespace cvephands {

// A view on msg.data (valid while msg lives). Throws std::invalid_argument (naming the problem)
// if the data size does not match the dims or the geometry is not finite and positive.
ProbabilityGridView gridView(const tabletop_msgs::VoxelVolume& msg);

void toMessage(const TriangleMesh& mesh, tabletop_msgs::HandMesh* out);

// TRIANGLE_LIST marker: 3 points per triangle in the mesh's winding (rviz has no index buffer).
void toMarker(const TriangleMesh& mesh, const std::string& ns, int id,
              const std_msgs::ColorRGBA& color, visualization_msgs::Marker* out);

}  // namespace cvephands
