#include "tabletop_sim/tracking_evaluator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace tabletop_sim {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool isHandTarget(int t) { return t < 2; }

const TrackedPoint* findTrack(const std::vector<TrackedPoint>& tracked, uint32_t id, bool hand) {
  for (const auto& p : tracked)
    if (p.active && p.id == id && p.hand == hand) return &p;
  return nullptr;
}

}  // namespace

void setHandAxes(const std::array<Eigen::Vector3d, 2>& wrist, TruthPoints* truth) {
  for (int side = 0; side < 2; ++side)
    if (wrist[side].allFinite() && truth->position[side].allFinite())
      truth->axis[side] = (truth->position[side] - wrist[side]).normalized();
}

const char* TrackingEvaluator::targetName(int t) {
  static const char* names[3] = {"left hand", "right hand", "head"};
  return t >= 0 && t < 3 ? names[t] : "?";
}

TrackingEvaluator::TrackingEvaluator(const TrackingEvaluatorParams& params) : params_(params) {}

void TrackingEvaluator::add(double time, const std::vector<TrackedPoint>& tracked,
                            const TruthPoints& truth) {
  ++frames_;
  times_.push_back(time);
  for (int t = 0; t < kTargets; ++t) {
    const bool hand = isHandTarget(t);
    Binding& b = bind_[t];
    TargetReport& r = reports_[t];
    const bool visible = truth.visible[t];
    const Eigen::Vector3d& truth_pos = truth.position[t];
    const TrackedPoint* track = b.bound ? findTrack(tracked, b.id, hand) : nullptr;

    if (!visible) {
      if (b.bound && b.merged) {
        // It shared the other hand's target, which goes on tracking that hand: nothing of
        // this hand's own is left to be reported lost.
        b.bound = false;
        b.merged = false;
      }
      if (was_visible_[t] && b.bound) b.left_at = time;  // waiting for the track to end
      if (b.bound && !track) {
        if (b.left_at >= 0) r.loss_report_delay_s.add(time - b.left_at);
        b.bound = false;
        b.merged = false;
        b.left_at = -1.0;
      } else if (b.bound && b.left_at >= 0 && time - b.left_at > 1.0) {
        ++r.unreported_exits;  // counted once: the binding is released
        b.bound = false;
        b.merged = false;
        b.left_at = -1.0;
      }
      b.visible_since = -1.0;
      was_visible_[t] = false;
      series_mm_[t].push_back(kNaN);
      continue;
    }
    ++r.visible_frames;
    if (!was_visible_[t]) b.visible_since = time;
    was_visible_[t] = true;
    b.left_at = -1.0;

    if (b.bound && !track && hand) {  // merged with the other hand's target?
      const Binding& o = bind_[1 - t];
      const TrackedPoint* other = o.bound ? findTrack(tracked, o.id, true) : nullptr;
      if (other && (other->position - truth_pos).norm() <= params_.match_radius) {
        ++r.merges;
        if (!b.merged) b.own_id = b.id;
        b.merged = true;
        b.id = other->id;
        track = other;
      }
    }
    if (b.bound && !track) {  // the bound track died while the truth is in view
      ++r.losses;
      b.bound = false;
      b.merged = false;
      b.visible_since = time;
    }
    // Nearest active track of the right type.
    const TrackedPoint* nearest = nullptr;
    double best = std::numeric_limits<double>::infinity();
    for (const auto& p : tracked) {
      if (!p.active || p.hand != hand) continue;
      const double d = (p.position - truth_pos).norm();
      if (d < best) best = d, nearest = &p;
    }
    if (!b.bound) {
      if (nearest && best <= params_.match_radius) {
        b.bound = true;
        b.id = nearest->id;
        track = nearest;
        ++r.acquisitions;
        if (b.visible_since >= 0) r.acquisition_delay_s.add(time - b.visible_since);
      }
    } else if (b.merged && nearest && nearest->id == b.own_id && best <= params_.match_radius) {
      // The split: the hand's own target is back.
      ++r.splits_recovered;
      b.merged = false;
      b.id = nearest->id;
      track = nearest;
    } else if (nearest && nearest->id != b.id) {
      const double bound_d = (track->position - truth_pos).norm();
      if (bound_d > params_.match_radius && best + params_.switch_margin < bound_d &&
          best <= params_.match_radius) {
        ++r.identity_switches;
        b.merged = false;
        b.id = nearest->id;
        track = nearest;
      }
    }
    if (b.bound && track) {
      const double err = 1e3 * (track->position - truth_pos).norm();
      r.error_mm.add(err);
      r.bias_sum_mm += 1e3 * (track->position - truth_pos);
      r.error_vectors_mm.push_back(1e3 * (track->position - truth_pos));
      const Eigen::Vector3d& axis = truth.axis[t];
      if (axis.allFinite() && axis.squaredNorm() > 1e-12) {
        const Eigen::Vector3d e = 1e3 * (track->position - truth_pos), u = axis.normalized();
        r.along_mm.add(e.dot(u));
        r.across_mm.add((e - e.dot(u) * u).norm());
      }
      ++r.tracked_frames;
      series_mm_[t].push_back(err);
    } else {
      series_mm_[t].push_back(kNaN);
    }
  }
  // Tracks that follow nothing real (e.g. a target born while nobody is there).
  for (const auto& p : tracked) {
    if (!p.active) continue;
    bool near_truth = false;
    for (int t = 0; t < kTargets; ++t)
      near_truth = near_truth || (truth.visible[t] && isHandTarget(t) == p.hand &&
                                  (p.position - truth.position[t]).norm() <= params_.match_radius);
    if (!near_truth) {
      ++false_target_frames_;
      break;
    }
  }
}

