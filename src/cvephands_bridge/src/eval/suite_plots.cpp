#include "cvephands_bridge/eval/suite_plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cvephands_bridge/eval/scenario_evaluation.h"

namespace cvephands {
namespace {

const cv::Scalar kBlack(0, 0, 0), kGrey(60, 60, 60), kLight(225, 225, 225), kBar(200, 140, 60),
    kFailedBar(60, 60, 200);
// Limit lines: colour by bar set (design, then any other), style by statistic.
const cv::Scalar kSetColours[2] = {cv::Scalar(0, 150, 0), cv::Scalar(160, 40, 160)};

void text(cv::Mat& img, const std::string& s, cv::Point p, double scale, const cv::Scalar& c) {
  cv::putText(img, s, p, cv::FONT_HERSHEY_SIMPLEX, scale, c, 1, cv::LINE_AA);
}

// Dashed (or dotted) horizontal line.
void dashed(cv::Mat& img, int x0, int x1, int y, const cv::Scalar& c, int on, int off) {
  for (int x = x0; x < x1; x += on + off) cv::line(img, {x, y}, {std::min(x + on, x1), y}, c, 2);
}

// 1, 2, 2.5 or 5 times a power of ten, about range / 5.
double niceStep(double range) {
  const double raw = range / 5.0, p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 2.5, 5.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

// Labels under the bars: "random-12" -> "12", others cut to 12 characters; where one scenario
// runs several times (e.g. the quick subset: one scenario, four scripts), the script instead.
std::vector<std::string> labels(const std::vector<ScenarioFigures>& scenarios) {
  std::vector<std::string> out;
  for (const ScenarioFigures& s : scenarios) {
    int same = 0;
    for (const ScenarioFigures& o : scenarios) same += o.name == s.name;
    std::string l = same > 1 ? s.script : s.name;
    if (same == 1 && l.rfind("random-", 0) == 0) l = l.substr(7);
    out.push_back(l.size() > 12 ? l.substr(0, 12) : l);
  }
  return out;
}

void panel(cv::Mat& img, int top, int height, const MeasureDef& d,
           const std::vector<ScenarioFigures>& scenarios, const std::vector<BarSet>& sets) {
  // The legend (one line per limit drawn) sits above the plot area, right-aligned.
  int lines = 0;
  for (const BarSet& set : sets)
    for (const Bar& b : set.bars) lines += b.key == d.key;
  const int left = 70, right = 20, ptop = top + 28 + 15 * std::max(0, lines - 1), bottom = top + height - 34;
  const int w = img.cols - left - right;
  // Range: 0 .. the largest value or limit, rounded up to a tick (ratios: 0 .. 1).
  const bool ratio = std::string(d.unit).empty() && d.better == Better::kHigher;
  double vmax = ratio ? 1.0 : 0.0;
  for (const ScenarioFigures& s : scenarios)
    if (s.ran() && std::isfinite(s.*d.field)) vmax = std::max(vmax, s.*d.field);
  for (const BarSet& set : sets)
    for (const Bar& b : set.bars)
      if (b.key == d.key) vmax = std::max(vmax, b.limit);
  if (vmax <= 0) vmax = 1.0;
  const double step = ratio ? 0.25 : niceStep(vmax * 1.1);
  vmax = ratio ? 1.0 : std::ceil(vmax * 1.1 / step) * step;
  auto py = [&](double v) { return bottom - static_cast<int>(std::clamp(v / vmax, 0.0, 1.0) * (bottom - ptop)); };
  const std::string unit = *d.unit ? std::string(" (") + d.unit + ")" : std::string();
  text(img, std::string(d.label) + unit + (d.better == Better::kHigher ? ", higher is better" : ", lower is better"),
       {left, top + 18}, 0.5, kBlack);
  const int tick_decimals = step >= 1.0 ? 0 : (step >= 0.1 ? 1 : 2) + (ratio ? 1 : 0);
  for (double v = 0; v <= vmax + 1e-9; v += step) {
    cv::line(img, {left, py(v)}, {left + w, py(v)}, kLight);
    text(img, formatValue(v, tick_decimals), {8, py(v) + 4}, 0.4, kGrey);
  }
  cv::line(img, {left, bottom}, {left + w, bottom}, kBlack);
  cv::line(img, {left, ptop}, {left, bottom}, kBlack);
  const int n = std::max<int>(1, static_cast<int>(scenarios.size()));
  const double slot = double(w) / n;
  const int bw = std::clamp(static_cast<int>(slot * 0.6), 2, 60);
  const std::vector<std::string> names = labels(scenarios);
  for (int i = 0; i < static_cast<int>(scenarios.size()); ++i) {
    const ScenarioFigures& s = scenarios[i];
    const int cx = left + static_cast<int>((i + 0.5) * slot);
    const double v = s.ran() ? s.*d.field : std::nan("");
    if (std::isnan(v)) {  // failed to run / not measured: a cross on the axis
      cv::line(img, {cx - 5, bottom - 10}, {cx + 5, bottom}, kFailedBar, 2);
      cv::line(img, {cx - 5, bottom}, {cx + 5, bottom - 10}, kFailedBar, 2);
    } else if (std::isinf(v)) {  // never tracked: a full-height bar, labelled
      cv::rectangle(img, {cx - bw / 2, ptop}, {cx + bw / 2, bottom}, kFailedBar, cv::FILLED);
      text(img, "never", {cx - bw / 2, ptop - 2}, 0.35, kFailedBar);
    } else {
      cv::rectangle(img, {cx - bw / 2, py(v)}, {cx + bw / 2, bottom}, kBar, cv::FILLED);
    }
    text(img, names[i], {cx - bw / 2, bottom + 14 + 11 * (i % 2)}, 0.35, kGrey);
  }
  int legend = 0;
  for (size_t k = 0; k < sets.size(); ++k) {
    const cv::Scalar c = kSetColours[std::min<size_t>(k, 1)];
    for (const Bar& b : sets[k].bars) {
      if (b.key != d.key) continue;
      const int y = py(b.limit);
      if (b.statistic == Statistic::kMedian) cv::line(img, {left, y}, {left + w, y}, c, 2);
      else if (b.statistic == Statistic::kWorstDecile) dashed(img, left, left + w, y, c, 12, 8);
      else dashed(img, left, left + w, y, c, 3, 5);
      const char* style = b.statistic == Statistic::kMedian        ? "(solid)"
                          : b.statistic == Statistic::kWorstDecile ? "(dashed)"
                                                                   : "(dotted)";
      text(img, sets[k].name + " " + statisticName(b.statistic) + " " + formatValue(b.limit, d.decimals) + " " + style,
           {img.cols - right - 300, top + 18 + 15 * legend++}, 0.42, c);
    }
  }
}

}  // namespace

bool writeSuiteBarsPlot(const std::string& path, const std::vector<ScenarioFigures>& scenarios,
                        const std::vector<BarSet>& bars, const std::vector<std::string>& keys, int width,
                        int panel_height) {
  if (keys.empty()) return false;
  cv::Mat img(panel_height * static_cast<int>(keys.size()), width, CV_8UC3, cv::Scalar(255, 255, 255));
  for (size_t k = 0; k < keys.size(); ++k)
    panel(img, static_cast<int>(k) * panel_height, panel_height, measureDef(keys[k]), scenarios, bars);
  return cv::imwrite(path, img);
}

bool writeBodyBarsPlot(const std::string& path, const std::vector<ScenarioFigures>& scenarios, int width,
                       int panel_height) {
  return writeSuiteBarsPlot(path, scenarios, {bodyReferenceBars()},
                            {"body_hand_mm", "body_head_mm", "body_elbow_mm", "body_shoulder_mm",
                             "body_upper_arm_deg", "body_forearm_deg", "body_tracked_fraction"},
                            width, panel_height);
}

bool writeVolumeIoUPlot(const std::string& path, const ScenarioEvalResult& r, int width, int height) {
  std::vector<const ScenarioFrame*> f;
  for (const ScenarioFrame& s : r.frames)
    if (s.person) f.push_back(&s);
  if (f.empty()) return false;
  const int left = 60, right = 20, top = 30, bottom = 40;
  cv::Mat img(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const double t0 = f.front()->time, t1 = std::max(f.back()->time, t0 + 1e-3);
  auto px = [&](double t, double v) {
    return cv::Point(left + static_cast<int>((t - t0) / (t1 - t0) * (width - left - right)),
                     height - bottom - static_cast<int>(std::clamp(v, 0.0, 1.0) * (height - top - bottom)));
  };
  for (int k = 0; k <= 5; ++k) {
    const double v = k / 5.0;
    cv::line(img, px(t0, v), px(t1, v), kLight);
    text(img, formatValue(v, 1), px(t0, v) + cv::Point(-40, 4), 0.4, kGrey);
  }
  cv::line(img, px(t0, 0), px(t1, 0), kBlack);
  cv::line(img, px(t0, 0), px(t0, 1), kBlack);
  char buf[200];
  std::snprintf(buf, sizeof(buf), "time (s): %.1f .. %.1f", t0, t1);
  text(img, buf, {left, height - 12}, 0.45, kBlack);
  std::snprintf(buf, sizeof(buf), "volume IoU vs the oracle (p >= %.2f), scenario %s",
                r.occupancy_threshold, r.scenario.c_str());
  text(img, buf, {left, 20}, 0.5, kBlack);
  const cv::Scalar body(200, 80, 0), skin(0, 100, 220);
  for (size_t i = 1; i < f.size(); ++i) {
    if (std::isfinite(f[i - 1]->body_iou) && std::isfinite(f[i]->body_iou))
      cv::line(img, px(f[i - 1]->time, f[i - 1]->body_iou), px(f[i]->time, f[i]->body_iou), body, 1, cv::LINE_AA);
    if (std::isfinite(f[i - 1]->skin_iou) && std::isfinite(f[i]->skin_iou))
      cv::line(img, px(f[i - 1]->time, f[i - 1]->skin_iou), px(f[i]->time, f[i]->skin_iou), skin, 1, cv::LINE_AA);
  }
  text(img, "body", {width - right - 80, top + 18}, 0.45, body);
  text(img, "skin", {width - right - 80, top + 36}, 0.45, skin);
  return cv::imwrite(path, img);
}

}  // namespace cvephands
