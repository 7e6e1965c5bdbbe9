// Groups per-camera images into frame sets (one image per camera with the same stamp, or stamps
// within a tolerance) and emits complete sets in strictly increasing stamp order. ROS-free: the
// payload T is opaque (e.g. sensor_msgs::ImageConstPtr; default-constructible and movable, may
// be move-only), stamps are seconds as double (header.stamp.toSec(): equal ROS stamps give equal
// doubles, so exact mode works; resolution is ~0.2 us at today's epoch).
//
// Policy (DESIGN.md section 3, "A frame set"):
// - Matching: an image joins, among the pending sets whose anchor (the stamp of the set's first
//   image) is within `tolerance` of its stamp (0 = exact equality: hardware sync), the nearest
//   one that has no image from this camera yet. If all such sets already have one, the image is
//   a duplicate: the first one is kept. If there is no such set, a new one is opened, anchored
//   at this stamp. Because a set is only opened when no pending anchor is within tolerance,
//   pending anchors are always more than `tolerance` apart (so at most two candidates).
// - Output order: when a set completes, every pending set with an older anchor is dropped as
//   incomplete ("superseded") and the complete one is emitted. With per-camera FIFO delivery
//   (ROS topics are), an older set can only be incomplete at that point if one of its images
//   was really lost, so waiting for it would only add latency; and the output stays monotonic.
// - Watermark: the anchor of the newest set emitted or dropped. An image that does not match a
//   pending set and whose stamp is <= watermark + tolerance belongs to a finished set (or is
//   older than it): it is counted as late and dropped, never emitted out of order.
// - Timeout: a pending set whose anchor is more than `timeout` older than the newest stamp seen
//   (or the `now_stamp` given to expire()) is dropped as incomplete. Call expire() from a timer
//   so the last sets are flushed when all streams stop.
// - Bound: at most `max_pending` sets are pending; opening one more drops the oldest.
// - Degraded sets (max_missing > 0): a set that lacks at most max_missing cameras is emitted
//   (partial, its `present` flags say which cameras are in it) wherever it would otherwise be
//   dropped (timeout, superseded, overflow), so that a silent camera costs that camera, not the
//   whole set. A camera that missed `absent_after` emitted or dropped sets in a row is absent:
//   sets stop waiting for it (no timeout latency per set) until its next image arrives.
// - Every dropped or partial set adds one to missing_per_camera[c] for each camera c it lacked,
//   so diagnostics can name a dead or lossy camera.
// - Time going backwards (bag restarted, /clock reset) makes everything late: call reset().
//
// Not thread-safe: the caller serialises add()/expire()/takeCompleted() (one mutex in the node).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace tabletop_capture {

struct FrameSetAssemblerConfig {
  int num_cameras = 1;
  double tolerance = 0.0;     // seconds; 0 = stamps must be equal (hardware sync)
  double timeout = 0.5;       // seconds; +infinity disables the stamp-based timeout
  std::size_t max_pending = 8;  // pending (incomplete) sets kept at most
  int max_missing = 0;   // a set lacking at most this many cameras is emitted partial (0: never)
  int absent_after = 3;  // sets missed in a row before a camera is no longer waited for
};

// One emitted set. frames[c] / stamps[c] belong to camera c; for a camera not in a partial set
// present[c] is false, frames[c] default-constructed and stamps[c] 0.
template <typename T>
struct FrameSet {
  double stamp = 0.0;  // earliest image stamp (= the common stamp in exact mode)
  std::vector<double> stamps;
  std::vector<T> frames;
  std::vector<bool> present;
  bool complete() const { return std::find(present.begin(), present.end(), false) == present.end(); }
};

// Outcome of one add(). Only kPending and kCompleted keep the image.
enum class AddResult {
  kPending,    // stored in an incomplete set
  kCompleted,  // completed a set (now in takeCompleted())
  kLate,       // belongs to a set already emitted or dropped, or older: dropped
  kDuplicate,  // its set already has an image from this camera: dropped, first one kept
  kBadCamera,  // camera index outside [0, num_cameras): dropped
  kBadStamp,   // stamp is NaN or infinite: dropped
  kOverflow,   // opened a set older than all max_pending others, dropped at once (counted in
               // incomplete_overflow)
};

inline const char* toString(AddResult r) {
  switch (r) {
    case AddResult::kPending: return "pending";
    case AddResult::kCompleted: return "completed";
    case AddResult::kLate: return "late";
    case AddResult::kDuplicate: return "duplicate";
    case AddResult::kBadCamera: return "bad_camera";
    case AddResult::kBadStamp: return "bad_stamp";
    case AddResult::kOverflow: return "overflow";
  }
  return "unknown";
}

