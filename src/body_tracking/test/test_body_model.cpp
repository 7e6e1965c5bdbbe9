// The quadric body model: forward kinematics against the simulated rig's (the same state must
// mean the same pose), the joint rotations' conversions, swing-twist limits on random
// quaternions, the truncated quadrics' inside tests and weights against sampled points, and the
// YAML body profile.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

#include "body_tracking/body_parts.h"
#include "body_tracking/kinematics.h"
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
