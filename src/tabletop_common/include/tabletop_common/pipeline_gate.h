// The one place where the pipeline drops frame sets, and the lockstep of the closed loop.
//
// A stage that cannot keep up with the cameras must drop whole frame sets, once and as early as
// possible, so that every set that goes on gets all its later products (volumes, targets, hand
// volumes, meshes). The pSfS stage holds its pending sets in a PipelineGate:
//  - live (capacity 1-2): a new set beyond the capacity pushes out the OLDEST pending one (the
//    newest image is what a live user wants), and the drop is counted here and nowhere else;
//  - offline (a capacity larger than the recording): nothing is dropped, every set is processed
//    in order at whatever speed the machine has.
// Sets marked `keep` (the background-learning sets) are never dropped whatever the capacity.
//
// Closed loop (thesis 4.3): the hand ROIs of set t+1 come from the tracker's targets for set t.
// After publishing set t the stage calls expectAck(t); pop() then hands out nothing until ack(s)
// with s >= t arrives or ack_timeout seconds pass (a dead tracker must not stop the pipeline).
// This makes the result independent of thread timing: the same input gives the same ROIs.
//
// ROS-free and not thread-safe: the caller holds one mutex around every call. Times are seconds
// on any monotonic clock; stamps are integers that grow with time (e.g. ros::Time::toNSec()).
#pragma once

#include <algorithm>
#include <cstdint>
#include <deque>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <utility>

namespace tabletop_common {

struct PipelineGateConfig {
  size_t capacity = 1;        // pending sets kept; beyond it the oldest droppable one goes
  double ack_timeout = 1.0;   // s to wait for the ack of the last published set
};

struct PipelineGateCounters {
  uint64_t pushed = 0;        // sets offered
  uint64_t dropped = 0;       // sets pushed out unprocessed (the only drop point)
  uint64_t popped = 0;        // sets handed out for processing
  uint64_t acks = 0;          // expected acks that arrived in time
  uint64_t ack_timeouts = 0;  // expected acks given up on
};

template <typename T>
class PipelineGate {
 public:
  explicit PipelineGate(const PipelineGateConfig& config = {}) { setConfig(config); }

  void setConfig(const PipelineGateConfig& config) {
    if (config.capacity < 1) throw std::invalid_argument("PipelineGate: capacity must be >= 1");
    if (!(config.ack_timeout >= 0)) throw std::invalid_argument("PipelineGate: ack_timeout must be >= 0");
    config_ = config;
  }
  const PipelineGateConfig& config() const { return config_; }

  // Queues a set. Returns the sets pushed out to make room (oldest first); `keep` sets are
  // never pushed out (the queue may then exceed the capacity).
  std::deque<T> push(T item, bool keep = false) {
    ++counters_.pushed;
    pending_.push_back(Entry{std::move(item), keep});
    std::deque<T> out;
    size_t droppable = 0;
    for (const Entry& e : pending_) droppable += !e.keep;
    for (auto it = pending_.begin(); droppable > config_.capacity && it != pending_.end();) {
      if (it->keep || std::next(it) == pending_.end()) {  // never the set just pushed
        ++it;
        continue;
      }
      out.push_back(std::move(it->item));
      it = pending_.erase(it);
      --droppable;
      ++counters_.dropped;
    }
    return out;
  }

  // The next set to process, if one is pending and the last ack is in (or timed out).
  std::optional<T> pop(double now) {
    if (pending_.empty() || waiting(now)) return std::nullopt;
    T item = std::move(pending_.front().item);
    pending_.pop_front();
    ++counters_.popped;
    return item;
  }

  // After publishing the set with this stamp: hold the next one until its ack.
  void expectAck(uint64_t stamp, double now) {
    expected_ = stamp;
    expect_since_ = now;
    awaiting_ = !(have_ack_ && last_ack_ >= stamp);  // the ack may have come first
    if (!awaiting_) ++counters_.acks;
  }

  // An ack (e.g. the tracker's targets) for the set with this stamp.
  void ack(uint64_t stamp) {
    if (!have_ack_ || stamp > last_ack_) last_ack_ = stamp;
    have_ack_ = true;
    if (awaiting_ && stamp >= expected_) {
      awaiting_ = false;
      ++counters_.acks;
    }
  }

  // True while the last published set's ack is outstanding (and not yet timed out). Counts a
  // timeout once, when it is noticed.
  bool waiting(double now) {
    if (!awaiting_) return false;
    if (now - expect_since_ < config_.ack_timeout) return true;
    awaiting_ = false;
    ++counters_.ack_timeouts;
    return false;
  }

  // Seconds until waiting() can change by itself (the ack timeout), or -1 when it cannot.
  double secondsUntilTimeout(double now) const {
    return awaiting_ ? std::max(0.0, expect_since_ + config_.ack_timeout - now) : -1.0;
  }

  size_t pendingCount() const { return pending_.size(); }
  const PipelineGateCounters& counters() const { return counters_; }

  // Forgets pending sets and the outstanding ack (e.g. when time jumps back); counters stay.
  std::deque<T> clear() {
    std::deque<T> out;
    for (Entry& e : pending_) out.push_back(std::move(e.item));
    pending_.clear();
    awaiting_ = have_ack_ = false;
    return out;
  }

 private:
  struct Entry {
    T item;
    bool keep;
  };
  PipelineGateConfig config_;
  PipelineGateCounters counters_;
  std::deque<Entry> pending_;
  bool awaiting_ = false, have_ack_ = false;
  uint64_t expected_ = 0, last_ack_ = 0;
  double expect_since_ = 0;
};

}  // namespace tabletop_common
