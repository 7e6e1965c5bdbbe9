#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include "tabletop_capture/frame_set_assembler.h"

using namespace tabletop_capture;

namespace {

constexpr double kPeriod = 1.0 / 30.0;
constexpr double kT0 = 1000.0;
double setStamp(int k) { return kT0 + k * kPeriod; }
// Payload encodes (set, camera) so tests can check every frame landed in the right slot.
int tag(int set, int camera) { return set * 100 + camera; }

FrameSetAssemblerConfig makeConfig(int n, double tolerance, double timeout, size_t max_pending) {
  FrameSetAssemblerConfig c;
  c.num_cameras = n;
  c.tolerance = tolerance;
  c.timeout = timeout;
  c.max_pending = max_pending;
  return c;
}

void expectStrictlyIncreasing(const std::vector<FrameSet<int>>& sets) {
  for (size_t i = 1; i < sets.size(); ++i) {
    EXPECT_GT(sets[i].stamp, sets[i - 1].stamp) << "at output " << i;
  }
}

}  // namespace

TEST(FrameSetAssembler, ExactStampsShuffledArrival) {
  FrameSetAssembler<int> a(makeConfig(8, 0.0, 0.5, 8));
  std::mt19937 rng(42);
  std::vector<int> order(8);
  std::iota(order.begin(), order.end(), 0);
  for (int k = 0; k < 20; ++k) {
    std::shuffle(order.begin(), order.end(), rng);
    for (int i = 0; i < 8; ++i) {
      const AddResult r = a.add(order[i], setStamp(k), tag(k, order[i]));
      EXPECT_EQ(r, i == 7 ? AddResult::kCompleted : AddResult::kPending) << k << " " << i;
    }
  }
  const auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 20u);
  for (int k = 0; k < 20; ++k) {
    EXPECT_EQ(out[k].stamp, setStamp(k));
    ASSERT_EQ(out[k].frames.size(), 8u);
    for (int c = 0; c < 8; ++c) {
      EXPECT_EQ(out[k].frames[c], tag(k, c));
      EXPECT_EQ(out[k].stamps[c], setStamp(k));
    }
  }
  const auto& n = a.counters();
  EXPECT_EQ(n.complete, 20u);
  EXPECT_EQ(n.incomplete(), 0u);
  EXPECT_EQ(n.late + n.duplicate + n.bad_camera + n.bad_stamp, 0u);
  EXPECT_EQ(a.pendingCount(), 0u);
  EXPECT_TRUE(a.takeCompleted().empty());  // drained
}

// Per-camera FIFO with a different lag per camera (camera c is c frames behind): several sets
// are pending at once, but each completes in order and none is dropped.
TEST(FrameSetAssembler, ExactStampsInterleavedCameraLag) {
  FrameSetAssembler<int> a(makeConfig(8, 0.0, 1.0, 10));
  for (int t = 0; t < 40; ++t) {
    for (int c = 0; c < 8; ++c) {
      const int k = t - c;
      if (k >= 0 && k < 30) a.add(c, setStamp(k), tag(k, c));
    }
  }
  const auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 30u);
  for (int k = 0; k < 30; ++k) {
    EXPECT_EQ(out[k].stamp, setStamp(k));
    for (int c = 0; c < 8; ++c) EXPECT_EQ(out[k].frames[c], tag(k, c));
  }
  EXPECT_EQ(a.counters().incomplete(), 0u);
  EXPECT_EQ(a.counters().late, 0u);
}

TEST(FrameSetAssembler, ToleranceJitterJoins) {
  const double tol = 0.004;
  FrameSetAssembler<int> a(makeConfig(8, tol, 0.5, 8));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.0015, 0.0015);  // spread < tol
  std::vector<std::vector<double>> sent(10, std::vector<double>(8));
  for (int k = 0; k < 10; ++k) {
    for (int c = 7; c >= 0; --c) {
      sent[k][c] = setStamp(k) + jitter(rng);
      a.add(c, sent[k][c], tag(k, c));
    }
  }
  const auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 10u);
  for (int k = 0; k < 10; ++k) {
    EXPECT_EQ(out[k].stamp, *std::min_element(sent[k].begin(), sent[k].end()));
    for (int c = 0; c < 8; ++c) {
      EXPECT_EQ(out[k].frames[c], tag(k, c));
      EXPECT_EQ(out[k].stamps[c], sent[k][c]);
    }
  }
  EXPECT_EQ(a.counters().incomplete(), 0u);
}

