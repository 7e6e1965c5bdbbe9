// The quadric body model: forward kinematics against the simulated rig's (the same state must
// mean the same pose), the joint rotations' conversions, swing-twist limits on random
// quaternions, the truncated quadrics' inside tests and weights against sampled points, and the
// YAML body profile.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

#include "body_tracking/arm_ik.h"
#include "body_tracking/body_parts.h"
#include "body_tracking/joint_limits.h"
#include "body_tracking/kinematics.h"
#include "body_tracking/part_collision.h"
#include "body_tracking/state_tangent.h"
#include "body_tracking/swing_twist.h"
#include "tabletop_sim/body_model.h"

namespace body_tracking {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector3d;

BodyState randomState(std::mt19937* rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  BodyState s{};
  s[dof::TORSO_X] = 0.05 * u(*rng);
  s[dof::TORSO_Y] = -0.48 + 0.05 * u(*rng);
  s[dof::TORSO_Z] = -0.17 + 0.03 * u(*rng);
  s[dof::TORSO_ROLL] = 0.2 * u(*rng);
  s[dof::TORSO_PITCH] = 0.15 * u(*rng);
  s[dof::TORSO_YAW] = 0.4 * u(*rng);
  s[dof::SPINE_BEND] = 0.1 + 0.2 * u(*rng);
  s[dof::HEAD_YAW] = 0.6 * u(*rng);
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    s[armDof(side, 0)] = -0.6 + 0.8 * u(*rng);
    s[armDof(side, 1)] = 0.6 * u(*rng);
    s[armDof(side, 2)] = 0.02 * u(*rng);
    s[armDof(side, 3)] = 1.2 + 1.0 * u(*rng);
    s[armDof(side, 4)] = 0.8 * u(*rng);
  }
  return s;
}

Quaterniond randomQuaternion(std::mt19937* rng) {
  std::normal_distribution<double> n;
  return Quaterniond(n(*rng), n(*rng), n(*rng), n(*rng)).normalized();
}

double rotationDistance(const Quaterniond& a, const Quaterniond& b) {
  return a.angularDistance(b);
}

TEST(Kinematics, AgreesWithTheSimulatedRig) {
  // The default profile is the simulator's medium adult: joints and the head centre must match
  // its kinematics to rounding, and the hand (no wrist DOF) its palm centre with a straight wrist.
  const BodyProfile profile;
  const tabletop_sim::BodyModel sim;
  std::mt19937 rng(3);
  for (int k = 0; k < 200; ++k) {
    const BodyState s = randomState(&rng);
    tabletop_sim::BodyPose pose;
    for (int i = 0; i < dof::COUNT; ++i) pose.state[i] = s[i];
    for (auto& h : pose.hands) h = tabletop_sim::HandPose();
    const tabletop_sim::BodyFrames t = sim.forward(pose);
    const BodyFrames f = forwardKinematics(profile, s);
    for (Side side : {Side::LEFT, Side::RIGHT}) {
      const int i = static_cast<int>(side);
      EXPECT_LT((f.shoulder[i] - t.shoulder[i]).norm(), 1e-9);
      EXPECT_LT((f.elbow[i] - t.elbow[i]).norm(), 1e-9);
      EXPECT_LT((f.wrist[i] - t.wrist[i]).norm(), 1e-9);
      EXPECT_LT((f.hand[i] - t.palm[i].translation()).norm(), 1e-9);
    }
    EXPECT_LT((f.head_centre - sim.headCentre(pose)).norm(), 1e-9);
    EXPECT_LT((f.chest.matrix() - t.chest.matrix()).norm(), 1e-9);
  }
}

