// Connected components of an indexed triangle mesh (triangles sharing a vertex are connected),
// and the removal of small ones. A hand's skin hull carries specks: a voxel or two of
// skin-coloured desk or noise that enough views agree on, each meshed as a tiny closed surface
// centimetres from the hand. They are not hand geometry, they spoil the display and every
// distance statistic, and no amount of smoothing moves them; dropping components below a few
// dozen triangles removes them without touching the hand (a fingertip cut off by the hull is a
// few hundred triangles at 3.6 mm). A hand's mesh also keeps only the components near the hand
// (keepHandComponents).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "cvephands_bridge/mesh/triangle_mesh.h"

namespace cvephands {

// Labels vertices by component; returns the number of components (vertices used by no
// triangle get their own).
size_t labelComponents(const TriangleMesh& mesh, std::vector<uint32_t>* vertex_label);

// Removes the components with fewer than `min_triangles` triangles; the kept vertices and
// triangles keep their order (deterministic), normals follow their vertices, unused vertices
// are dropped. Returns the number of triangles removed. min_triangles <= 1 keeps everything.
size_t removeSmallComponents(TriangleMesh* mesh, size_t min_triangles);

// What the hand meshing stage keeps of the mesh of a hand's sub-volume centred on `centre` (the
// tracked hand): the components with at least `min_triangles` triangles (<= 1: any size) that
// come within `keep_radius` of the centre (0: anywhere). A 30 cm cube around a hand also holds
// the face, the other hand, and skin-coloured hair, clothing or clutter when they come near:
// other targets' skin or nobody's, not this hand. Nothing near the centre: an empty mesh.
// Returns the number of triangles removed (order and normals as removeSmallComponents).
size_t keepHandComponents(TriangleMesh* mesh, const Eigen::Vector3f& centre, size_t min_triangles,
                          float keep_radius);

}  // namespace cvephands
