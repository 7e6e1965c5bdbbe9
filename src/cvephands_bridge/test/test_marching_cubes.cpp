// Marching cubes on probability volumes: topology (watertight, Euler characteristic,
// components, winding) and geometry (distance to the analytic iso-surface, normals, enclosed
// volume) on analytic shapes; crack-freeness on random fields that hit every cell case; one
// vertex per crossed grid edge at the interpolated crossing; the binary variant; edge cases;
// output independent of the thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>

#include "cvephands_bridge/mesh/marching_cubes.h"
#include "mesh_checks.h"
#include "synthetic_volumes.h"

namespace {

using cvephands::MarchingCubes;
using cvephands::MarchingCubesOptions;
using cvephands::MeshingMode;
using cvephands::TriangleMesh;
using cvephands_test::MeshTopology;
using cvephands_test::Sdf;
using cvephands_test::TestVolume;
using cvephands_test::topology;
using Eigen::Vector3d;
using Eigen::Vector3i;

constexpr double kPi = 3.14159265358979323846;

TriangleMesh mesh(const TestVolume& v, const MarchingCubesOptions& o = MarchingCubesOptions()) {
  return cvephands::marchingCubes(v.view(), o);
}
MarchingCubesOptions binaryOptions() {
  MarchingCubesOptions o;
  o.mode = MeshingMode::kBinary;
  return o;
}
MarchingCubesOptions openOptions() {
  MarchingCubesOptions o;
  o.close_at_border = false;
  return o;
}

template <typename F>
void expectInvalidArgument(F&& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "expected std::invalid_argument mentioning '" << needle << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

// Distance of the vertices (in voxels) to the level set sd = level of an exact distance field.
struct Distances {
  double max = 0.0, mean = 0.0;
};
Distances distances(const TriangleMesh& m, const Sdf& sd, double level, double voxel) {
  Distances d;
  for (const auto& v : m.vertices) {
    const double e = std::abs(sd(v.cast<double>()) - level) / voxel;
    d.max = std::max(d.max, e);
    d.mean += e;
  }
  if (!m.vertices.empty()) d.mean /= double(m.vertices.size());
  return d;
}

// The sample lattice the cells join (with close_at_border: a ring of zeros around the volume).
struct Lattice {
  const TestVolume& v;
  float iso;
  int L;
  Vector3i m;
  Lattice(const TestVolume& vol, const MarchingCubesOptions& o)
      : v(vol), iso(o.iso), L(o.close_at_border ? 1 : 0), m(vol.dims + Vector3i::Constant(2 * L)) {}
  float value(const Vector3i& p) const {
    const Vector3i i = p - Vector3i::Constant(L);
    if ((i.array() < 0).any() || (i.array() >= v.dims.array()).any()) return 0.0f;
    return v.data[v.index(i.x(), i.y(), i.z())];
  }
  bool above(const Vector3i& p) const { return value(p) > iso; }
  bool inside(const Vector3i& p) const { return (p.array() >= 0).all() && (p.array() < m.array()).all(); }
  size_t crossedEdges() const {
    size_t n = 0;
    for (int z = 0; z < m.z(); ++z)
      for (int y = 0; y < m.y(); ++y)
        for (int x = 0; x < m.x(); ++x)
          for (int a = 0; a < 3; ++a) {
            const Vector3i p(x, y, z), q = p + Vector3i::Unit(a);
            if (inside(q) && above(p) != above(q)) ++n;
          }
    return n;
  }
  // Cell cases (corner bit set = above), counted over all cells.
  std::vector<size_t> caseHistogram() const {
    static const int off[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                  {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    std::vector<size_t> h(256, 0);
    for (int z = 0; z + 1 < m.z(); ++z)
      for (int y = 0; y + 1 < m.y(); ++y)
        for (int x = 0; x + 1 < m.x(); ++x) {
          int c = 0;
          for (int k = 0; k < 8; ++k)
            c |= int(above(Vector3i(x + off[k][0], y + off[k][1], z + off[k][2]))) << k;
          ++h[c];
        }
    return h;
  }
};

// Every vertex sits on a distinct crossed grid edge, at the crossing the mode prescribes
// (linear interpolation of the two bytes, or the midpoint), and every crossed edge has one.
void expectOneVertexPerCrossedEdge(const TestVolume& v, const TriangleMesh& m,
                                   const MarchingCubesOptions& o) {
  const Lattice lat(v, o);
  EXPECT_EQ(m.numVertices(), lat.crossedEdges());
  std::set<std::tuple<int, int, int, int>> seen;
  size_t bad = 0;
  for (const auto& vert : m.vertices) {
    // Lattice coordinates: two are integers, the third carries the crossing.
    const Vector3d u = (vert.cast<double>() - v.origin) / v.voxel - Vector3d::Constant(0.5 - lat.L);
    int axis = -1, fractional = 0;
    Vector3i p;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(u[a] - std::round(u[a])) > 1e-3) {
        axis = a;
        ++fractional;
        p[a] = int(std::floor(u[a]));
      } else {
        p[a] = int(std::lround(u[a]));
      }
    }
    if (fractional != 1) {
      ++bad;
      continue;
    }
    const Vector3i q = p + Vector3i::Unit(axis);
    if (!lat.inside(p) || !lat.inside(q) || lat.above(p) == lat.above(q)) {
      ++bad;
      continue;
    }
    const float fa = lat.value(p), fb = lat.value(q);
    const double t = o.mode == MeshingMode::kBinary ? 0.5 : (o.iso - fa) / (fb - fa);
    if (std::abs(u[axis] - p[axis] - t) > 1e-4) ++bad;
    if (!seen.insert({p.x(), p.y(), p.z(), axis}).second) ++bad;
  }
  EXPECT_EQ(bad, 0u) << "vertices off their crossed edge or sharing one";
}

void expectSameMesh(const TriangleMesh& a, const TriangleMesh& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.normals.size(), b.normals.size());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  EXPECT_EQ(0, std::memcmp(a.vertices.data(), b.vertices.data(), a.vertices.size() * sizeof(a.vertices[0])));
  EXPECT_EQ(0, std::memcmp(a.normals.data(), b.normals.data(), a.normals.size() * sizeof(a.normals[0])));
  EXPECT_EQ(0, std::memcmp(a.triangles.data(), b.triangles.data(), a.triangles.size() * sizeof(uint32_t)));
}

// ---- analytic shapes ------------------------------------------------------------------------
struct SphereScene {
  Vector3d centre{20.3, 19.6, 20.1};
  double radius = 12.0, width = 3.0;  // voxels; ramp 3 voxels wide
  TestVolume volume = cvephands_test::sampleSdf(Vector3i(41, 40, 42), Vector3d::Zero(), 1.0,
                                                cvephands_test::sphere(centre, radius), width);
  Sdf sd = cvephands_test::sphere(centre, radius);
  double level = cvephands_test::isoDistance(153.5, width);  // the p = 153.5/255 level set
};

TEST(MarchingCubes, SphereIsClosedAccurateAndOutward) {
  const SphereScene s;
  const TriangleMesh m = mesh(s.volume);
  const MeshTopology t = topology(m);
  EXPECT_TRUE(t.watertight()) << t.boundary_edges << " boundary, " << t.nonmanifold_edges
                              << " non-manifold, " << t.misoriented_edges << " misoriented";
  EXPECT_EQ(t.euler(), 2);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.unreferenced_vertices, 0u);
  EXPECT_EQ(cvephands_test::duplicatePositions(m), 0u);
  expectOneVertexPerCrossedEdge(s.volume, m, MarchingCubesOptions());

