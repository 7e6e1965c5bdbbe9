// The arms' length refinement (arm_length.h) on volumes drawn from the body model with arms
// longer or shorter than the profile's. The tracked pose is the drawn one's angles, so the
// profile's arm puts its hand short of (or beyond) the drawn hand, as a tracker fitted with the
// profile's lengths would; the found hand is the drawn hand's centre. The factor it settles on
// is the drawn one within 0.06: one working voxel (the observation's 32 mm) over the 0.6 m from
// shoulder to hand, what the volume resolves. Also: arms without a found hand do not vote, the
// PAPF tracks with the refined arms and forgets them on reset, it is on by default, and bad
// ladder parameters (this refinement's and the trunk girth's) throw naming their key.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <string>
#include <utility>

#include "body_tracking/arm_length.h"
#include "body_tracking/body_parts.h"
#include "body_tracking/papf.h"
#include "body_tracking/trunk_girth.h"
#include "drawn_body.h"

namespace body_tracking {
namespace {

constexpr double kTolerance = 0.06;  // 32 mm / (upper arm + forearm + wrist to hand) ~ 0.053

// Seated in the middle of the grid; the arms reach forward over the desk, the left one nearly
// straight (where length shows most) and the right one bent.
BodyState reaching() {
  BodyState s{};
  s[dof::TORSO_Y] = -0.30;
  s[dof::TORSO_Z] = 0.0;
  s[dof::SPINE_BEND] = 0.1;
  s[armDof(Side::LEFT, 0)] = -0.45;
  s[armDof(Side::LEFT, 1)] = -0.2;
  s[armDof(Side::LEFT, 3)] = 0.35;
  s[armDof(Side::RIGHT, 0)] = -0.9;
  s[armDof(Side::RIGHT, 1)] = -0.15;
  s[armDof(Side::RIGHT, 3)] = 1.2;
  return s;
}

struct Drawn {
  psfs::ProbabilityVolume body, skin;
  RefinedHands hands;
};

Drawn drawn(const BodyProfile& profile, const BodyState& s, double arms) {
  const BodyProfile p = ArmLength::scaled(profile, arms);
  const BodyFrames f = forwardKinematics(p, s);
  const BodyParts parts = buildParts(p, f);
  Drawn d;
  d.body = test::drawnVolume(parts);
  d.skin = test::drawnVolume(parts, {Part::HEAD, Part::LEFT_HAND, Part::RIGHT_HAND});
  for (int i = 0; i < 2; ++i) {
    d.hands.position[i] = f.hand[i];
    d.hands.from_skin[i] = true;
  }
  return d;
}

TEST(ArmLength, SettlesOnTheDrawnLengthWithinAWorkingVoxel) {
  const BodyProfile profile;
  const BodyState s = reaching();
  ArmLengthParams p;
  p.frames = 3;
  for (double truth : {0.88, 0.92, 1.0, 1.08, 1.12}) {  // 0.92 / 1.08: the ladder's ends fail
    const Drawn d = drawn(profile, s, truth);
    Eigen::Vector3i v;
    for (int i = 0; i < 2; ++i)  // the test means nothing if a hand is off the grid
      ASSERT_TRUE(d.body.grid.voxelOf(d.hands.position[i], &v)) << "hand " << i << " outside the grid";
    VolumeObservation obs;
    obs.setVolumes(d.body, &d.skin);
    ArmLength a(p);
    EXPECT_EQ(a.factor(), 1.0);
    for (int k = 0; k < 3; ++k) {
      EXPECT_TRUE(a.refining());
      a.add(obs, profile, s, d.hands);
    }
    EXPECT_FALSE(a.refining());
    std::printf("[ arms     ] drawn %.3f -> %.3f\n", truth, a.factor());
    EXPECT_NEAR(a.factor(), truth, kTolerance) << "drawn arm length " << truth;
    const double settled = a.factor();
    a.add(obs, profile, s, d.hands);  // done: more frames change nothing
    EXPECT_EQ(a.factor(), settled);
    a.reset();
    EXPECT_EQ(a.factor(), 1.0);
    EXPECT_EQ(a.frames(), 0);
  }
}

// The same with a one-voxel halo of p = 0.59 around the body, as the pSfS hull has: it must not
// move the factor. (A halo this even does not tell the weightings apart: p itself passes too. On
// generated people's volumes p read the arms 0.06-0.11 long, docs/benchmarks.md.)
TEST(ArmLength, SettlesOnTheDrawnLengthThroughAHalo) {
  const BodyProfile profile;
  const BodyState s = reaching();
  ArmLengthParams p;
  p.frames = 3;
  for (double truth : {0.88, 1.0, 1.12}) {
    Drawn d = drawn(profile, s, truth);
    test::addHalo(&d.body, 150);
    VolumeObservation obs;
    obs.setVolumes(d.body, &d.skin);
    ArmLength a(p);
    for (int k = 0; k < 3; ++k) a.add(obs, profile, s, d.hands);
    std::printf("[ arms     ] drawn %.3f with a halo -> %.3f\n", truth, a.factor());
    EXPECT_NEAR(a.factor(), truth, kTolerance) << "drawn arm length " << truth;
  }
}

TEST(ArmLength, OnlyArmsWithAFoundHandVote) {
  const BodyProfile profile;
  const BodyState s = reaching();
  Drawn d = drawn(profile, s, 1.12);
  VolumeObservation obs;
  obs.setVolumes(d.body, &d.skin);
  ArmLengthParams p;
  p.frames = 2;
  ArmLength a(p);
  d.hands.from_skin = {{false, false}};
  a.add(obs, profile, s, d.hands);
  EXPECT_EQ(a.frames(), 0);
  EXPECT_EQ(a.factor(), 1.0);
  d.hands.from_skin[static_cast<int>(Side::LEFT)] = true;  // the straight arm alone settles it
  a.add(obs, profile, s, d.hands);
  a.add(obs, profile, s, d.hands);
  EXPECT_FALSE(a.refining());
  EXPECT_NEAR(a.factor(), 1.12, kTolerance);
}

TEST(ArmLength, ThePapfTracksWithTheRefinedArmsAndForgetsThemOnReset) {
  const BodyProfile profile;
  const BodyState s = reaching();
  const Drawn d = drawn(profile, s, 1.12);
  PapfParams p;
  p.arm_length.frames = 4;
  p.threads = 1;
  Papf papf(profile, p);
  papf.startAt(s);
  for (int k = 0; k < 6; ++k) papf.update(d.body, &d.skin);
  const BodyEstimate& e = papf.estimate();
  std::printf("[ arms     ] papf: factor %.3f, left hand %.1f mm from the drawn one\n", e.arm_length,
              1e3 * (e.hands.position[0] - d.hands.position[0]).norm());
  EXPECT_NEAR(e.arm_length, 1.12, kTolerance);
  // The reported joints are those of the profile in use.
  const BodyFrames now = forwardKinematics(papf.profile(), e.state);
  for (int i = 0; i < 2; ++i) EXPECT_LT((e.frames.elbow[i] - now.elbow[i]).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(papf.profile().upper_arm, e.arm_length * profile.upper_arm);
  EXPECT_DOUBLE_EQ(papf.profile().forearm, e.arm_length * profile.forearm);
  EXPECT_EQ(papf.profile().chest_half_width, profile.chest_half_width);
  EXPECT_EQ(papf.profile().wrist_to_hand, profile.wrist_to_hand);
  papf.reset();
  EXPECT_EQ(papf.profile().upper_arm, profile.upper_arm);
  papf.startAt(s);  // a new track reads the length again
  for (int k = 0; k < 6; ++k) papf.update(d.body, &d.skin);
  EXPECT_NEAR(papf.estimate().arm_length, 1.12, kTolerance);
  // Off: the profile stays as given.
  PapfParams off;
  off.arm_length.frames = 0;
  Papf plain(profile, off);
  plain.startAt(s);
  for (int k = 0; k < 3; ++k) plain.update(d.body, &d.skin);
  EXPECT_EQ(plain.estimate().arm_length, 1.0);
  EXPECT_EQ(plain.profile().upper_arm, profile.upper_arm);
}

TEST(ArmLength, ScalesOnlyTheArmBonesAndOnByDefault) {
  const BodyProfile base;
  const BodyProfile longer = ArmLength::scaled(base, 1.1);
  EXPECT_DOUBLE_EQ(longer.upper_arm, 1.1 * base.upper_arm);
  EXPECT_DOUBLE_EQ(longer.forearm, 1.1 * base.forearm);
  EXPECT_EQ(longer.wrist_to_hand, base.wrist_to_hand);
  EXPECT_EQ(longer.upper_arm_radius, base.upper_arm_radius);
  EXPECT_EQ(longer.chest_half_width, base.chest_half_width);
  ArmLength on;  // the default: 50 voting frames (papf.yaml shape/arm_frames)
  EXPECT_TRUE(on.refining());
  EXPECT_EQ(on.params().frames, 50);
}

// Both refinements' ladders (shape_ladder.h) reject bad parameters, naming papf.yaml's key.
template <class Refinement, class Params>
void expectRejected(Params bad, const std::string& key) {
  try {
    Refinement{bad};
    ADD_FAILURE() << key << " accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("shape/" + key), std::string::npos) << e.what();
  }
}

template <class Refinement, class Params>
void expectLadderChecks(const std::string& prefix, const std::string& frames_key) {
  const std::pair<std::string, std::function<void(Params*)>> bad[] = {
      {prefix + "_min", [](Params* p) { p->min = 1.2; }},
      {prefix + "_max", [](Params* p) { p->max = 0.9; }},
      {prefix + "_step", [](Params* p) { p->step = 0.0; }},
      {frames_key, [](Params* p) { p->frames = -1; }}};
  for (const auto& b : bad) {
    Params p;
    b.second(&p);
    expectRejected<Refinement>(p, b.first);
  }
}

TEST(ShapeLadder, BadParametersThrowNamingTheirKey) {
  expectLadderChecks<ArmLength, ArmLengthParams>("arm", "arm_frames");
  expectLadderChecks<TrunkGirth, TrunkGirthParams>("girth", "frames");
}

}  // namespace
}  // namespace body_tracking
