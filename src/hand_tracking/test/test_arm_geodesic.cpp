// The hand at the far end of a bare arm, found along the skin (arm_geodesic.h), on synthetic
// skin volumes on the tracker's 16 mm reference grid. Arms are capsules of the radii a hull
// gives at 16 mm (forearm 3.5 cm, hand 2.5 cm half thickness), hands 19 cm from wrist to tips.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "hand_tracking/arm_geodesic.h"
#include "psfs_reconstruction/voxel_grid.h"

namespace {

using hand_tracking::ArmEnd;
using hand_tracking::ArmWalkParams;
using hand_tracking::armHandEnd;
using Eigen::Vector3d;

double segmentDistance(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * ab)).norm();
}

psfs::ProbabilityVolume emptyVolume() {
  psfs::ProbabilityVolume v;
  v.grid = psfs::referenceGrid(psfs::Resolution::k16mm);
  v.data.assign(v.grid.numVoxels(), 0);
  return v;
}

void fillCapsule(psfs::ProbabilityVolume* v, const Vector3d& a, const Vector3d& b, double r) {
  const psfs::VoxelGrid& g = v->grid;
  for (int z = 0; z < g.dims.z(); ++z)
    for (int y = 0; y < g.dims.y(); ++y)
      for (int x = 0; x < g.dims.x(); ++x)
        if (segmentDistance(g.centre(x, y, z), a, b) <= r) v->data[g.index(x, y, z)] = 230;
}

// A bare forearm (3.5 cm) from the elbow to the wrist and a hand (2.5 cm) on to the tips.
void fillArm(psfs::ProbabilityVolume* v, const Vector3d& elbow, const Vector3d& wrist,
             const Vector3d& tips) {
  fillCapsule(v, elbow, wrist, 0.035);
  fillCapsule(v, wrist, tips, 0.025);
}

// The skin centroid of the voxels within the capsule [a, b] of radius r (the hand's truth as the
// volume holds it).
Vector3d capsuleCentroid(const psfs::ProbabilityVolume& v, const Vector3d& a, const Vector3d& b,
                         double r) {
  const psfs::VoxelGrid& g = v.grid;
  Vector3d sum = Vector3d::Zero();
  double n = 0;
  for (int z = 0; z < g.dims.z(); ++z)
    for (int y = 0; y < g.dims.y(); ++y)
      for (int x = 0; x < g.dims.x(); ++x)
        if (v.data[g.index(x, y, z)] > 0 && segmentDistance(g.centre(x, y, z), a, b) <= r)
          sum += g.centre(x, y, z), ++n;
  return sum / n;
}

constexpr uint8_t kThreshold = 153;  // the tracker's 0.6
constexpr double kStartRadius = 0.10;
const Vector3d kHead(0.0, -0.42, 0.58);

ArmEnd walk(const psfs::ProbabilityVolume& skin, const Vector3d& start,
            const Vector3d* previous = nullptr, const ArmWalkParams& params = ArmWalkParams()) {
  return armHandEnd(skin, kThreshold, start, kStartRadius, {}, params, kHead, {}, previous);
}

// A forearm and hand stretched forward over the desk (reaching): the particles sit on the
// elbow, 40 cm from the hand; the walk finds the hand end.
TEST(ArmGeodesic, FindsTheHandOfAStretchedForearmFromTheElbow) {
  psfs::ProbabilityVolume skin = emptyVolume();
  const Vector3d elbow(-0.33, -0.31, 0.15), wrist(-0.335, -0.09, 0.15), tips(-0.34, 0.10, 0.15);
  fillArm(&skin, elbow, wrist, tips);
  const Vector3d hand = capsuleCentroid(skin, wrist, tips, 0.025);
  const ArmEnd e = walk(skin, elbow);
  std::printf("[ figures  ] stretched arm: length %.3f m, cross-section %.4f m^2, hand %.1f mm "
              "from the hand's centroid\n",
              e.length, e.cross_section, 1e3 * (e.centroid - hand).norm());
  ASSERT_EQ(e.arm_weight, 1.0);
  // The blob is elbow to tips plus the caps' radii, less a voxel (centre to centre); along an
  // axis 26-neighbour steps measure straight lines exactly.
  EXPECT_NEAR(e.length, (tips - elbow).norm() + 0.035 + 0.025 - 0.0156, 0.04);
  EXPECT_NEAR(e.hand_end.y(), tips.y(), 0.03);
  // The default 17 cm from the end hold most of the 19 cm hand and its 2.5 cm cap: their
  // centroid lies ~2.5 cm towards the tips of the hand's (a voxel and a quarter more allowed),
  // not on the forearm (the elbow is 40 cm away).
  EXPECT_LT((e.centroid - hand).norm(), 0.045);
  EXPECT_GT(e.centroid.y() - hand.y(), 0.0);
}

