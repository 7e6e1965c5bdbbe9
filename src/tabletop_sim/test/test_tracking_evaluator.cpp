// The tracking evaluator counts what the tracker tests and the demo report: errors, losses and
// how fast they are reported, re-acquisitions and identity switches, on scripted tracks.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <limits>

#include "tabletop_sim/tracking_evaluator.h"

using tabletop_sim::TrackedPoint;
using tabletop_sim::TrackingEvaluator;
using tabletop_sim::TruthPoints;

namespace {

constexpr double kDt = 0.04;

TruthPoints truthAt(double t, bool left_visible = true) {
  TruthPoints p;
  p.position[0] = Eigen::Vector3d(-0.2 + 0.05 * t, 0.1, 0.2);
  p.position[1] = Eigen::Vector3d(0.2, 0.1, 0.2);
  p.position[2] = Eigen::Vector3d(0.0, 0.4, 0.6);
  p.visible = {left_visible, true, true};
  return p;
}

TrackedPoint track(uint32_t id, bool hand, const Eigen::Vector3d& p, bool active = true) {
  TrackedPoint t;
  t.id = id;
  t.hand = hand;
  t.position = p;
  t.active = active;
  return t;
}

// Frames 10-29 of the fold tests: the hands clasped, the left one 2 cm beside the right.
bool clasped(int i) { return i >= 10 && i < 30; }
TruthPoints foldTruth(int i) {
  TruthPoints tr = truthAt(0.0);
  if (clasped(i)) tr.position[0] = tr.position[1] + Eigen::Vector3d(-0.02, 0.0, 0.0);
  return tr;
}

}  // namespace

TEST(TrackingEvaluator, ConstantOffsetIsTheError) {
  TrackingEvaluator ev;
  const Eigen::Vector3d off(0.003, 0.004, 0.0);  // 5 mm
  for (int i = 0; i < 50; ++i) {
    const TruthPoints tr = truthAt(i * kDt);
    ev.add(i * kDt, {track(7, true, tr.position[0] + off), track(8, true, tr.position[1] - off),
                     track(9, false, tr.position[2])},
           tr);
  }
  EXPECT_NEAR(ev.report(0).error_mm.mean(), 5.0, 1e-9);
  EXPECT_NEAR(ev.report(1).error_mm.max(), 5.0, 1e-9);
  EXPECT_NEAR(ev.report(2).error_mm.mean(), 0.0, 1e-9);
  for (int t = 0; t < 3; ++t) {
    EXPECT_EQ(ev.report(t).tracked_frames, 50);
    EXPECT_EQ(ev.report(t).losses, 0);
    EXPECT_EQ(ev.report(t).identity_switches, 0);
    EXPECT_EQ(ev.report(t).acquisitions, 1);
  }
  EXPECT_EQ(ev.falseTargetFrames(), 0);
  std::printf("%s", ev.summary().c_str());
}

TEST(TrackingEvaluator, SwappedHandTracksCountOneSwitchEach) {
  TrackingEvaluator ev;
  for (int i = 0; i < 40; ++i) {
    const TruthPoints tr = truthAt(i * kDt);
    const bool swapped = i >= 20;  // track ids trade places half way
    ev.add(i * kDt, {track(swapped ? 2 : 1, true, tr.position[0]),
                     track(swapped ? 1 : 2, true, tr.position[1]), track(3, false, tr.position[2])},
           tr);
  }
  EXPECT_EQ(ev.report(0).identity_switches, 1);
  EXPECT_EQ(ev.report(1).identity_switches, 1);
  EXPECT_EQ(ev.report(2).identity_switches, 0);
}

TEST(TrackingEvaluator, LeavingAndReenteringTimesLossAndReacquisition) {
  TrackingEvaluator ev;
  // The left hand is out of the workspace from frame 20 to 39; the tracker drops its track 5
  // frames (0.2 s) after it leaves and picks it up again 3 frames (0.12 s) after it returns,
  // under a new id.
  for (int i = 0; i < 60; ++i) {
    const bool visible = i < 20 || i >= 40;
    const TruthPoints tr = truthAt(i * kDt, visible);
    std::vector<TrackedPoint> tracks = {track(2, true, tr.position[1]), track(3, false, tr.position[2])};
    if (i < 25) tracks.push_back(track(1, true, tr.position[0]));
    if (i >= 43) tracks.push_back(track(4, true, tr.position[0]));
    ev.add(i * kDt, tracks, tr);
  }
  const auto& r = ev.report(0);
  EXPECT_EQ(r.losses, 0);  // the truth was out of view when the track ended: not a loss
  EXPECT_EQ(r.acquisitions, 2);
  ASSERT_EQ(r.loss_report_delay_s.count(), 1u);
  EXPECT_NEAR(r.loss_report_delay_s.mean(), 5 * kDt, 1e-9);
  EXPECT_NEAR(r.acquisition_delay_s.max(), 3 * kDt, 1e-9);
  EXPECT_EQ(r.identity_switches, 0);
  EXPECT_EQ(r.tracked_frames, 20 + 17);
  EXPECT_EQ(ev.falseTargetFrames(), 5);  // track 1 while its hand was gone
}

