#include "cvephands_bridge/eval/suite_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "cvephands_bridge/eval/scenario_evaluation.h"

namespace cvephands {
namespace {

constexpr double kNaN = ScenarioFigures::kNaN;

std::vector<double> measured(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return std::isnan(x); }), v.end());
  return v;
}

// Best first.
std::vector<double> sortedBestFirst(std::vector<double> v, Better better) {
  v = measured(std::move(v));
  if (better == Better::kHigher)
    std::sort(v.begin(), v.end(), [](double a, double b) { return a > b; });
  else
    std::sort(v.begin(), v.end());
  return v;
}

std::string cell(const std::string& s) {  // a markdown table cell: no '|' or line breaks
  std::string out;
  for (char c : s) {
    if (c == '|') out += "\\|";
    else if (c == '\n' || c == '\r') out += ' ';
    else out += c;
  }
  return out;
}

std::string fmt(double v, int decimals) { return formatValue(v, decimals); }

std::string verdictTable(const std::vector<MeasureSummary>& summaries, const BarSet& set) {
  std::string s = "| bar | value | verdict |\n|---|---:|---|\n";
  for (const BarVerdict& v : checkBars(summaries, set)) {
    const MeasureDef& d = measureDef(v.bar.key);
    s += "| " + describeBar(v.bar) + " | " + fmt(v.value, d.decimals) + " | " +
         (v.pass ? "PASS" : (v.measured ? "FAIL" : "FAIL (not measured)")) + " |\n";
  }
  return s;
}

// The upper-body (PAPF) section: per scenario, the suite's statistics, the reference bars.
std::string bodySection(const std::vector<ScenarioFigures>& scenarios,
                        const std::vector<MeasureSummary>& summaries) {
  std::string s = "\n## Upper body (PAPF)\n\n";
  int ran = 0;
  for (const ScenarioFigures& f : scenarios) ran += f.bodyRan();
  if (ran == 0) return s + "The PAPF did not run (`--no-body`, or no scenario ran).\n";
  s += "The upper-body tracker (body_tracking's PAPF, seeded with the scenario seed) on the same "
       "body and skin volumes, scored as test_papf_sim scores it: on the person frames with a "
       "pose reported, hands (the estimate's hands vs the palm + fingers centroid), head centre, "
       "elbows and shoulders, both sides pooled, mean mm; the arms' angle errors (upper-arm and "
       "forearm directions, elbow flexion; from the joint positions), mean degrees; `never` = "
       "the person there for a "
       "second or more and no pose ever reported. Untracked: person frames without a pose "
       "(before the first start, or after a loss); starts include the first; losses: the pose "
       "dropped with the person there; empty: empty-scene frames with a pose. No design bar, "
       "and the CI subset asserts no more than loose regression floors (medians of head, hands "
       "and tracked fraction, about twice today's figures): the PAPF generalises "
       "poorly to generated scenarios today (arms fold into the trunk; docs/benchmarks.md, "
       "\"PAPF upper-body tracker\"), and these figures show it. Body/volume: the body volume "
       "the body tracker publishes (the pSfS body volume with the tracked model as a prior, "
       "body_tracking/model_prior.h: less phantom volume), IoU against the oracle as for the "
       "body IoU above.\n\n";
  s += "| scenario | script | body/volume IoU | tracked | untracked | starts | losses | empty | "
       "hands | hands max | head | head max | elbows | shoulders | upper arms deg | forearms deg | "
       "elbow flexion deg | PAPF ms |\n";
  s += "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const ScenarioFigures& f : scenarios) {
    s += "| " + cell(f.name) + " | " + cell(f.script) + " | ";
    if (!f.ran()) {
      s += "- | - | - | - | - | - | - | - | - | - | - | - | - | - | - | **failed to run** |\n";
      continue;
    }
    s += fmt(f.body_volume_iou, 3) + " | " + fmt(f.body_tracked_fraction, 3) + " | " +
         fmt(f.body_untracked_frames, 0) + " | " +
         fmt(f.body_starts, 0) + " | " + fmt(f.body_losses, 0) + " | " +
         fmt(f.body_false_frames_empty, 0) + " | " + fmt(f.body_hand_mm, 1) + " | " +
         fmt(f.body_hand_max_mm, 1) + " | " + fmt(f.body_head_mm, 1) + " | " +
         fmt(f.body_head_max_mm, 1) + " | " + fmt(f.body_elbow_mm, 1) + " | " +
         fmt(f.body_shoulder_mm, 1) + " | " + fmt(f.body_upper_arm_deg, 1) + " | " +
         fmt(f.body_forearm_deg, 1) + " | " + fmt(f.body_elbow_flex_deg, 1) + " | " +
         fmt(f.papf_ms, 1) + " |\n";
  }
  s += "\nOver " + std::to_string(ran) + " scenarios with the PAPF:\n\n";
  s += "| measure | scenarios | median | worst decile | worst |\n|---|---:|---:|---:|---:|\n";
  for (const std::string& key : bodyMeasureKeys())
    for (const MeasureSummary& m : summaries) {
      if (m.key != key) continue;
      const MeasureDef& d = measureDef(m.key);
      const std::string unit = *d.unit ? std::string(" (") + d.unit + ")" : std::string();
      s += "| " + std::string(d.label) + unit + " | " + std::to_string(m.count) + " | " +
           fmt(m.median, d.decimals) + " | " + fmt(m.worst_decile, d.decimals) + " | " +
           fmt(m.worst, d.decimals) + " |\n";
    }
  const BarSet ref = bodyReferenceBars();
  s += "\n" + ref.note + "\n\n" + verdictTable(summaries, ref);
  return s;
}

}  // namespace

