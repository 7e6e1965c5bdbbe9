// Topology and geometry measurements of triangle meshes for the meshing tests.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <numeric>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cvephands_bridge/mesh/triangle_mesh.h"

namespace cvephands_test {

struct MeshTopology {
  size_t vertices = 0, edges = 0, faces = 0;
  size_t unreferenced_vertices = 0;
  size_t bad_indices = 0;           // index >= vertex count
  size_t degenerate_triangles = 0;  // an index repeated within a triangle
  size_t boundary_edges = 0;        // used by one triangle
  size_t nonmanifold_edges = 0;     // used by more than two triangles
  size_t misoriented_edges = 0;     // two triangles traverse the edge the same way
  size_t components = 0;            // connected via shared vertices
  long euler() const { return long(vertices) - long(edges) + long(faces); }
  // Closed, 2-manifold along edges, consistently wound.
  bool watertight() const {
    return boundary_edges == 0 && nonmanifold_edges == 0 && misoriented_edges == 0 &&
           bad_indices == 0 && degenerate_triangles == 0;
  }
};

inline MeshTopology topology(const cvephands::TriangleMesh& m) {
  MeshTopology t;
  t.faces = m.numTriangles();
  const size_t nv = m.numVertices();
  std::vector<int> used(nv, 0);
  std::vector<size_t> parent(nv);
  std::iota(parent.begin(), parent.end(), size_t(0));
  auto find = [&](size_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  // Undirected edge -> (uses, uses in the a<b direction).
  std::map<std::pair<uint32_t, uint32_t>, std::array<int, 2>> edges;
  for (size_t f = 0; f < t.faces; ++f) {
    const uint32_t* v = &m.triangles[3 * f];
    if (v[0] >= nv || v[1] >= nv || v[2] >= nv) {
      ++t.bad_indices;
      continue;
    }
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) ++t.degenerate_triangles;
    for (int i = 0; i < 3; ++i) {
      const uint32_t a = v[i], b = v[(i + 1) % 3];
      used[a] = 1;
      parent[find(a)] = find(b);
      auto& e = edges[{std::min(a, b), std::max(a, b)}];
      ++e[0];
      e[1] += a < b;
    }
  }
  t.edges = edges.size();
  for (const auto& kv : edges) {
    const int uses = kv.second[0], forward = kv.second[1];
    if (uses == 1) ++t.boundary_edges;
    if (uses > 2) ++t.nonmanifold_edges;
    if (uses == 2 && forward != 1) ++t.misoriented_edges;
  }
  for (size_t i = 0; i < nv; ++i) {
    if (!used[i]) {
      ++t.unreferenced_vertices;
      continue;
    }
    ++t.vertices;
    if (find(i) == i) ++t.components;
  }
  return t;
}

// Edges used by a single triangle, as vertex pairs.
inline std::vector<std::pair<uint32_t, uint32_t>> boundaryEdges(const cvephands::TriangleMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  for (size_t f = 0; f < m.numTriangles(); ++f)
    for (int i = 0; i < 3; ++i) {
      const uint32_t a = m.triangles[3 * f + i], b = m.triangles[3 * f + (i + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<std::pair<uint32_t, uint32_t>> r;
  for (const auto& kv : uses)
    if (kv.second == 1) r.push_back(kv.first);
  return r;
}

// Signed volume enclosed by a closed, outward-wound mesh (divergence theorem).
inline double enclosedVolume(const cvephands::TriangleMesh& m) {
  double v = 0.0;
  for (size_t f = 0; f < m.numTriangles(); ++f) {
    const Eigen::Vector3d a = m.vertices[m.triangles[3 * f]].cast<double>();
    const Eigen::Vector3d b = m.vertices[m.triangles[3 * f + 1]].cast<double>();
    const Eigen::Vector3d c = m.vertices[m.triangles[3 * f + 2]].cast<double>();
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

// Unnormalised face normal (right-hand rule over the stored order).
inline Eigen::Vector3d faceNormal(const cvephands::TriangleMesh& m, size_t f) {
  const Eigen::Vector3d a = m.vertices[m.triangles[3 * f]].cast<double>();
  const Eigen::Vector3d b = m.vertices[m.triangles[3 * f + 1]].cast<double>();
  const Eigen::Vector3d c = m.vertices[m.triangles[3 * f + 2]].cast<double>();
  return (b - a).cross(c - a);
}
inline Eigen::Vector3d faceCentroid(const cvephands::TriangleMesh& m, size_t f) {
  return (m.vertices[m.triangles[3 * f]].cast<double>() +
          m.vertices[m.triangles[3 * f + 1]].cast<double>() +
          m.vertices[m.triangles[3 * f + 2]].cast<double>()) /
         3.0;
}

inline size_t duplicatePositions(const cvephands::TriangleMesh& m) {
  std::vector<std::array<float, 3>> p;
  for (const auto& v : m.vertices) p.push_back({v.x(), v.y(), v.z()});
  std::sort(p.begin(), p.end());
  return p.size() - size_t(std::unique(p.begin(), p.end()) - p.begin());
}

}  // namespace cvephands_test