double TrackingEvaluator::TargetReport::alignedErrorMeanMm() const {
  if (error_vectors_mm.empty()) return 0.0;
  const Eigen::Vector3d bias = biasMm();
  double sum = 0.0;
  for (const Eigen::Vector3d& e : error_vectors_mm) sum += (e - bias).norm();
  return sum / static_cast<double>(error_vectors_mm.size());
}

std::string TrackingEvaluator::summary() const {
  std::string s;
  char buf[320];
  for (int t = 0; t < kTargets; ++t) {
    const TargetReport& r = reports_[t];
    if (r.visible_frames == 0) {
      std::snprintf(buf, sizeof(buf), "  %-10s  never visible\n", targetName(t));
    } else {
      std::snprintf(buf, sizeof(buf),
                    "  %-10s  error mean %.1f mm, std %.1f, max %.1f | tracked %d/%d frames | "
                    "losses %d, identity switches %d | bias (%+.1f, %+.1f, %+.1f) mm",
                    targetName(t), r.error_mm.mean(), r.error_mm.stddev(), r.error_mm.max(),
                    r.tracked_frames, r.visible_frames, r.losses, r.identity_switches, r.biasMm().x(),
                    r.biasMm().y(), r.biasMm().z());
      s += buf;
      if (!isHandTarget(t)) {
        std::snprintf(buf, sizeof(buf), " | aligned %.1f mm (bias removed, thesis 7.1)",
                      r.alignedErrorMeanMm());
        s += buf;
      }
      if (r.along_mm.count() > 0) {
        std::snprintf(buf, sizeof(buf),
                      isHandTarget(t) ? " | along the hand %+.1f mm (+: towards the fingers), across %.1f"
                                      : " | along its axis %+.1f mm, across %.1f",
                      r.along_mm.mean(), r.across_mm.mean());
        s += buf;
      }
      if (r.merges > 0) {
        std::snprintf(buf, sizeof(buf), " | merged with the other hand %d time(s), own id back %d",
                      r.merges, r.splits_recovered);
        s += buf;
      }
      if (r.acquisition_delay_s.count() > 0) {
        std::snprintf(buf, sizeof(buf), " | acquired after %.2f s (max %.2f; %d acquisitions)",
                      r.acquisition_delay_s.mean(), r.acquisition_delay_s.max(), r.acquisitions);
        s += buf;
      }
      if (r.loss_report_delay_s.count() > 0) {
        std::snprintf(buf, sizeof(buf), " | exits reported after %.2f s (max %.2f)",
                      r.loss_report_delay_s.mean(), r.loss_report_delay_s.max());
        s += buf;
      }
      if (r.unreported_exits > 0) {
        std::snprintf(buf, sizeof(buf), " | %d exits never reported", r.unreported_exits);
        s += buf;
      }
      std::snprintf(buf, sizeof(buf), "\n");
    }
    s += buf;
  }
  std::snprintf(buf, sizeof(buf), "  frames with a target on nothing: %d of %d\n",
                false_target_frames_, frames_);
  s += buf;
  return s;
}

bool TrackingEvaluator::writePlot(const std::string& path, int width, int height) const {
  if (times_.empty()) return false;
  const int left = 60, right = 20, top = 30, bottom = 40;
  cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  double max_err = 10.0;
  for (const auto& s : series_mm_)
    for (double e : s)
      if (std::isfinite(e)) max_err = std::max(max_err, e);
  max_err = std::ceil(max_err / 10.0) * 10.0;
  const double t0 = times_.front(), t1 = std::max(times_.back(), t0 + 1e-3);
  auto px = [&](double t, double e) {
    return cv::Point(left + static_cast<int>((t - t0) / (t1 - t0) * (width - left - right)),
                     height - bottom - static_cast<int>(e / max_err * (height - top - bottom)));
  };
  // Axes and grid (every 10 mm or a fifth of the range).
  const double step = max_err <= 50 ? 10.0 : std::ceil(max_err / 50.0) * 10.0;
  for (double e = 0; e <= max_err + 1e-9; e += step) {
    cv::line(img, px(t0, e), px(t1, e), cv::Scalar(225, 225, 225));
    cv::putText(img, std::to_string(static_cast<int>(e)), px(t0, e) + cv::Point(-40, 4),
                cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  }
  cv::line(img, px(t0, 0), px(t1, 0), cv::Scalar(0, 0, 0));
  cv::line(img, px(t0, 0), px(t0, max_err), cv::Scalar(0, 0, 0));
  char buf[64];
  std::snprintf(buf, sizeof(buf), "time (s): 0 .. %.1f", t1 - t0);
  cv::putText(img, buf, cv::Point(left, height - 12), cv::FONT_HERSHEY_SIMPLEX, 0.45,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, "centroid error (mm) vs ground truth", cv::Point(left, 20),
              cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  const cv::Scalar colours[3] = {cv::Scalar(200, 80, 0), cv::Scalar(0, 140, 0), cv::Scalar(0, 0, 200)};
  for (int t = 0; t < kTargets; ++t) {
    const auto& s = series_mm_[t];
    for (size_t i = 1; i < s.size(); ++i)
      if (std::isfinite(s[i - 1]) && std::isfinite(s[i]))
        cv::line(img, px(times_[i - 1], s[i - 1]), px(times_[i], s[i]), colours[t], 1, cv::LINE_AA);
    cv::putText(img, targetName(t), cv::Point(width - right - 110, top + 18 * (t + 1)),
                cv::FONT_HERSHEY_SIMPLEX, 0.45, colours[t], 1, cv::LINE_AA);
  }
  return cv::imwrite(path, img);
}

}  // namespace tabletop_sim
