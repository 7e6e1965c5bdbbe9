#include "marching_cubes_cases.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <stdexcept>
#include <utility>
#include <vector>

namespace cvephands {
namespace mc {
namespace {

Eigen::Vector3f cornerPos(int k) {
  return Eigen::Vector3f(kCornerOffset[k][0], kCornerOffset[k][1], kCornerOffset[k][2]);
}
Eigen::Vector3f edgeMid(int e) {
  return 0.5f * (cornerPos(kEdgeCorners[e][0]) + cornerPos(kEdgeCorners[e][1]));
}

// Faces are numbered 2 * axis + side (side 1: the face at coordinate 1).
bool onFace(int corner, int face) { return kCornerOffset[corner][face / 2] == face % 2; }
bool edgeOnFace(int e, int face) {
  return onFace(kEdgeCorners[e][0], face) && onFace(kEdgeCorners[e][1], face);
}
bool edgesShareFace(int a, int b) {
  for (int f = 0; f < 6; ++f)
    if (edgeOnFace(a, f) && edgeOnFace(b, f)) return true;
  return false;
}
int sharedCorner(int a, int b) {
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      if (kEdgeCorners[a][i] == kEdgeCorners[b][j]) return kEdgeCorners[a][i];
  return -1;
}

// An oriented contour segment on one face, from cell edge `from` to cell edge `to`.
struct Segment {
  int from, to;
};

// The segments of case c on face f, oriented so that, seen from outside the cell, the corners
// above the iso level lie to the right of the walking direction. With that orientation a loop
// runs clockwise around the above region seen from outside the cell, which makes its
// triangles counter-clockwise seen from the below side, i.e. from outside the surface.
void faceSegments(int c, int f, std::vector<Segment>* out) {
  auto inside = [c](int k) { return (c >> k) & 1; };
  std::vector<int> corners, edges;
  for (int k = 0; k < 8; ++k)
    if (onFace(k, f)) corners.push_back(k);
  for (int e = 0; e < 12; ++e)
    if (edgeOnFace(e, f)) edges.push_back(e);
  int n_in = 0;
  for (int k : corners) n_in += inside(k);
  if (n_in == 0 || n_in == 4) return;

  // The two face edges at corner k.
  auto around = [&](int k) {
    std::vector<int> r;
    for (int e : edges)
      if (kEdgeCorners[e][0] == k || kEdgeCorners[e][1] == k) r.push_back(e);
    return r;
  };
  std::vector<std::vector<int>> pairs;
  if (n_in == 1 || n_in == 3) {
    for (int k : corners)
      if (inside(k) == (n_in == 1)) pairs.push_back(around(k));  // cut off the lone corner
  } else {
    std::vector<int> crossed;
    for (int e : edges)
      if (inside(kEdgeCorners[e][0]) != inside(kEdgeCorners[e][1])) crossed.push_back(e);
    if (crossed.size() == 2) {
      pairs.push_back(crossed);  // two adjacent corners above: one straight cut
    } else {
      for (int k : corners)  // ambiguous face: separate the two corners above
        if (inside(k)) pairs.push_back(around(k));
    }
  }

  const Eigen::Vector3f normal =
      Eigen::Vector3f::Unit(f / 2) * (f % 2 == 1 ? 1.0f : -1.0f);  // outward from the cell
  for (const auto& p : pairs) {
    int ref = sharedCorner(p[0], p[1]);
    if (ref < 0) ref = corners[0];  // a straight cut: any corner tells the sides apart
    const Eigen::Vector3f a = edgeMid(p[0]), b = edgeMid(p[1]);
    const Eigen::Vector3f left = normal.cross(b - a);
    const bool ref_left = left.dot(cornerPos(ref) - 0.5f * (a + b)) > 0.0f;
    // Above corners to the right: a lone above corner must not be on the left.
    const bool keep = inside(ref) ? !ref_left : ref_left;
    out->push_back(keep ? Segment{p[0], p[1]} : Segment{p[1], p[0]});
  }
}

// Triangulates loop v (counter-clockwise from outside) with no diagonal joining two vertices
// on a common cell face. Tries fans first (apex order 0..n-1), then any triangulation.
bool triangulate(const std::vector<int>& v, std::vector<int>* tris) {
  const int n = static_cast<int>(v.size());
  for (int apex = 0; apex < n; ++apex) {
    bool ok = true;
    for (int j = 2; j <= n - 2 && ok; ++j) ok = !edgesShareFace(v[apex], v[(apex + j) % n]);
    if (!ok) continue;
    for (int j = 1; j <= n - 2; ++j) {
      tris->push_back(v[apex]);
      tris->push_back(v[(apex + j) % n]);
      tris->push_back(v[(apex + j + 1) % n]);
    }
    return true;
  }
  // General case: triangle (v0, v1, vk) splits the polygon into two smaller ones.
  if (n == 3) {
    tris->insert(tris->end(), v.begin(), v.end());
    return true;
  }
  for (int k = 2; k < n; ++k) {
    if (k > 2 && edgesShareFace(v[1], v[k])) continue;
    if (k < n - 1 && edgesShareFace(v[0], v[k])) continue;
    std::vector<int> t = {v[0], v[1], v[k]};
    std::vector<int> right(v.begin() + 1, v.begin() + k + 1);  // v1..vk
    std::vector<int> left = {v[0]};                           // vk..v(n-1), v0
    left.insert(left.begin(), v.begin() + k, v.end());
    if (right.size() >= 3 && !triangulate(right, &t)) continue;
    if (left.size() >= 3 && !triangulate(left, &t)) continue;
    tris->insert(tris->end(), t.begin(), t.end());
    return true;
  }
  return false;
}

CaseTable buildTable() {
  CaseTable t{};
  for (int e = 0; e < 12; ++e) {
    const int a = kEdgeCorners[e][0], b = kEdgeCorners[e][1];
    for (int i = 0; i < 3; ++i) {
      t.edge_offset[e][i] = static_cast<uint8_t>(kCornerOffset[a][i]);
      if (kCornerOffset[b][i] != kCornerOffset[a][i]) t.edge_axis[e] = static_cast<uint8_t>(i);
    }
  }
  int slots = 0;
  for (int e = 0; e < 12; ++e) {
    const uint8_t key[3] = {t.edge_offset[e][1], t.edge_offset[e][2], t.edge_axis[e]};
    int s = 0;
    while (s < slots && !std::equal(key, key + 3, t.slot[s])) ++s;
    if (s == slots) {
      if (slots == 8) throw std::logic_error("marching cubes table: more than 8 edge rows");
      std::copy(key, key + 3, t.slot[slots++]);
    }
    t.edge_slot[e] = static_cast<uint8_t>(s);
  }
  for (int c = 0; c < 256; ++c) {
    std::vector<Segment> segs;
    for (int f = 0; f < 6; ++f) faceSegments(c, f, &segs);
    // Every crossed edge lies on two faces: it ends one segment and starts the next.
    int next[12];
    for (int& n : next) n = -1;
    for (const Segment& s : segs) {
      if (next[s.from] != -1) throw std::logic_error("marching cubes table: edge starts twice");
      next[s.from] = s.to;
    }
    std::vector<int> tris;
    bool seen[12] = {};
    for (int e = 0; e < 12; ++e) {
      if (next[e] < 0 || seen[e]) continue;
      std::vector<int> loop;
      for (int v = e; !seen[v]; v = next[v]) {
        if (next[v] < 0) throw std::logic_error("marching cubes table: open contour");
        seen[v] = true;
        loop.push_back(v);
      }
      if (!triangulate(loop, &tris))
        throw std::logic_error("marching cubes table: loop without a valid triangulation");
    }
    if (tris.size() > sizeof(t.edges[c]))
      throw std::logic_error("marching cubes table: too many triangles in a cell");
    t.num_triangles[c] = static_cast<uint8_t>(tris.size() / 3);
    t.edge_mask[c] = 0;
    for (size_t i = 0; i < tris.size(); ++i) {
      t.edges[c][i] = static_cast<uint8_t>(tris[i]);
      t.edge_mask[c] = static_cast<uint16_t>(t.edge_mask[c] | 1u << tris[i]);
    }
  }
  return t;
}

}  // namespace

const CaseTable& caseTable() {
  static const CaseTable table = buildTable();
  return table;
}

}  // namespace mc
}  // namespace cvephands
