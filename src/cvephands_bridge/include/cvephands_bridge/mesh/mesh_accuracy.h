// Accuracy of a hand mesh against the true surface: distances (mm) from the mesh to the truth and
// from the truth to the mesh, as mean, 95th percentile and maximum. The truth is a set of points
// sampled uniformly in area on the true surface (for the simulated rig:
// tabletop_sim/surface_samples.h); this file takes plain points, so it depends on
// neither ROS nor the simulator.
//
// - mesh_to_truth: for each mesh vertex used by a triangle, the distance to the NEAREST TRUTH
//   SAMPLE (point to point). It sees spurious geometry (blobs, a surface too far out). Because the
//   samples are discrete it overestimates: a vertex exactly on the true surface still reads the
//   distance to the nearest sample, about 0.40 (mean) / 0.68 (p95) x the sample spacing with the
//   simulator's blue-noise samples, i.e. 0.4 / 0.7 mm at 1 mm spacing. The bias fades as the
//   error grows (sqrt(d^2 + e^2) - d: at d = 2 mm it is ~0.05 mm on the mean); sample at 0.5 mm
//   to halve it. Vertices are not area-weighted (marching-cubes vertices are close to uniform).
// - truth_to_mesh: for each truth sample, the exact distance to the nearest point ON THE MESH
//   TRIANGLES (point to triangle). It sees missing geometry (a finger not reconstructed) and,
//   the samples being uniform in area, it is an area-weighted statistic of the true surface.
//
// Both use a bounding-volume hierarchy (median split, <= 4 items per leaf) with branch-and-bound
// nearest queries. Why not a uniform grid: a missing finger puts thousands of samples centimetres
// from the mesh, where a grid's ring search grows with (distance / cell)^3 while the tree's cost
// barely changes. Why not a library: nanoflann is not installed, PCL's KdTreeFLANN would pull in
// PCL and FLANN for points only, and the triangle queries need the tree anyway.
// Cost: see docs/benchmarks.md (test_mesh_accuracy prints the time of a large mesh).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "cvephands_bridge/mesh/triangle_mesh.h"

namespace cvephands {

struct SurfaceDistanceStats {
  // NaN (and count 0) when there is nothing to measure: no triangles or no truth points.
  double mean_mm = std::numeric_limits<double>::quiet_NaN();
  double p95_mm = std::numeric_limits<double>::quiet_NaN();  // linear between order statistics
  double max_mm = std::numeric_limits<double>::quiet_NaN();
  size_t count = 0;  // distances measured (vertices used by triangles / truth points)
};

struct MeshAccuracy {
  SurfaceDistanceStats mesh_to_truth;  // vertex -> nearest truth sample
  SurfaceDistanceStats truth_to_mesh;  // truth sample -> nearest point on the triangles
};

// Positions in metres (any common frame); triangles as in TriangleMesh (3 indices each).
// Throws std::invalid_argument if triangles.size() is not a multiple of 3 or an index is out of
// range. Degenerate triangles are measured as their edges.
MeshAccuracy meshAccuracy(const std::vector<Eigen::Vector3f>& mesh_vertices,
                          const std::vector<uint32_t>& triangles,
                          const std::vector<Eigen::Vector3f>& truth_points);

inline MeshAccuracy meshAccuracy(const TriangleMesh& mesh,
                                 const std::vector<Eigen::Vector3f>& truth_points) {
  return meshAccuracy(mesh.vertices, mesh.triangles, truth_points);
}

// The two halves alone (same arguments, checks and results), for callers that measure each
// direction on a different subset (e.g. leaving out a band along the volume's faces) and would
// otherwise pay for the half they discard.
SurfaceDistanceStats meshToTruth(const std::vector<Eigen::Vector3f>& mesh_vertices,
                                 const std::vector<uint32_t>& triangles,
                                 const std::vector<Eigen::Vector3f>& truth_points);
SurfaceDistanceStats truthToMesh(const std::vector<Eigen::Vector3f>& mesh_vertices,
                                 const std::vector<uint32_t>& triangles,
                                 const std::vector<Eigen::Vector3f>& truth_points);

}  // namespace cvephands
