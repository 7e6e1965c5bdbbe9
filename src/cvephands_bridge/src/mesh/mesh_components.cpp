#include "cvephands_bridge/mesh/mesh_components.h"

#include <algorithm>
#include <limits>
#include <numeric>

namespace cvephands {
namespace {

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t v) {
  while (parent[v] != v) {
    parent[v] = parent[parent[v]];  // path halving
    v = parent[v];
  }
  return v;
}

}  // namespace

size_t labelComponents(const TriangleMesh& mesh, std::vector<uint32_t>* vertex_label) {
  const size_t n = mesh.vertices.size();
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  for (size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const uint32_t a = findRoot(parent, mesh.triangles[t]);
    for (int k = 1; k < 3; ++k) {
      const uint32_t b = findRoot(parent, mesh.triangles[t + k]);
      if (a != b) parent[b] = a;
    }
  }
  // Dense labels in order of first appearance.
  std::vector<uint32_t> label_of_root(n, UINT32_MAX);
  vertex_label->assign(n, 0);
  size_t count = 0;
  for (size_t v = 0; v < n; ++v) {
    const uint32_t r = findRoot(parent, uint32_t(v));
    if (label_of_root[r] == UINT32_MAX) label_of_root[r] = uint32_t(count++);
    (*vertex_label)[v] = label_of_root[r];
  }
  return count;
}

namespace {

// Keeps the triangles of the components with keep[label] set; vertices in the order of their
// first use (deterministic), normals follow their vertices. Returns the triangles removed.
size_t keepComponents(TriangleMesh* mesh, const std::vector<uint32_t>& label,
                      const std::vector<bool>& keep) {
  std::vector<uint32_t> new_index(mesh->vertices.size(), UINT32_MAX);
  std::vector<uint32_t> kept;
  kept.reserve(mesh->triangles.size());
  uint32_t next = 0;
  for (size_t t = 0; t + 2 < mesh->triangles.size(); t += 3) {
    if (!keep[label[mesh->triangles[t]]]) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh->triangles[t + k];
      if (new_index[v] == UINT32_MAX) new_index[v] = next++;
      kept.push_back(new_index[v]);
    }
  }
  const size_t removed = (mesh->triangles.size() - kept.size()) / 3;
  if (removed == 0) return 0;
  std::vector<Eigen::Vector3f> vertices(next), normals(mesh->hasNormals() ? next : 0);
  for (size_t v = 0; v < new_index.size(); ++v) {
    if (new_index[v] == UINT32_MAX) continue;
    vertices[new_index[v]] = mesh->vertices[v];
    if (mesh->hasNormals()) normals[new_index[v]] = mesh->normals[v];
  }
  mesh->vertices.swap(vertices);
  mesh->normals.swap(normals);
  mesh->triangles.swap(kept);
  return removed;
}

}  // namespace

size_t removeSmallComponents(TriangleMesh* mesh, size_t min_triangles) {
  return keepHandComponents(mesh, Eigen::Vector3f::Zero(), min_triangles, 0.0f);
}

size_t keepHandComponents(TriangleMesh* mesh, const Eigen::Vector3f& centre, size_t min_triangles,
                          float keep_radius) {
  const bool by_size = min_triangles > 1, by_distance = keep_radius > 0;
  if ((!by_size && !by_distance) || mesh->triangles.empty()) return 0;
  std::vector<uint32_t> label;
  const size_t components = labelComponents(*mesh, &label);
  std::vector<size_t> triangles_of(components, 0);
  for (size_t t = 0; t + 2 < mesh->triangles.size(); t += 3) ++triangles_of[label[mesh->triangles[t]]];
  // Each component's nearest approach to the centre, over the vertices its triangles use.
  std::vector<float> nearest(components, std::numeric_limits<float>::infinity());
  if (by_distance)
    for (uint32_t v : mesh->triangles)
      nearest[label[v]] = std::min(nearest[label[v]], (mesh->vertices[v] - centre).norm());
  std::vector<bool> keep(components);
  for (size_t c = 0; c < components; ++c)
    keep[c] = (!by_size || triangles_of[c] >= min_triangles) && (!by_distance || nearest[c] <= keep_radius);
  return keepComponents(mesh, label, keep);
}

}  // namespace cvephands
