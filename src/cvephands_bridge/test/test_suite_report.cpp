// The scenario suite's aggregation (suite_report.h) on hand-made figures: median, worst decile
// (nearest rank, worst one below 10 scenarios), bar verdicts at and around the limits, failed
// and unmeasured scenarios, and the markdown report's tables.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cvephands_bridge/eval/scenario_evaluation.h"
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
  f.body_hand_mm = 20, f.body_head_mm = 12, f.body_elbow_mm = 35, f.body_shoulder_mm = 30;
  f.body_hand_max_mm = 60, f.body_head_max_mm = 25;
  f.body_upper_arm_deg = 8, f.body_forearm_deg = 11, f.body_elbow_flex_deg = 9;
  f.body_tracked_fraction = 1.0, f.body_untracked_frames = 0, f.body_starts = 1;
  f.body_restarts = 0, f.body_losses = 0, f.body_false_frames_empty = 0, f.papf_ms = 25;
  f.body_volume_iou = 0.78, f.body_volume_precision = 0.85, f.body_volume_recall = 0.90;
  return f;
}

const cvephands::MeasureSummary& summaryOf(const std::vector<cvephands::MeasureSummary>& v,
                                           const std::string& key) {
  for (const auto& m : v)
    if (m.key == key) return m;
  throw std::runtime_error("no summary " + key);
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

TEST(SuiteBody, BodyMeasuresAggregateMedianAndWorstDecileWithMissingAndNeverTrackedValues) {
  // 10 scenarios with the PAPF, one where it was off (--no-body style: NaN), one failed.
  std::vector<ScenarioFigures> s;
  for (int i = 0; i < 10; ++i) {
    s.push_back(good("s" + std::to_string(i)));
    s[i].body_head_mm = 10.0 + i;           // 10 .. 19
    s[i].body_elbow_mm = 30.0 + 10.0 * i;   // 30 .. 120
    s[i].body_tracked_fraction = 1.0 - 0.05 * i;  // 1.00 .. 0.55
    s[i].body_restarts = i >= 8 ? 3 : 0;
  }
  s[9].body_hand_mm = kInf;  // the person there, never a pose: the worst
  ScenarioFigures off = good("off");
  off.body_hand_mm = off.body_head_mm = off.body_elbow_mm = off.body_shoulder_mm = kNaN;
  off.body_upper_arm_deg = off.body_forearm_deg = off.body_elbow_flex_deg = kNaN;
  off.body_tracked_fraction = off.body_untracked_frames = off.body_starts = kNaN;
  off.body_restarts = off.body_losses = off.body_false_frames_empty = off.papf_ms = kNaN;
  off.body_volume_iou = off.body_volume_precision = off.body_volume_recall = kNaN;
  EXPECT_FALSE(off.bodyRan());
  EXPECT_TRUE(off.ran());
  s.push_back(off);
  s.push_back(ScenarioFigures::failed("f", "all", "", "boom"));
  const auto sums = cvephands::summarize(s);
  // Head: 10 values (the PAPF-off and the failed one left out); median of 14 and 15; worst
  // decile of 10 = the second worst.
  EXPECT_EQ(summaryOf(sums, "body_head_mm").count, 10);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_head_mm").median, 14.5);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_head_mm").worst_decile, 18.0);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_head_mm").worst, 19.0);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_elbow_mm").median, 75.0);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_elbow_mm").worst_decile, 110.0);
  EXPECT_EQ(summaryOf(sums, "body_forearm_deg").count, 10);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_forearm_deg").median, 11.0);
  // Tracked fraction: higher is better, the worst decile is the second lowest.
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_tracked_fraction").worst_decile, 0.60);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_tracked_fraction").worst, 0.55);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_restarts").median, 0.0);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_restarts").worst_decile, 3.0);
  // Never tracked in one of 10: the worst, and the worst decile is the second worst (finite).
  EXPECT_EQ(summaryOf(sums, "body_hand_mm").worst, kInf);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_hand_mm").worst_decile, 20.0);
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_hand_mm").median, 20.0);
  // Every body key is a suite measure; the reference bars are issue 16's and are neither
  // design bars nor asserted regression guards beyond what regressionBars() lists.
  for (const std::string& k : cvephands::bodyMeasureKeys()) EXPECT_NO_THROW(cvephands::measureDef(k));
  const BarSet ref = cvephands::bodyReferenceBars();
  ASSERT_EQ(ref.bars.size(), 5u);
  EXPECT_EQ(cvephands::describeBar(ref.bars[0]), "PAPF hands vs palm + fingers centroid median <= 16.0 mm");
  EXPECT_EQ(cvephands::describeBar(ref.bars[4]), "body IoU, body/volume (model prior) worst decile >= 0.650");
  EXPECT_DOUBLE_EQ(summaryOf(sums, "body_volume_iou").median, 0.78);
  EXPECT_EQ(summaryOf(sums, "body_volume_iou").count, 10);
  const std::vector<std::string> keys = cvephands::bodyMeasureKeys();
  for (const Bar& b : cvephands::designBars().bars)
    EXPECT_EQ(std::find(keys.begin(), keys.end(), b.key), keys.end()) << b.key;
  EXPECT_THROW(cvephands::barSetByName("issue16"), std::invalid_argument);
  // The regression set: loose floors on three PAPF medians and on body/volume's IoU (median and
  // worst decile) when it ran, none without it.
  int floors = 0;
  for (const Bar& b : cvephands::regressionBars(true).bars)
    if (std::find(keys.begin(), keys.end(), b.key) != keys.end()) {
      ++floors;
      if (b.key != "body_volume_iou") {
        EXPECT_EQ(b.statistic, Statistic::kMedian) << b.key;
      }
    }
  EXPECT_EQ(floors, 5);
  for (const Bar& b : cvephands::regressionBars(false).bars)
    EXPECT_EQ(std::find(keys.begin(), keys.end(), b.key), keys.end()) << b.key;
  EXPECT_EQ(cvephands::regressionBars(false).bars.size() + 5, cvephands::regressionBars().bars.size());
}

