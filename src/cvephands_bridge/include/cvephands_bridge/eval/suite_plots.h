// PNG plots of the scenario suite (OpenCV drawing, no plotting library): per-scenario bars of
// the measures that have design bars, with the bars' limits drawn, and a scenario's volume IoU
// over time. (A scenario's tracking error over time is TrackingEvaluator::writePlot.)
// Part of cvephands_eval.
#pragma once

#include <string>
#include <vector>

#include "cvephands_bridge/eval/suite_report.h"

namespace cvephands {

struct ScenarioEvalResult;

// One panel per measure (default: body IoU, hands vs visible skin, head absolute), one bar per
// scenario (a cross where it failed to run or was not measured, a red full bar for "never"), and
// a horizontal line per bar of each set on that measure (colour: the set, the first one green;
// solid: median, dashed: worst decile, dotted: worst). False if the file cannot be written.
bool writeSuiteBarsPlot(const std::string& path, const std::vector<ScenarioFigures>& scenarios,
                        const std::vector<BarSet>& bars,
                        const std::vector<std::string>& keys = {"body_iou", "hand_skin_mm", "head_mm"},
                        int width = 1000, int panel_height = 260);

// The upper-body (PAPF) figures per scenario: hands, head, elbows, shoulders (mean mm) and the
// tracked fraction, with bodyReferenceBars() drawn (for reference, not asserted). False if the
// file cannot be written.
bool writeBodyBarsPlot(const std::string& path, const std::vector<ScenarioFigures>& scenarios,
                       int width = 1000, int panel_height = 220);

// Body and skin IoU per person frame over time. False if nothing to plot or not written.
bool writeVolumeIoUPlot(const std::string& path, const ScenarioEvalResult& result, int width = 900,
                        int height = 360);

}  // namespace cvephands