// ---- per-scenario figures -----------------------------------------------------------------

ScenarioFigures ScenarioFigures::of(const ScenarioEvalResult& r) {
  ScenarioFigures f;
  f.name = r.scenario;
  f.script = r.script;
  f.description = r.description;
  f.empty_frames = r.empty_frames;
  f.person_frames = r.person_frames;
  if (r.body_iou.count()) {
    f.body_iou = r.body_iou.mean(), f.body_iou_min = r.body_iou.min();
    f.skin_iou = r.skin_iou.mean(), f.skin_iou_min = r.skin_iou.min();
  }
  if (r.body_precision.count()) f.body_precision = r.body_precision.mean();
  if (r.body_recall.count()) f.body_recall = r.body_recall.mean();
  f.hand_skin_mm = r.handErrorMeanMm(0);
  f.hand_skin_max_mm = r.handErrorMaxMm(0);
  f.hand_palm_mm = r.handErrorMeanMm(1);
  f.head_mm = r.headErrorMeanMm();
  f.head_max_mm = r.headErrorMaxMm();
  f.head_aligned_mm = r.headAlignedErrorMeanMm();
  f.tracked_fraction = r.trackedFraction();
  if (r.person_frames > 0) {
    f.losses = r.losses();
    f.identity_switches = r.identitySwitches();
    f.false_targets_person = r.false_target_frames_person;
  }
  if (r.empty_frames > 0) f.false_targets_empty = r.false_target_frames_empty;
  f.meshes = static_cast<int>(r.meshes.size());
  if (r.mesh_to_truth_mm.count())
    f.mesh_mm = r.mesh_to_truth_mm.mean(), f.mesh_max_mm = r.mesh_to_truth_mm.max();
  if (r.psfs_ms.count()) f.psfs_ms = r.psfs_ms.mean(), f.mpf_ms = r.mpf_ms.mean();
  f.wall_s = r.wall_s;
  const BodyTrackingFigures& b = r.body;
  if (b.ran) {
    f.body_hand_mm = b.meanError(b.hand_mm);
    f.body_head_mm = b.meanError(b.head_mm);
    f.body_elbow_mm = b.meanError(b.elbow_mm);
    f.body_shoulder_mm = b.meanError(b.shoulder_mm);
    f.body_upper_arm_deg = b.meanError(b.upper_arm_deg);
    f.body_forearm_deg = b.meanError(b.forearm_deg);
    f.body_elbow_flex_deg = b.meanError(b.elbow_flex_deg);
    if (b.hand_mm.count()) f.body_hand_max_mm = b.hand_mm.max();
    if (b.head_mm.count()) f.body_head_max_mm = b.head_mm.max();
    f.body_tracked_fraction = b.trackedFraction();
    if (b.person_frames > 0) {
      f.body_untracked_frames = b.untrackedFrames();
      f.body_losses = b.losses;
    }
    f.body_starts = b.starts;
    f.body_restarts = b.restarts();
    if (r.empty_frames > 0) f.body_false_frames_empty = b.empty_tracked_frames;
    if (b.papf_ms.count()) f.papf_ms = b.papf_ms.mean();
    if (b.volume_iou.count()) f.body_volume_iou = b.volume_iou.mean();
    if (b.volume_precision.count()) f.body_volume_precision = b.volume_precision.mean();
    if (b.volume_recall.count()) f.body_volume_recall = b.volume_recall.mean();
  }
  return f;
}