TEST(Kinematics, JointAngleConversionsRoundTrip) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 500; ++k) {
    const double s1 = 1.5 * u(rng), s2 = 1.4 * u(rng);
    double a, b;
    shoulderAngles(shoulderRotation(s1, s2), &a, &b);
    EXPECT_NEAR(a, s1, 1e-9);
    EXPECT_NEAR(b, s2, 1e-9);
    const double flex = 0.05 + 1.5 * (u(rng) + 1.0), twist = 3.0 * u(rng);
    double f = 0, t = 0;
    elbowAngles(elbowRotation(flex, twist), &f, &t);
    EXPECT_NEAR(f, flex, 1e-9);
    EXPECT_NEAR(t, twist, 1e-9);
    const double r = 1.4 * u(rng), p = 1.4 * u(rng), y = 3.0 * u(rng);
    double r2, p2, y2;
    torsoAngles(torsoRotation(r, p, y), &r2, &p2, &y2);
    EXPECT_NEAR(r2, r, 1e-9);
    EXPECT_NEAR(p2, p, 1e-9);
    EXPECT_NEAR(y2, y, 1e-9);
  }
}

TEST(SwingTwist, DecompositionOfRandomQuaternions) {
  std::mt19937 rng(7);
  for (int k = 0; k < 2000; ++k) {
    const Quaterniond q = randomQuaternion(&rng);
    const Vector3d axis = randomQuaternion(&rng) * Vector3d::UnitY();
    Quaterniond swing, twist;
    swingTwist(q, axis, &swing, &twist);
    EXPECT_LT(rotationDistance(swing * twist, q), 1e-9);
    // The twist turns about the axis only; the swing's axis is perpendicular to it.
    EXPECT_LT((twist * axis - axis).norm(), 1e-9);
    EXPECT_LT(std::abs(swing.vec().dot(axis)), 1e-9);
  }
}

TEST(SwingTwist, ClampOnRandomQuaternions) {
  SwingTwistLimit limit;
  limit.axis = Vector3d::UnitY();
  limit.u = Vector3d::UnitX();
  limit.max_swing_u = 1.2;
  limit.max_swing_v = 0.5;
  limit.min_twist = -0.3;
  limit.max_twist = 0.7;
  std::mt19937 rng(11);
  int inside = 0;
  for (int k = 0; k < 5000; ++k) {
    const Quaterniond q = randomQuaternion(&rng);
    const Quaterniond c = limit.clamp(q);
    ASSERT_TRUE(limit.satisfied(c, 1e-7)) << "clamped rotation outside the limits";
    EXPECT_LT(rotationDistance(limit.clamp(c), c), 1e-7) << "clamp is not idempotent";
    if (limit.satisfied(q)) {
      ++inside;
      EXPECT_LT(rotationDistance(c, q), 1e-9) << "a rotation within the limits was changed";
    }
  }
  EXPECT_GT(inside, 20);  // the random set does exercise the pass-through branch
  // A swing beyond the cone along u comes back to the cone's edge in the same direction.
  const Quaterniond over(Eigen::AngleAxisd(1.5, Vector3d::UnitX()));
  const Quaterniond back = limit.clamp(over);
  EXPECT_NEAR(back.angularDistance(Quaterniond::Identity()), 1.2, 1e-9);
  EXPECT_LT((back * Vector3d::UnitY() - Eigen::AngleAxisd(1.2, Vector3d::UnitX()) * Vector3d::UnitY())
                .norm(), 1e-9);
}