TEST(TrackingEvaluator, FoldedHandsMergeAndSplitWithoutLossOrSwitch) {
  TrackingEvaluator ev;
  // Frames 10-29 the hands are clasped 2 cm apart and the tracker reports one target (the right
  // hand's id 2); from frame 30 they are apart again and the left hand gets its id 1 back.
  for (int i = 0; i < 50; ++i) {
    const TruthPoints tr = foldTruth(i);
    std::vector<TrackedPoint> tracks = {track(2, true, tr.position[1]),
                                        track(3, false, tr.position[2])};
    if (!clasped(i)) tracks.push_back(track(1, true, tr.position[0]));
    ev.add(i * kDt, tracks, tr);
  }
  const auto& left = ev.report(0);
  EXPECT_EQ(left.losses, 0);
  EXPECT_EQ(left.identity_switches, 0);
  EXPECT_EQ(left.merges, 1);
  EXPECT_EQ(left.splits_recovered, 1);
  EXPECT_EQ(left.tracked_frames, 50);  // the shared target counts for the clasped hand
  EXPECT_EQ(ev.report(1).identity_switches, 0);
  EXPECT_EQ(ev.report(1).merges, 0);
}

TEST(TrackingEvaluator, ASplitUnderANewIdIsASwitch) {
  TrackingEvaluator ev;
  for (int i = 0; i < 50; ++i) {
    const TruthPoints tr = foldTruth(i);
    std::vector<TrackedPoint> tracks = {track(2, true, tr.position[1]),
                                        track(3, false, tr.position[2])};
    if (i < 10) tracks.push_back(track(1, true, tr.position[0]));
    if (i >= 30) tracks.push_back(track(7, true, tr.position[0]));  // not the left hand's id
    ev.add(i * kDt, tracks, tr);
  }
  EXPECT_EQ(ev.report(0).merges, 1);
  EXPECT_EQ(ev.report(0).splits_recovered, 0);
  EXPECT_EQ(ev.report(0).identity_switches, 1);
}

TEST(TrackingEvaluator, TrackDyingInViewIsALoss) {
  TrackingEvaluator ev;
  for (int i = 0; i < 30; ++i) {
    const TruthPoints tr = truthAt(i * kDt);
    std::vector<TrackedPoint> tracks = {track(2, true, tr.position[1]), track(3, false, tr.position[2])};
    if (i < 10 || i >= 15) tracks.push_back(track(i < 10 ? 1 : 5, true, tr.position[0]));
    ev.add(i * kDt, tracks, tr);
  }
  EXPECT_EQ(ev.report(0).losses, 1);
  EXPECT_EQ(ev.report(0).acquisitions, 2);
  EXPECT_NEAR(ev.report(0).acquisition_delay_s.max(), 5 * kDt, 1e-9);
}

TEST(TrackingEvaluator, WritesAPlot) {
  TrackingEvaluator ev;
  for (int i = 0; i < 30; ++i) {
    const TruthPoints tr = truthAt(i * kDt);
    ev.add(i * kDt, {track(1, true, tr.position[0] + Eigen::Vector3d(0.001 * i, 0, 0))}, tr);
  }
  const std::string path = "/tmp/tracking_evaluator_test_" + std::to_string(::getpid()) + ".png";
  EXPECT_TRUE(ev.writePlot(path));
  std::remove(path.c_str());
}

// Where the truth gives an axis (the hands: wrist -> hand), the error is split into a signed
// part along it and a distance across it; without one nothing is reported.
TEST(TrackingEvaluator, TheErrorSplitsAlongTheHandsAxis) {
  TrackingEvaluator ev;
  const Eigen::Vector3d along(0.0, 0.012, 0.0), across(0.003, 0.0, 0.004);  // +12 mm, 5 mm
  for (int i = 0; i < 20; ++i) {
    TruthPoints tr = truthAt(i * kDt);
    tr.axis[0] = Eigen::Vector3d(0.0, 2.0, 0.0);   // any length: only the direction counts
    tr.axis[1] = Eigen::Vector3d(0.0, -1.0, 0.0);  // the right hand points the other way
    ev.add(i * kDt, {track(7, true, tr.position[0] + along + across),
                     track(8, true, tr.position[1] + along), track(9, false, tr.position[2] + along)},
           tr);
  }
  EXPECT_NEAR(ev.report(0).along_mm.mean(), 12.0, 1e-9);
  EXPECT_NEAR(ev.report(0).across_mm.mean(), 5.0, 1e-9);
  EXPECT_NEAR(ev.report(0).error_mm.mean(), 13.0, 1e-9);
  EXPECT_NEAR(ev.report(1).along_mm.mean(), -12.0, 1e-9);
  EXPECT_NEAR(ev.report(1).across_mm.mean(), 0.0, 1e-9);
  EXPECT_EQ(ev.report(2).along_mm.count(), 0u);  // the head has no axis
  const std::string s = ev.summary();
  EXPECT_NE(s.find("along the hand +12.0 mm (+: towards the fingers), across 5.0"), std::string::npos) << s;
  EXPECT_NE(s.find("along the hand -12.0 mm"), std::string::npos) << s;
}

// The hands' axes from the wrists: unit vectors towards the hands; none without a finite wrist.
TEST(TrackingEvaluator, HandAxesPointFromTheWristsToTheHands) {
  TruthPoints tr = truthAt(0.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  tabletop_sim::setHandAxes({tr.position[0] - Eigen::Vector3d(0.0, 0.08, 0.0), Eigen::Vector3d(nan, 0.0, 0.0)},
                            &tr);
  EXPECT_NEAR((tr.axis[0] - Eigen::Vector3d(0.0, 1.0, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(tr.axis[1], Eigen::Vector3d::Zero());
  EXPECT_EQ(tr.axis[2], Eigen::Vector3d::Zero());
}