  // Linear interpolation of a linear ramp is exact up to the sphere's curvature along an edge
  // and byte rounding: far inside the 0.5 voxel the design allows.
  const Distances d = distances(m, s.sd, s.level, 1.0);
  EXPECT_LT(d.max, 0.5);
  EXPECT_LT(d.max, 0.05);
  EXPECT_LT(d.mean, 0.02);

  const double r = s.radius + s.level;
  const double expected = 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(cvephands_test::enclosedVolume(m), expected, 0.01 * expected);

  ASSERT_EQ(m.normals.size(), m.vertices.size());
  size_t inward = 0, off_radial = 0;
  for (size_t f = 0; f < m.numTriangles(); ++f)
    if (cvephands_test::faceNormal(m, f).dot(cvephands_test::faceCentroid(m, f) - s.centre) <= 0) ++inward;
  EXPECT_EQ(inward, 0u) << "triangles wound clockwise seen from outside";
  for (size_t i = 0; i < m.numVertices(); ++i) {
    const Vector3d n = m.normals[i].cast<double>();
    const Vector3d radial = (m.vertices[i].cast<double>() - s.centre).normalized();
    EXPECT_NEAR(n.norm(), 1.0, 1e-5);
    if (n.dot(radial) <= 0) ++inward;
    if (n.dot(radial) < std::cos(5.0 * kPi / 180.0)) ++off_radial;  // gradient of the ramp
  }
  EXPECT_EQ(inward, 0u) << "vertex normals pointing inward";
  EXPECT_EQ(off_radial, 0u) << "vertex normals more than 5 degrees off the sphere normal";
}

