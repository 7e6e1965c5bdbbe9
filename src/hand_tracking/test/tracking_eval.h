// Scoring MPF output against the simulated rig's ground truth, frame by frame.
// - A hand track is associated with a true hand when it is acquired (its first active frame:
//   the nearest hand, preferring hands inside the workspace) and keeps that association.
// - Error: per frame and true hand inside the workspace, the distance from its associated
//   active track; a hand inside the workspace without one is a missed frame.
// - Identity switch: a track nearer the other hand than its own (both inside the workspace
//   and more than 15 cm apart, so folded hands do not count).
// - Loss / re-acquisition: when a hand leaves the workspace, the time until no active track
//   is associated with it any more; when it comes back, the time until one is again.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <string>
#include <vector>

#include "hand_tracking/target.h"
#include "sim_stream.h"

namespace hand_tracking_test {

struct ErrorStats {
  std::vector<double> e;
  void add(double v) { e.push_back(v); }
  int n() const { return static_cast<int>(e.size()); }
  double mean() const {
    return e.empty() ? NAN : std::accumulate(e.begin(), e.end(), 0.0) / n();
  }
  double max() const { return e.empty() ? NAN : *std::max_element(e.begin(), e.end()); }
  double stddev() const {
    if (e.size() < 2) return 0;
    const double m = mean();
    double s = 0;
    for (double v : e) s += (v - m) * (v - m);
    return std::sqrt(s / (n() - 1));
  }
  double percentile(double p) const {
    if (e.empty()) return NAN;
    std::vector<double> s = e;
    std::sort(s.begin(), s.end());
    return s[std::min(s.size() - 1, static_cast<size_t>(p * (s.size() - 1) + 0.5))];
  }
};

struct Latency {
  double at = 0;        // time of the workspace transition (s)
  double latency = -1;  // s until the tracker followed (-1: never)
};

class TrackScorer {
 public:
  explicit TrackScorer(double apart = 0.15) : apart_(apart) {}

  void add(const StreamFrame& f, const std::vector<hand_tracking::Target>& targets) {
    const FrameTruth& t = f.truth;
    if (t.person && t.head_in) {
      if (targets[0].active)
      {
        head.add((targets[0].position - t.head).norm());
        head_offsets.push_back(targets[0].position - t.head);
      }
      else
        ++head_missed;
    }
    bool covered[2] = {false, false};
    int active = 0;
    for (size_t i = 1; i < targets.size(); ++i) {
      const hand_tracking::Target& tg = targets[i];
      if (!tg.active) continue;
      ++active;
      auto it = association.find(tg.id);
      if (it == association.end()) {
        if (!t.person) continue;
        int best = -1;
        double bd = 1e9;
        for (int pass = 0; pass < 2 && best < 0; ++pass)
          for (int h = 0; h < 2; ++h) {
            const double d = (tg.position - t.hand(h)).norm();
            if ((pass == 1 || t.handIn(h)) && d < bd) {
              bd = d;
              best = h;
            }
          }
        it = association.emplace(tg.id, best).first;
        std::printf("[ track    ] t=%.2f s: track %u acquired, associated with the %s hand "
                    "(%.0f mm away)\n", f.time, tg.id, best == 0 ? "left" : "right", 1e3 * bd);
      }
      const int h = it->second;
      if (!t.person) continue;
      covered[h] = true;
      if (t.handIn(h)) {
        const double e = (tg.position - t.hand(h)).norm();
        hand[h].add(e);
        hands.add(e);
      }
      if (t.handIn(0) && t.handIn(1) && (t.left - t.right).norm() > apart_ &&
          (tg.position - t.hand(1 - h)).norm() < (tg.position - t.hand(h)).norm())
        ++switches;
    }
    int in = 0;
    for (int h = 0; h < 2; ++h) {
      const bool is_in = t.handIn(h);
      in += is_in;
      if (is_in && !covered[h]) {
        ++missed[h];
        if (ever_covered_[h]) ++missed_after_acquisition[h];
      }
      ever_covered_[h] |= covered[h];
      // Workspace transitions.
      if (started_ && is_in != was_in_[h]) {
        (is_in ? reacquisitions[h] : losses[h]).push_back({f.time, -1});
        pending_[h] = is_in ? 2 : 1;
      }
      if (pending_[h] == 1 && !covered[h]) {
        losses[h].back().latency = f.time - losses[h].back().at;
        pending_[h] = 0;
      } else if (pending_[h] == 2 && covered[h]) {
        reacquisitions[h].back().latency = f.time - reacquisitions[h].back().at;
        pending_[h] = 0;
      }
      was_in_[h] = is_in;
    }
    if (active > in) ++extra;
    started_ = true;
  }

