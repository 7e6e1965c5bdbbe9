// Mesh accuracy (mesh <-> true surface distances): exact point-to-triangle distances in every
// Voronoi region and on degenerate triangles, the tree search against brute force, the
// statistics' definitions, analytic spheres (chord error, a 2 mm offset, a missing half), edge
// cases, and the speed the accuracy tool needs.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "cvephands_bridge/mesh/mesh_accuracy.h"

namespace {

using cvephands::MeshAccuracy;
using cvephands::meshAccuracy;
using cvephands::TriangleMesh;
using Eigen::Vector3d;
using Eigen::Vector3f;

// Icosahedron subdivided `level` times, vertices pushed onto the sphere (counter-clockwise seen
// from outside).
TriangleMesh icosphere(const Vector3d& centre, double radius, int level) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vector3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                             {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                             {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<uint32_t> t = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                             4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                             6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = uint32_t(v.size() - 1);
    };
    std::vector<uint32_t> next;
    for (size_t f = 0; f < t.size(); f += 3) {
      const uint32_t a = t[f], b = t[f + 1], c = t[f + 2];
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    t.swap(next);
  }
  TriangleMesh m;
  for (const auto& p : v) m.vertices.push_back((centre + radius * p).cast<float>());
  m.triangles = t;
  return m;
}

// Fibonacci lattice: points uniform in area on a sphere, about `spacing` apart.
std::vector<Vector3f> sphereSamples(const Vector3d& centre, double radius, double spacing) {
  const int n = int(std::lround(4.0 * M_PI * radius * radius / (spacing * spacing)));
  std::vector<Vector3f> out;
  const double ga = M_PI * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < n; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / n, s = std::sqrt(1.0 - z * z);
    out.push_back(
        (centre + radius * Vector3d(s * std::cos(ga * k), s * std::sin(ga * k), z)).cast<float>());
  }
  return out;
}

// Independent reference: project onto the plane; inside -> plane distance, else nearest edge.
double refTriangleDist(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  auto seg = [&](const Vector3d& u, const Vector3d& w) {
    const double l2 = (w - u).squaredNorm();
    const double s = l2 > 0 ? std::clamp((p - u).dot(w - u) / l2, 0.0, 1.0) : 0.0;
    return (p - (u + s * (w - u))).norm();
  };
  const double edges = std::min({seg(a, b), seg(b, c), seg(c, a)});
  const Vector3d n = (b - a).cross(c - a);
  if (n.squaredNorm() == 0.0) return edges;
  const Vector3d q = p - n * (p - a).dot(n) / n.squaredNorm();
  const bool inside = n.dot((b - a).cross(q - a)) >= 0 && n.dot((c - b).cross(q - b)) >= 0 &&
                      n.dot((a - c).cross(q - c)) >= 0;
  return inside ? (p - q).norm() : edges;
}

// Largest distance from the sphere to an inscribed mesh: over triangles, radius minus the
// distance from the centre to the triangle's plane.
double maxChordError(const TriangleMesh& m, const Vector3d& centre, double radius) {
  double e = 0.0;
  for (size_t f = 0; f < m.numTriangles(); ++f) {
    const Vector3d a = m.vertices[m.triangles[3 * f]].cast<double>();
    const Vector3d b = m.vertices[m.triangles[3 * f + 1]].cast<double>();
    const Vector3d c = m.vertices[m.triangles[3 * f + 2]].cast<double>();
    const Vector3d n = (b - a).cross(c - a).normalized();
    e = std::max(e, radius - std::abs((a - centre).dot(n)));
  }
  return e;
}

const Vector3d kCentre(0.12, -0.25, 0.08);  // a hand-ish place on the desk
constexpr double kR = 0.05;

