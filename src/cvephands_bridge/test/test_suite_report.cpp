// The scenario suite's aggregation (suite_report.h) on hand-made figures: median, worst decile
// (nearest rank, worst one below 10 scenarios), bar verdicts at and around the limits, failed
// and unmeasured scenarios, and the markdown report's tables.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "cvephands_bridge/eval/suite_report.h"

namespace {

using cvephands::Bar;
using cvephands::BarSet;
using cvephands::Better;
using cvephands::ScenarioFigures;
using cvephands::Statistic;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<double> range(int n, double first = 1.0) {  // first, first + 1, ... (shuffled)
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(first + ((i * 7) % n));
  return v;
}

// A scenario that meets every design bar.
ScenarioFigures good(const std::string& name) {
  ScenarioFigures f;
  f.name = name;
  f.script = "all";
  f.description = "hand-made " + name;
  f.empty_frames = 10;
  f.person_frames = 100;
  f.body_iou = 0.80, f.body_precision = 0.85, f.body_recall = 0.93, f.skin_iou = 0.40;
  f.hand_skin_mm = 6.0, f.hand_palm_mm = 9.0, f.head_mm = 10.0, f.head_aligned_mm = 4.0;
  f.tracked_fraction = 1.0, f.losses = 0, f.identity_switches = 0;
  f.false_targets_empty = 0, f.false_targets_person = 0;
  f.mesh_mm = 7.0, f.meshes = 10;
  f.psfs_ms = 50, f.mpf_ms = 1, f.wall_s = 10;
  return f;
}

const cvephands::BarVerdict& verdict(const std::vector<cvephands::BarVerdict>& v,
                                     const std::string& key, Statistic s) {
  for (const auto& x : v)
    if (x.bar.key == key && x.bar.statistic == s) return x;
  throw std::runtime_error("no bar " + key);
}

TEST(SuiteStatistics, MedianIsTheMiddleValueOrTheMeanOfTheTwoMiddleOnesAndSkipsNaN) {
  EXPECT_DOUBLE_EQ(cvephands::median({3, 1, 2}), 2.0);
  EXPECT_DOUBLE_EQ(cvephands::median({4, 1, 3, 2}), 2.5);
  EXPECT_DOUBLE_EQ(cvephands::median({kNaN, 1, 3}), 2.0);
  EXPECT_DOUBLE_EQ(cvephands::median({5}), 5.0);
  EXPECT_TRUE(std::isnan(cvephands::median({})));
  EXPECT_TRUE(std::isnan(cvephands::median({kNaN, kNaN})));
  // A failed value (+inf, e.g. a hand never tracked) is a value like any other: the worst.
  EXPECT_DOUBLE_EQ(cvephands::median({1, 2, kInf}), 2.0);
  EXPECT_EQ(cvephands::median({1, kInf}), kInf);
}

TEST(SuiteStatistics, WorstDecileIsTheWorstBelowTenScenariosThenTheNearestRank90thPercentile) {
  // Errors (lower is better): the (floor(n/10)+1)-th largest.
  EXPECT_DOUBLE_EQ(cvephands::worstDecile({4}, Better::kLower), 4.0);
  EXPECT_DOUBLE_EQ(cvephands::worstDecile(range(5), Better::kLower), 5.0);
  EXPECT_DOUBLE_EQ(cvephands::worstDecile(range(9), Better::kLower), 9.0);
  EXPECT_DOUBLE_EQ(cvephands::worstDecile(range(10), Better::kLower), 9.0);   // 2nd worst
  EXPECT_DOUBLE_EQ(cvephands::worstDecile(range(19), Better::kLower), 18.0);  // 2nd worst
  EXPECT_DOUBLE_EQ(cvephands::worstDecile(range(20), Better::kLower), 18.0);  // 3rd worst
  EXPECT_DOUBLE_EQ(cvephands::worstDecile(range(24), Better::kLower), 22.0);  // 3rd worst
  // IoU (higher is better): the 10th percentile, i.e. the (floor(n/10)+1)-th smallest.
  EXPECT_DOUBLE_EQ(cvephands::worstDecile(range(5), Better::kHigher), 1.0);
  EXPECT_DOUBLE_EQ(cvephands::worstDecile(range(10), Better::kHigher), 2.0);
  EXPECT_DOUBLE_EQ(cvephands::worstDecile(range(24), Better::kHigher), 3.0);
  // NaN (not measured) is left out; +inf (failed) is the worst error.
  EXPECT_DOUBLE_EQ(cvephands::worstDecile({1, kNaN, 3, 2}, Better::kLower), 3.0);
  EXPECT_EQ(cvephands::worstDecile({1, kInf, 2}, Better::kLower), kInf);
  EXPECT_TRUE(std::isnan(cvephands::worstDecile({kNaN}, Better::kLower)));
  EXPECT_DOUBLE_EQ(cvephands::worstValue(range(24), Better::kLower), 24.0);
  EXPECT_DOUBLE_EQ(cvephands::worstValue(range(24), Better::kHigher), 1.0);
}

TEST(SuiteSummary, FailedScenariosAreLeftOutAndUnmeasuredValuesAreNotCounted) {
  std::vector<ScenarioFigures> s = {good("a"), good("b"), good("c"),
                                    ScenarioFigures::failed("d", "all", "", "unknown scenario 'd'")};
  s[0].body_iou = 0.70, s[1].body_iou = 0.90;  // c: 0.80
  s[2].mesh_mm = kNaN;                          // meshes off in c
  const auto sums = cvephands::summarize(s);
  ASSERT_EQ(sums.size(), cvephands::suiteMeasures().size());
  for (const auto& m : sums) {
    if (m.key == "body_iou") {
      EXPECT_EQ(m.count, 3);
      EXPECT_DOUBLE_EQ(m.median, 0.80);
      EXPECT_DOUBLE_EQ(m.worst_decile, 0.70);
      EXPECT_DOUBLE_EQ(m.worst, 0.70);
    }
    if (m.key == "mesh_mm") {
      EXPECT_EQ(m.count, 2);
      EXPECT_DOUBLE_EQ(m.median, 7.0);
    }
  }
  EXPECT_FALSE(s[3].ran());
  EXPECT_EQ(s[3].error, "unknown scenario 'd'");
}

TEST(SuiteBars, DesignBarsPassAtTheLimitsAndFailJustBeyondThem) {
  // 10 scenarios: the worst decile is the second worst.
  std::vector<ScenarioFigures> s;
  for (int i = 0; i < 10; ++i) s.push_back(good("s" + std::to_string(i)));
  s[0].body_iou = 0.10;   // the worst one does not count for the worst decile...
  s[1].body_iou = 0.65;   // ...the second worst does: exactly at the limit passes
  s[0].hand_skin_mm = 50;
  s[1].hand_skin_mm = 12.0;
  s[0].losses = 3;        // one scenario with losses: the median still has none
  auto v = cvephands::checkBars(cvephands::summarize(s), cvephands::designBars());
  EXPECT_EQ(v.size(), cvephands::designBars().bars.size());
  EXPECT_TRUE(cvephands::allPass(v));
  EXPECT_DOUBLE_EQ(verdict(v, "body_iou", Statistic::kWorstDecile).value, 0.65);
  EXPECT_DOUBLE_EQ(verdict(v, "hand_skin_mm", Statistic::kWorstDecile).value, 12.0);

  s[1].body_iou = 0.649;  // just below the worst-decile bar
  s[2].hand_skin_mm = 12.5, s[1].hand_skin_mm = 12.5;
  s[3].false_targets_empty = 1;  // one false-target frame in one empty scene: "none" fails
  v = cvephands::checkBars(cvephands::summarize(s), cvephands::designBars());
  EXPECT_FALSE(verdict(v, "body_iou", Statistic::kWorstDecile).pass);
  EXPECT_TRUE(verdict(v, "body_iou", Statistic::kMedian).pass);
  EXPECT_FALSE(verdict(v, "hand_skin_mm", Statistic::kWorstDecile).pass);
  EXPECT_TRUE(verdict(v, "hand_skin_mm", Statistic::kMedian).pass);
  EXPECT_FALSE(verdict(v, "false_targets_empty", Statistic::kWorst).pass);
  EXPECT_TRUE(verdict(v, "losses", Statistic::kMedian).pass);
  EXPECT_FALSE(cvephands::allPass(v));

  // Losses in 6 of 10 scenarios: the median scenario has one.
  for (int i = 0; i < 6; ++i) s[i].losses = 1;
  v = cvephands::checkBars(cvephands::summarize(s), cvephands::designBars());
  EXPECT_FALSE(verdict(v, "losses", Statistic::kMedian).pass);
  EXPECT_DOUBLE_EQ(verdict(v, "losses", Statistic::kMedian).value, 1.0);
}

TEST(SuiteBars, NeverTrackedIsTheWorstAndAnUnmeasuredBarDoesNotPass) {
  std::vector<ScenarioFigures> s = {good("a"), good("b"), good("c")};
  s[2].hand_skin_mm = kInf;  // a hand visible but never tracked
  for (auto& f : s) f.mesh_mm = kNaN;  // meshes off everywhere
  const auto v = cvephands::checkBars(cvephands::summarize(s), cvephands::designBars());
  EXPECT_EQ(verdict(v, "hand_skin_mm", Statistic::kWorstDecile).value, kInf);
  EXPECT_FALSE(verdict(v, "hand_skin_mm", Statistic::kWorstDecile).pass);
  EXPECT_TRUE(verdict(v, "hand_skin_mm", Statistic::kMedian).pass);
  EXPECT_FALSE(verdict(v, "mesh_mm", Statistic::kMedian).measured);
  EXPECT_FALSE(verdict(v, "mesh_mm", Statistic::kMedian).pass);
}

TEST(SuiteBars, DesignBarsAreTheIssue15TableAndRegressionGuardsCoverEachOfThem) {
  const BarSet d = cvephands::designBars();
  auto limit = [](const BarSet& b, const std::string& key, Statistic s) {
    for (const Bar& x : b.bars)
      if (x.key == key && x.statistic == s) return x.limit;
    return kNaN;
  };
  EXPECT_EQ(limit(d, "body_iou", Statistic::kMedian), 0.75);
  EXPECT_EQ(limit(d, "body_iou", Statistic::kWorstDecile), 0.65);
  EXPECT_EQ(limit(d, "hand_skin_mm", Statistic::kMedian), 8.0);
  EXPECT_EQ(limit(d, "hand_skin_mm", Statistic::kWorstDecile), 12.0);
  EXPECT_EQ(limit(d, "head_mm", Statistic::kMedian), 12.0);
  EXPECT_EQ(limit(d, "head_mm", Statistic::kWorstDecile), 20.0);
  EXPECT_EQ(limit(d, "losses", Statistic::kMedian), 0.0);
  EXPECT_EQ(limit(d, "identity_switches", Statistic::kMedian), 0.0);
  EXPECT_EQ(limit(d, "false_targets_empty", Statistic::kWorst), 0.0);
  EXPECT_EQ(limit(d, "mesh_mm", Statistic::kMedian), 8.0);
  // Reported without bars.
  for (const Bar& b : d.bars) {
    EXPECT_NE(b.key, "skin_iou");
    EXPECT_NE(b.key, "hand_palm_mm");
    EXPECT_NE(b.key, "head_aligned_mm");
  }
  // The regression guards (--quick in CI) watch everything the design bars judge, with the
  // same statistic; where today's figures beat a design bar the guard may be the stricter one.
  const BarSet r = cvephands::regressionBars();
  for (const Bar& b : d.bars)
    EXPECT_FALSE(std::isnan(limit(r, b.key, b.statistic))) << cvephands::describeBar(b);
  EXPECT_EQ(cvephands::barSetByName("regression").name, "regression");
  EXPECT_THROW(cvephands::barSetByName("strict"), std::invalid_argument);
  EXPECT_EQ(cvephands::describeBar(d.bars[0]), "body IoU median >= 0.750");
}

TEST(SuiteReport, MarkdownHasARowPerScenarioTheSummaryTableVerdictsAndFailures) {
  std::vector<ScenarioFigures> s = {good("default"), good("random-7"),
                                    ScenarioFigures::failed("random-8", "all", "eight", "boom | bang")};
  s[1].body_iou = 0.60;
  s[1].hand_skin_mm = kInf;
  cvephands::ReportContext c;
  c.date = "2026-12-02";
  c.command_line = "scenario_suite --quick";
  c.git_revision = "abc1234";
  c.cpu_model = "Test CPU";
  c.cpu_cores = 2;
  c.isa = "AVX2";
  c.plots = {"suite_bars.png"};
  c.asserted = "regression";
  const std::string md = cvephands::markdownReport(s, cvephands::summarize(s), c);
  EXPECT_NE(md.find("- command: `scenario_suite --quick`"), std::string::npos);
  EXPECT_NE(md.find("abc1234"), std::string::npos);
  EXPECT_NE(md.find("Test CPU, 2 cores, AVX2"), std::string::npos);
  EXPECT_NE(md.find("| default | all | 10 / 100 | 0.800 |"), std::string::npos) << md;
  EXPECT_NE(md.find("hand-made random-7"), std::string::npos);
  EXPECT_NE(md.find("| never |"), std::string::npos);
  // The failed one: a row saying so (its '|' escaped) and the list of failures.
  EXPECT_NE(md.find("**failed to run:** boom \\| bang"), std::string::npos) << md;
  EXPECT_NE(md.find("## Scenarios that failed to run"), std::string::npos);
  EXPECT_NE(md.find("## Summary over 2 scenarios"), std::string::npos);
  EXPECT_NE(md.find("| body IoU | 2 | 0.700 | 0.600 | 0.600 |"), std::string::npos) << md;
  EXPECT_NE(md.find("## Bars: design (reported)"), std::string::npos);
  EXPECT_NE(md.find("## Bars: regression (asserted)"), std::string::npos);
  EXPECT_NE(md.find("| body IoU median >= 0.750 | 0.700 | FAIL |"), std::string::npos) << md;
  EXPECT_NE(md.find("| hand mesh to truth median <= 8.00 mm | 7.00 | PASS |"), std::string::npos) << md;
  EXPECT_NE(md.find("design bars: FAIL"), std::string::npos);
  EXPECT_NE(md.find("[suite_bars.png](suite_bars.png)"), std::string::npos);
}

TEST(SuiteReport, ValuesAreFormattedWithNotMeasuredAndNeverSpelledOut) {
  EXPECT_EQ(cvephands::formatValue(0.73149, 3), "0.731");
  EXPECT_EQ(cvephands::formatValue(12.26, 1), "12.3");
  EXPECT_EQ(cvephands::formatValue(kNaN, 1), "n/a");
  EXPECT_EQ(cvephands::formatValue(kInf, 1), "never");
}

}  // namespace