TEST(FrameSetAssembler, ToleranceBoundary) {
  FrameSetAssembler<int> a(makeConfig(2, 0.004, 0.5, 8));
  EXPECT_EQ(a.add(0, 10.0, 1), AddResult::kPending);
  EXPECT_EQ(a.add(1, 10.0041, 2), AddResult::kPending);  // beyond tolerance: opens a new set
  EXPECT_EQ(a.pendingCount(), 2u);
  // Within tolerance of both anchors; 10.0041 is nearer but already has camera 1, so the
  // image joins 10.0 (the nearest set it can complete).
  EXPECT_EQ(a.add(1, 10.0039, 3), AddResult::kCompleted);
  auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].stamp, 10.0);
  EXPECT_EQ(out[0].frames[0], 1);
  EXPECT_EQ(out[0].frames[1], 3);
  EXPECT_EQ(out[0].stamps[1], 10.0039);
  EXPECT_EQ(a.pendingCount(), 1u);  // the 10.0041 set is still waiting for camera 0
  // The only set within tolerance already has camera 1: duplicate, first image kept.
  EXPECT_EQ(a.add(1, 10.0050, 4), AddResult::kDuplicate);
  EXPECT_EQ(a.counters().duplicate, 1u);
  EXPECT_EQ(a.add(0, 10.0060, 5), AddResult::kCompleted);
  out = a.takeCompleted();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].stamp, 10.0041);
  EXPECT_EQ(out[0].frames, (std::vector<int>{5, 2}));
}

TEST(FrameSetAssembler, ToleranceNearestPendingSet) {
  FrameSetAssembler<int> a(makeConfig(2, 0.004, 0.5, 8));
  a.add(0, 10.000, 1);
  a.add(0, 10.006, 2);  // 6 ms > tol: its own set
  // 10.004 is within tolerance of both anchors; the nearest (10.006, 2 ms) wins, which
  // completes it and supersedes the older incomplete 10.000 set.
  EXPECT_EQ(a.add(1, 10.004, 3), AddResult::kCompleted);
  auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].stamp, 10.004);  // earliest member stamp
  EXPECT_EQ(out[0].frames[0], 2);
  EXPECT_EQ(out[0].frames[1], 3);
  EXPECT_EQ(a.counters().incomplete_superseded, 1u);
  EXPECT_EQ(a.counters().missing_per_camera, (std::vector<uint64_t>{0, 1}));
  // A camera-1 image for the dropped 10.000 set is now late (within tolerance of a finished set).
  EXPECT_EQ(a.add(1, 10.001, 4), AddResult::kLate);
  EXPECT_EQ(a.counters().late, 1u);
}

TEST(FrameSetAssembler, OutOfToleranceCameraNeverJoins) {
  FrameSetAssembler<int> a(makeConfig(8, 0.004, 0.5, 8));
  for (int c = 0; c < 8; ++c) a.add(c, c == 3 ? 10.010 : 10.0, c);  // cam3 10 ms off
  EXPECT_EQ(a.counters().complete, 0u);
  EXPECT_EQ(a.pendingCount(), 2u);
  for (int c = 0; c < 8; ++c) a.add(c, 10.0 + kPeriod, 10 + c);
  const auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_DOUBLE_EQ(out[0].stamp, 10.0 + kPeriod);
  const auto& n = a.counters();
  EXPECT_EQ(n.incomplete_superseded, 2u);
  // Set 10.000 lacked camera 3; set 10.010 lacked everything but camera 3.
  EXPECT_EQ(n.missing_per_camera, (std::vector<uint64_t>{1, 1, 1, 1, 1, 1, 1, 1}));
}