// A forearm raised to wave: the hand is nearer the head than the elbow, so the head alone
// picks the elbow; the hand is in front of the elbow (frontal), and that decides.
TEST(ArmGeodesic, ARaisedHandIsTheFrontalEndNotTheEndAwayFromTheHead) {
  psfs::ProbabilityVolume skin = emptyVolume();
  const Vector3d elbow(0.45, -0.47, 0.26), wrist(0.32, -0.31, 0.46), tips(0.24, -0.20, 0.60);
  fillArm(&skin, elbow, wrist, tips);
  ASSERT_LT((tips - kHead).norm(), (elbow - kHead).norm());
  const Vector3d hand = capsuleCentroid(skin, wrist, tips, 0.025);
  const ArmEnd e = walk(skin, elbow);
  ASSERT_EQ(e.arm_weight, 1.0);
  EXPECT_LT((e.hand_end - tips).norm(), 0.05);
  EXPECT_LT((e.centroid - hand).norm(), 0.045);  // as above
  // Without the frontal rule (no margin is ever reached) the head decides: the elbow.
  ArmWalkParams no_frontal;
  no_frontal.frontal_margin = 1.0;
  const ArmEnd by_head = walk(skin, elbow, nullptr, no_frontal);
  EXPECT_LT((by_head.hand_end - elbow).norm(), 0.06);
}

// Ends level along the frontal direction (a forearm across the body): the end the hand was at
// in the last frame wins over the head's rule.
TEST(ArmGeodesic, LevelEndsKeepTheLastFramesHandEnd) {
  psfs::ProbabilityVolume skin = emptyVolume();
  const Vector3d elbow(0.30, -0.25, 0.12), wrist(0.08, -0.25, 0.12), tips(-0.11, -0.25, 0.12);
  fillArm(&skin, elbow, wrist, tips);
  const ArmEnd by_head = walk(skin, elbow);
  ASSERT_EQ(by_head.arm_weight, 1.0);
  // The tips are nearer the head (x = 0) than the elbow: the head's rule takes the elbow.
  EXPECT_LT((by_head.hand_end - elbow).norm(), 0.06);
  const Vector3d last = tips + Vector3d(0.02, 0.01, 0.0);
  const ArmEnd kept = walk(skin, elbow, &last);
  EXPECT_LT((kept.hand_end - tips).norm(), 0.05);
  // A last hand end far from both ends (a jump the hand cannot make in a frame) is no help.
  const Vector3d far(0.0, 0.3, 0.4);
  EXPECT_LT((walk(skin, elbow, &far).hand_end - elbow).norm(), 0.06);
}

// A sleeve just beyond one end (the foreign-body probe) marks the arm's root: it outranks last
// frame's end and the head, and yields to the frontal rule.
TEST(ArmGeodesic, TheSleeveBeyondAnEndMarksTheRoot) {
  psfs::ProbabilityVolume skin = emptyVolume();
  const Vector3d elbow(0.30, -0.25, 0.12), wrist(0.08, -0.25, 0.12), tips(-0.11, -0.25, 0.12);
  fillArm(&skin, elbow, wrist, tips);
  // The sleeve goes on past the elbow (x > 0.33 m): body that is not skin there.
  const hand_tracking::ForeignBodyProbe sleeve = [](const Vector3d& p) {
    return p.x() > 0.33 ? 0.5 : 0.0;
  };
  const Vector3d last_at_elbow = elbow + Vector3d(0.01, 0.0, 0.0);
  const ArmEnd e = armHandEnd(skin, kThreshold, elbow, kStartRadius, {}, ArmWalkParams(), kHead,
                              sleeve, &last_at_elbow);
  ASSERT_EQ(e.arm_weight, 1.0);
  EXPECT_LT((e.hand_end - tips).norm(), 0.05);  // not the elbow the head and last frame name
  // A sleeve read at the tips' end instead is outranked by the hand in front (the arm turned
  // to point at the screen: the tips 20 cm further along +y than the elbow).
  psfs::ProbabilityVolume pointing = emptyVolume();
  const Vector3d p_elbow(0.30, -0.35, 0.12), p_wrist(0.22, -0.14, 0.12), p_tips(0.16, 0.04, 0.12);
  fillArm(&pointing, p_elbow, p_wrist, p_tips);
  const hand_tracking::ForeignBodyProbe at_tips = [](const Vector3d& p) {
    return p.y() > 0.03 ? 0.5 : 0.0;
  };
  const ArmEnd f = armHandEnd(pointing, kThreshold, p_elbow, kStartRadius, {}, ArmWalkParams(),
                              kHead, at_tips, nullptr);
  ASSERT_EQ(f.arm_weight, 1.0);
  EXPECT_LT((f.hand_end - p_tips).norm(), 0.05);
}

