// CaptureStats on synthetic stamp sequences: exact 25 fps, known jitter, gaps, the window,
// restarts and stamps that do not increase.
#include <gtest/gtest.h>

#include <cmath>

#include "tabletop_capture/capture_stats.h"

using namespace tabletop_capture;

TEST(CaptureStats, SteadyRateHasNoJitterAndNoDrops) {
  CaptureStats s(25.0, 50);
  for (int i = 0; i < 100; ++i) s.add(1000.0 + 0.04 * i);
  EXPECT_NEAR(s.rate(), 25.0, 1e-6);
  EXPECT_NEAR(s.jitterMs(), 0.0, 1e-6);
  EXPECT_EQ(s.droppedTotal(), 0u);
  EXPECT_EQ(s.intervals(), 50u);
  EXPECT_EQ(s.frames(), 100u);
}

// Intervals alternate 35 ms and 45 ms: mean 40 ms (25 Hz), sample std dev of 50 values
// +-5 ms = 5 * sqrt(50 / 49).
TEST(CaptureStats, AlternatingIntervalsGiveKnownJitter) {
  CaptureStats s(25.0, 50);
  double t = 0;
  s.add(t);
  for (int i = 0; i < 50; ++i) s.add(t += (i % 2 ? 0.045 : 0.035));
  EXPECT_NEAR(s.rate(), 25.0, 1e-6);
  EXPECT_NEAR(s.jitterMs(), 5.0 * std::sqrt(50.0 / 49.0), 1e-6);
  EXPECT_EQ(s.droppedTotal(), 0u);  // 45 ms < 1.5 periods
}

// Gaps: 60 ms (exactly 1.5 periods) is not a drop, 61 ms is one, 120 ms is two, 200 ms four.
TEST(CaptureStats, GapsCountTheFramesMissed) {
  EXPECT_EQ(CaptureStats::missedIn(0.060, 0.04), 0u);
  EXPECT_EQ(CaptureStats::missedIn(0.061, 0.04), 1u);
  EXPECT_EQ(CaptureStats::missedIn(0.080, 0.04), 1u);
  EXPECT_EQ(CaptureStats::missedIn(0.120, 0.04), 2u);
  EXPECT_EQ(CaptureStats::missedIn(0.200, 0.04), 4u);
  CaptureStats s(25.0, 10);
  const double stamps[] = {0.0, 0.04, 0.08, 0.20, 0.24, 0.28, 0.48};
  for (double t : stamps) s.add(t);
  EXPECT_EQ(s.droppedTotal(), 2u + 4u);
  EXPECT_EQ(s.droppedInWindow(), 6u);
  // The drops leave the window after 10 more steady intervals; the total keeps them.
  for (int i = 1; i <= 10; ++i) s.add(0.48 + 0.04 * i);
  EXPECT_EQ(s.droppedInWindow(), 0u);
  EXPECT_EQ(s.droppedTotal(), 6u);
  EXPECT_NEAR(s.rate(), 25.0, 1e-6);
}

// After restart() (device re-opened) the outage is neither an interval nor a drop.
TEST(CaptureStats, RestartForgetsTheGap) {
  CaptureStats s(25.0, 50);
  for (int i = 0; i < 5; ++i) s.add(0.04 * i);
  s.restart();
  for (int i = 0; i < 5; ++i) s.add(10.0 + 0.04 * i);
  EXPECT_EQ(s.droppedTotal(), 0u);
  EXPECT_EQ(s.intervals(), 8u);
  EXPECT_NEAR(s.rate(), 25.0, 1e-6);
}

TEST(CaptureStats, NonIncreasingStampsAreCountedNotMeasured) {
  CaptureStats s(25.0, 50);
  s.add(1.0);
  s.add(1.04);
  s.add(1.04);
  s.add(1.00);
  s.add(1.08);
  EXPECT_EQ(s.nonIncreasing(), 2u);
  EXPECT_EQ(s.intervals(), 2u);
  EXPECT_NEAR(s.rate(), 25.0, 1e-6);
  EXPECT_EQ(s.frames(), 5u);
}

TEST(CaptureStats, EmptyAndBadArguments) {
  CaptureStats s(25.0);
  EXPECT_EQ(s.rate(), 0.0);
  EXPECT_EQ(s.jitterMs(), 0.0);
  EXPECT_THROW(CaptureStats(0.0), std::invalid_argument);
  EXPECT_THROW(CaptureStats(25.0, 0), std::invalid_argument);
}