TEST(MeshAccuracy, ExactInEveryVoronoiRegion) {
  const Vector3d a(0, 0, 0), b(0.1, 0, 0), c(0, 0.1, 0);
  const std::vector<Vector3f> v = {a.cast<float>(), b.cast<float>(), c.cast<float>()};
  const std::vector<uint32_t> tri = {0, 1, 2};
  const std::vector<std::pair<Vector3d, double>> cases = {
      {{0.02, 0.02, 0.03}, 0.03},                            // face
      {{0.02, 0.02, -0.03}, 0.03},                           // face, other side
      {{-0.01, -0.01, 0.0}, std::sqrt(2e-4)},                // vertex a
      {{0.12, -0.01, 0.02}, std::sqrt(4e-4 + 1e-4 + 4e-4)},  // vertex b
      {{-0.01, 0.13, 0.0}, std::sqrt(1e-4 + 9e-4)},          // vertex c
      {{0.05, -0.02, 0.01}, std::sqrt(4e-4 + 1e-4)},         // edge ab
      {{-0.02, 0.05, 0.0}, 0.02},                            // edge ca
      {{0.1, 0.1, 0.0}, 0.1 / std::sqrt(2.0)},               // edge bc
  };
  for (const auto& [p, expected] : cases) {
    const MeshAccuracy acc = meshAccuracy(v, tri, {p.cast<float>()});
    ASSERT_EQ(acc.truth_to_mesh.count, 1u);
    EXPECT_NEAR(acc.truth_to_mesh.max_mm, 1e3 * expected, 1e-4) << p.transpose();
    EXPECT_NEAR(acc.truth_to_mesh.mean_mm, acc.truth_to_mesh.max_mm, 1e-12);
    EXPECT_NEAR(acc.truth_to_mesh.p95_mm, acc.truth_to_mesh.max_mm, 1e-12);
  }
}

TEST(MeshAccuracy, DegenerateTrianglesAreTheirEdges) {
  // Collinear corners and a repeated corner: no NaN, distance to the segment.
  const std::vector<Vector3f> v = {{0, 0, 0}, {0.1f, 0, 0}, {0.2f, 0, 0}};
  for (const std::vector<uint32_t>& tri :
       {std::vector<uint32_t>{0, 1, 2}, std::vector<uint32_t>{0, 2, 2}}) {
    const MeshAccuracy acc = meshAccuracy(v, tri, {Vector3f(0.15f, 0.03f, 0.04f)});
    EXPECT_NEAR(acc.truth_to_mesh.max_mm, 50.0, 1e-3);
    const MeshAccuracy end = meshAccuracy(v, tri, {Vector3f(-0.03f, 0.0f, 0.04f)});
    EXPECT_NEAR(end.truth_to_mesh.max_mm, 50.0, 1e-3);
  }
}

TEST(MeshAccuracy, TreeSearchMatchesBruteForce) {
  // Random triangle soup and points, some far outside it: every distance must be the minimum.
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(-0.1, 0.1), small(-0.01, 0.01);
  std::vector<Vector3f> v;
  std::vector<uint32_t> tri;
  for (int f = 0; f < 300; ++f) {
    const double cx = u(g), cy = u(g), cz = u(g);
    for (int k = 0; k < 3; ++k) {
      const double dx = small(g), dy = small(g), dz = small(g);  // sequenced: reproducible
      v.emplace_back(float(cx + dx), float(cy + dy), float(cz + dz));
    }
    tri.insert(tri.end(), {uint32_t(3 * f), uint32_t(3 * f + 1), uint32_t(3 * f + 2)});
  }
  std::vector<Vector3f> queries;  // generated first: one float value for every use below
  for (int k = 0; k < 400; ++k) {
    const double s = k % 4 == 0 ? 5.0 : 1.0;  // a quarter far away
    const double x = u(g), y = u(g), z = u(g);
    queries.emplace_back(float(s * x), float(s * y), float(s * z));
  }
  for (const Vector3f& p : queries) {
    const Vector3d pd = p.cast<double>();
    double ref_tri = INFINITY, ref_pt = INFINITY;
    for (size_t f = 0; f < tri.size(); f += 3)
      ref_tri = std::min(ref_tri,
                         refTriangleDist(pd, v[tri[f]].cast<double>(), v[tri[f + 1]].cast<double>(),
                                         v[tri[f + 2]].cast<double>()));
    for (const Vector3f& q : v) ref_pt = std::min(ref_pt, (q.cast<double>() - pd).norm());
    const MeshAccuracy acc = meshAccuracy(v, tri, {p});
    ASSERT_NEAR(acc.truth_to_mesh.max_mm, 1e3 * ref_tri, 1e-6);
    // Nearest truth sample: the soup's vertices as truth, p as a one-vertex (degenerate) mesh.
    const MeshAccuracy back = meshAccuracy({p}, {0, 0, 0}, v);
    ASSERT_EQ(back.mesh_to_truth.count, 1u);
    ASSERT_NEAR(back.mesh_to_truth.max_mm, 1e3 * ref_pt, 1e-6);
  }
}