TEST(TruncatedQuadric, InsideTestsAndWeightsAgainstSampledPoints) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 20; ++k) {
    Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
    frame.linear() = randomQuaternion(&rng).toRotationMatrix();
    frame.translation() = Vector3d(u(rng), u(rng), u(rng));
    const double len = 0.2 + 0.1 * u(rng), hx = 0.05 + 0.02 * u(rng), hz = 0.04 + 0.02 * u(rng);
    const Vector3d semi(0.06 + 0.02 * u(rng), 0.09 + 0.02 * u(rng), 0.05 + 0.02 * u(rng));
    const TruncatedQuadric cyl = TruncatedQuadric::cylinder(frame, len, hx, hz);
    const TruncatedQuadric ell = TruncatedQuadric::ellipsoid(frame, semi);
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
      const Vector3d l(0.2 * u(rng), 0.2 + 0.2 * u(rng), 0.2 * u(rng));  // local point
      const Vector3d p = frame * l;
      const double rc = std::pow(l.x() / hx, 2) + std::pow(l.z() / hz, 2);
      const bool c_in = rc <= 1.0 && l.y() >= 0 && l.y() <= len;
      ASSERT_EQ(cyl.contains(p), c_in);
      EXPECT_NEAR(cyl.algebraic(p), rc - 1.0, 1e-9);  // -1 on the axis, 0 on the surface
      if (c_in) {
        EXPECT_TRUE(cyl.bounds.contains(p));
      }
      const Vector3d e = frame * (l - Vector3d(0, 0.2, 0));  // ellipsoid centred at the origin
      const Vector3d m = (l - Vector3d(0, 0.2, 0)).cwiseQuotient(semi);
      ASSERT_EQ(ell.contains(e), m.squaredNorm() <= 1.0);
      EXPECT_NEAR(ell.algebraic(e), m.squaredNorm() - 1.0, 1e-9);
      if (m.squaredNorm() <= 1.0) {
        EXPECT_TRUE(ell.bounds.contains(e));
      }
    }
    // Volumes: Monte Carlo in the tight bounds, where the solid fills 30-80 %, so 40000 samples
    // give a binomial error below 0.5 %.
    for (const TruncatedQuadric* q : {&cyl, &ell}) {
      const Eigen::AlignedBox3d& b = q->bounds;
      int hits = 0;
      const int m = 40000;
      for (int i = 0; i < m; ++i) {
        const Vector3d r = 0.5 * (Vector3d(u(rng), u(rng), u(rng)) + Vector3d::Ones());
        if (q->contains(b.min() + r.cwiseProduct(b.sizes()))) ++hits;
      }
      EXPECT_NEAR(hits * b.volume() / m, q->volume(), 0.03 * q->volume());
    }
  }
}

TEST(BodyParts, PartsSitOnTheirBones) {
  const BodyProfile profile;
  std::mt19937 rng(17);
  for (int k = 0; k < 50; ++k) {
    const BodyState s = randomState(&rng);
    const BodyFrames f = forwardKinematics(profile, s);
    const BodyParts parts = buildParts(profile, f);
    for (Side side : {Side::LEFT, Side::RIGHT}) {
      const int i = static_cast<int>(side);
      const TruncatedQuadric& ua = parts[static_cast<int>(upperArmPart(side))];
      const TruncatedQuadric& fa = parts[static_cast<int>(forearmPart(side))];
      const TruncatedQuadric& hand = parts[static_cast<int>(handPart(side))];
      EXPECT_TRUE(ua.contains(0.5 * (f.shoulder[i] + f.elbow[i])));
      EXPECT_NEAR(ua.algebraic(0.5 * (f.shoulder[i] + f.elbow[i])), -1.0, 1e-9);
      EXPECT_TRUE(fa.contains(0.5 * (f.elbow[i] + f.wrist[i])));
      EXPECT_FALSE(fa.contains(f.wrist[i] + 0.01 * (f.wrist[i] - f.elbow[i]).normalized()));
      EXPECT_TRUE(hand.contains(f.hand[i]));
      EXPECT_LT((hand.centre() - f.hand[i]).norm(), 1e-12);
    }
    EXPECT_TRUE(parts[static_cast<int>(Part::HEAD)].contains(f.head_centre));
    EXPECT_TRUE(parts[static_cast<int>(Part::CHEST)].contains(f.chest * Vector3d(0, 0, 0.15)));
    EXPECT_TRUE(parts[static_cast<int>(Part::ABDOMEN)].contains(f.pelvis * Vector3d(0, 0, 0.1)));
    EXPECT_FALSE(parts[static_cast<int>(Part::CHEST)].contains(f.chest * Vector3d(0, 0.2, 0.15)));
  }
}

// Two states are the same pose when every joint and the head sit in the same place.
double poseDistance(const BodyProfile& p, const BodyState& a, const BodyState& b) {
  const BodyFrames fa = forwardKinematics(p, a), fb = forwardKinematics(p, b);
  double d = (fa.head_centre - fb.head_centre).norm();
  for (int i = 0; i < 2; ++i)
    d = std::max({d, (fa.shoulder[i] - fb.shoulder[i]).norm(), (fa.elbow[i] - fb.elbow[i]).norm(),
                  (fa.hand[i] - fb.hand[i]).norm()});
  return d;
}