ScenarioFigures ScenarioFigures::failed(const std::string& name, const std::string& script,
                                        const std::string& description, const std::string& error) {
  ScenarioFigures f;
  f.name = name;
  f.script = script;
  f.description = description;
  f.error = error.empty() ? "unknown error" : error;
  return f;
}

// ---- measures and statistics --------------------------------------------------------------

const std::vector<MeasureDef>& suiteMeasures() {
  using F = ScenarioFigures;
  static const std::vector<MeasureDef> defs = {
      {"body_iou", "body IoU", "", Better::kHigher, &F::body_iou, 3},
      {"body_precision", "body precision", "", Better::kHigher, &F::body_precision, 3},
      {"body_recall", "body recall", "", Better::kHigher, &F::body_recall, 3},
      {"skin_iou", "skin IoU", "", Better::kHigher, &F::skin_iou, 3},
      {"hand_skin_mm", "hands vs visible-skin centroid", "mm", Better::kLower, &F::hand_skin_mm, 1},
      {"hand_palm_mm", "hands vs palm + fingers centroid", "mm", Better::kLower, &F::hand_palm_mm, 1},
      {"head_mm", "head centre, absolute", "mm", Better::kLower, &F::head_mm, 1},
      {"head_aligned_mm", "head centre, aligned", "mm", Better::kLower, &F::head_aligned_mm, 1},
      {"tracked_fraction", "tracked fraction", "", Better::kHigher, &F::tracked_fraction, 3},
      {"losses", "track losses", "", Better::kLower, &F::losses, 1},
      {"identity_switches", "identity switches", "", Better::kLower, &F::identity_switches, 1},
      {"false_targets_empty", "false-target frames, empty scene", "", Better::kLower,
       &F::false_targets_empty, 1},
      {"false_targets_person", "false-target frames, with person", "", Better::kLower,
       &F::false_targets_person, 1},
      {"mesh_mm", "hand mesh to truth", "mm", Better::kLower, &F::mesh_mm, 2},
      {"body_volume_iou", "body IoU, body/volume (model prior)", "", Better::kHigher,
       &F::body_volume_iou, 3},
      {"body_volume_precision", "body precision, body/volume", "", Better::kHigher,
       &F::body_volume_precision, 3},
      {"body_volume_recall", "body recall, body/volume", "", Better::kHigher,
       &F::body_volume_recall, 3},
      {"body_hand_mm", "PAPF hands vs palm + fingers centroid", "mm", Better::kLower,
       &F::body_hand_mm, 1},
      {"body_head_mm", "PAPF head centre", "mm", Better::kLower, &F::body_head_mm, 1},
      {"body_elbow_mm", "PAPF elbows", "mm", Better::kLower, &F::body_elbow_mm, 1},
      {"body_shoulder_mm", "PAPF shoulders", "mm", Better::kLower, &F::body_shoulder_mm, 1},
      {"body_upper_arm_deg", "PAPF upper-arm direction", "deg", Better::kLower,
       &F::body_upper_arm_deg, 1},
      {"body_forearm_deg", "PAPF forearm direction", "deg", Better::kLower, &F::body_forearm_deg, 1},
      {"body_elbow_flex_deg", "PAPF elbow flexion", "deg", Better::kLower, &F::body_elbow_flex_deg, 1},
      {"body_tracked_fraction", "PAPF tracked fraction", "", Better::kHigher,
       &F::body_tracked_fraction, 3},
      {"body_untracked_frames", "PAPF person frames without a pose", "", Better::kLower,
       &F::body_untracked_frames, 1},
      {"body_restarts", "PAPF restarts", "", Better::kLower, &F::body_restarts, 1},
      {"body_losses", "PAPF losses", "", Better::kLower, &F::body_losses, 1},
      {"body_false_frames_empty", "PAPF frames tracked in the empty scene", "", Better::kLower,
       &F::body_false_frames_empty, 1},
  };
  return defs;
}

