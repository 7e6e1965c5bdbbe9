// Connected components of an indexed triangle mesh (triangles sharing a vertex are connected),
// and the removal of small ones. A hand's skin hull carries specks: a voxel or two of
// skin-coloured desk or noise that enough views agree on, each meshed as a tiny closed surface
// centimetres from the hand. They are not hand geometry, they spoil the display and every
// distance statistic, and no amount of smoothing moves them; dropping components below a few
// dozen triangles removes them without touching the hand (a fingertip cut off by the hull is a
// few hundred triangles at 3.6 mm).
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

}  // namespace cvephands
