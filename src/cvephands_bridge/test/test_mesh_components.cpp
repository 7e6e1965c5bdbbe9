// Speck removal on meshes from marching cubes: a ball of radius 6 voxels next to a one-voxel
// speck; components are counted and only the ball survives. The hand's component choice: of two
// balls in one cube, the one near the hand's centre is kept.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "cvephands_bridge/mesh/marching_cubes.h"
#include "cvephands_bridge/mesh/mesh_components.h"

namespace cvephands {
namespace {

// Marching cubes of an n^3 grid of 1 cm voxels holding balls (centre voxel on the diagonal,
// radius in voxels) and single-voxel specks (each meshes to an octahedron of 8 triangles).
TriangleMesh ballsAndSpecks(int n, const std::vector<std::pair<int, double>>& balls,
                            const std::vector<int>& specks) {
  static std::vector<uint8_t> data;
  data.assign(size_t(n) * n * n, 0);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        for (const auto& [c, r] : balls)
          if (std::sqrt(double((x - c) * (x - c) + (y - c) * (y - c) + (z - c) * (z - c))) < r)
            data[x + n * (y + size_t(n) * z)] = 255;
  for (int v : specks) data[v + n * (v + size_t(n) * v)] = 255;
  ProbabilityGridView g;
  g.data = data.data();
  g.dims = Eigen::Vector3i(n, n, n);
  g.voxel_size = 0.01;
  return marchingCubes(g);
}

// A ball of radius 6 voxels at voxel 10 and a speck at voxel 25.
TriangleMesh ballAndSpeck(int n) { return ballsAndSpecks(n, {{10, 6.0}}, {25}); }

TEST(MeshComponents, CountsAndRemovesSpecks) {
  TriangleMesh m = ballAndSpeck(30);
  std::vector<uint32_t> label;
  EXPECT_EQ(labelComponents(m, &label), 2u);
  const size_t before = m.numTriangles();
  const size_t removed = removeSmallComponents(&m, 64);
  EXPECT_EQ(removed, 8u);  // a single voxel meshes to an octahedron
  EXPECT_EQ(m.numTriangles(), before - 8);
  EXPECT_EQ(labelComponents(m, &label), 1u);
  EXPECT_EQ(m.normals.size(), m.vertices.size());
  for (uint32_t i : m.triangles) ASSERT_LT(i, m.vertices.size());
  // Every remaining vertex lies on the ball (centre at voxel 10's centre, 0.105 m).
  for (const Eigen::Vector3f& v : m.vertices)
    EXPECT_LT((v - Eigen::Vector3f::Constant(0.105f)).norm(), 0.08f);
  EXPECT_EQ(removeSmallComponents(&m, 64), 0u);  // idempotent
  EXPECT_EQ(removeSmallComponents(&m, 1), 0u);   // 1 keeps everything
  TriangleMesh empty;
  EXPECT_EQ(removeSmallComponents(&empty, 64), 0u);
}

// Two balls of radius 4 voxels centred at voxels (8, 8, 8) and (22, 22, 22), i.e. at 0.085 m
// and 0.225 m on each axis, their surfaces 0.16 m apart.
TriangleMesh twoBalls() { return ballsAndSpecks(30, {{8, 4.0}, {22, 4.0}}, {}); }

size_t verticesNear(const TriangleMesh& m, const Eigen::Vector3f& c, float r) {
  size_t k = 0;
  for (const Eigen::Vector3f& v : m.vertices) k += (v - c).norm() < r;
  return k;
}

TEST(MeshComponents, TheHandKeepsTheComponentsNearItsCentre) {
  const Eigen::Vector3f a = Eigen::Vector3f::Constant(0.085f), b = Eigen::Vector3f::Constant(0.225f);
  const TriangleMesh both = twoBalls();
  std::vector<uint32_t> label;
  ASSERT_EQ(labelComponents(both, &label), 2u);
  // A hand at the first ball's centre, 8 cm: the other ball (its surface 0.20 m away) goes.
  TriangleMesh m = both;
  EXPECT_GT(keepHandComponents(&m, a, 64, 0.08f), 0u);
  EXPECT_EQ(labelComponents(m, &label), 1u);
  EXPECT_EQ(verticesNear(m, a, 0.05f), m.vertices.size());
  EXPECT_EQ(m.normals.size(), m.vertices.size());
  // A centre 3 cm outside the second ball's surface still keeps that ball and only it.
  m = both;
  keepHandComponents(&m, b + Eigen::Vector3f(0.07f, 0, 0), 64, 0.08f);
  EXPECT_EQ(verticesNear(m, b, 0.05f), m.vertices.size());
  EXPECT_GT(m.numTriangles(), 64u);
  // No component within the radius (a centre 8 cm from both balls' surfaces): nothing is this
  // hand's, the mesh is empty.
  m = both;
  EXPECT_EQ(keepHandComponents(&m, Eigen::Vector3f(0.155f, 0.155f, 0.155f), 64, 0.02f),
            both.numTriangles());
  EXPECT_TRUE(m.empty());
  // A radius that reaches both keeps both; 0 turns the choice off.
  m = both;
  EXPECT_EQ(keepHandComponents(&m, a, 64, 0.5f), 0u);
  EXPECT_EQ(keepHandComponents(&m, a, 64, 0.0f), 0u);
  EXPECT_EQ(m.numTriangles(), both.numTriangles());
  TriangleMesh empty;
  EXPECT_EQ(keepHandComponents(&empty, a, 64, 0.08f), 0u);
}

}  // namespace
}  // namespace cvephands
