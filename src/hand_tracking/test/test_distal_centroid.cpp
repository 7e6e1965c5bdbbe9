// Distal centroid: the hand at the far end of a bare forearm, on synthetic skin voxels at the
// tracker's 16 mm spacing.
#include <cstdio>

#include <gtest/gtest.h>

#include "hand_tracking/distal_centroid.h"

namespace {

using hand_tracking::distalCentroid;
using hand_tracking::WeightedPoint;
using Eigen::Vector3d;

constexpr double kVoxel = 1.0 / 64;

// Voxels of a box [min, max] on the 16 mm lattice, weight 1.
void addBox(const Vector3d& min, const Vector3d& max, std::vector<WeightedPoint>* out) {
  for (double z = min.z(); z <= max.z(); z += kVoxel)
    for (double y = min.y(); y <= max.y(); y += kVoxel)
      for (double x = min.x(); x <= max.x(); x += kVoxel) out->emplace_back(Vector3d(x, y, z), 1.0);
}

Vector3d centroidOf(const std::vector<WeightedPoint>& v) {
  Vector3d s = Vector3d::Zero();
  double w = 0;
  for (const auto& [p, m] : v) s += m * p, w += m;
  return s / w;
}

}  // namespace

TEST(DistalCentroid, BareForearmGivesTheHandEnd) {
  // A forearm reaching from the body (y = -0.30) to the wrist (y = -0.05) and a hand from
  // there to the finger tips (y = +0.13), head far behind. The answer must lie near the hand's
  // centre (y = +0.04): within half the cut's leftover forearm (0.17 - 0.18 m of hand: none)
  // plus a voxel.
  std::vector<WeightedPoint> skin;
  addBox(Vector3d(0.10, -0.30, 0.10), Vector3d(0.14, -0.05, 0.14), &skin);  // forearm, 4 cm thick
  addBox(Vector3d(0.08, -0.05, 0.10), Vector3d(0.16, 0.13, 0.13), &skin);   // hand, 8 cm wide
  std::vector<WeightedPoint> hand_only;
  addBox(Vector3d(0.08, -0.05, 0.10), Vector3d(0.16, 0.13, 0.13), &hand_only);
  const Vector3d head(0.0, -0.40, 0.55);
  const Vector3d c = centroidOf(skin), truth = centroidOf(hand_only);
  const Vector3d d = distalCentroid(skin, c, head, 0.17);
  std::printf("plain centroid %.1f mm from the hand's, distal %.1f mm\n", 1e3 * (c - truth).norm(),
              1e3 * (d - truth).norm());
  EXPECT_GT((c - truth).norm(), 0.05);
  EXPECT_LT((d - truth).norm(), 0.02);
}

TEST(DistalCentroid, HandAloneOrCompactBlobIsUnchanged) {
  // Long sleeves: only the hand is skin. It is elongated but no longer than the cut.
  std::vector<WeightedPoint> hand;
  addBox(Vector3d(0.08, -0.05, 0.10), Vector3d(0.16, 0.11, 0.13), &hand);
  const Vector3d c = centroidOf(hand);
  EXPECT_EQ(distalCentroid(hand, c, Vector3d(0, -0.4, 0.55), 0.17), c);
  // A fist: compact, not elongated.
  std::vector<WeightedPoint> fist;
  addBox(Vector3d(0.08, 0.0, 0.10), Vector3d(0.17, 0.09, 0.18), &fist);
  const Vector3d f = centroidOf(fist);
  EXPECT_EQ(distalCentroid(fist, f, Vector3d(0, -0.4, 0.55), 0.17), f);
  // Nothing at all.
  EXPECT_EQ(distalCentroid({}, f, Vector3d(0, -0.4, 0.55), 0.17), f);
}