struct FrameSetCounters {
  std::uint64_t complete = 0;            // complete sets emitted
  std::uint64_t partial = 0;             // sets emitted without some cameras (max_missing)
  std::uint64_t incomplete_timeout = 0;  // dropped: older than timeout
  std::uint64_t incomplete_superseded = 0;  // dropped: a newer set completed first
  std::uint64_t incomplete_overflow = 0;    // dropped: more than max_pending pending
  std::uint64_t late = 0;
  std::uint64_t duplicate = 0;
  std::uint64_t bad_camera = 0;
  std::uint64_t bad_stamp = 0;
  // missing_per_camera[c]: dropped or partial sets that lacked camera c (size num_cameras).
  std::vector<std::uint64_t> missing_per_camera;

  std::uint64_t incomplete() const {
    return incomplete_timeout + incomplete_superseded + incomplete_overflow;
  }
};

template <typename T>
class FrameSetAssembler {
 public:
  // Throws std::invalid_argument for num_cameras < 1, negative/NaN tolerance or timeout,
  // max_pending < 1.
  explicit FrameSetAssembler(const FrameSetAssemblerConfig& config) : config_((validate(config), config)) {
    counters_.missing_per_camera.assign(config_.num_cameras, 0);
    missed_in_a_row_.assign(config_.num_cameras, 0);
  }

  static void validate(const FrameSetAssemblerConfig& c) {
    if (c.num_cameras < 1)
      throw std::invalid_argument("FrameSetAssembler: num_cameras must be >= 1, got " +
                                  std::to_string(c.num_cameras));
    if (!(c.tolerance >= 0.0) || !std::isfinite(c.tolerance))
      throw std::invalid_argument("FrameSetAssembler: tolerance must be finite and >= 0");
    if (!(c.timeout >= 0.0))
      throw std::invalid_argument("FrameSetAssembler: timeout must be >= 0");
    if (c.max_pending < 1)
      throw std::invalid_argument("FrameSetAssembler: max_pending must be >= 1");
    if (c.max_missing < 0 || c.max_missing >= c.num_cameras)
      throw std::invalid_argument("FrameSetAssembler: max_missing must lie in [0, num_cameras - 1]");
    if (c.absent_after < 1)
      throw std::invalid_argument("FrameSetAssembler: absent_after must be >= 1");
  }

  AddResult add(int camera, double stamp, T payload) {
    if (camera < 0 || camera >= config_.num_cameras) {
      ++counters_.bad_camera;
      return AddResult::kBadCamera;
    }
    if (!std::isfinite(stamp)) {
      ++counters_.bad_stamp;
      return AddResult::kBadStamp;
    }
    missed_in_a_row_[camera] = 0;  // heard from: waited for again, even if this image is late
    if (!have_newest_ || stamp > newest_stamp_) {
      newest_stamp_ = stamp;
      have_newest_ = true;
    }
    // Expire first, so an image can never revive a set that is already past its timeout.
    expire(newest_stamp_);

    bool duplicate = false;
    auto it = findNearest(stamp, camera, &duplicate);
    if (duplicate) {
      ++counters_.duplicate;
      return AddResult::kDuplicate;
    }
    if (it == pending_.end()) {
      if (have_watermark_ && stamp <= watermark_ + config_.tolerance) {
        ++counters_.late;
        return AddResult::kLate;
      }
      Pending p;
      p.frames.resize(config_.num_cameras);
      p.stamps.assign(config_.num_cameras, 0.0);
      p.present.assign(config_.num_cameras, false);
      it = pending_.emplace(stamp, std::move(p)).first;
    }

    Pending& set = it->second;
    set.present[camera] = true;
    set.stamps[camera] = stamp;
    set.frames[camera] = std::move(payload);
    ++set.count;

    if (set.count == config_.num_cameras || (degraded() && waitingFor(set) == 0 &&
                                             set.count >= config_.num_cameras - config_.max_missing)) {
      emit(it);
      return AddResult::kCompleted;
    }
    // Enforce the bound after inserting: if the new set is itself the oldest, it is the one
    // dropped (and the image with it), which keeps the watermark rule simple.
    const bool dropped_self = pending_.size() > config_.max_pending && it == pending_.begin();
    while (pending_.size() > config_.max_pending) {
      finishIncomplete(pending_.begin(), &counters_.incomplete_overflow);
    }
    return dropped_self ? AddResult::kOverflow : AddResult::kPending;
  }

  // Finishes pending sets whose anchor is older than now_stamp - timeout: emitted partial if
  // they lack at most max_missing cameras, else dropped. Returns how many.
  std::size_t expire(double now_stamp) {
    std::size_t n = 0;
    while (!pending_.empty() && now_stamp - pending_.begin()->first > config_.timeout) {
      finishIncomplete(pending_.begin(), &counters_.incomplete_timeout);
      ++n;
    }
    return n;
  }

  // True for a camera sets no longer wait for (it missed absent_after sets in a row).
  bool absent(int camera) const {
    return degraded() && missed_in_a_row_[camera] >= config_.absent_after;
  }