TEST(SuiteBody, MarkdownHasTheUpperBodySectionOrSaysThePapfDidNotRun) {
  std::vector<ScenarioFigures> s = {good("default"), good("random-7"),
                                    ScenarioFigures::failed("random-8", "all", "eight", "boom")};
  s[1].body_hand_mm = 250.0, s[1].body_head_mm = kInf, s[1].body_starts = 4, s[1].body_restarts = 3;
  s[1].body_tracked_fraction = 0.5, s[1].body_untracked_frames = 50;
  cvephands::ReportContext c;
  const std::string md = cvephands::markdownReport(s, cvephands::summarize(s), c);
  EXPECT_NE(md.find("## Upper body (PAPF)"), std::string::npos) << md;
  EXPECT_NE(md.find("| default | all | 0.780 | 1.000 | 0 | 1 | 0 | 0 | 20.0 | 60.0 | 12.0 | 25.0 | 35.0 | 30.0 | "
                    "8.0 | 11.0 | 9.0 | 25.0 |"),
            std::string::npos) << md;
  EXPECT_NE(md.find("| random-7 | all | 0.780 | 0.500 | 50 | 4 | 0 | 0 | 250.0 | 60.0 | never |"), std::string::npos) << md;
  EXPECT_NE(md.find("| random-8 | all | - |"), std::string::npos);
  EXPECT_NE(md.find("Over 2 scenarios with the PAPF"), std::string::npos) << md;
  // Suite statistics of the body measures (2 values: median = their mean, worst = worst decile).
  EXPECT_NE(md.find("| PAPF hands vs palm + fingers centroid (mm) | 2 | 135.0 | 250.0 | 250.0 |"),
            std::string::npos) << md;
  EXPECT_NE(md.find("| PAPF head centre (mm) | 2 | never | never | never |"), std::string::npos) << md;
  EXPECT_NE(md.find("| PAPF tracked fraction | 2 | 0.750 | 0.500 | 0.500 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| PAPF elbow flexion (deg) | 2 | 9.0 | 9.0 | 9.0 |"), std::string::npos) << md;
  // The reference bars: reported with a verdict, never asserted.
  EXPECT_NE(md.find("| PAPF head centre median <= 15.0 mm | never | FAIL |"), std::string::npos) << md;
  EXPECT_NE(md.find("| PAPF elbows median <= 25.0 mm | 35.0 | FAIL |"), std::string::npos) << md;
  // ...and only there: the pipeline's summary table does not repeat them.
  const size_t body = md.find("## Upper body (PAPF)");
  EXPECT_EQ(md.rfind("| PAPF elbows (mm) |", body), std::string::npos);

  // The PAPF off everywhere (--no-body): a line says so, no table.
  for (auto& f : s) {
    f.body_hand_mm = f.body_head_mm = f.body_elbow_mm = f.body_shoulder_mm = kNaN;
    f.body_upper_arm_deg = f.body_forearm_deg = f.body_elbow_flex_deg = kNaN;
    f.body_tracked_fraction = kNaN;
    f.body_volume_iou = f.body_volume_precision = f.body_volume_recall = kNaN;
  }
  c.asserted = "regression";
  const std::string off = cvephands::markdownReport(s, cvephands::summarize(s), c);
  EXPECT_NE(off.find("## Upper body (PAPF)\n\nThe PAPF did not run"), std::string::npos) << off;
  EXPECT_EQ(off.find("Over 2 scenarios with the PAPF"), std::string::npos);
  // ...and the asserted regression set has no PAPF floor to fail as "not measured".
  EXPECT_EQ(off.find("PAPF head centre median"), std::string::npos) << off;
  EXPECT_NE(off.find("regression bars: all PASS"), std::string::npos) << off;
}

