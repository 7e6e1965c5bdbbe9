// The trunk's girth refinement (trunk_girth.h) on volumes drawn from the body model with a trunk
// wider or narrower than the profile's: scored at the true pose, the factor it settles on is the
// drawn one within one ladder step (the shell, 3 cm, is about one working voxel of 31 mm, so a
// step of 5 % of a 15 cm half width, 7.5 mm, is below what one voxel resolves; one step is the
// physics' tolerance). Also: the ladder holds 1 exactly, refining stops after `frames` frames,
// reset() returns to the profile (bad parameters: test_arm_length).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "body_tracking/body_parts.h"
#include "body_tracking/papf.h"
#include "body_tracking/trunk_girth.h"
#include "drawn_body.h"

namespace body_tracking {
namespace {

// A person at `state` with the trunk of `profile` scaled by `girth` (drawn_body.h); the trunk
// stands wholly inside the grid.
psfs::ProbabilityVolume drawn(const BodyProfile& profile, const BodyState& state, double girth) {
  return test::drawnVolume(buildParts(TrunkGirth::scaled(profile, girth), state));
}

BodyState seatedInsideTheGrid() {
  BodyState s{};
  s[dof::TORSO_Y] = -0.25;  // trunk, arms and head inside the grid, shell included
  s[dof::TORSO_Z] = 0.05;
  s[dof::SPINE_BEND] = 0.1;
  for (Side side : {Side::LEFT, Side::RIGHT}) {
    s[armDof(side, 0)] = -1.2;
    s[armDof(side, 1)] = side == Side::LEFT ? 0.3 : -0.3;
    s[armDof(side, 3)] = 1.3;
  }
  return s;
}

TEST(TrunkGirth, SettlesOnTheDrawnGirthWithinOneStep) {
  const BodyProfile profile;
  const BodyState s = seatedInsideTheGrid();
  TrunkGirthParams p;
  p.frames = 3;
  for (double truth : {0.85, 1.0, 1.2, 1.3}) {
    const psfs::ProbabilityVolume body = drawn(profile, s, truth);
    VolumeObservation obs;
    obs.setVolumes(body, nullptr);
    TrunkGirth g(p);
    EXPECT_EQ(g.factor(), 1.0);
    for (int k = 0; k < 3; ++k) {
      EXPECT_TRUE(g.refining());
      g.add(obs, profile, s);
    }
    EXPECT_FALSE(g.refining());
    std::printf("[ girth    ] drawn %.2f -> %.2f\n", truth, g.factor());
    EXPECT_NEAR(g.factor(), truth, p.step + 1e-9) << "drawn girth " << truth;
    // Done: more frames change nothing; a reset starts again from the profile.
    const double settled = g.factor();
    g.add(obs, profile, s);
    EXPECT_EQ(g.factor(), settled);
    g.reset();
    EXPECT_EQ(g.factor(), 1.0);
    EXPECT_EQ(g.frames(), 0);
  }
}

TEST(TrunkGirth, ThePapfTracksWithTheRefinedTrunkAndForgetsItOnReset) {
  const BodyProfile profile;
  const BodyState s = seatedInsideTheGrid();
  const psfs::ProbabilityVolume body = drawn(profile, s, 1.2);
  PapfParams p;
  p.shape.frames = 4;
  p.threads = 1;
  Papf papf(profile, p);
  papf.startAt(s);
  for (int k = 0; k < 6; ++k) papf.update(body, nullptr);
  EXPECT_GE(papf.estimate().trunk_girth, 1.1);
  EXPECT_DOUBLE_EQ(papf.profile().chest_half_width, papf.estimate().trunk_girth * profile.chest_half_width);
  EXPECT_EQ(papf.profile().upper_arm, profile.upper_arm);
  papf.reset();
  EXPECT_EQ(papf.profile().chest_half_width, profile.chest_half_width);
  // Off (the default): the profile stays as given.
  Papf plain(profile, PapfParams());
  plain.startAt(s);
  for (int k = 0; k < 3; ++k) plain.update(body, nullptr);
  EXPECT_EQ(plain.estimate().trunk_girth, 1.0);
  EXPECT_EQ(plain.profile().chest_half_width, profile.chest_half_width);
}

TEST(TrunkGirth, ScalesOnlyTheTrunkAndOffByDefault) {
  const BodyProfile base;
  const BodyProfile wide = TrunkGirth::scaled(base, 1.2);
  EXPECT_DOUBLE_EQ(wide.chest_half_width, 1.2 * base.chest_half_width);
  EXPECT_DOUBLE_EQ(wide.abdomen_half_depth, 1.2 * base.abdomen_half_depth);
  EXPECT_EQ(wide.upper_arm, base.upper_arm);
  EXPECT_EQ(wide.head_half_width, base.head_half_width);
  EXPECT_EQ(wide.shoulder_half_width, base.shoulder_half_width);
  TrunkGirth off;
  EXPECT_FALSE(off.refining());
  // Bad parameters: test_arm_length's ladder test checks both refinements' keys.
}

}  // namespace
}  // namespace body_tracking
