// Integral volumes against brute-force sums: random volumes (odd sizes, off-origin grids),
// random boxes including boxes clipped by the border and boxes entirely outside; the world-box
// mean's voxel-centre rule; the smooth (fractional) box integral against a supersampled sum.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "hand_tracking/integral_volume.h"

namespace hand_tracking {
namespace {

psfs::ProbabilityVolume randomVolume(std::mt19937_64& rng, const Eigen::Vector3i& dims,
                                     double voxel, const Eigen::Vector3d& origin) {
  psfs::ProbabilityVolume v;
  v.grid.dims = dims;
  v.grid.voxel_size = voxel;
  v.grid.origin = origin;
  v.data.resize(v.grid.numVoxels());
  std::uniform_int_distribution<int> byte(0, 255);
  std::bernoulli_distribution sparse(0.3);
  for (auto& b : v.data) b = sparse(rng) ? static_cast<uint8_t>(byte(rng)) : 0;
  return v;
}

uint64_t bruteSum(const psfs::ProbabilityVolume& v, Eigen::Vector3i lo, Eigen::Vector3i hi) {
  uint64_t s = 0;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(lo[a], 0);
    hi[a] = std::min(hi[a], v.grid.dims[a]);
  }
  for (int z = lo.z(); z < hi.z(); ++z)
    for (int y = lo.y(); y < hi.y(); ++y)
      for (int x = lo.x(); x < hi.x(); ++x) s += v.at(x, y, z);
  return s;
}

TEST(IntegralVolume, BoxSumsEqualBruteForce) {
  std::mt19937_64 rng(7);
  int boxes = 0, clipped = 0, outside = 0;
  for (const Eigen::Vector3i& dims : {Eigen::Vector3i(1, 1, 1), Eigen::Vector3i(7, 5, 3),
                                     Eigen::Vector3i(17, 13, 11), Eigen::Vector3i(64, 64, 48)}) {
    const psfs::ProbabilityVolume v = randomVolume(rng, dims, 0.015625, {-0.5, -0.5, 0.0});
    IntegralVolume iv;
    iv.build(v);
    ASSERT_EQ(iv.grid(), v.grid);
    // Whole grid.
    uint64_t total = 0;
    for (uint8_t b : v.data) total += b;
    EXPECT_EQ(iv.boxSum({0, 0, 0}, dims), total);
    for (int k = 0; k < 3000; ++k) {
      Eigen::Vector3i lo, hi;
      for (int a = 0; a < 3; ++a) {
        // Mostly inside (lo in [0, dims)), some reaching over the border or entirely outside.
        const int n = dims[a];
        std::uniform_int_distribution<int> start(k % 4 == 0 ? -n / 2 - 3 : 0,
                                                 k % 4 == 0 ? n + 3 : n - 1);
        std::uniform_int_distribution<int> length(k % 7 == 0 ? -1 : 0, std::max(1, n / 2 + 1));
        lo[a] = start(rng);
        hi[a] = lo[a] + length(rng);  // length <= 0: an empty box
      }
      bool is_clipped = false, is_outside = false;
      for (int a = 0; a < 3; ++a) {
        is_clipped |= lo[a] < 0 || hi[a] > dims[a];
        is_outside |= hi[a] <= 0 || lo[a] >= dims[a];
      }
      clipped += is_clipped;
      outside += is_outside;
      ++boxes;
      ASSERT_EQ(iv.boxSum(lo, hi), bruteSum(v, lo, hi))
          << "dims " << dims.transpose() << " box " << lo.transpose() << " .. " << hi.transpose();
      if (is_outside) {
        ASSERT_EQ(iv.boxSum(lo, hi), 0u);
      }
    }
  }
  std::printf("[ figures  ] %d random boxes (%d clipped by the border, %d entirely outside) "
              "equal brute force\n", boxes, clipped, outside);
  EXPECT_GT(clipped, 500);
  EXPECT_GT(outside, 200);
}

TEST(IntegralVolume, RebuildReusesAndReplaces) {
  std::mt19937_64 rng(3);
  IntegralVolume iv;
  const auto a = randomVolume(rng, {9, 8, 7}, 0.02, {0, 0, 0});
  const auto b = randomVolume(rng, {4, 6, 5}, 0.01, {1, 2, 3});
  iv.build(a);
  iv.build(b);
  EXPECT_EQ(iv.grid(), b.grid);
  EXPECT_EQ(iv.boxSum({0, 0, 0}, {4, 6, 5}), bruteSum(b, {0, 0, 0}, {4, 6, 5}));
}

TEST(IntegralVolume, WorldBoxMeanUsesVoxelCentres) {
  std::mt19937_64 rng(11);
  const psfs::ProbabilityVolume v = randomVolume(rng, {20, 16, 12}, 0.05, {-0.5, -0.4, 0.1});
  const IntegralVolume iv(v);
  const psfs::VoxelGrid& g = v.grid;
  std::uniform_real_distribution<double> u(-0.3, 1.3);
  int tested = 0;
  for (int k = 0; k < 2000; ++k) {
    Eigen::Vector3d a, b;
    for (int i = 0; i < 3; ++i) {
      const double ext = g.voxel_size * g.dims[i];
      a[i] = g.origin[i] + u(rng) * ext;
      b[i] = a[i] + std::abs(u(rng)) * 0.5 * ext;
    }
    // Brute force: voxels whose centre lies in [a, b].
    uint64_t sum = 0;
    int count = 0;
    for (int z = 0; z < g.dims.z(); ++z)
      for (int y = 0; y < g.dims.y(); ++y)
        for (int x = 0; x < g.dims.x(); ++x) {
          const Eigen::Vector3d c = g.centre(x, y, z);
          if ((c.array() >= a.array()).all() && (c.array() <= b.array()).all()) {
            sum += v.at(x, y, z);
            ++count;
          }
        }
    int n = -1;
    const double m = iv.boxMean(a, b, &n);
    ASSERT_EQ(n, count) << a.transpose() << " .. " << b.transpose();
    ASSERT_NEAR(m, count ? sum / (255.0 * count) : 0.0, 1e-12);
    ++tested;
  }
  // Entirely outside, and inverted boxes.
  int n = -1;
  EXPECT_EQ(iv.boxMean({5, 5, 5}, {6, 6, 6}, &n), 0.0);
  EXPECT_EQ(n, 0);
  EXPECT_EQ(iv.boxMean({0.2, 0.2, 0.3}, {0.1, 0.3, 0.4}, &n), 0.0);
  EXPECT_EQ(n, 0);
  EXPECT_EQ(iv.boxMean(Eigen::Vector3d::Constant(NAN), {0, 0, 0}, &n), 0.0);
  EXPECT_EQ(iv.boxMean({-1e30, -1e30, -1e30}, {1e30, 1e30, 1e30}, &n),
            iv.boxSum({0, 0, 0}, g.dims) / (255.0 * g.numVoxels()));
  EXPECT_EQ(n, static_cast<int>(g.numVoxels()));
  std::printf("[ figures  ] %d world boxes: means and voxel counts equal brute force\n", tested);
}

TEST(IntegralVolume, SmoothBoxIntegralIsTheCoveredFraction) {
  std::mt19937_64 rng(5);
  const psfs::ProbabilityVolume v = randomVolume(rng, {10, 9, 8}, 0.1, {0, 0, 0});
  const IntegralVolume iv(v);
  std::uniform_real_distribution<double> u(-0.2, 1.1);
  double worst = 0;
  for (int k = 0; k < 300; ++k) {
    Eigen::Vector3d a(u(rng), u(rng), u(rng)), b;
    b = a + Eigen::Vector3d(std::abs(u(rng)), std::abs(u(rng)), std::abs(u(rng))) * 0.6;
    // Exact: per voxel, the product of the per-axis overlaps (in voxel units).
    double exact = 0;
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 9; ++y)
        for (int x = 0; x < 10; ++x) {
          const Eigen::Vector3d lo(x * 0.1, y * 0.1, z * 0.1);
          double f = 1;
          for (int i = 0; i < 3; ++i)
            f *= std::max(0.0, std::min(b[i], lo[i] + 0.1) - std::max(a[i], lo[i])) / 0.1;
          exact += f * v.at(x, y, z);
        }
    const double got = iv.boxIntegral(a, b);
    worst = std::max(worst, std::abs(got - exact));
    ASSERT_NEAR(got, exact, 1e-6 * (1 + exact)) << a.transpose() << " .. " << b.transpose();
    const double vol = (b - a).prod() / 1e-3;
    ASSERT_NEAR(iv.boxMeanSmooth(a, b), exact / (255 * vol), 1e-9);
  }
  // Voxel-aligned boxes agree with the integer sums.
  EXPECT_NEAR(iv.boxIntegral({0.1, 0.2, 0.3}, {0.5, 0.6, 0.7}),
              static_cast<double>(iv.boxSum({1, 2, 3}, {5, 6, 7})), 1e-6);
  EXPECT_EQ(iv.boxIntegral({3, 3, 3}, {4, 4, 4}), 0.0);
  std::printf("[ figures  ] smooth box integrals: worst error %.2e byte-voxels\n", worst);
}

TEST(IntegralVolume, RejectsInconsistentVolumes) {
  psfs::ProbabilityVolume v;
  IntegralVolume iv;
  EXPECT_THROW(iv.build(v), std::invalid_argument);  // empty grid
  v.grid.dims = {4, 4, 4};
  v.grid.voxel_size = 0.1;
  v.data.resize(63);
  EXPECT_THROW(iv.build(v), std::invalid_argument);  // size mismatch
  EXPECT_EQ(iv.boxSum({0, 0, 0}, {4, 4, 4}), 0u);
  EXPECT_EQ(iv.boxMean({0, 0, 0}, {1, 1, 1}), 0.0);
}

}  // namespace
}  // namespace hand_tracking