TEST(FrameSetAssembler, DroppedCameraTimesOutAndLaterSetsFlow) {
  // Camera 5 sends nothing for sets 10..19. Timeout 0.09 s (< 3 periods): set k is dropped
  // when the first image of set k+3 arrives.
  FrameSetAssembler<int> a(makeConfig(8, 0.0, 0.09, 8));
  for (int k = 0; k < 40; ++k) {
    for (int c = 0; c < 8; ++c) {
      if (c == 5 && k >= 10 && k < 20) continue;
      a.add(c, setStamp(k), tag(k, c));
    }
  }
  const auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 30u);
  expectStrictlyIncreasing(out);
  for (size_t i = 0; i < out.size(); ++i) {
    const int k = i < 10 ? static_cast<int>(i) : static_cast<int>(i) + 10;
    EXPECT_EQ(out[i].stamp, setStamp(k));
    EXPECT_EQ(out[i].frames[5], tag(k, 5));
  }
  const auto& n = a.counters();
  EXPECT_EQ(n.complete, 30u);
  // Sets 10..16 time out while sets 13..19 arrive; the first image of set 20 times out set 17;
  // sets 18 and 19 are superseded when set 20 completes.
  EXPECT_EQ(n.incomplete_timeout, 8u);
  EXPECT_EQ(n.incomplete_superseded, 2u);
  EXPECT_EQ(n.incomplete(), 10u);
  std::vector<uint64_t> missing(8, 0);
  missing[5] = 10;
  EXPECT_EQ(n.missing_per_camera, missing);
  EXPECT_EQ(n.late, 0u);
}

TEST(FrameSetAssembler, DegradedSetsCarryOnWithoutASilentCamera) {
  // As above, with max_missing 1: the sets without camera 5 are emitted partial instead of
  // dropped. Sets 10..12 wait for it (timeout 0.09 s: each leaves when the first image of the
  // set three periods later arrives); then camera 5 has missed absent_after = 3 sets in a row
  // and sets 13..19 no longer wait: each leaves with its last image. Set 20 waits for camera 5
  // again (its image came back) and is complete.
  FrameSetAssemblerConfig cfg = makeConfig(8, 0.0, 0.09, 8);
  cfg.max_missing = 1;
  cfg.absent_after = 3;
  FrameSetAssembler<int> a(cfg);
  std::vector<AddResult> last_add(40);
  for (int k = 0; k < 40; ++k) {
    for (int c = 0; c < 8; ++c) {
      if (c == 5 && k >= 10 && k < 20) continue;
      last_add[k] = a.add(c, setStamp(k), tag(k, c));
    }
    EXPECT_EQ(a.absent(5), k >= 15 && k < 20) << "after set " << k;
  }
  const auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 40u);
  expectStrictlyIncreasing(out);
  for (int k = 0; k < 40; ++k) {
    const bool silent = k >= 10 && k < 20;
    EXPECT_EQ(out[k].stamp, setStamp(k));
    EXPECT_EQ(out[k].complete(), !silent) << "set " << k;
    for (int c = 0; c < 8; ++c) {
      EXPECT_EQ(out[k].present[c], !(silent && c == 5)) << "set " << k << " camera " << c;
      if (out[k].present[c]) EXPECT_EQ(out[k].frames[c], tag(k, c));
    }
    // From set 15 on (camera 5 absent after sets 10..12 left) a set leaves with its last image.
    if (k >= 15) EXPECT_EQ(last_add[k], AddResult::kCompleted) << "set " << k;
  }
  const auto& n = a.counters();
  EXPECT_EQ(n.complete, 30u);
  EXPECT_EQ(n.partial, 10u);
  EXPECT_EQ(n.incomplete(), 0u);
  std::vector<uint64_t> missing(8, 0);
  missing[5] = 10;
  EXPECT_EQ(n.missing_per_camera, missing);
}