TEST(BodyLimits, EnforceGivesAllowedStatesAndKeepsAllowedOnes) {
  const BodyLimits limits;
  const BodyProfile profile;
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int unchanged = 0;
  for (int k = 0; k < 2000; ++k) {
    BodyState s = randomState(&rng);
    if (k % 2) {  // and wild ones
      for (int i = dof::TORSO_ROLL; i < dof::COUNT; ++i) s[i] = 3.0 * u(rng);
      s[dof::L_SHIFT] = 0.1 * u(rng);
      s[dof::R_SHIFT] = 0.1 * u(rng);
    }
    BodyState c = s;
    limits.enforce(&c);
    ASSERT_TRUE(limits.satisfied(c, 1e-6)) << "state " << k;
    if (limits.satisfied(s)) {
      ++unchanged;
      EXPECT_LT(poseDistance(profile, s, c), 1e-9) << "an allowed pose was moved";
    }
  }
  EXPECT_GT(unchanged, 500);
  // The simulator's rest pose is allowed.
  BodyState rest;
  const tabletop_sim::BodyPose sp = tabletop_sim::BodyModel::restPose();
  for (int i = 0; i < dof::COUNT; ++i) rest[i] = sp.state[i];
  EXPECT_TRUE(limits.satisfied(rest));
}

TEST(StateTangent, RoundTripAndMean) {
  const BodyProfile profile;
  std::mt19937 rng(23);
  std::normal_distribution<double> n(0.0, 0.05);
  for (int k = 0; k < 300; ++k) {
    const BodyState at = randomState(&rng), s = randomState(&rng);
    // Coordinates of s at `at` lead back to s (the same pose; the angles may differ by 2 pi).
    EXPECT_LT(poseDistance(profile, fromTangent(at, toTangent(at, s)), s), 1e-7);
    EXPECT_LT(toTangent(at, at).norm(), 1e-9);
    // Small steps: coordinates of a stepped state give the step back.
    Tangent step;
    for (int i = 0; i < kTangentDim; ++i) step[i] = n(rng);
    EXPECT_LT((toTangent(at, fromTangent(at, step)) - step).norm(), 1e-7);
  }
  // The weighted mean of states spread symmetrically about a pose is that pose.
  const BodyState c = randomState(&rng);
  std::vector<BodyState> set;
  std::vector<double> w;
  for (int k = 0; k < 20; ++k) {
    Tangent step;
    for (int i = 0; i < kTangentDim; ++i) step[i] = n(rng);
    set.push_back(fromTangent(c, step));
    set.push_back(fromTangent(c, -step));
    w.push_back(1.0);
    w.push_back(1.0);
  }
  EXPECT_LT(poseDistance(profile, weightedMean(set.data(), w.data(), 40, set[0], 3), c), 2e-3);
}

TEST(ArmIk, PutsTheHandOnReachableTargets) {
  const BodyProfile profile;
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int reachable = 0;
  for (int k = 0; k < 500; ++k) {
    BodyState s = randomState(&rng);
    const Side side = k % 2 ? Side::LEFT : Side::RIGHT;
    const BodyFrames f = forwardKinematics(profile, s);
    const int i = static_cast<int>(side);
    const Vector3d target = f.shoulder[i] + 0.6 * Vector3d(u(rng), u(rng), u(rng));
    const Vector3d pole = f.shoulder[i] + Vector3d(0, 0, -0.5);
    const bool ok = solveArmIk(profile, side, target, pole, &s);
    const BodyFrames g = forwardKinematics(profile, s);
    const double reach = profile.upper_arm + profile.forearm + profile.wrist_to_hand;
    const double d = (target - f.shoulder[i]).norm();
    EXPECT_EQ(ok, d <= reach - 1e-4 && d >= std::abs(profile.upper_arm - profile.forearm - profile.wrist_to_hand) + 1e-4);
    if (ok) {
      ++reachable;
      EXPECT_LT((g.hand[i] - target).norm(), 1e-6);
      // The elbow bends towards the pole (below the shoulder-target line here).
      const Vector3d axis = (target - g.shoulder[i]).normalized();
      const Vector3d e = g.elbow[i] - g.shoulder[i];
      const Vector3d off = e - axis * e.dot(axis);
      const Vector3d pd = (pole - g.shoulder[i]) - axis * (pole - g.shoulder[i]).dot(axis);
      if (off.norm() > 1e-3 && pd.norm() > 1e-3) {
        EXPECT_GT(off.dot(pd), 0.0);
      }
    }
    // The other arm is untouched.
    EXPECT_LT((g.hand[1 - i] - f.hand[1 - i]).norm(), 1e-12);
  }
  EXPECT_GT(reachable, 200);
}

