// skinPathFraction (skin_path.h) on a 16 mm grid: a bare forearm joins a hand to its elbow,
// also from a point beside the arm, empty space between the two hands does not, gaps count in
// proportion, and the outside of the grid and empty volumes count as no skin.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hand_tracking/integral_volume.h"
#include "hand_tracking/skin_path.h"
#include "psfs_reconstruction/voxel_grid.h"
#include "tabletop_sim/primitives.h"

namespace hand_tracking {
namespace {

using Eigen::Vector3d;

psfs::ProbabilityVolume emptySkin() {
  psfs::ProbabilityVolume v;
  v.grid = psfs::referenceGrid(psfs::Resolution::k16mm);
  v.data.assign(v.grid.numVoxels(), 10);  // the noise floor, far below 0.5
  return v;
}

// Skin (0.9) in the simulator's capsule of radius r around [a, b] (its inside test).
void paintRod(psfs::ProbabilityVolume* v, const Vector3d& a, const Vector3d& b, double r) {
  const tabletop_sim::Primitive cap = tabletop_sim::Primitive::capsule(
      a, b, r, tabletop_sim::Material::SKIN, tabletop_sim::BodyPart::TORSO);
  const psfs::VoxelGrid& g = v->grid;
  for (size_t i = 0; i < v->data.size(); ++i) {
    const Eigen::Vector3i c = g.coords(i);
    if (cap.contains(g.centre(c.x(), c.y(), c.z()))) v->data[i] = 230;
  }
}

constexpr double kHalf = 0.025, kMin = 0.25;  // the tracker's cube and fill (mpf_tracker.cpp)

double fraction(const psfs::ProbabilityVolume& skin, const Vector3d& a, const Vector3d& b) {
  return skinPathFraction(IntegralVolume(skin), a, b, kHalf, kMin);
}

TEST(SkinPath, AForearmJoinsTheHandToTheElbowEvenFromItsSurface) {
  psfs::ProbabilityVolume skin = emptySkin();
  const Vector3d elbow(0.30, -0.45, 0.15), hand(0.18, -0.20, 0.05);
  paintRod(&skin, elbow, hand, 0.035);  // a 7 cm thick bare forearm, 29 cm long
  EXPECT_DOUBLE_EQ(fraction(skin, elbow, hand), 1.0);
  EXPECT_DOUBLE_EQ(fraction(skin, hand, elbow), 1.0);
  // From 4 cm below the axis near the elbow (where a palm box still holds half the arm) to
  // the hand: still the limb.
  const Vector3d below = elbow + 0.1 * (hand - elbow) - Vector3d(0, 0, 0.04);
  EXPECT_GT(fraction(skin, below, hand), 0.9);
  // The other hand, 36 cm across empty space: the line holds skin only near its own ends.
  const Vector3d other(-0.18, -0.20, 0.05);
  paintRod(&skin, other, other + Vector3d(0, 0.05, 0), 0.03);
  const double across = fraction(skin, hand, other);
  std::printf("[ figures  ] forearm surface to hand %.2f, hand to the other hand %.2f\n",
              fraction(skin, below, hand), across);
  EXPECT_LT(across, 0.3);
  EXPECT_GT(across, 0.0);
}

TEST(SkinPath, AGapCountsInProportion) {
  psfs::ProbabilityVolume skin = emptySkin();
  const Vector3d a(-0.20, 0.0, 0.30), b(0.20, 0.0, 0.30);
  paintRod(&skin, a, b, 0.03);
  // Clear a 12 cm stretch in the middle (0.3 of the 40 cm line); the cube (5 cm) sees skin
  // up to about 1.5 cm into the gap from each side.
  const psfs::VoxelGrid& g = skin.grid;
  for (size_t i = 0; i < skin.data.size(); ++i) {
    const Eigen::Vector3i c = g.coords(i);
    if (std::abs(g.centre(c.x(), c.y(), c.z()).x()) < 0.06) skin.data[i] = 10;
  }
  EXPECT_NEAR(fraction(skin, a, b), 0.7 + 2 * 0.015 / 0.40, 0.05);
  EXPECT_DOUBLE_EQ(skinPathFraction(IntegralVolume(skin), a, b, kHalf, 0.95), 0.0);
}

TEST(SkinPath, OutsideTheGridAndEmptyVolumesAreNoSkin) {
  psfs::ProbabilityVolume skin = emptySkin();
  std::fill(skin.data.begin(), skin.data.end(), 255);
  // From the grid's centre to 1 m beyond its +x face: the part outside does not count.
  const Vector3d c = skin.grid.origin + 0.5 * (skin.grid.maxCorner() - skin.grid.origin);
  const Vector3d out(skin.grid.maxCorner().x() + 1.0, c.y(), c.z());
  EXPECT_NEAR(fraction(skin, c, out), 0.5 / 1.5, 0.03);  // 0.5 m inside of 1.5 m
  EXPECT_EQ(skinPathFraction(IntegralVolume(), c, c, kHalf, kMin), 0.0);
  // A zero-length path is the one point.
  EXPECT_EQ(fraction(skin, c, c), 1.0);
}

}  // namespace
}  // namespace hand_tracking