  // Emitted sets in emission order (strictly increasing stamp); clears the queue. The caller
  // must drain it regularly: it is not bounded.
  std::vector<FrameSet<T>> takeCompleted() {
    std::vector<FrameSet<T>> out;
    out.swap(completed_);
    return out;
  }

  // Live tuning: tolerance and timeout for the images that arrive from now on (pending sets
  // keep their anchors). Throws std::invalid_argument (nothing changed) as the constructor does.
  void setTiming(double tolerance, double timeout) {
    FrameSetAssemblerConfig c = config_;
    c.tolerance = tolerance;
    c.timeout = timeout;
    validate(c);
    config_ = c;
  }

  // Forgets pending and completed sets and the watermark (not the counters). For time jumps.
  void reset() {
    pending_.clear();
    completed_.clear();
    have_watermark_ = false;
    have_newest_ = false;
  }

  const FrameSetCounters& counters() const { return counters_; }
  const FrameSetAssemblerConfig& config() const { return config_; }
  std::size_t pendingCount() const { return pending_.size(); }
  std::size_t completedCount() const { return completed_.size(); }

 private:
  struct Pending {
    int count = 0;
    std::vector<bool> present;
    std::vector<double> stamps;
    std::vector<T> frames;
  };
  using Map = std::map<double, Pending>;  // keyed by anchor stamp, oldest first

  // Pending set with the anchor nearest to stamp within tolerance that lacks `camera`, or
  // end(); *duplicate is set if there are sets within tolerance but all have `camera`.
  typename Map::iterator findNearest(double stamp, int camera, bool* duplicate) {
    auto best = pending_.end();
    double best_d = std::numeric_limits<double>::infinity();
    auto hi = pending_.lower_bound(stamp);
    *duplicate = false;
    auto consider = [&](typename Map::iterator c) {
      const double d = std::abs(c->first - stamp);
      if (d > config_.tolerance) return;
      if (c->second.present[camera]) {
        *duplicate = true;
      } else if (d < best_d) {
        best = c;
        best_d = d;
      }
    };
    if (hi != pending_.end()) consider(hi);
    if (hi != pending_.begin()) consider(std::prev(hi));
    if (best != pending_.end()) *duplicate = false;
    return best;
  }

  void advanceWatermark(double anchor) {
    if (!have_watermark_ || anchor > watermark_) watermark_ = anchor;
    have_watermark_ = true;
  }

  bool degraded() const { return config_.max_missing > 0; }

  // Cameras the set lacks that are not absent.
  int waitingFor(const Pending& set) const {
    int n = 0;
    for (int c = 0; c < config_.num_cameras; ++c) n += !set.present[c] && !absent(c);
    return n;
  }

  void countMissing(const Pending& set) {
    for (int c = 0; c < config_.num_cameras; ++c) {
      if (set.present[c]) continue;
      ++counters_.missing_per_camera[c];
      ++missed_in_a_row_[c];
    }
  }

  // A set that will not complete: emitted partial when degraded output allows it, else
  // dropped and counted under `reason`.
  void finishIncomplete(typename Map::iterator it, std::uint64_t* reason) {
    if (degraded() && it->second.count >= config_.num_cameras - config_.max_missing) {
      emitOne(it);
      return;
    }
    countMissing(it->second);
    ++*reason;
    advanceWatermark(it->first);
    pending_.erase(it);
  }

  void emit(typename Map::iterator it) {
    while (pending_.begin() != it)
      finishIncomplete(pending_.begin(), &counters_.incomplete_superseded);
    emitOne(it);
  }

  void emitOne(typename Map::iterator it) {
    Pending& set = it->second;
    FrameSet<T> out;
    out.stamp = std::numeric_limits<double>::infinity();
    for (int c = 0; c < config_.num_cameras; ++c)
      if (set.present[c]) {
        out.stamp = std::min(out.stamp, set.stamps[c]);
        missed_in_a_row_[c] = 0;
      }
    const bool complete = set.count == config_.num_cameras;
    if (!complete) countMissing(set);
    ++(complete ? counters_.complete : counters_.partial);
    out.stamps = std::move(set.stamps);
    out.frames = std::move(set.frames);
    out.present = std::move(set.present);
    advanceWatermark(it->first);
    pending_.erase(it);
    completed_.push_back(std::move(out));
  }

  FrameSetAssemblerConfig config_;
  FrameSetCounters counters_;
  Map pending_;
  std::vector<FrameSet<T>> completed_;
  std::vector<int> missed_in_a_row_;  // per camera: emitted or dropped sets missed since its last image
  double watermark_ = 0.0;  // anchor of the newest set emitted or dropped
  bool have_watermark_ = false;
  double newest_stamp_ = 0.0;
  bool have_newest_ = false;
};

}  // namespace tabletop_capture
