#include "cvephands_bridge/mesh/mesh_accuracy.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace cvephands {

namespace {

using Eigen::Vector3d;
using Eigen::Vector3f;

// Bounding-volume hierarchy over items given by their boxes (see the header for why). Nodes are
// stored depth first: an inner node's left child follows it, `right` names the other one.
class Bvh {
 public:
  static constexpr uint32_t kLeafSize = 4;

  explicit Bvh(std::vector<Eigen::AlignedBox3f> boxes) : boxes_(std::move(boxes)) {
    order_.resize(boxes_.size());
    for (uint32_t i = 0; i < order_.size(); ++i) order_[i] = i;
    centres_.reserve(boxes_.size());
    for (const auto& b : boxes_) centres_.push_back(b.center());
    if (!order_.empty()) build(0, uint32_t(order_.size()));
  }

  // The smallest dist2(item) over items (squared distance from the query point q), starting from
  // the bound `best2`: subtrees whose box is not nearer than the best so far are skipped.
  template <typename Dist2>
  double nearest(const Vector3d& q, double best2, Dist2&& dist2) const {
    if (nodes_.empty()) return best2;
    std::array<uint32_t, 96> stack;  // depth <= log2(n / leaf) + 1 per pushed sibling
    size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (boxDist2(n.box, q) >= best2) continue;
      if (n.count > 0) {
        for (uint32_t k = n.first; k < n.first + n.count; ++k)
          best2 = std::min(best2, dist2(order_[k]));
        continue;
      }
      const uint32_t l = uint32_t(&n - nodes_.data()) + 1, r = n.right;
      const double dl = boxDist2(nodes_[l].box, q), dr = boxDist2(nodes_[r].box, q);
      // Push the farther child first so the nearer one is searched first (tightens best2).
      if (dl <= dr) {
        if (dr < best2) stack[top++] = r;
        if (dl < best2) stack[top++] = l;
      } else {
        if (dl < best2) stack[top++] = l;
        if (dr < best2) stack[top++] = r;
      }
    }
    return best2;
  }

 private:
  struct Node {
    Eigen::AlignedBox3f box;
    uint32_t first = 0, count = 0;  // leaf: items order_[first, first + count)
    uint32_t right = 0;             // inner node: the right child
  };

  static double boxDist2(const Eigen::AlignedBox3f& b, const Vector3d& q) {
    const Vector3d lo = b.min().cast<double>(), hi = b.max().cast<double>();
    return (lo - q).cwiseMax(q - hi).cwiseMax(0.0).squaredNorm();
  }

  uint32_t build(uint32_t begin, uint32_t end) {
    const uint32_t idx = uint32_t(nodes_.size());
    nodes_.emplace_back();
    Eigen::AlignedBox3f box, cbox;
    for (uint32_t k = begin; k < end; ++k) {
      box.extend(boxes_[order_[k]]);
      cbox.extend(centres_[order_[k]]);
    }
    nodes_[idx].box = box;
    if (end - begin <= kLeafSize) {
      nodes_[idx].first = begin;
      nodes_[idx].count = end - begin;
      return idx;
    }
    int axis;
    cbox.sizes().maxCoeff(&axis);
    const uint32_t mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                     [&](uint32_t a, uint32_t b) { return centres_[a][axis] < centres_[b][axis]; });
    build(begin, mid);
    const uint32_t right = build(mid, end);
    nodes_[idx].right = right;
    return idx;
  }

  std::vector<Eigen::AlignedBox3f> boxes_;
  std::vector<Vector3f> centres_;
  std::vector<uint32_t> order_;
  std::vector<Node> nodes_;
};

double segmentDist2(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).squaredNorm();
}

