// PipelineGate: the single drop point (oldest pending set out, learning sets kept) and the
// closed-loop lockstep (hold the next set until the tracker's ack or a timeout).
#include <gtest/gtest.h>

#include "tabletop_common/pipeline_gate.h"

using tabletop_common::PipelineGate;
using tabletop_common::PipelineGateConfig;

namespace {
PipelineGateConfig config(size_t capacity, double timeout = 1.0) {
  PipelineGateConfig c;
  c.capacity = capacity;
  c.ack_timeout = timeout;
  return c;
}
}  // namespace

TEST(PipelineGate, LiveCapacityDropsTheOldestAndCountsIt) {
  PipelineGate<int> g(config(1));
  EXPECT_TRUE(g.push(1).empty());
  const auto out = g.push(2);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out.front(), 1);
  EXPECT_EQ(g.counters().dropped, 1u);
  EXPECT_EQ(g.pop(0.0).value(), 2);
  EXPECT_FALSE(g.pop(0.0).has_value());
}

TEST(PipelineGate, OfflineCapacityKeepsEverySetInOrder) {
  PipelineGate<int> g(config(1000));
  for (int i = 0; i < 300; ++i) EXPECT_TRUE(g.push(i).empty());
  for (int i = 0; i < 300; ++i) EXPECT_EQ(g.pop(0.0).value(), i);
  EXPECT_EQ(g.counters().dropped, 0u);
  EXPECT_EQ(g.counters().popped, 300u);
}

TEST(PipelineGate, LearningSetsAreNeverDropped) {
  PipelineGate<int> g(config(1));
  for (int i = 0; i < 25; ++i) EXPECT_TRUE(g.push(i, /*keep=*/true).empty());
  // A live set after them: the queue exceeds the capacity, but nothing kept goes.
  EXPECT_TRUE(g.push(100).empty());
  const auto out = g.push(101);  // the live set 100 goes, the learning sets stay
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out.front(), 100);
  for (int i = 0; i < 25; ++i) EXPECT_EQ(g.pop(0.0).value(), i);
  EXPECT_EQ(g.pop(0.0).value(), 101);
}

TEST(PipelineGate, HoldsTheNextSetUntilTheAck) {
  PipelineGate<int> g(config(10, 2.0));
  g.push(1);
  g.push(2);
  EXPECT_EQ(g.pop(0.0).value(), 1);
  g.expectAck(1000, 0.0);
  EXPECT_FALSE(g.pop(0.5).has_value());
  EXPECT_NEAR(g.secondsUntilTimeout(0.5), 1.5, 1e-12);
  g.ack(999);  // an older set's ack does not release it
  EXPECT_FALSE(g.pop(0.6).has_value());
  g.ack(1000);
  EXPECT_EQ(g.pop(0.7).value(), 2);
  EXPECT_EQ(g.counters().acks, 1u);
  EXPECT_EQ(g.counters().ack_timeouts, 0u);
}

TEST(PipelineGate, AnAckThatCameFirstIsNotWaitedFor) {
  PipelineGate<int> g(config(10));
  g.push(1);
  g.ack(2000);  // the tracker answered before the stage noted what it expects
  g.expectAck(2000, 0.0);
  EXPECT_EQ(g.pop(0.0).value(), 1);
}

TEST(PipelineGate, ADeadTrackerCostsOneTimeoutPerSetNotAStall) {
  PipelineGate<int> g(config(10, 1.0));
  g.push(1);
  g.push(2);
  ASSERT_TRUE(g.pop(0.0).has_value());
  g.expectAck(1, 0.0);
  EXPECT_FALSE(g.pop(0.99).has_value());
  EXPECT_EQ(g.pop(1.0).value(), 2);
  EXPECT_EQ(g.counters().ack_timeouts, 1u);
  EXPECT_EQ(g.secondsUntilTimeout(1.0), -1.0);
}

TEST(PipelineGate, ClearForgetsPendingSetsAndTheOutstandingAck) {
  PipelineGate<int> g(config(10));
  g.push(1);
  g.push(2);
  ASSERT_TRUE(g.pop(0.0).has_value());
  g.expectAck(5, 0.0);
  EXPECT_EQ(g.clear().size(), 1u);
  g.push(3);
  EXPECT_EQ(g.pop(0.0).value(), 3);
}

TEST(PipelineGate, RejectsAZeroCapacity) {
  EXPECT_THROW(PipelineGate<int>(config(0)), std::invalid_argument);
}