TEST(MeshAccuracy, StatisticsDefinitions) {
  // Truth points 1..100 mm above a large triangle: mean 50.5, p95 (linear) 95.05, max 100.
  const std::vector<Vector3f> v = {{-1, -1, 0}, {2, -1, 0}, {-1, 2, 0}};
  std::vector<Vector3f> truth;
  for (int k = 100; k >= 1; --k) truth.emplace_back(0.1f, 0.2f, 1e-3f * k);
  const MeshAccuracy acc = meshAccuracy(v, {0, 1, 2}, truth);
  EXPECT_EQ(acc.truth_to_mesh.count, 100u);
  EXPECT_NEAR(acc.truth_to_mesh.mean_mm, 50.5, 1e-4);
  EXPECT_NEAR(acc.truth_to_mesh.p95_mm, 95.05, 1e-4);
  EXPECT_NEAR(acc.truth_to_mesh.max_mm, 100.0, 1e-4);
  // Mesh -> truth: each corner to the nearest truth point (0.1, 0.2, 1 mm).
  EXPECT_EQ(acc.mesh_to_truth.count, 3u);
  const double d0 = Vector3d(1.1, 1.2, 0.001).norm(), d1 = Vector3d(1.9, 1.2, 0.001).norm(),
               d2 = Vector3d(1.1, 1.8, 0.001).norm();
  EXPECT_NEAR(acc.mesh_to_truth.mean_mm, 1e3 * (d0 + d1 + d2) / 3, 1e-3);
  EXPECT_NEAR(acc.mesh_to_truth.max_mm, 1e3 * std::max({d0, d1, d2}), 1e-3);
}

TEST(MeshAccuracy, SphereAgainstItsOwnSamples) {
  // A coarse icosphere (3.3 mm edges): truth -> mesh is the chord error, never more; its
  // vertices lie on the sphere, so mesh -> truth is only the sampling bias (< spacing).
  const double spacing = 0.001;
  const auto truth = sphereSamples(kCentre, kR, spacing);
  for (int level : {3, 4}) {
    const TriangleMesh m = icosphere(kCentre, kR, level);
    const double chord = maxChordError(m, kCentre, kR);
    const MeshAccuracy acc = meshAccuracy(m, truth);
    std::printf(
        "icosphere level %d (%zu triangles, chord error %.3f mm): truth->mesh mean %.3f "
        "p95 %.3f max %.3f mm; mesh->truth mean %.3f p95 %.3f max %.3f mm\n",
        level, m.numTriangles(), 1e3 * chord, acc.truth_to_mesh.mean_mm, acc.truth_to_mesh.p95_mm,
        acc.truth_to_mesh.max_mm, acc.mesh_to_truth.mean_mm, acc.mesh_to_truth.p95_mm,
        acc.mesh_to_truth.max_mm);
    EXPECT_EQ(acc.truth_to_mesh.count, truth.size());
    EXPECT_EQ(acc.mesh_to_truth.count, m.numVertices());
    EXPECT_LE(acc.truth_to_mesh.max_mm, 1e3 * chord + 1e-3);
    EXPECT_GT(acc.truth_to_mesh.mean_mm, 0.1 * 1e3 * chord);
    EXPECT_LT(acc.truth_to_mesh.mean_mm, 1e3 * chord);
    EXPECT_LT(acc.mesh_to_truth.mean_mm, 0.5e3 * spacing);
    EXPECT_LT(acc.mesh_to_truth.max_mm, 1e3 * spacing);
  }
}