// What is not an arm leaves the caller's centroid alone (arm_weight 0): a hand alone (23 cm
// with its caps, 21 cm centre to centre: under min_arm_length's 27 cm), skin longer than an arm
// (a skin-coloured desk), skin thicker than an arm (a skin-coloured shirt), and no skin near
// the start.
TEST(ArmGeodesic, WhatIsNotAnArmIsLeftAlone) {
  {
    psfs::ProbabilityVolume skin = emptyVolume();
    fillCapsule(&skin, {0.1, -0.2, 0.05}, {0.1, -0.03, 0.05}, 0.03);
    const ArmEnd e = walk(skin, {0.1, -0.12, 0.05});
    EXPECT_GT(e.length, 0.15);
    EXPECT_EQ(e.arm_weight, 0.0);
  }
  {
    psfs::ProbabilityVolume skin = emptyVolume();
    fillCapsule(&skin, {-0.4, -0.2, 0.03}, {0.4, -0.2, 0.03}, 0.03);
    const ArmEnd e = walk(skin, {0.0, -0.2, 0.03});
    EXPECT_GT(e.length, 0.75);
    EXPECT_EQ(e.arm_weight, 0.0);
  }
  {
    psfs::ProbabilityVolume skin = emptyVolume();
    fillCapsule(&skin, {0.0, -0.35, 0.15}, {0.0, -0.35, 0.50}, 0.12);
    const ArmEnd e = walk(skin, {0.0, -0.35, 0.3});
    EXPECT_GT(e.cross_section, 0.015);
    EXPECT_EQ(e.arm_weight, 0.0);
  }
  {
    psfs::ProbabilityVolume skin = emptyVolume();
    fillCapsule(&skin, {0.1, -0.2, 0.05}, {0.1, 0.2, 0.05}, 0.03);
    const ArmEnd e = walk(skin, {-0.3, -0.2, 0.05});
    EXPECT_EQ(e.arm_weight, 0.0);
    EXPECT_FALSE(e.centroid.allFinite());
  }
}

// The caller's filter (the target's Voronoi cell) bounds the walk: the other hand's arm, joined
// to this one where the hands touch, is not walked.
TEST(ArmGeodesic, TheFilterKeepsTheWalkOnItsOwnSide) {
  psfs::ProbabilityVolume skin = emptyVolume();
  const Vector3d left_elbow(-0.30, -0.35, 0.12), left_tips(0.0, -0.05, 0.08);
  const Vector3d right_elbow(0.30, -0.35, 0.12), right_tips(0.0, -0.05, 0.08);
  fillCapsule(&skin, left_elbow, left_tips, 0.03);
  fillCapsule(&skin, right_elbow, right_tips, 0.03);
  const auto left_side = [](const Vector3d& p) { return p.x() < 0.0; };
  const ArmEnd e = armHandEnd(skin, kThreshold, left_elbow, kStartRadius, left_side, ArmWalkParams(),
                              kHead, {}, nullptr);
  ASSERT_GT(e.arm_weight, 0.0);
  // Unfiltered, the blob would be both arms, elbow to elbow (0.85 m), with no tips at its ends;
  // the left arm alone is 0.43 m (walked on the lattice's diagonal steps, up to 13 % longer).
  EXPECT_LT((e.hand_end - left_tips).norm(), 0.05);
  EXPECT_LT(e.length, 1.13 * (left_tips - left_elbow).norm() + 0.03);
}

}  // namespace