TEST(MarchingCubes, TorusHasGenusOne) {
  const Vector3d c(24.2, 23.7, 16.3);
  const double width = 3.0;
  const Sdf sd = cvephands_test::torus(c, 12.0, 5.0);
  const TestVolume v = cvephands_test::sampleSdf(Vector3i(48, 48, 32), Vector3d::Zero(), 1.0, sd, width);
  const TriangleMesh m = mesh(v);
  const MeshTopology t = topology(m);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.euler(), 0);
  EXPECT_EQ(t.components, 1u);
  const Distances d = distances(m, sd, cvephands_test::isoDistance(153.5, width), 1.0);
  EXPECT_LT(d.max, 0.5);
  EXPECT_LT(d.max, 0.08);  // tube radius 4.7 voxels: more curvature than the sphere
  // Pappus: 2 pi R * pi r^2 for the iso level's tube radius.
  const double r = 5.0 + cvephands_test::isoDistance(153.5, width);
  const double expected = 2.0 * kPi * 12.0 * kPi * r * r;
  EXPECT_NEAR(cvephands_test::enclosedVolume(m), expected, 0.02 * expected);
}

TEST(MarchingCubes, BoxesTouchingFaceToFaceFormOneSurface) {
  using cvephands_test::box;
  const Sdf a = box(Vector3d(12.2, 16.1, 15.9), Vector3d(6, 6, 6));   // x in [6.2, 18.2]
  const Sdf b = box(Vector3d(24.2, 16.3, 16.1), Vector3d(6, 5, 5));   // x in [18.2, 30.2]
  const TestVolume v = cvephands_test::sampleSdf(Vector3i(40, 32, 32), Vector3d::Zero(), 1.0,
                                                 cvephands_test::unite({a, b}), 2.0);
  const MeshTopology t = topology(mesh(v));
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.euler(), 2);
  EXPECT_EQ(t.components, 1u);
}

TEST(MarchingCubes, SeparatedBoxesFormTwoSurfaces) {
  using cvephands_test::box;
  const Sdf a = box(Vector3d(12.2, 16.1, 15.9), Vector3d(6, 6, 6));  // x up to 18.2
  const Sdf b = box(Vector3d(27.4, 16.3, 16.1), Vector3d(6, 5, 5));  // x from 21.4
  const TestVolume v = cvephands_test::sampleSdf(Vector3i(40, 32, 32), Vector3d::Zero(), 1.0,
                                                 cvephands_test::unite({a, b}), 2.0);
  const TriangleMesh m = mesh(v);
  const MeshTopology t = topology(m);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.euler(), 4);
  EXPECT_EQ(t.components, 2u);
  EXPECT_GT(cvephands_test::enclosedVolume(m), 0.0);
}

TEST(MarchingCubes, HandVolumeIsWatertight) {
  const TestVolume v = cvephands_test::handVolume(7);
  const TriangleMesh m = mesh(v);
  const MeshTopology t = topology(m);
  EXPECT_TRUE(t.watertight());
  EXPECT_GT(m.numTriangles(), 5000u);
  EXPECT_EQ(t.euler() % 2, 0);
  expectOneVertexPerCrossedEdge(v, m, MarchingCubesOptions());
  // The hand is one closed body; noise (+-20 bytes) stays far below the iso level.
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.euler(), 2);
}