TEST(MeshAccuracy, OffsetAlongTheNormalIsMeasuredBothWays) {
  // Fine mesh (chord error 0.01 mm) 2 mm outside / inside the true sphere; truth at 0.5 mm
  // spacing keeps the point-to-point bias of mesh -> truth small (sqrt(2^2 + 0.3^2) = 2.02).
  const auto truth = sphereSamples(kCentre, kR, 0.0005);
  for (double offset : {0.002, -0.002}) {
    const MeshAccuracy acc = meshAccuracy(icosphere(kCentre, kR + offset, 5), truth);
    for (const auto* s : {&acc.mesh_to_truth, &acc.truth_to_mesh}) {
      EXPECT_NEAR(s->mean_mm, 2.0, 0.1) << offset;
      EXPECT_NEAR(s->p95_mm, 2.0, 0.1) << offset;
      EXPECT_NEAR(s->max_mm, 2.0, 0.1) << offset;
    }
  }
}

TEST(MeshAccuracy, MissingPartShowsInTruthToMeshOnly) {
  const auto truth = sphereSamples(kCentre, kR, 0.001);
  TriangleMesh full = icosphere(kCentre, kR, 4);
  TriangleMesh half = full;
  half.triangles.clear();
  for (size_t f = 0; f < full.numTriangles(); ++f) {
    Vector3f c = Vector3f::Zero();
    for (int k = 0; k < 3; ++k) c += full.vertices[full.triangles[3 * f + k]];
    if (c.z() / 3 < kCentre.z())
      half.triangles.insert(half.triangles.end(), &full.triangles[3 * f],
                            &full.triangles[3 * f + 3]);
  }
  ASSERT_NEAR(double(half.numTriangles()) / full.numTriangles(), 0.5, 0.05);
  const MeshAccuracy a = meshAccuracy(full, truth), b = meshAccuracy(half, truth);
  std::printf(
      "full: truth->mesh p95 %.3f mm; lower half: truth->mesh mean %.2f p95 %.2f max "
      "%.2f mm, mesh->truth p95 %.3f -> %.3f mm\n",
      a.truth_to_mesh.p95_mm, b.truth_to_mesh.mean_mm, b.truth_to_mesh.p95_mm,
      b.truth_to_mesh.max_mm, a.mesh_to_truth.p95_mm, b.mesh_to_truth.p95_mm);
  // The upper hemisphere is up to r * sqrt(2) from the remaining rim; its p95 ~ r.
  EXPECT_GT(b.truth_to_mesh.p95_mm, 30.0);
  EXPECT_NEAR(b.truth_to_mesh.max_mm, 1e3 * kR * std::sqrt(2.0), 3.0);
  // Mesh -> truth only sees the remaining (correct) vertices: unchanged.
  EXPECT_LT(b.mesh_to_truth.count, a.mesh_to_truth.count);
  EXPECT_NEAR(b.mesh_to_truth.mean_mm, a.mesh_to_truth.mean_mm, 0.05);
  EXPECT_NEAR(b.mesh_to_truth.p95_mm, a.mesh_to_truth.p95_mm, 0.1);
}