const MeasureDef& measureDef(const std::string& key) {
  for (const MeasureDef& d : suiteMeasures())
    if (key == d.key) return d;
  throw std::invalid_argument("unknown suite measure '" + key + "'");
}

double median(std::vector<double> v) {
  v = measured(std::move(v));
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  if (n % 2) return v[n / 2];
  const double a = v[n / 2 - 1], b = v[n / 2];
  if (std::isinf(a) || std::isinf(b)) return a == b ? a : (std::isinf(a) ? a : b);
  return 0.5 * (a + b);
}

double worstDecile(std::vector<double> v, Better better) {
  v = sortedBestFirst(std::move(v), better);
  if (v.empty()) return kNaN;
  // Nearest rank: the ceil(0.9 n)-th best = the (n / 10 + 1)-th worst (integer arithmetic, so
  // that n = 10 gives the 9th best and not, through 0.9 * 10 = 9.000000000000002, the 10th).
  return v[v.size() - 1 - v.size() / 10];
}

double worstValue(std::vector<double> v, Better better) {
  v = sortedBestFirst(std::move(v), better);
  return v.empty() ? kNaN : v.back();
}

std::vector<MeasureSummary> summarize(const std::vector<ScenarioFigures>& scenarios) {
  std::vector<MeasureSummary> out;
  for (const MeasureDef& d : suiteMeasures()) {
    std::vector<double> v;
    for (const ScenarioFigures& s : scenarios)
      if (s.ran()) v.push_back(s.*d.field);
    MeasureSummary m;
    m.key = d.key;
    m.count = static_cast<int>(measured(v).size());
    m.median = median(v);
    m.worst_decile = worstDecile(v, d.better);
    m.worst = worstValue(v, d.better);
    out.push_back(m);
  }
  return out;
}

const char* statisticName(Statistic s) {
  switch (s) {
    case Statistic::kMedian: return "median";
    case Statistic::kWorstDecile: return "worst decile";
    case Statistic::kWorst: return "worst";
  }
  return "?";
}

// ---- bars ---------------------------------------------------------------------------------

BarSet designBars() {
  BarSet b;
  b.name = "design";
  b.note = "DESIGN.md section 6 / issue 15: accuracy over the scenario suite.";
  b.bars = {
      {"body_iou", Statistic::kMedian, 0.75},
      {"body_iou", Statistic::kWorstDecile, 0.65},
      {"hand_skin_mm", Statistic::kMedian, 8.0},
      {"hand_skin_mm", Statistic::kWorstDecile, 12.0},
      {"head_mm", Statistic::kMedian, 12.0},
      {"head_mm", Statistic::kWorstDecile, 20.0},
      {"losses", Statistic::kMedian, 0.0},
      {"identity_switches", Statistic::kMedian, 0.0},
      {"false_targets_empty", Statistic::kWorst, 0.0},
      {"mesh_mm", Statistic::kMedian, 8.0},
  };
  return b;
}

// REGRESSION GUARDS, not the design bars (those are reported on every run, whatever is
// asserted). Floors a little below what `scenario_suite --quick` measured when they were set
// (2026-12-02: the default scenario on 4 scripts, before the scenario generator;
// docs/benchmarks.md, "Scenario suite"): they catch a change that makes the pipeline worse
// than it was, while today's pipeline still misses several design bars. The figures are
// deterministic (the same on every machine and ISA), so the margins are not for noise: they
// leave room for harmless changes. Raise them when the pipeline improves; re-measure them when
// the quick subset changes. Measured on the quick subset of 2026-12-03 (default x2, cuffs,
// four_cameras, lights_on, random-5; the worst values come from random-5 unless noted), after
// the intensity classifier and the head model (2026-12-02's figures in brackets).
namespace regression {
constexpr double kBodyIouMedian = 0.62;          // measured 0.653 (0.646)
constexpr double kBodyIouWorstDecile = 0.55;     // measured 0.575 (0.580; default, fold_hands)
constexpr double kSkinIouMedian = 0.24;          // measured 0.255 (0.282; no design bar: a guard)
constexpr double kHandSkinMmMedian = 10.0;       // measured 8.4 (9.1)
constexpr double kHandSkinMmWorstDecile = 24.0;  // measured 21.0 (22.3)
constexpr double kHeadMmMedian = 10.0;           // measured 8.0 (10.1; design bar 12)
constexpr double kHeadMmWorstDecile = 14.0;      // measured 12.2 (37.3; design bar 20)
constexpr double kMeshMmMedian = 11.0;  // measured 9.90 (13.86 before the desk clip and keep radius)
// The PAPF (issue 16 item 4; 2026-12-03, the same subset: head 8.5-16.9 mm on the five default-
// person runs, 36.5 on random-5; hands 15.3-25.1, 183 on random-5; tracked in every person
// frame). LOOSE FLOORS on medians only, about twice today's figures: the PAPF generalises
// poorly (an arm folds into the trunk on generated scenarios, random-5 here; docs/benchmarks.md)
// and its worst cases are chaotic (a different random draw folds a different arm), so no
// worst-decile guard and no floor on elbows or shoulders; these catch a broken link (wrong
// volumes, frames or truth) or a tracker that no longer starts, not a few millimetres.
constexpr double kBodyHeadMmMedian = 20.0;         // measured 9.0
constexpr double kBodyHandMmMedian = 40.0;         // measured 19.2
constexpr double kBodyTrackedFractionMedian = 0.9; // measured 1.000
// body/volume, the body volume with the PAPF's model as a prior (2026-12-05, the same subset):
// its IoU depends on the PAPF's fit, so a wider margin than the hull's own guards.
constexpr double kBodyVolumeIouMedian = 0.75;       // measured 0.795
constexpr double kBodyVolumeIouWorstDecile = 0.60;  // measured 0.655 (random-5)
}  // namespace regression