TEST(SuiteBody, ArmAngleErrorsAreBoneDirectionsAndTheElbowFlexionInDegrees) {
  using Eigen::Vector3d;
  const Vector3d s(0.17, -0.5, 0.4), e = s + Vector3d(0, 0, -0.29), w = e + Vector3d(0, -0.26, 0);
  // The same arm: no error.
  cvephands::ArmAngleErrors a = cvephands::armAngleErrors(s, e, w, s, e, w);
  EXPECT_NEAR(a.upper_arm_deg, 0.0, 1e-9);
  EXPECT_NEAR(a.forearm_deg, 0.0, 1e-9);
  EXPECT_NEAR(a.elbow_flex_deg, 0.0, 1e-9);
  // The whole arm swung 30 degrees about the shoulder (x axis), and moved 5 cm: both bones 30
  // degrees off, the flexion (90 degrees) the same; lengths and position do not matter.
  const Eigen::AngleAxisd r(30.0 * M_PI / 180.0, Vector3d::UnitX());
  const Vector3d off(0.05, 0, 0);
  const Vector3d e2 = s + off + 1.1 * (r * (e - s));
  a = cvephands::armAngleErrors(s + off, e2, e2 + 0.9 * (r * (w - e)), s, e, w);
  EXPECT_NEAR(a.upper_arm_deg, 30.0, 1e-9);
  EXPECT_NEAR(a.forearm_deg, 30.0, 1e-9);
  EXPECT_NEAR(a.elbow_flex_deg, 0.0, 1e-9);
  // A straight arm against the bent truth: the upper arm right, the forearm and flexion 90 off.
  a = cvephands::armAngleErrors(s, e, e + Vector3d(0, 0, -0.26), s, e, w);
  EXPECT_NEAR(a.upper_arm_deg, 0.0, 1e-9);
  EXPECT_NEAR(a.forearm_deg, 90.0, 1e-9);
  EXPECT_NEAR(a.elbow_flex_deg, 90.0, 1e-9);
  // A truth without joints (no person) or a zero-length bone is not scored.
  const Vector3d nan = Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  a = cvephands::armAngleErrors(s, e, w, nan, nan, nan);
  EXPECT_TRUE(std::isnan(a.upper_arm_deg) && std::isnan(a.forearm_deg) && std::isnan(a.elbow_flex_deg));
  a = cvephands::armAngleErrors(s, s, w, s, e, w);
  EXPECT_TRUE(std::isnan(a.upper_arm_deg));
  EXPECT_TRUE(std::isnan(a.elbow_flex_deg));
}

TEST(SuiteReport, ValuesAreFormattedWithNotMeasuredAndNeverSpelledOut) {
  EXPECT_EQ(cvephands::formatValue(0.73149, 3), "0.731");
  EXPECT_EQ(cvephands::formatValue(12.26, 1), "12.3");
  EXPECT_EQ(cvephands::formatValue(kNaN, 1), "n/a");
  EXPECT_EQ(cvephands::formatValue(kInf, 1), "never");
}

}  // namespace
