// Speck removal on meshes from marching cubes: a ball of radius 6 voxels next to a one-voxel
// speck; components are counted and only the ball survives.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "cvephands_bridge/mesh/marching_cubes.h"
#include "cvephands_bridge/mesh/mesh_components.h"

namespace cvephands {
namespace {

TriangleMesh ballAndSpeck(int n) {
  static std::vector<uint8_t> data;
  data.assign(size_t(n) * n * n, 0);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double d = std::sqrt(double((x - 10) * (x - 10) + (y - 10) * (y - 10) + (z - 10) * (z - 10)));
        data[x + n * (y + size_t(n) * z)] = d < 6.0 ? 255 : 0;
      }
  data[25 + n * (25 + size_t(n) * 25)] = 255;  // the speck: one voxel, 8 triangles
  ProbabilityGridView g;
  g.data = data.data();
  g.dims = Eigen::Vector3i(n, n, n);
  g.voxel_size = 0.01;
  return marchingCubes(g);
}

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

}  // namespace
}  // namespace cvephands