TEST(FrameSetAssembler, DegradedSetsStillNeedAllButMaxMissing) {
  // Two of four cameras silent with max_missing 1: nothing may be emitted from two views.
  FrameSetAssemblerConfig cfg = makeConfig(4, 0.0, 0.09, 8);
  cfg.max_missing = 1;
  FrameSetAssembler<int> a(cfg);
  for (int k = 0; k < 20; ++k)
    for (int c = 0; c < 4; ++c)
      if (!(k >= 5 && k < 15 && (c == 1 || c == 2))) a.add(c, setStamp(k), tag(k, c));
  a.expire(setStamp(30));
  const auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 10u);
  for (const auto& set : out) EXPECT_TRUE(set.complete());
  EXPECT_EQ(a.counters().partial, 0u);
  EXPECT_EQ(a.counters().incomplete(), 10u);
  EXPECT_EQ(a.counters().missing_per_camera, (std::vector<uint64_t>{0, 10, 10, 0}));
}

TEST(FrameSetAssembler, ExpireFlushesWhenStreamsStop) {
  FrameSetAssembler<int> a(makeConfig(3, 0.0, 0.2, 8));
  a.add(0, 5.0, 1);
  a.add(2, 5.0, 2);
  EXPECT_EQ(a.expire(5.1), 0u);  // not old enough
  EXPECT_EQ(a.pendingCount(), 1u);
  EXPECT_EQ(a.expire(5.3), 1u);
  EXPECT_EQ(a.pendingCount(), 0u);
  EXPECT_EQ(a.counters().incomplete_timeout, 1u);
  EXPECT_EQ(a.counters().missing_per_camera, (std::vector<uint64_t>{0, 1, 0}));
  EXPECT_EQ(a.add(1, 5.0, 3), AddResult::kLate);  // its set is gone
}

TEST(FrameSetAssembler, LateFramesDroppedAndOutputMonotonic) {
  FrameSetAssembler<int> a(makeConfig(4, 0.0, 0.5, 8));
  // Set 0 lacks camera 2; set 1 completes and supersedes it.
  for (int c : {0, 1, 3}) a.add(c, setStamp(0), tag(0, c));
  for (int c = 0; c < 4; ++c) a.add(c, setStamp(1), tag(1, c));
  EXPECT_EQ(a.add(2, setStamp(0), tag(0, 2)), AddResult::kLate);  // missing frame too late
  // A whole repeated set 1 (e.g. a driver resend) and something far older are late too.
  for (int c = 0; c < 4; ++c) EXPECT_EQ(a.add(c, setStamp(1), tag(1, c)), AddResult::kLate);
  EXPECT_EQ(a.add(0, setStamp(-100), 0), AddResult::kLate);
  for (int c = 0; c < 4; ++c) a.add(c, setStamp(2), tag(2, c));
  const auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].stamp, setStamp(1));
  EXPECT_EQ(out[1].stamp, setStamp(2));
  const auto& n = a.counters();
  EXPECT_EQ(n.late, 6u);
  EXPECT_EQ(n.complete, 2u);
  EXPECT_EQ(n.incomplete_superseded, 1u);
  EXPECT_EQ(n.missing_per_camera, (std::vector<uint64_t>{0, 0, 1, 0}));
}

TEST(FrameSetAssembler, DuplicateKeepsFirst) {
  FrameSetAssembler<int> a(makeConfig(3, 0.0, 0.5, 8));
  EXPECT_EQ(a.add(1, 2.0, 10), AddResult::kPending);
  EXPECT_EQ(a.add(1, 2.0, 11), AddResult::kDuplicate);
  EXPECT_EQ(a.add(0, 2.0, 20), AddResult::kPending);
  EXPECT_EQ(a.add(2, 2.0, 30), AddResult::kCompleted);
  const auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].frames, (std::vector<int>{20, 10, 30}));
  EXPECT_EQ(a.counters().duplicate, 1u);
  EXPECT_EQ(a.counters().complete, 1u);
}