TEST(MeshAccuracy, HalvesMatchTheWhole) {
  const TriangleMesh m = icosphere(kCentre, kR + 0.001, 3);
  const auto truth = sphereSamples(kCentre, kR, 0.002);
  const MeshAccuracy acc = meshAccuracy(m, truth);
  const cvephands::SurfaceDistanceStats m2t =
      cvephands::meshToTruth(m.vertices, m.triangles, truth);
  const cvephands::SurfaceDistanceStats t2m =
      cvephands::truthToMesh(m.vertices, m.triangles, truth);
  EXPECT_EQ(m2t.count, acc.mesh_to_truth.count);
  EXPECT_EQ(m2t.mean_mm, acc.mesh_to_truth.mean_mm);
  EXPECT_EQ(m2t.p95_mm, acc.mesh_to_truth.p95_mm);
  EXPECT_EQ(m2t.max_mm, acc.mesh_to_truth.max_mm);
  EXPECT_EQ(t2m.count, acc.truth_to_mesh.count);
  EXPECT_EQ(t2m.mean_mm, acc.truth_to_mesh.mean_mm);
  EXPECT_EQ(t2m.p95_mm, acc.truth_to_mesh.p95_mm);
  EXPECT_EQ(t2m.max_mm, acc.truth_to_mesh.max_mm);
  EXPECT_THROW(cvephands::meshToTruth(m.vertices, {0, 1}, truth), std::invalid_argument);
  EXPECT_THROW(cvephands::truthToMesh(m.vertices, {0, 1, 99999}, truth), std::invalid_argument);
}

TEST(MeshAccuracy, EmptyInputsGiveNaN) {
  const TriangleMesh m = icosphere(kCentre, kR, 1);
  const auto truth = sphereSamples(kCentre, kR, 0.005);
  auto isEmpty = [](const cvephands::SurfaceDistanceStats& s) {
    return s.count == 0 && std::isnan(s.mean_mm) && std::isnan(s.p95_mm) && std::isnan(s.max_mm);
  };
  for (const MeshAccuracy& acc :
       {meshAccuracy(TriangleMesh(), truth), meshAccuracy(m, {}), meshAccuracy({}, {}, {}),
        meshAccuracy(m.vertices, {}, truth)}) {  // vertices but no triangles: no surface
    EXPECT_TRUE(isEmpty(acc.mesh_to_truth));
    EXPECT_TRUE(isEmpty(acc.truth_to_mesh));
  }
}

TEST(MeshAccuracy, RejectsMalformedTriangles) {
  const std::vector<Vector3f> v = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_THROW(meshAccuracy(v, {0, 1}, {Vector3f::Zero()}), std::invalid_argument);
  EXPECT_THROW(meshAccuracy(v, {0, 1, 3}, {Vector3f::Zero()}), std::invalid_argument);
}

TEST(MeshAccuracy, LargeMeshWithDistractors) {
  // 30k triangles (a marching-cubes hand at ~2 mm voxels is smaller) x 100k samples, with two
  // spheres away from the truth: truth->mesh still finds the right one. The time is printed for
  // information only (performance belongs in benchmarks; ~0.13 s on one core here).
  const TriangleMesh ico = icosphere(kCentre, kR, 5);  // 20480 triangles
  TriangleMesh m = ico;  // plus two smaller spheres (5120 triangles each) away from the truth
  for (double dx : {-0.1, 0.1}) {
    const TriangleMesh small = icosphere(kCentre + Vector3d(dx, 0, 0), 0.02, 4);
    const uint32_t base = uint32_t(m.numVertices());
    m.vertices.insert(m.vertices.end(), small.vertices.begin(), small.vertices.end());
    for (uint32_t t : small.triangles) m.triangles.push_back(base + t);
  }
  auto truth = sphereSamples(kCentre, kR + 0.001, 0.00056);  // ~100k samples, 1 mm off
  ASSERT_EQ(m.numTriangles(), 30720u);
  const auto t0 = std::chrono::steady_clock::now();
  const MeshAccuracy acc = meshAccuracy(m, truth);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%zu triangles, %zu vertices x %zu samples: %.3f s\n", m.numTriangles(),
              m.numVertices(), truth.size(), s);
  EXPECT_NEAR(acc.truth_to_mesh.mean_mm, 1.0, 0.05);
}

}  // namespace