TEST(PartCollision, ArmThroughTheChestOrHandOnTheFaceCollidesHandsOnTheDeskDoNot) {
  const BodyProfile profile;
  BodyState rest;
  const tabletop_sim::BodyPose sp = tabletop_sim::BodyModel::restPose();
  for (int i = 0; i < dof::COUNT; ++i) rest[i] = sp.state[i];
  BodyFrames f = forwardKinematics(profile, rest);
  EXPECT_FALSE(bodyCollides(profile, f, buildParts(profile, f)));
  // Swing the left upper arm across the chest (towards +x, the person's right).
  BodyState s = rest;
  s[dof::L_SWING_1] = 0.0;
  s[dof::L_SWING_2] = -1.4;
  s[dof::L_FLEX] = 0.0;
  f = forwardKinematics(profile, s);
  EXPECT_TRUE(bodyCollides(profile, f, buildParts(profile, f)));
  // Forearms through each other: both pointing at the same spot in front of the chest.
  s = rest;
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    const Vector3d target(side == Side::LEFT ? 0.12 : -0.12, -0.10, 0.10);
    solveArmIk(profile, side, target, Vector3d(0, -0.6, -0.3), &s);
  }
  f = forwardKinematics(profile, s);
  EXPECT_TRUE(bodyCollides(profile, f, buildParts(profile, f)));
  // A hand on the face, its centre 3 cm in front of the head part (the face is skin: the hand
  // part would lock on to it), collides; the same hand beside the head, 25 cm out, does not.
  f = forwardKinematics(profile, rest);
  const Vector3d face = f.head_centre + f.chest.linear() * Vector3d(0.0, profile.head_half_depth + 0.03, 0.0);
  const Vector3d beside = f.head_centre + f.chest.linear() * Vector3d(-0.25, 0.0, 0.0);
  for (const auto& [target, collides] : {std::pair<Vector3d, bool>{face, true}, {beside, false}}) {
    s = rest;
    ASSERT_TRUE(solveArmIk(profile, Side::LEFT, target, f.shoulder[0] + Vector3d(-0.3, 0, -0.3), &s));
    const BodyFrames g = forwardKinematics(profile, s);
    EXPECT_EQ(bodyCollides(profile, g, buildParts(profile, g)), collides)
        << "hand " << (g.hand[0] - g.head_centre).norm() << " m from the head centre";
  }
}

TEST(BodyProfile, YamlMergeAndErrors) {
  const std::string path = ::testing::TempDir() + "/body_profile_test.yaml";
  {
    std::ofstream out(path);
    out << "body_profile:\n  upper_arm: 0.31\n  forearm_radius: 0.045\n";
  }
  const BodyProfile p = BodyProfile::fromYamlFile(path);
  EXPECT_DOUBLE_EQ(p.upper_arm, 0.31);
  EXPECT_DOUBLE_EQ(p.forearm_radius, 0.045);
  EXPECT_DOUBLE_EQ(p.forearm, BodyProfile().forearm);  // missing keys keep the default
  {
    std::ofstream out(path);
    out << "body_profile:\n  uper_arm: 0.31\n";
  }
  EXPECT_THROW(BodyProfile::fromYamlFile(path), std::invalid_argument);
  {
    std::ofstream out(path);
    out << "body_profile:\n  upper_arm: -0.3\n";
  }
  EXPECT_THROW(BodyProfile::fromYamlFile(path), std::invalid_argument);
  EXPECT_THROW(BodyProfile::fromYamlFile(path + ".missing"), std::invalid_argument);
}

}  // namespace
}  // namespace body_tracking
