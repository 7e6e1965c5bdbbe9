// An indexed triangle mesh: what the meshing stage hands to compression and the CVE stream.
// Positions in metres in the frame of the volume it came from (world for hand sub-volumes).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace cvephands {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  // Unit outward normals, one per vertex; empty when the producer was asked for none.
  std::vector<Eigen::Vector3f> normals;
  // 3 vertex indices per triangle, counter-clockwise seen from outside (right-hand rule gives
  // the outward face normal).
  std::vector<uint32_t> triangles;

  size_t numVertices() const { return vertices.size(); }
  size_t numTriangles() const { return triangles.size() / 3; }
  bool empty() const { return triangles.empty(); }
  bool hasNormals() const { return !normals.empty(); }
  void clear() {
    vertices.clear();
    normals.clear();
    triangles.clear();
  }
};

}  // namespace cvephands