// ---- random fields: every cell case, crack-freeness -----------------------------------------
TEST(MarchingCubes, RandomFieldsAreWatertightWhenClosed) {
  const Vector3i sizes[] = {{2, 2, 2}, {7, 5, 3}, {3, 9, 4}, {16, 16, 16}, {40, 40, 40}, {70, 13, 9}};
  uint32_t seed = 1;
  for (const Vector3i& dims : sizes)
    for (int mode = 0; mode < 2; ++mode) {
      SCOPED_TRACE(testing::Message() << dims.transpose() << (mode ? " binary" : " probabilistic"));
      const TestVolume v = cvephands_test::noiseVolume(dims, seed++);
      MarchingCubesOptions o;
      o.mode = mode ? MeshingMode::kBinary : MeshingMode::kProbabilistic;
      const TriangleMesh m = mesh(v, o);
      const MeshTopology t = topology(m);
      EXPECT_TRUE(t.watertight()) << t.boundary_edges << " boundary, " << t.nonmanifold_edges
                                  << " non-manifold, " << t.misoriented_edges << " misoriented";
      EXPECT_EQ(t.bad_indices, 0u);
      EXPECT_EQ(t.degenerate_triangles, 0u);
      EXPECT_EQ(t.unreferenced_vertices, 0u);
      EXPECT_EQ(t.euler() % 2, 0);  // closed orientable surfaces
      EXPECT_EQ(cvephands_test::duplicatePositions(m), 0u);
      expectOneVertexPerCrossedEdge(v, m, o);
    }
}

TEST(MarchingCubes, RandomFieldCoversEveryCellCase) {
  // The watertightness test above is only as good as the cases it meets: all 254 must occur.
  const TestVolume v = cvephands_test::noiseVolume(Vector3i(40, 40, 40), 9);
  const std::vector<size_t> h = Lattice(v, MarchingCubesOptions()).caseHistogram();
  for (int c = 1; c < 255; ++c) EXPECT_GT(h[c], 0u) << "case " << c;
}

TEST(MarchingCubes, OpenBorderLeavesHolesOnlyOnTheBorder) {
  const TestVolume v = cvephands_test::noiseVolume(Vector3i(12, 9, 7), 21);
  const TriangleMesh m = mesh(v, openOptions());
  const MeshTopology t = topology(m);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_EQ(t.misoriented_edges, 0u);
  EXPECT_EQ(t.degenerate_triangles, 0u);
  expectOneVertexPerCrossedEdge(v, m, openOptions());
  const auto boundary = cvephands_test::boundaryEdges(m);
  EXPECT_GT(boundary.size(), 0u);
  size_t interior = 0;
  for (const auto& e : boundary) {
    // Both ends on one outermost sample plane (lattice coordinate 0 or n-1, here = voxel index).
    const Vector3d a = m.vertices[e.first].cast<double>() - Vector3d::Constant(0.5);
    const Vector3d b = m.vertices[e.second].cast<double>() - Vector3d::Constant(0.5);
    bool on_border = false;
    for (int ax = 0; ax < 3; ++ax)
      for (double plane : {0.0, double(v.dims[ax] - 1)})
        on_border |= std::abs(a[ax] - plane) < 1e-5 && std::abs(b[ax] - plane) < 1e-5;
    interior += !on_border;
  }
  EXPECT_EQ(interior, 0u);
}

TEST(MarchingCubes, SurfaceCutByTheVolumeFaceIsCappedWhenClosed) {
  // A sphere poking out of the +x face: capped with close_at_border, open without.
  const TestVolume v = cvephands_test::sampleSdf(Vector3i(24, 30, 30), Vector3d::Zero(), 1.0,
                                                 cvephands_test::sphere(Vector3d(20, 15, 15), 9), 2.0);
  const MeshTopology closed = topology(mesh(v));
  EXPECT_TRUE(closed.watertight());
  EXPECT_EQ(closed.euler(), 2);
  const MeshTopology open = topology(mesh(v, openOptions()));
  EXPECT_GT(open.boundary_edges, 0u);
  EXPECT_EQ(open.euler(), 1);  // a disk
}

// ---- binary variant -------------------------------------------------------------------------
TEST(MarchingCubes, BinaryVariantUsesMidpointsAndIsLessAccurate) {
  const SphereScene s;
  const TriangleMesh prob = mesh(s.volume);
  const TriangleMesh bin = mesh(s.volume, binaryOptions());
  const MeshTopology t = topology(bin);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.euler(), 2);
  expectOneVertexPerCrossedEdge(s.volume, bin, binaryOptions());
  // Same crossed edges, so the same vertex count and connectivity; only positions differ.
  EXPECT_EQ(bin.numVertices(), prob.numVertices());
  EXPECT_EQ(bin.triangles, prob.triangles);

  // Thesis fig. 6.6: interpolating the probabilities is more accurate than thresholding.
  const Distances dp = distances(prob, s.sd, s.level, 1.0);
  const Distances db = distances(bin, s.sd, s.level, 1.0);
  EXPECT_GT(db.mean, dp.mean);
  EXPECT_GT(db.mean, 5.0 * dp.mean);
  EXPECT_LT(db.max, 0.5 + 1e-4);  // a midpoint is at most half an edge from the crossing
  std::printf("sphere r=%.0f: mean/max vertex distance %.4f/%.4f voxel (probabilistic), "
              "%.4f/%.4f (binary)\n", s.radius, dp.mean, dp.max, db.mean, db.max);

  size_t inward = 0;
  for (size_t i = 0; i < bin.numVertices(); ++i)
    if (bin.normals[i].cast<double>().dot(bin.vertices[i].cast<double>() - s.centre) <= 0) ++inward;
  EXPECT_EQ(inward, 0u);
}

