// How far a decoded hand mesh is from the mesh of the original volume (codec tests and
// benchmark): point-to-triangle distances both ways (mesh_accuracy.h's truthToMesh with each
// mesh's vertices as the points), so neither direction's vertex spacing biases the figure.
#pragma once

#include <algorithm>
#include <limits>

#include "cvephands_bridge/mesh/mesh_accuracy.h"
#include "cvephands_bridge/mesh/triangle_mesh.h"

namespace cvephands_test {

struct MeshDifference {
  double mean_mm = 0;  // over the vertices of both meshes
  double p95_mm = 0;   // the larger of the two directions' 95th percentiles
  double max_mm = 0;
  bool same_triangles = false;  // identical index lists (same topology, same vertex numbering)
};

inline MeshDifference meshDifference(const cvephands::TriangleMesh& original,
                                     const cvephands::TriangleMesh& decoded) {
  MeshDifference d;
  d.same_triangles = original.triangles == decoded.triangles;
  if (original.empty() && decoded.empty()) return d;
  if (original.empty() || decoded.empty()) {
    d.mean_mm = d.p95_mm = d.max_mm = std::numeric_limits<double>::infinity();
    return d;
  }
  const cvephands::SurfaceDistanceStats a =
      cvephands::truthToMesh(decoded.vertices, decoded.triangles, original.vertices);
  const cvephands::SurfaceDistanceStats b =
      cvephands::truthToMesh(original.vertices, original.triangles, decoded.vertices);
  d.mean_mm = (a.mean_mm * a.count + b.mean_mm * b.count) / double(a.count + b.count);
  d.p95_mm = std::max(a.p95_mm, b.p95_mm);
  d.max_mm = std::max(a.max_mm, b.max_mm);
  return d;
}

}  // namespace cvephands_test