// Squared distance from p to triangle abc: the closest point by Voronoi regions (Ericson,
// Real-Time Collision Detection, 5.1.5); degenerate triangles fall back to their edges, where
// the barycentric division would be 0/0.
double triangleDist2(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a;
  const double n2 = ab.cross(ac).squaredNorm();
  const double e2 = std::max({ab.squaredNorm(), ac.squaredNorm(), (c - b).squaredNorm()});
  if (!(n2 > 1e-12 * e2 * e2))
    return std::min({segmentDist2(p, a, b), segmentDist2(p, b, c), segmentDist2(p, c, a)});
  const Vector3d ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.squaredNorm();
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return (ap - d1 / (d1 - d3) * ab).squaredNorm();
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return (ap - d2 / (d2 - d6) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
    return (bp - (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)).squaredNorm();
  const double inv = 1.0 / (va + vb + vc);
  return (ap - ab * (vb * inv) - ac * (vc * inv)).squaredNorm();
}

// Sorts `d` (metres) and summarises it in millimetres.
SurfaceDistanceStats summarise(std::vector<double>& d) {
  SurfaceDistanceStats s;
  if (d.empty()) return s;
  std::sort(d.begin(), d.end());
  double sum = 0.0;
  for (double x : d) sum += x;
  const double pos = 0.95 * double(d.size() - 1);
  const size_t i = size_t(pos);
  const double p95 = i + 1 < d.size() ? d[i] + (pos - double(i)) * (d[i + 1] - d[i]) : d[i];
  s.count = d.size();
  s.mean_mm = 1e3 * sum / double(d.size());
  s.p95_mm = 1e3 * p95;
  s.max_mm = 1e3 * d.back();
  return s;
}

// Throws for malformed triangles; true when there is something to measure.
bool checkInputs(const std::vector<Vector3f>& vertices, const std::vector<uint32_t>& triangles,
                 const std::vector<Vector3f>& truth) {
  if (triangles.size() % 3 != 0)
    throw std::invalid_argument("meshAccuracy: triangles.size() = " +
                                std::to_string(triangles.size()) + " is not a multiple of 3");
  for (uint32_t v : triangles)
    if (v >= vertices.size())
      throw std::invalid_argument("meshAccuracy: vertex index " + std::to_string(v) +
                                  " out of range (" + std::to_string(vertices.size()) +
                                  " vertices)");
  return !triangles.empty() && !truth.empty();
}

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

SurfaceDistanceStats meshToTruth(const std::vector<Vector3f>& vertices,
                                 const std::vector<uint32_t>& triangles,
                                 const std::vector<Vector3f>& truth) {
  if (!checkInputs(vertices, triangles, truth)) return SurfaceDistanceStats();
  std::vector<Eigen::AlignedBox3f> boxes;
  boxes.reserve(truth.size());
  for (const Vector3f& p : truth) boxes.emplace_back(p, p);
  const Bvh tree(std::move(boxes));
  // Vertices used by a triangle only: an unused vertex is not on the surface.
  std::vector<char> used(vertices.size(), 0);
  for (uint32_t v : triangles) used[v] = 1;
  std::vector<double> d;
  d.reserve(vertices.size());
  for (size_t v = 0; v < vertices.size(); ++v) {
    if (!used[v]) continue;
    const Vector3d q = vertices[v].cast<double>();
    d.push_back(std::sqrt(tree.nearest(
        q, kInf, [&](uint32_t k) { return (truth[k].cast<double>() - q).squaredNorm(); })));
  }
  return summarise(d);
}

SurfaceDistanceStats truthToMesh(const std::vector<Vector3f>& vertices,
                                 const std::vector<uint32_t>& triangles,
                                 const std::vector<Vector3f>& truth) {
  if (!checkInputs(vertices, triangles, truth)) return SurfaceDistanceStats();
  const size_t nt = triangles.size() / 3;
  std::vector<Vector3d> corners(3 * nt);
  std::vector<Eigen::AlignedBox3f> boxes(nt);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const Vector3f& v = vertices[triangles[3 * t + k]];
      corners[3 * t + k] = v.cast<double>();
      boxes[t].extend(v);
    }
  const Bvh tree(std::move(boxes));
  std::vector<double> d;
  d.reserve(truth.size());
  for (const Vector3f& p : truth) {
    const Vector3d q = p.cast<double>();
    d.push_back(std::sqrt(tree.nearest(q, kInf, [&](uint32_t t) {
      return triangleDist2(q, corners[3 * t], corners[3 * t + 1], corners[3 * t + 2]);
    })));
  }
  return summarise(d);
}

MeshAccuracy meshAccuracy(const std::vector<Vector3f>& vertices,
                          const std::vector<uint32_t>& triangles,
                          const std::vector<Vector3f>& truth) {
  MeshAccuracy out;
  out.mesh_to_truth = meshToTruth(vertices, triangles, truth);
  out.truth_to_mesh = truthToMesh(vertices, triangles, truth);
  return out;
}

}  // namespace cvephands