// ---- edge cases -----------------------------------------------------------------------------
TEST(MarchingCubes, EmptyAndFullVolumes) {
  for (auto mode : {MeshingMode::kProbabilistic, MeshingMode::kBinary}) {
    MarchingCubesOptions o;
    o.mode = mode;
    EXPECT_TRUE(mesh(cvephands_test::constantVolume(Vector3i(20, 20, 20), 0), o).empty());
    EXPECT_TRUE(mesh(cvephands_test::constantVolume(Vector3i(20, 20, 20), 153), o).empty());

    const TestVolume full = cvephands_test::constantVolume(Vector3i(5, 4, 3), 255);
    const TriangleMesh box = mesh(full, o);
    const MeshTopology t = topology(box);
    EXPECT_TRUE(t.watertight());
    EXPECT_EQ(t.euler(), 2);
    EXPECT_EQ(t.components, 1u);
    expectOneVertexPerCrossedEdge(full, box, o);
    // The cap sits between the outermost centres and the zero ring: a box a bit larger than
    // the samples' hull (4 x 3 x 2), smaller than the ring's (6 x 5 x 4).
    const double vol = cvephands_test::enclosedVolume(box);
    EXPECT_GT(vol, 4.0 * 3.0 * 2.0);
    EXPECT_LT(vol, 6.0 * 5.0 * 4.0);

    o.close_at_border = false;
    EXPECT_TRUE(mesh(full, o).empty());
  }
}

TEST(MarchingCubes, SingleVoxel) {
  const TestVolume one = cvephands_test::constantVolume(Vector3i(1, 1, 1), 255);
  const TriangleMesh m = mesh(one);
  const MeshTopology t = topology(m);
  EXPECT_EQ(m.numVertices(), 6u);  // an octahedron around the voxel centre
  EXPECT_EQ(m.numTriangles(), 8u);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.euler(), 2);
  const double d = 1.0 - 153.5 / 255.0;  // crossing between the centre (255) and the ring (0)
  for (size_t i = 0; i < m.numVertices(); ++i) {
    EXPECT_NEAR((m.vertices[i].cast<double>() - Vector3d::Constant(0.5)).norm(), d, 1e-6);
    EXPECT_GT(m.normals[i].cast<double>().dot(m.vertices[i].cast<double>() - Vector3d::Constant(0.5)), 0.0);
  }
  EXPECT_GT(cvephands_test::enclosedVolume(m), 0.0);
  EXPECT_TRUE(mesh(cvephands_test::constantVolume(Vector3i(1, 1, 1), 153)).empty());
  EXPECT_TRUE(mesh(one, openOptions()).empty());  // no cell without the ring
}

TEST(MarchingCubes, ThinVolumesWithoutBorderHaveNoCells) {
  const TestVolume flat = cvephands_test::noiseVolume(Vector3i(10, 10, 1), 3);
  EXPECT_TRUE(mesh(flat, openOptions()).empty());
  EXPECT_TRUE(topology(mesh(flat)).watertight());
}