BarSet regressionBars(bool body) {
  using namespace regression;
  BarSet b;
  b.name = "regression";
  b.note = "Regression guards for --quick (a little below its figures when they were set), not "
           "the design bars.";
  b.bars = {
      {"body_iou", Statistic::kMedian, kBodyIouMedian},
      {"body_iou", Statistic::kWorstDecile, kBodyIouWorstDecile},
      {"skin_iou", Statistic::kMedian, kSkinIouMedian},
      {"hand_skin_mm", Statistic::kMedian, kHandSkinMmMedian},
      {"hand_skin_mm", Statistic::kWorstDecile, kHandSkinMmWorstDecile},
      {"head_mm", Statistic::kMedian, kHeadMmMedian},
      {"head_mm", Statistic::kWorstDecile, kHeadMmWorstDecile},
      // No loss or switch in the median scenario and no false target in an empty scene hold
      // today (none at all in the subset): kept as the design states them.
      {"losses", Statistic::kMedian, 0.0},
      {"identity_switches", Statistic::kMedian, 0.0},
      {"false_targets_empty", Statistic::kWorst, 0.0},
      {"mesh_mm", Statistic::kMedian, kMeshMmMedian},
  };
  if (body) {
    b.bars.push_back({"body_head_mm", Statistic::kMedian, kBodyHeadMmMedian});
    b.bars.push_back({"body_hand_mm", Statistic::kMedian, kBodyHandMmMedian});
    b.bars.push_back({"body_tracked_fraction", Statistic::kMedian, kBodyTrackedFractionMedian});
    b.bars.push_back({"body_volume_iou", Statistic::kMedian, kBodyVolumeIouMedian});
    b.bars.push_back({"body_volume_iou", Statistic::kWorstDecile, kBodyVolumeIouWorstDecile});
  }
  return b;
}

BarSet bodyReferenceBars() {
  BarSet b;
  b.name = "issue16";
  b.note = "Issue 16's PAPF bars (set for the mean over one sequence; here on the suite median) "
           "and the design's body IoU bars applied to body/volume, for reference: reported, never "
           "asserted. The PAPF generalises poorly to generated scenarios today (docs/benchmarks.md, "
           "\"PAPF upper-body tracker\").";
  b.bars = {
      {"body_hand_mm", Statistic::kMedian, 16.0},
      {"body_head_mm", Statistic::kMedian, 15.0},
      {"body_elbow_mm", Statistic::kMedian, 25.0},
      {"body_volume_iou", Statistic::kMedian, 0.75},
      {"body_volume_iou", Statistic::kWorstDecile, 0.65},
  };
  return b;
}

std::vector<std::string> bodyMeasureKeys() {
  return {"body_volume_iou", "body_volume_precision", "body_volume_recall",
          "body_hand_mm",          "body_head_mm",  "body_elbow_mm", "body_shoulder_mm",
          "body_upper_arm_deg",    "body_forearm_deg", "body_elbow_flex_deg",
          "body_tracked_fraction", "body_untracked_frames", "body_restarts", "body_losses",
          "body_false_frames_empty"};
}