TEST(FrameSetAssembler, MaxPendingBound) {
  FrameSetAssembler<int> a(makeConfig(2, 0.0, 100.0, 3));
  for (int i = 1; i <= 5; ++i) {
    EXPECT_EQ(a.add(0, i, i), AddResult::kPending);
    EXPECT_LE(a.pendingCount(), 3u);
  }
  EXPECT_EQ(a.pendingCount(), 3u);
  EXPECT_EQ(a.counters().incomplete_overflow, 2u);  // sets 1 and 2 dropped
  EXPECT_EQ(a.counters().missing_per_camera, (std::vector<uint64_t>{0, 2}));
  EXPECT_EQ(a.add(1, 2.0, 0), AddResult::kLate);
  EXPECT_EQ(a.add(1, 3.0, 30), AddResult::kCompleted);
  // A new set older than all pending ones while full is dropped at once.
  a.add(0, 6.0, 6);                // pending: 4, 5, 6
  EXPECT_EQ(a.add(0, 3.5, 35), AddResult::kOverflow);
  EXPECT_EQ(a.pendingCount(), 3u);
  EXPECT_EQ(a.counters().incomplete_overflow, 3u);
  const auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].stamp, 3.0);
  EXPECT_EQ(out[0].frames, (std::vector<int>{3, 30}));
}

TEST(FrameSetAssembler, BadCameraAndStamp) {
  FrameSetAssembler<int> a(makeConfig(8, 0.0, 0.5, 8));
  EXPECT_EQ(a.add(-1, 1.0, 0), AddResult::kBadCamera);
  EXPECT_EQ(a.add(8, 1.0, 0), AddResult::kBadCamera);
  EXPECT_EQ(a.add(0, std::numeric_limits<double>::quiet_NaN(), 0), AddResult::kBadStamp);
  EXPECT_EQ(a.add(0, std::numeric_limits<double>::infinity(), 0), AddResult::kBadStamp);
  EXPECT_EQ(a.counters().bad_camera, 2u);
  EXPECT_EQ(a.counters().bad_stamp, 2u);
  EXPECT_EQ(a.pendingCount(), 0u);
  // Rejected input did not move time: a normal set still completes.
  for (int c = 0; c < 8; ++c) a.add(c, 1.0, c);
  EXPECT_EQ(a.counters().complete, 1u);
}

TEST(FrameSetAssembler, InvalidConfigThrows) {
  EXPECT_THROW(FrameSetAssembler<int>(makeConfig(0, 0.0, 0.5, 8)), std::invalid_argument);
  EXPECT_THROW(FrameSetAssembler<int>(makeConfig(2, -0.1, 0.5, 8)), std::invalid_argument);
  EXPECT_THROW(FrameSetAssembler<int>(makeConfig(2, 0.0, -1.0, 8)), std::invalid_argument);
  EXPECT_THROW(FrameSetAssembler<int>(makeConfig(2, 0.0, 0.5, 0)), std::invalid_argument);
  EXPECT_NO_THROW(FrameSetAssembler<int>(
      makeConfig(2, 0.0, std::numeric_limits<double>::infinity(), 1)));
  FrameSetAssemblerConfig c = makeConfig(3, 0.0, 0.5, 8);
  c.max_missing = 3;  // a set needs at least one camera
  EXPECT_THROW(FrameSetAssembler<int>{c}, std::invalid_argument);
  c.max_missing = -1;
  EXPECT_THROW(FrameSetAssembler<int>{c}, std::invalid_argument);
  c.max_missing = 2;
  c.absent_after = 0;
  EXPECT_THROW(FrameSetAssembler<int>{c}, std::invalid_argument);
}

TEST(FrameSetAssembler, ResetAfterBackwardTimeJump) {
  FrameSetAssembler<int> a(makeConfig(2, 0.0, 0.5, 8));
  a.add(0, 50.0, 1);
  a.add(1, 50.0, 2);
  EXPECT_EQ(a.add(0, 1.0, 3), AddResult::kLate);  // bag restarted
  a.reset();
  a.add(0, 1.0, 3);
  EXPECT_EQ(a.add(1, 1.0, 4), AddResult::kCompleted);
  EXPECT_EQ(a.takeCompleted().size(), 1u);  // reset() discarded the 50.0 set not yet taken
  EXPECT_EQ(a.counters().complete, 2u);     // counters survive reset()
}