TEST(MarchingCubes, RejectsBadInput) {
  cvephands::ProbabilityGridView g;
  g.dims = Vector3i(4, 4, 4);
  expectInvalidArgument([&] { cvephands::marchingCubes(g); }, "'data'");
  g.dims = Vector3i(4, -1, 4);
  expectInvalidArgument([&] { cvephands::marchingCubes(g); }, "'dims'");

  const TestVolume v = cvephands_test::constantVolume(Vector3i(4, 4, 4), 200);
  g = v.view();
  g.voxel_size = 0.0;
  expectInvalidArgument([&] { cvephands::marchingCubes(g); }, "'voxel_size'");
  g = v.view();
  g.origin.x() = std::nan("");
  expectInvalidArgument([&] { cvephands::marchingCubes(g); }, "'origin'");

  for (float iso : {0.0f, 255.0f, -3.0f, 300.0f, std::nanf("")}) {
    MarchingCubesOptions o;
    o.iso = iso;
    expectInvalidArgument([&] { MarchingCubes mc(o); }, "'iso'");
  }
  MarchingCubesOptions o;
  o.threads = -1;
  expectInvalidArgument([&] { MarchingCubes mc(o); }, "'threads'");
  expectInvalidArgument([&] { MarchingCubes().extract(v.view(), nullptr); }, "'mesh'");
}

TEST(MarchingCubes, ZeroDimensionsGiveAnEmptyMesh) {
  cvephands::ProbabilityGridView g;  // null data is fine: there is nothing to read
  for (const Vector3i& dims : {Vector3i(0, 0, 0), Vector3i(0, 5, 5), Vector3i(5, 0, 5), Vector3i(5, 5, 0)}) {
    g.dims = dims;
    TriangleMesh m;
    m.triangles = {0, 1, 2};  // replaced, not appended to
    MarchingCubes().extract(g, &m);
    EXPECT_TRUE(m.empty());
    EXPECT_EQ(m.numVertices(), 0u);
  }
}

// ---- placement, options, threads ------------------------------------------------------------
TEST(MarchingCubes, VerticesAreInTheGridFrame) {
  // A hand sub-volume: 3.6 mm voxels, min corner somewhere in the workspace.
  TestVolume unit = cvephands_test::sampleSdf(Vector3i(30, 30, 30), Vector3d::Zero(), 1.0,
                                              cvephands_test::sphere(Vector3d(14.6, 15.2, 15.1), 9), 2.0);
  TestVolume world = unit;
  world.origin = Vector3d(-0.15, 0.2, 0.05);
  world.voxel = 0.0036;
  const TriangleMesh a = mesh(unit), b = mesh(world);
  ASSERT_EQ(a.numVertices(), b.numVertices());
  EXPECT_EQ(a.triangles, b.triangles);
  for (size_t i = 0; i < a.numVertices(); ++i) {
    const Vector3d expect = world.origin + world.voxel * a.vertices[i].cast<double>();
    EXPECT_LT((b.vertices[i].cast<double>() - expect).norm(), 1e-6);
    EXPECT_LT((b.normals[i] - a.normals[i]).norm(), 1e-6f);
  }
}

TEST(MarchingCubes, NormalsAreOptional) {
  const TestVolume v = cvephands_test::handVolume(3);
  MarchingCubesOptions o;
  o.compute_normals = false;
  const TriangleMesh with = mesh(v), without = mesh(v, o);
  EXPECT_TRUE(without.normals.empty());
  EXPECT_EQ(with.vertices, without.vertices);
  EXPECT_EQ(with.triangles, without.triangles);
}

TEST(MarchingCubes, OutputIsIdenticalForAnyThreadCount) {
  const TestVolume volumes[] = {cvephands_test::handVolume(11), cvephands_test::noiseVolume(Vector3i(33, 70, 29), 5),
                                cvephands_test::personVolume(Vector3i(128, 128, 96), 2)};
  for (const TestVolume& v : volumes)
    for (auto mode : {MeshingMode::kProbabilistic, MeshingMode::kBinary}) {
      MarchingCubesOptions o;
      o.mode = mode;
      o.threads = 1;
      const TriangleMesh ref = mesh(v, o);
      EXPECT_FALSE(ref.empty());
      for (int threads : {2, 3, 8}) {
        o.threads = threads;
        expectSameMesh(ref, mesh(v, o));
      }
    }
}

TEST(MarchingCubes, ReusedObjectGivesTheSameResult) {
  // Scratch buffers keep their size between calls; a smaller grid after a larger one must not
  // see stale bits.
  MarchingCubes mc;
  TriangleMesh m;
  const TestVolume big = cvephands_test::noiseVolume(Vector3i(70, 40, 30), 1);
  const TestVolume small = cvephands_test::handVolume(4);
  mc.extract(big.view(), &m);
  mc.extract(small.view(), &m);
  expectSameMesh(m, mesh(small));
  mc.extract(big.view(), &m);
  expectSameMesh(m, mesh(big));
}

}  // namespace