TEST(DistalCentroid, TheEndAwayFromTheHeadWins) {
  // The same arm seen with the head on the other side: the cut keeps the other end.
  std::vector<WeightedPoint> arm;
  addBox(Vector3d(0.10, -0.30, 0.10), Vector3d(0.14, 0.10, 0.14), &arm);
  const Vector3d c = centroidOf(arm);
  const Vector3d towards_plus_y = distalCentroid(arm, c, Vector3d(0.1, -0.6, 0.3), 0.17);
  const Vector3d towards_minus_y = distalCentroid(arm, c, Vector3d(0.1, 0.4, 0.3), 0.17);
  EXPECT_GT(towards_plus_y.y(), c.y() + 0.08);
  EXPECT_LT(towards_minus_y.y(), c.y() - 0.08);
}

TEST(DistalCentroid, ArmWeightRisesSmoothlyWithTheLength) {
  // Straight 4 x 4 cm "arms" of growing length along y: no arm up to 0.22 m (hand + smear),
  // then a weight that grows with the length and reaches 1 five centimetres later, never
  // jumping by more than what one more voxel of length adds (16 mm of 50: 0.32).
  const Vector3d head(0.12, -0.6, 0.4);
  double last = 0.0;
  for (double len = 0.16; len <= 0.36; len += kVoxel) {
    std::vector<WeightedPoint> arm;
    addBox(Vector3d(0.10, -0.30, 0.10), Vector3d(0.14, -0.30 + len, 0.14), &arm);
    double w = -1.0;
    distalCentroid(arm, centroidOf(arm), head, 0.17, &w);
    EXPECT_GE(w, 0.0);
    EXPECT_LE(w, 1.0);
    EXPECT_GE(w, last - 1e-12) << "length " << len;
    EXPECT_LE(w - last, 0.33) << "length " << len;
    if (len < 0.22 - 1e-9) {
      EXPECT_EQ(w, 0.0) << "length " << len;
    }
    if (len > 0.28) {
      EXPECT_EQ(w, 1.0) << "length " << len;
    }
    last = w;
  }
}

TEST(DistalCentroid, ARaisedForearmsHandIsTheEndWithoutBodyBeyondIt) {
  // A forearm raised to wave: elbow at z = 0.27 m beside the trunk, hand up at z = 0.45-0.60 m,
  // the hand nearer the head (0.39 m) than the elbow (0.45 m). The head's rule cuts at the elbow;
  // with the sleeve (body that is not skin) around the elbow, the cut keeps the hand.
  const Vector3d head(0.0, -0.42, 0.49);
  std::vector<WeightedPoint> arm;
  addBox(Vector3d(0.37, -0.44, 0.27), Vector3d(0.41, -0.40, 0.45), &arm);  // forearm, 4 cm
  std::vector<WeightedPoint> hand;
  addBox(Vector3d(0.35, -0.45, 0.45), Vector3d(0.43, -0.42, 0.60), &hand);  // flat hand
  arm.insert(arm.end(), hand.begin(), hand.end());
  const Vector3d c = centroidOf(arm), truth = centroidOf(hand);
  // The sleeve: body that is not skin below z = 0.32 around the arm.
  const auto sleeve = [](const Vector3d& p) { return p.z() < 0.32 ? 0.6 : 0.05; };
  const Vector3d by_head = distalCentroid(arm, c, head, 0.17);
  const Vector3d by_body = distalCentroid(arm, c, head, 0.17, nullptr, sleeve);
  std::printf("head's rule %.1f mm from the hand, with the sleeve %.1f mm\n",
              1e3 * (by_head - truth).norm(), 1e3 * (by_body - truth).norm());
  EXPECT_LT(by_head.z(), c.z());  // the elbow's end, as before
  EXPECT_LT((by_body - truth).norm(), 0.03);
  // Both ends alike (a hand on the chest, say): the head's rule decides.
  const auto same = [](const Vector3d&) { return 0.4; };
  EXPECT_EQ(distalCentroid(arm, c, head, 0.17, nullptr, same), by_head);
  // An end only a little fuller than the other (within kForeignMargin): no change either.
  const auto slight = [](const Vector3d& p) { return p.z() < 0.32 ? 0.45 : 0.4; };
  EXPECT_EQ(distalCentroid(arm, c, head, 0.17, nullptr, slight), by_head);
}
