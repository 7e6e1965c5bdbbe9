#include "cvephands_bridge/eval/scenario_evaluation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <memory>
#include <stdexcept>

#include "body_tracking/model_prior.h"
#include "body_tracking/papf.h"
#include "body_tracking/papf_config.h"
#include "hand_tracking/mpf_config.h"
#include "hand_tracking/mpf_tracker.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/reconstructor.h"
#include "psfs_reconstruction/reconstructor_config.h"
#include "tabletop_sim/scenario.h"
#include "tabletop_sim/simulated_rig.h"

namespace cvephands {
namespace {

namespace sim = tabletop_sim;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
// A target visible in at least this many scored frames but never tracked is a failure (+inf
// error), not "not measured": one second at 25 fps, longer than any acquisition delay the
// tracker should need, so a hand that enters in the run's last frames does not count.
constexpr int kNeverTrackedMinFrames = 25;

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<sim::TrackedPoint> toPoints(const std::vector<hand_tracking::Target>& targets) {
  std::vector<sim::TrackedPoint> out;
  for (const auto& t : targets) {
    sim::TrackedPoint p;
    p.id = t.id;
    p.hand = t.type == hand_tracking::Target::kHand;
    p.position = t.position;
    p.active = t.active;
    out.push_back(p);
  }
  return out;
}

// definition 0: the hands' visible skin centroids (the MPF's target), 1: palm + fingers.
sim::TruthPoints truthOf(const sim::GroundTruth& g, int definition) {
  const Eigen::Vector3d& l = definition == 0 ? g.left_hand_skin : g.left_hand;
  const Eigen::Vector3d& r = definition == 0 ? g.right_hand_skin : g.right_hand;
  sim::TruthPoints t;
  t.position = {l, r, g.head};
  t.visible = {g.person_present && g.left_hand_in_workspace && l.allFinite(),
               g.person_present && g.right_hand_in_workspace && r.allFinite(),
               g.person_present && g.head_in_workspace && g.head.allFinite()};
  sim::setHandAxes(g.wrist, &t);  // the hand target's error splits along wrist -> hand
  return t;
}

struct Overlap {
  size_t both = 0, reconstructed = 0, truth = 0;
  double precision() const { return reconstructed ? double(both) / reconstructed : kNaN; }
  double recall() const { return truth ? double(both) / truth : kNaN; }
  // psfs::volumeIoU's value from the same counts (1 where both are empty).
  double iou() const {
    const size_t either = reconstructed + truth - both;
    return either == 0 ? 1.0 : double(both) / double(either);
  }
};

Overlap overlap(const psfs::ProbabilityVolume& v, uint8_t tb, const std::vector<uint8_t>& truth) {
  Overlap o;
  for (size_t i = 0; i < truth.size(); ++i) {
    const bool a = v.data[i] > tb, b = truth[i] != 0;
    o.both += a && b;
    o.reconstructed += a;
    o.truth += b;
  }
  return o;
}

// Mean of a target's errors pooled over targets, with the never-tracked rule above.
double pooledMean(const sim::TrackingEvaluator& ev, std::initializer_list<int> targets) {
  double sum = 0;
  uint64_t n = 0;
  bool visible = false, never_tracked = false;
  for (int t : targets) {
    const auto& r = ev.report(t);
    visible = visible || r.visible_frames > 0;
    never_tracked = never_tracked || (r.tracked_frames == 0 && r.visible_frames >= kNeverTrackedMinFrames);
    sum += r.error_mm.mean() * double(r.error_mm.count());
    n += r.error_mm.count();
  }
  if (never_tracked) return kInf;
  if (n == 0) return visible ? kInf : kNaN;
  return sum / double(n);
}

double pooledMax(const sim::TrackingEvaluator& ev, std::initializer_list<int> targets) {
  const double mean = pooledMean(ev, targets);
  if (!std::isfinite(mean)) return mean;
  double m = 0;
  for (int t : targets)
    if (ev.report(t).error_mm.count()) m = std::max(m, ev.report(t).error_mm.max());
  return m;
}

// Euclidean distance in mm; NaN when the truth is not finite (not scored).
double distMm(const Eigen::Vector3d& estimate, const Eigen::Vector3d& truth) {
  return truth.allFinite() ? 1000.0 * (estimate - truth).norm() : kNaN;
}

// Mean of the finite values among a and b (NaN if none).
double meanOf(double a, double b) {
  if (std::isfinite(a) && std::isfinite(b)) return 0.5 * (a + b);
  return std::isfinite(a) ? a : b;
}

// Angle between two vectors in degrees; NaN if either is not finite or has no length.
double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double na = a.norm(), nb = b.norm();
  if (!a.allFinite() || !b.allFinite() || na < 1e-9 || nb < 1e-9) return kNaN;
  // atan2 of |a x b| and a . b: exact near 0 and 180 degrees, where acos of the dot loses digits.
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

// The PAPF after one frame: tracking state, starts, losses and the errors against the truth
// (the conventions of body_tracking's test_papf_sim; scenario_evaluation.h).
void scoreBody(const body_tracking::BodyEstimate& e, const sim::GroundTruth& g, bool was_tracking,
               BodyTrackingFigures* b, ScenarioFrame* sf) {
  sf->body_tracking = e.tracking;
  sf->body_started = e.started;
  b->starts += e.started;
  if (!g.person_present) {
    b->empty_tracked_frames += e.tracking;
    return;
  }
  ++b->person_frames;
  if (was_tracking && !e.tracking) ++b->losses;
  if (!e.tracking) return;
  ++b->tracked_frames;
  double hand[2], elbow[2], shoulder[2];
  ArmAngleErrors angles[2];
  for (int i = 0; i < 2; ++i) {
    angles[i] = armAngleErrors(e.frames.shoulder[i], e.frames.elbow[i], e.frames.wrist[i],
                               g.shoulder[i], g.elbow[i], g.wrist[i]);
    if (std::isfinite(angles[i].upper_arm_deg)) b->upper_arm_deg.add(angles[i].upper_arm_deg);
    if (std::isfinite(angles[i].forearm_deg)) b->forearm_deg.add(angles[i].forearm_deg);
    if (std::isfinite(angles[i].elbow_flex_deg)) b->elbow_flex_deg.add(angles[i].elbow_flex_deg);
    const bool in_ws = i == 0 ? g.left_hand_in_workspace : g.right_hand_in_workspace;
    hand[i] = in_ws ? distMm(e.hands.position[i], i == 0 ? g.left_hand : g.right_hand) : kNaN;
    elbow[i] = distMm(e.frames.elbow[i], g.elbow[i]);
    shoulder[i] = distMm(e.frames.shoulder[i], g.shoulder[i]);
    if (std::isfinite(hand[i])) b->hand_mm.add(hand[i]);
    if (std::isfinite(elbow[i])) b->elbow_mm.add(elbow[i]);
    if (std::isfinite(shoulder[i])) b->shoulder_mm.add(shoulder[i]);
  }
  const double head = g.head_in_workspace ? distMm(e.frames.head_centre, g.head) : kNaN;
  if (std::isfinite(head)) b->head_mm.add(head);
  sf->body_hand_mm = meanOf(hand[0], hand[1]);
  sf->body_head_mm = head;
  sf->body_elbow_mm = meanOf(elbow[0], elbow[1]);
  sf->body_shoulder_mm = meanOf(shoulder[0], shoulder[1]);
  sf->body_upper_arm_deg = meanOf(angles[0].upper_arm_deg, angles[1].upper_arm_deg);
  sf->body_forearm_deg = meanOf(angles[0].forearm_deg, angles[1].forearm_deg);
  sf->body_elbow_flex_deg = meanOf(angles[0].elbow_flex_deg, angles[1].elbow_flex_deg);
}

}  // namespace

ArmAngleErrors armAngleErrors(const Eigen::Vector3d& shoulder, const Eigen::Vector3d& elbow,
                              const Eigen::Vector3d& wrist, const Eigen::Vector3d& true_shoulder,
                              const Eigen::Vector3d& true_elbow, const Eigen::Vector3d& true_wrist) {
  const Eigen::Vector3d upper = elbow - shoulder, fore = wrist - elbow;
  const Eigen::Vector3d true_upper = true_elbow - true_shoulder, true_fore = true_wrist - true_elbow;
  ArmAngleErrors a;
  a.upper_arm_deg = angleDeg(upper, true_upper);
  a.forearm_deg = angleDeg(fore, true_fore);
  a.elbow_flex_deg = std::abs(angleDeg(upper, fore) - angleDeg(true_upper, true_fore));
  return a;
}

double BodyTrackingFigures::trackedFraction() const {
  return ran && person_frames > 0 ? double(tracked_frames) / person_frames : kNaN;
}

double BodyTrackingFigures::meanError(const tabletop_common::RunningStats& s) const {
  if (!ran || person_frames == 0) return kNaN;
  if (s.count() == 0) return person_frames >= kNeverTrackedMinFrames ? kInf : kNaN;
  return s.mean();
}

std::string describeScenario(const std::string& scenario) {
  // Also called for a scenario that failed to run, so a bad name is described, not thrown.
  try {
    return tabletop_sim::scenarioByName(scenario).describe();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
}

ScenarioEvalResult evaluateScenario(const ScenarioEvalOptions& o) {
  const auto wall0 = std::chrono::steady_clock::now();
  if (o.empty_frames < 0) throw std::invalid_argument("evaluateScenario: empty_frames must be >= 0");
  if (o.frames < 0) throw std::invalid_argument("evaluateScenario: frames must be >= 0");
  if (o.mesh_every < 0) throw std::invalid_argument("evaluateScenario: mesh_every must be >= 0");
  if (!(o.occupancy_threshold > 0.0 && o.occupancy_threshold < 1.0))
    throw std::invalid_argument("evaluateScenario: occupancy_threshold must lie in (0, 1)");

  // The stages as the pipeline configures them.
  psfs::ReconstructorParams rp;
  std::string skin_model = o.skin_model;
  if (!o.psfs_config.empty()) {
    const psfs::ReconstructorConfig c = psfs::loadReconstructorConfig(o.psfs_config);
    rp = c.params;
    if (skin_model.empty()) skin_model = c.skin_model_path;
  }
  if (skin_model.empty())
    throw std::invalid_argument("evaluateScenario: no skin model (set skin_model or psfs_config)");
  hand_tracking::MpfParams mp;
  if (!o.mpf_config.empty()) mp = hand_tracking::loadMpfConfig(o.mpf_config).params;
  // The PAPF: its file's parameters, the scenario's seed (same options, same figures).
  std::unique_ptr<body_tracking::Papf> papf;
  bool papf_skin = true;
  body_tracking::ModelPriorParams volume_prior;  // the nodelet's body/volume
  if (o.body) {
    body_tracking::PapfConfig pc;
    if (!o.papf_config.empty()) pc = body_tracking::loadPapfConfig(o.papf_config);
    pc.params.seed = o.seed;
    const body_tracking::BodyProfile profile =
        pc.nodelet.body_profile_file.empty()
            ? body_tracking::BodyProfile()  // what config/body_profile.yaml holds
            : body_tracking::BodyProfile::fromYamlFile(pc.nodelet.body_profile_file);
    papf = std::make_unique<body_tracking::Papf>(profile, pc.params);
    papf_skin = pc.nodelet.use_skin_volume;
    volume_prior = pc.nodelet.volume_prior;
  }
  psfs::ProbabilityVolume prior_volume;  // body/volume of the frame
  HandMeshEvalOptions mo = o.mesh;
  mo.seed = static_cast<int>(o.seed);  // truth surface samples
  HandMeshScorer scorer(mo);

  sim::SimOptions so;
  so.scenario = o.scenario;
  so.script = o.script;
  so.seed = o.seed;
  const int learning = rp.background.learning_frames;
  so.empty_frames = learning + o.empty_frames;
  const sim::SimulatedRig rig(so);  // throws std::invalid_argument for an unknown scenario
  psfs::Reconstructor recon(psfs::GaussianMixture2D::load(skin_model), rp);
  hand_tracking::MpfTracker tracker(mp, o.seed);

  ScenarioEvalResult res;
  res.scenario = o.scenario;
  res.script = o.script;
  res.description = o.describe ? o.describe(o.scenario) : describeScenario(o.scenario);
  res.seed = o.seed;
  res.occupancy_threshold = o.occupancy_threshold;
  res.body.ran = o.body;
  bool body_was_tracking = false;
  const uint8_t tb = psfs::thresholdByte(o.occupancy_threshold);
  const int first_person = rig.options().empty_frames;
  const int total = o.frames > 0 ? first_person + o.frames : rig.scriptFrames();
  const double dt = 1.0 / rig.options().fps;
  std::vector<uint8_t> truth_body, truth_skin;
  for (int f = 0; f < total; ++f) {
    const sim::SimFrame frame = rig.render(f);
    const sim::GroundTruth& g = frame.truth;
    // Hand sub-volumes around the true hands on the mesh frames only (they change nothing else).
    std::vector<Eigen::Vector3d> rois;
    std::vector<int> sides;
    const bool mesh_frame = g.person_present && o.mesh_every > 0 && (f - first_person) % o.mesh_every == 0;
    if (mesh_frame) {
      if (g.left_hand_in_workspace) rois.push_back(g.left_hand), sides.push_back(0);
      if (g.right_hand_in_workspace) rois.push_back(g.right_hand), sides.push_back(1);
    }
    const psfs::FrameResult r = recon.process(frame.images, rig.rig().cameras, rois);
    if (r.status == psfs::FrameResult::Status::kReconstructed) {
      tracker.update(r.skin, r.body, dt);
      const std::vector<sim::TrackedPoint> points = toPoints(tracker.targets());
      res.tracking_skin.add(frame.time, points, truthOf(g, 0));
      res.tracking_palm.add(frame.time, points, truthOf(g, 1));

      ScenarioFrame sf;
      sf.frame = f;
      sf.time = frame.time;
      sf.person = g.person_present;
      sf.psfs_ms = r.times.total;
      sf.mpf_ms = tracker.lastTimes().total_ms;
      for (const sim::TrackedPoint& p : points) sf.active_targets += p.active;
      if (papf) {
        const body_tracking::BodyEstimate& e = papf->update(r.body, papf_skin ? &r.skin : nullptr);
        sf.papf_ms = papf->lastTimes().total_ms;
        res.body.papf_ms.add(sf.papf_ms);
        scoreBody(e, g, body_was_tracking, &res.body, &sf);
        body_was_tracking = e.tracking;
        if (g.person_present) {
          if (e.tracking)
            body_tracking::applyModelPrior(
                r.body, body_tracking::priorSolids(papf->profile(), e.frames, volume_prior),
                volume_prior, &prior_volume);
          else
            prior_volume = r.body;
        }
      }
      if (res.grid.empty()) res.grid = r.body.grid.describe();
      if (r.body.grid != r.skin.grid)
        throw std::logic_error("evaluateScenario: body and skin volumes on different grids");
      if (!sf.person) {
        ++res.empty_frames;
        res.false_target_frames_empty += sf.active_targets > 0;
        sf.body_voxels = psfs::countAbove(r.body, tb);
        sf.skin_voxels = psfs::countAbove(r.skin, tb);
        res.empty_max_body_voxels = std::max(res.empty_max_body_voxels, sf.body_voxels);
        sf.body_iou = sf.body_precision = sf.body_recall = kNaN;
        sf.skin_iou = sf.skin_precision = sf.skin_recall = kNaN;
      } else {
        ++res.person_frames;
        const sim::Oracle oracle = rig.oracle(f);
        const psfs::VoxelGrid& grid = r.body.grid;
        oracle.sampleGrid(grid.origin, grid.voxel_size, grid.dims, &truth_body, &truth_skin);
        for (int k = 0; k < 2; ++k) {
          const psfs::ProbabilityVolume& rec = k == 0 ? r.body : r.skin;
          const Overlap ov = overlap(rec, tb, k == 0 ? truth_body : truth_skin);
          (k == 0 ? sf.body_iou : sf.skin_iou) = ov.iou();
          (k == 0 ? sf.body_precision : sf.skin_precision) = ov.precision();
          (k == 0 ? sf.body_recall : sf.skin_recall) = ov.recall();
          (k == 0 ? sf.body_voxels : sf.skin_voxels) = ov.reconstructed;
        }
        res.body_iou.add(sf.body_iou);
        if (papf) {
          const Overlap ov = overlap(prior_volume, tb, truth_body);
          sf.body_volume_iou = ov.iou();
          sf.body_volume_precision = ov.precision();
          sf.body_volume_recall = ov.recall();
          res.body.volume_iou.add(sf.body_volume_iou);
          if (std::isfinite(sf.body_volume_precision)) res.body.volume_precision.add(sf.body_volume_precision);
          if (std::isfinite(sf.body_volume_recall)) res.body.volume_recall.add(sf.body_volume_recall);
        }
        res.skin_iou.add(sf.skin_iou);
        // Precision of an empty reconstruction / recall of an empty truth: undefined, skipped.
        if (std::isfinite(sf.body_precision)) res.body_precision.add(sf.body_precision);
        if (std::isfinite(sf.body_recall)) res.body_recall.add(sf.body_recall);
        if (std::isfinite(sf.skin_precision)) res.skin_precision.add(sf.skin_precision);
        if (std::isfinite(sf.skin_recall)) res.skin_recall.add(sf.skin_recall);
        if (!sides.empty()) {
          const auto t0 = std::chrono::steady_clock::now();
          for (size_t h = 0; h < sides.size(); ++h) {
            HandMeshSample s = scorer.score(r.hands[h], oracle.primitives(), f, sides[h], false);
            if (s.probabilistic.mesh_to_truth.count) res.mesh_to_truth_mm.add(s.probabilistic.mesh_to_truth.mean_mm);
            if (s.probabilistic.truth_to_mesh.count) res.truth_to_mesh_mm.add(s.probabilistic.truth_to_mesh.mean_mm);
            res.meshes.push_back(std::move(s));
          }
          res.mesh_score_ms.add(msSince(t0));
        }
      }
      res.psfs_ms.add(sf.psfs_ms);
      res.mpf_ms.add(sf.mpf_ms);
      res.frames.push_back(sf);
    }
    if (o.progress) o.progress(f + 1, total);
  }
  res.false_target_frames_person = res.tracking_skin.falseTargetFrames() - res.false_target_frames_empty;
  res.wall_s = msSince(wall0) / 1000.0;
  return res;
}

double ScenarioEvalResult::handErrorMeanMm(int definition) const {
  return pooledMean(definition == 0 ? tracking_skin : tracking_palm, {0, 1});
}
double ScenarioEvalResult::handErrorMaxMm(int definition) const {
  return pooledMax(definition == 0 ? tracking_skin : tracking_palm, {0, 1});
}
double ScenarioEvalResult::headErrorMeanMm() const { return pooledMean(tracking_skin, {2}); }
double ScenarioEvalResult::headErrorMaxMm() const { return pooledMax(tracking_skin, {2}); }
double ScenarioEvalResult::headAlignedErrorMeanMm() const {
  const double mean = pooledMean(tracking_skin, {2});
  return std::isfinite(mean) ? tracking_skin.report(2).alignedErrorMeanMm() : mean;
}

int ScenarioEvalResult::losses() const {
  int n = 0;
  for (int t = 0; t < sim::TrackingEvaluator::kTargets; ++t) n += tracking_skin.report(t).losses;
  return n;
}
int ScenarioEvalResult::identitySwitches() const {
  int n = 0;
  for (int t = 0; t < sim::TrackingEvaluator::kTargets; ++t)
    n += tracking_skin.report(t).identity_switches;
  return n;
}
double ScenarioEvalResult::trackedFraction() const {
  int visible = 0, tracked = 0;
  for (int t = 0; t < sim::TrackingEvaluator::kTargets; ++t) {
    visible += tracking_skin.report(t).visible_frames;
    tracked += tracking_skin.report(t).tracked_frames;
  }
  return visible ? double(tracked) / visible : kNaN;
}

std::string ScenarioEvalResult::bodySummary() const {
  if (!body.ran) return "  PAPF: off\n";
  char buf[768];
  std::snprintf(buf, sizeof(buf),
                "  PAPF: tracked %d/%d person frames (%d untracked), %d start(s), %d loss(es), %d "
                "empty-scene frames tracked; hands %.1f mm (max %.1f), head %.1f (max %.1f), "
                "elbows %.1f (max %.1f), shoulders %.1f (max %.1f); arm angles: upper arms %.1f "
                "deg, forearms %.1f, elbow flexion %.1f; %.1f ms per set\n",
                body.tracked_frames, body.person_frames, body.untrackedFrames(), body.starts,
                body.losses, body.empty_tracked_frames, body.meanError(body.hand_mm), body.hand_mm.max(),
                body.meanError(body.head_mm), body.head_mm.max(), body.meanError(body.elbow_mm),
                body.elbow_mm.max(), body.meanError(body.shoulder_mm), body.shoulder_mm.max(),
                body.meanError(body.upper_arm_deg), body.meanError(body.forearm_deg),
                body.meanError(body.elbow_flex_deg),
                body.papf_ms.mean());
  return buf;
}

std::string ScenarioEvalResult::summary() const {
  char buf[2048];
  std::snprintf(
      buf, sizeof(buf),
      "scenario '%s', script '%s', seed %llu: %d empty + %d person frames scored (%s)\n"
      "  volumes (p >= %.2f) vs oracle: body IoU %.3f (min %.3f, precision %.3f, recall %.3f), "
      "skin IoU %.3f (min %.3f)\n"
      "  hands vs visible skin %.1f mm (max %.1f), vs palm + fingers %.1f mm; head %.1f mm "
      "(aligned %.1f, max %.1f)\n"
      "  losses %d, identity switches %d, tracked %.0f %%, false-target frames %d empty / %d "
      "person\n"
      "  hand meshes: %zu scored, mesh->truth %.2f mm, truth->mesh %.2f mm\n"
      "  pSfS %.1f ms, MPF %.2f ms per set; %.1f s wall\n%s",
      scenario.c_str(), script.c_str(), static_cast<unsigned long long>(seed), empty_frames,
      person_frames, grid.c_str(), occupancy_threshold, body_iou.mean(), body_iou.min(),
      body_precision.mean(), body_recall.mean(), skin_iou.mean(), skin_iou.min(),
      handErrorMeanMm(0), handErrorMaxMm(0), handErrorMeanMm(1), headErrorMeanMm(),
      headAlignedErrorMeanMm(), headErrorMaxMm(), losses(), identitySwitches(),
      100.0 * trackedFraction(), false_target_frames_empty, false_target_frames_person,
      meshes.size(), mesh_to_truth_mm.mean(), truth_to_mesh_mm.mean(), psfs_ms.mean(),
      mpf_ms.mean(), wall_s, bodySummary().c_str());
  return buf;
}

}  // namespace cvephands