// Payloads of dropped sets are released, and move-only-friendly shared pointers pass through.
TEST(FrameSetAssembler, PayloadsOfDroppedSetsReleased) {
  FrameSetAssembler<std::shared_ptr<const int>> a(makeConfig(2, 0.0, 0.1, 8));
  auto p = std::make_shared<const int>(7);
  a.add(0, 1.0, p);
  EXPECT_EQ(p.use_count(), 2);
  a.expire(2.0);
  EXPECT_EQ(p.use_count(), 1);
  auto q = std::make_shared<const int>(8);
  a.add(0, 3.0, q);
  a.add(1, 3.0, q);
  auto out = a.takeCompleted();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(*out[0].frames[1], 8);
  EXPECT_EQ(q.use_count(), 3);
}

// Random loss and per-camera delays: whatever happens, output is strictly increasing, every
// emitted frame is the one sent for that set and camera, and every set is accounted for. With
// max_missing 1, a set that lost one image is emitted partial, without exactly that camera.
void randomLossAndDelay(int max_missing) {
  const int n = 8, sets = 500;
  FrameSetAssemblerConfig cfg = makeConfig(n, 0.0, 0.2, 8);
  cfg.max_missing = max_missing;
  FrameSetAssembler<int> a(cfg);
  std::mt19937 rng(123);
  std::bernoulli_distribution lose(0.01);
  std::uniform_int_distribution<int> lag(0, 3);
  // Each camera's stream is FIFO; the interleaving between cameras is random.
  std::vector<std::deque<int>> queues(n);
  std::map<int, std::set<int>> lost;  // set -> cameras lost
  for (int k = 0; k < sets; ++k) {
    for (int c = 0; c < n; ++c) {
      if (lose(rng)) {
        lost[k].insert(c);
      } else {
        queues[c].push_back(k);
      }
    }
  }
  std::vector<FrameSet<int>> out;
  for (int t = 0; t < sets + 10; ++t) {
    for (int c = 0; c < n; ++c) {
      const int until = t - lag(rng);
      while (!queues[c].empty() && queues[c].front() <= until) {
        const int k = queues[c].front();
        queues[c].pop_front();
        const AddResult r = a.add(c, setStamp(k), tag(k, c));
        EXPECT_NE(r, AddResult::kDuplicate);
      }
    }
    for (auto& s : a.takeCompleted()) out.push_back(std::move(s));
  }
  a.expire(setStamp(sets + 100));
  for (auto& s : a.takeCompleted()) out.push_back(std::move(s));
  expectStrictlyIncreasing(out);
  size_t one_lost = 0;
  for (const auto& l : lost) one_lost += l.second.size() == 1;
  for (const auto& s : out) {
    const int k = static_cast<int>(std::lround((s.stamp - kT0) / kPeriod));
    const std::set<int> none;
    const std::set<int>& gone = lost.count(k) ? lost.at(k) : none;
    EXPECT_LE(gone.size(), static_cast<size_t>(max_missing)) << k;
    for (int c = 0; c < n; ++c) {
      EXPECT_EQ(s.present[c], gone.count(c) == 0) << k << " " << c;
      if (s.present[c]) EXPECT_EQ(s.frames[c], tag(k, c));
    }
  }
  const auto& cnt = a.counters();
  EXPECT_EQ(cnt.complete + cnt.partial, out.size());
  EXPECT_EQ(cnt.partial, max_missing > 0 ? one_lost : 0u);
  EXPECT_GE(cnt.complete, static_cast<size_t>(sets * 0.85));
  // Every set was either emitted or dropped (no set is left pending after expire()).
  EXPECT_EQ(a.pendingCount(), 0u);
  EXPECT_EQ(cnt.complete + cnt.partial + cnt.incomplete(), static_cast<uint64_t>(sets));
  EXPECT_EQ(cnt.incomplete(), lost.size() - cnt.partial);
}

TEST(FrameSetAssembler, RandomLossAndDelayInvariants) { randomLossAndDelay(0); }
TEST(FrameSetAssembler, RandomLossAndDelayInvariantsDegraded) { randomLossAndDelay(1); }