BarSet barSetByName(const std::string& name) {
  if (name == "design") return designBars();
  if (name == "regression") return regressionBars();
  throw std::invalid_argument("unknown bar set '" + name + "' (valid: design, regression)");
}

std::vector<BarVerdict> checkBars(const std::vector<MeasureSummary>& summaries, const BarSet& bars) {
  std::vector<BarVerdict> out;
  for (const Bar& bar : bars.bars) {
    const MeasureDef& d = measureDef(bar.key);
    BarVerdict v;
    v.bar = bar;
    for (const MeasureSummary& m : summaries) {
      if (m.key != bar.key) continue;
      v.value = bar.statistic == Statistic::kMedian        ? m.median
                : bar.statistic == Statistic::kWorstDecile ? m.worst_decile
                                                           : m.worst;
    }
    v.measured = !std::isnan(v.value);
    v.pass = v.measured && (d.better == Better::kHigher ? v.value >= bar.limit : v.value <= bar.limit);
    out.push_back(v);
  }
  return out;
}

bool allPass(const std::vector<BarVerdict>& verdicts) {
  for (const BarVerdict& v : verdicts)
    if (!v.pass) return false;
  return true;
}

std::string describeBar(const Bar& bar) {
  const MeasureDef& d = measureDef(bar.key);
  std::string s = std::string(d.label) + " " + statisticName(bar.statistic) +
                  (d.better == Better::kHigher ? " >= " : " <= ") + fmt(bar.limit, d.decimals);
  if (*d.unit) s += std::string(" ") + d.unit;
  return s;
}

std::string formatValue(double v, int decimals) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return "never";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
  return buf;
}

// ---- the report ---------------------------------------------------------------------------

