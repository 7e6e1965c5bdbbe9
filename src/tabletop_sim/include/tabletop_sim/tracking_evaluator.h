// Scores a hand/head tracker against ground truth (the simulated rig's, or any recorded truth):
// centroid errors per target, track losses with how long they took to be reported, re-acquisition
// delays and identity switches, and an error-over-time plot. ROS-free, so the evaluation tool,
// the demo monitor and the tests all count the same way.
//
// Association: each true target (left hand, right hand, head) is bound to the active tracked
// target of its type nearest to it (within match_radius) when it first becomes visible, and keeps
// that binding while the track stays active. If the bound track dies while the true target is
// visible, that is a loss; the next track to come within match_radius is bound again (a
// re-acquisition). If another track of the same type is nearer than the bound one by more than
// switch_margin while both are active and the bound one is outside match_radius, the binding
// moves and an identity switch is counted.
// Folded hands: when a hand's bound track dies while the other hand's track is within
// match_radius of it, the hands have merged into one target (DESIGN.md: clasped hands are one
// target). That is counted as a merge, not a loss; the hand follows the shared track, and when
// a track with its own earlier id comes back (the split) it returns to it without counting an
// identity switch. A different id after the split is a switch.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tabletop_common/running_stats.h"

namespace tabletop_sim {

struct TrackedPoint {
  uint32_t id = 0;
  bool hand = true;  // false: head
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  bool active = false;
};

// The three true targets in the order left hand, right hand, head (ids 0, 1, 2 of
// ground_truth/targets). visible: the person is present and the target is in the workspace.
struct TruthPoints {
  std::array<Eigen::Vector3d, 3> position{};
  std::array<bool, 3> visible{{false, false, false}};
  // Optional direction per target (any length; zero: none) along which the error is also
  // split. Hands: from the wrist towards the hand's centre, so that "along" says whether a
  // tracker reports a point nearer the fingers (+) or the forearm (-): the hand target's
  // systematic error on generated people lies along this axis (docs/benchmarks.md,
  // 2026-12-07). The simulator tools (scenario_suite, track_eval on the simulated rig) fill it;
  // truth read from ground_truth/targets (bags, the demo monitor) has no wrists and none.
  std::array<Eigen::Vector3d, 3> axis{
      {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}};
};

// The hands' axes (axis[0], axis[1]) from the wrists (left, right) to the hands' positions
// already in `truth`; a hand without a finite wrist or position keeps none.
void setHandAxes(const std::array<Eigen::Vector3d, 2>& wrist, TruthPoints* truth);

struct TrackingEvaluatorParams {
  double match_radius = 0.10;   // m: a track farther than this from the truth does not track it
  double switch_margin = 0.03;  // m: how much nearer another track must be to take over
};

class TrackingEvaluator {
 public:
  static constexpr int kTargets = 3;
  static const char* targetName(int t);  // "left hand", "right hand", "head"

  explicit TrackingEvaluator(const TrackingEvaluatorParams& params = {});

  // One frame at `time` (s, increasing).
  void add(double time, const std::vector<TrackedPoint>& tracked, const TruthPoints& truth);

  struct TargetReport {
    tabletop_common::RunningStats error_mm;        // over frames where the target is visible and tracked
    // Mean signed error (tracked - truth, world axes, mm) over the same frames: a bias that
    // the mean distance hides (e.g. a systematic offset of the reconstruction).
    Eigen::Vector3d bias_sum_mm = Eigen::Vector3d::Zero();
    Eigen::Vector3d biasMm() const {
      return error_mm.count() ? Eigen::Vector3d(bias_sum_mm / error_mm.count()) : Eigen::Vector3d::Zero();
    }
    // Where the truth has an axis: the signed error along it (mm, + in the axis' direction)
    // and the distance from the axis line (mm), over the tracked frames that have one.
    tabletop_common::RunningStats along_mm, across_mm;
    // The error vectors (tracked - truth, mm) of those frames.
    std::vector<Eigen::Vector3d> error_vectors_mm;
    // Mean distance from the truth once the mean offset (the bias) is removed: the thesis'
    // protocol for the head (7.1, lines ~6436-6440: head centroids are compared after
    // registering each participant's average head location, because where the "head centre"
    // lies between face and skull depends on how much of the head is skin-coloured).
    double alignedErrorMeanMm() const;
    int visible_frames = 0, tracked_frames = 0;
    int losses = 0;               // bound track died (or went inactive) while visible
    int identity_switches = 0;
    int acquisitions = 0;         // bindings made (first acquisition + re-acquisitions)
    int merges = 0;               // merged with the other hand into one target
    int splits_recovered = 0;     // back on its own id after a merge
    // Delays (s): from the truth leaving the workspace to its track going inactive, and from
    // the truth becoming visible to a track being bound.
    tabletop_common::RunningStats loss_report_delay_s, acquisition_delay_s;
    int unreported_exits = 0;     // left the workspace but the track stayed active > 1 s
  };
  const TargetReport& report(int t) const { return reports_[t]; }
  int frames() const { return frames_; }
  // Frames with a tracked target active although no visible truth of its type is near it.
  int falseTargetFrames() const { return false_target_frames_; }

  // Human-readable table (one line per target), as the tool and the demo print it.
  std::string summary() const;
  // Error over time (mm) per target, PNG. False if it cannot be written.
  bool writePlot(const std::string& path, int width = 900, int height = 420) const;

 private:
  struct Binding {
    bool bound = false;
    uint32_t id = 0;
    bool merged = false;          // following the other hand's track since a merge
    uint32_t own_id = 0;          // the id it had before the merge
    double visible_since = -1.0;  // time the truth became visible (waiting for a binding)
    double left_at = -1.0;        // time the truth stopped being visible with a bound track
  };
  TrackingEvaluatorParams params_;
  std::array<Binding, 3> bind_;
  std::array<TargetReport, 3> reports_;
  std::array<bool, 3> was_visible_{{false, false, false}};
  std::vector<double> times_;
  std::array<std::vector<double>, 3> series_mm_;  // NaN where not visible or not tracked
  int frames_ = 0, false_target_frames_ = 0;
};

}  // namespace tabletop_sim