  void print(const char* name) const {
    std::printf("[ figures  ] %s: hand centroid error mean %.1f mm, sd %.1f, p95 %.1f, max %.1f "
                "(%d hand-frames; left %.1f / %.1f, right %.1f / %.1f mean / max)\n",
                name, 1e3 * hands.mean(), 1e3 * hands.stddev(), 1e3 * hands.percentile(0.95),
                1e3 * hands.max(), hands.n(), 1e3 * hand[0].mean(), 1e3 * hand[0].max(),
                1e3 * hand[1].mean(), 1e3 * hand[1].max());
    std::printf("[ figures  ] %s: missed hand-frames L %d R %d (after acquisition L %d R %d), "
                "identity switches %d, frames with a spare hand track %d, %zu hand tracks; "
                "head error mean %.1f mm, sd %.1f, max %.1f, aligned %.1f (%d frames, missed %d)\n",
                name, missed[0], missed[1], missed_after_acquisition[0],
                missed_after_acquisition[1], switches, extra, association.size(),
                1e3 * head.mean(), 1e3 * head.stddev(), 1e3 * head.max(),
                1e3 * headAlignedMean(), head.n(), head_missed);
    for (int h = 0; h < 2; ++h) {
      for (const Latency& l : losses[h])
        std::printf("[ figures  ] %s: %s hand left the workspace at %.2f s, reported lost after "
                    "%.2f s\n", name, h ? "right" : "left", l.at, l.latency);
      for (const Latency& l : reacquisitions[h])
        std::printf("[ figures  ] %s: %s hand re-entered at %.2f s, re-acquired after %.2f s\n",
                    name, h ? "right" : "left", l.at, l.latency);
    }
  }

  // Mean head error once the mean offset is removed: the thesis' protocol (7.1, lines
  // ~6436-6440: head centroids compared after registering the average head location, since
  // where the estimate sits between face and skull depends on how much of the head is skin).
  double headAlignedMean() const {
    if (head_offsets.empty()) return NAN;
    Eigen::Vector3d bias = Eigen::Vector3d::Zero();
    for (const auto& o : head_offsets) bias += o;
    bias /= static_cast<double>(head_offsets.size());
    double sum = 0.0;
    for (const auto& o : head_offsets) sum += (o - bias).norm();
    return sum / static_cast<double>(head_offsets.size());
  }

  ErrorStats hand[2], hands, head;
  std::vector<Eigen::Vector3d> head_offsets;  // tracked - true head centre, per frame
  int missed[2] = {0, 0}, missed_after_acquisition[2] = {0, 0};
  int switches = 0, extra = 0, head_missed = 0;
  std::map<uint32_t, int> association;  // track id -> 0 left / 1 right
  std::vector<Latency> losses[2], reacquisitions[2];

 private:
  double apart_;
  bool started_ = false, was_in_[2] = {false, false}, ever_covered_[2] = {false, false};
  int pending_[2] = {0, 0};  // 1: waiting for the loss, 2: for the re-acquisition
};

// Centroid of the part of a hand inside the workspace (z >= desk top), from the oracle on a
// 6 mm lattice around the true centroid: what the cameras can see of the hand. The scripts
// press hands onto the desk, and the body model lets fingers and fists sink through its top,
// so the true centroid (of the whole hand) can lie up to ~15 mm from this.
inline Eigen::Vector3d visibleHandCentroid(const StreamFrame& f, int h) {
  const sim::Oracle oracle = f.rig->oracle(f.rig_frame);
  const sim::BodyPart part = h == 0 ? sim::BodyPart::LEFT_HAND : sim::BodyPart::RIGHT_HAND;
  const Eigen::Vector3d c = f.truth.hand(h);
  const double zmin = f.rig->options().workspace_min.z();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double n = 0;
  for (double x = -0.12; x <= 0.12; x += 0.006)
    for (double y = -0.12; y <= 0.12; y += 0.006)
      for (double z = -0.12; z <= 0.12; z += 0.006) {
        const Eigen::Vector3d p = c + Eigen::Vector3d(x, y, z);
        if (p.z() >= zmin && oracle.insidePart(p, part)) {
          sum += p;
          n += 1;
        }
      }
  return n > 0 ? Eigen::Vector3d(sum / n) : c;
}

}  // namespace hand_tracking_test