std::string markdownReport(const std::vector<ScenarioFigures>& scenarios,
                           const std::vector<MeasureSummary>& summaries, const ReportContext& c) {
  std::string s;
  int ran = 0;
  for (const ScenarioFigures& f : scenarios) ran += f.ran();
  s += "# " + c.title + "\n\n";
  s += "- date: " + c.date + "\n";
  s += "- command: `" + c.command_line + "`\n";
  s += "- git revision: " + (c.git_revision.empty() ? std::string("unknown") : c.git_revision) + "\n";
  s += "- machine: " + (c.cpu_model.empty() ? std::string("unknown CPU") : c.cpu_model) + ", " +
       std::to_string(c.cpu_cores) + " cores, " + c.isa + "\n";
  if (!c.settings.empty()) s += "- settings: " + c.settings + "\n";
  s += "- scenarios: " + std::to_string(scenarios.size()) + ", ran: " + std::to_string(ran) +
       ", failed to run: " + std::to_string(scenarios.size() - ran) + "\n";
  s += "\nTimings are for information only (no bar judges speed); errors are in mm.\n";

  s += "\n## Scenarios\n\n";
  s += "| scenario | script | frames empty / person | body IoU | skin IoU | hands vs skin | "
       "hands vs palm | head abs | head aligned | tracked | losses | switches | false targets "
       "empty / person | mesh | pSfS ms | MPF ms | wall s | description |\n";
  s += "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---|\n";
  for (const ScenarioFigures& f : scenarios) {
    s += "| " + cell(f.name) + " | " + cell(f.script) + " | ";
    if (!f.ran()) {
      s += "- | - | - | - | - | - | - | - | - | - | - | - | - | - | - | **failed to run:** " +
           cell(f.error) + " (" + cell(f.description) + ") |\n";
      continue;
    }
    s += std::to_string(f.empty_frames) + " / " + std::to_string(f.person_frames) + " | " +
         fmt(f.body_iou, 3) + " | " + fmt(f.skin_iou, 3) + " | " + fmt(f.hand_skin_mm, 1) + " | " +
         fmt(f.hand_palm_mm, 1) + " | " + fmt(f.head_mm, 1) + " | " + fmt(f.head_aligned_mm, 1) +
         " | " + fmt(f.tracked_fraction, 3) + " | " + fmt(f.losses, 0) + " | " +
         fmt(f.identity_switches, 0) + " | " + fmt(f.false_targets_empty, 0) + " / " +
         fmt(f.false_targets_person, 0) + " | " + fmt(f.mesh_mm, 2) + " | " + fmt(f.psfs_ms, 1) +
         " | " + fmt(f.mpf_ms, 2) + " | " + fmt(f.wall_s, 1) + " | " + cell(f.description) + " |\n";
  }

  s += "\n## Summary over " + std::to_string(ran) + " scenarios\n\n";
  const std::vector<std::string> body_keys = bodyMeasureKeys();
  auto isBody = [&](const std::string& key) {
    return std::find(body_keys.begin(), body_keys.end(), key) != body_keys.end();
  };
  s += "Pipeline measures; the PAPF's are in the upper-body section below.\n\n";
  s += "| measure | scenarios | median | worst decile | worst |\n|---|---:|---:|---:|---:|\n";
  for (const MeasureSummary& m : summaries) {
    if (isBody(m.key)) continue;
    const MeasureDef& d = measureDef(m.key);
    const std::string unit = *d.unit ? std::string(" (") + d.unit + ")" : std::string();
    s += "| " + std::string(d.label) + unit + " | " + std::to_string(m.count) + " | " +
         fmt(m.median, d.decimals) + " | " + fmt(m.worst_decile, d.decimals) + " | " +
         fmt(m.worst, d.decimals) + " |\n";
  }

  bool body_ran = false;
  for (const ScenarioFigures& f : scenarios) body_ran = body_ran || f.bodyRan();
  std::vector<BarSet> sets = {designBars()};
  if (c.asserted == "regression") sets.push_back(regressionBars(body_ran));
  for (const BarSet& set : sets) {
    const std::vector<BarVerdict> verdicts = checkBars(summaries, set);
    const bool asserted = c.asserted == set.name;
    s += "\n## Bars: " + set.name + (asserted ? " (asserted)" : " (reported)") + "\n\n" + set.note + "\n\n";
    s += "| bar | value | verdict |\n|---|---:|---|\n";
    for (const BarVerdict& v : verdicts) {
      const MeasureDef& d = measureDef(v.bar.key);
      s += "| " + describeBar(v.bar) + " | " + fmt(v.value, d.decimals) + " | " +
           (v.pass ? "PASS" : (v.measured ? "FAIL" : "FAIL (not measured)")) + " |\n";
    }
    s += std::string("\n") + set.name + " bars: " + (allPass(verdicts) ? "all PASS" : "FAIL") + "\n";
  }

  s += bodySection(scenarios, summaries);

  bool any_failed = false;
  for (const ScenarioFigures& f : scenarios) any_failed = any_failed || !f.ran();
  if (any_failed) {
    s += "\n## Scenarios that failed to run\n\n";
    for (const ScenarioFigures& f : scenarios)
      if (!f.ran()) s += "- `" + f.name + "` (script " + f.script + "): " + cell(f.error) + "\n";
  }

  if (!c.plots.empty()) {
    s += "\n## Plots\n\n";
    for (const std::string& p : c.plots) s += "- [" + p + "](" + p + ")\n";
  }

  s += "\n## Definitions\n\n"
       "- Per scenario: means over its scored frames. Body and skin IoU, precision and recall of "
       "the pSfS workspace volumes against the occupancy oracle on the same grid (person frames). "
       "Hands: both hands pooled, over the frames where a hand is visible and tracked, against "
       "the centroid of its visible skin (the MPF's target) and against the palm + fingers "
       "centroid; `never` = visible for a second or more but never tracked (sorted worst); each "
       "scenario's summary splits a hand's error along the wrist -> hand axis (+ towards the "
       "fingers) and across it. Head: "
       "the head ellipsoid's centre, absolute and with the mean offset removed (aligned). Losses, "
       "identity switches: all three targets. False-target frames: frames with an active target "
       "in the empty scene (after background learning), and with a target near no true target "
       "while the person is there. Mesh: mean distance from the probabilistic hand mesh to the "
       "true skin surface, per scored hand, averaged.\n"
       "- Over the suite (scenarios that ran, measures that were measured): median = middle value "
       "(mean of the two middle ones for an even count); worst decile = the value at the 90th "
       "percentile of badness by nearest rank, i.e. the (floor(n/10)+1)-th worst of n (the 10th "
       "percentile for IoU, the 90th for errors; the worst one with fewer than 10 scenarios); "
       "worst = the worst value.\n"
       "- A bar that cannot be checked (nothing measured) does not pass.\n";
  return s;
}

}  // namespace cvephands
