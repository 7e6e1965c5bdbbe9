// Evaluation tool of the hand/head tracker: prints hand and head centroid errors against ground
// truth (mean, std, max per target), track losses with how long they took to be reported,
// re-acquisition delays and identity switches, and writes the error over time as a PNG.
//
//   track_eval [--script all] [--frames N] [--seed 1] [--out DIR]     simulated rig, in process
//   track_eval --bag FILE [--out DIR]                                recorded pipeline output
//
// Simulated rig: renders the script (25 empty frames first, for the background), reconstructs
// each frame set with the pSfS stage's defaults and tracks with the MPF defaults, all in one
// process and deterministic (same script and seed, same figures). Bag: a recording of a run of
// the pipeline with /tabletop/hands/targets and /tabletop/ground_truth/targets (e.g.
// `rosbag record /tabletop/hands/targets /tabletop/ground_truth/targets` during the demo);
// targets and truth are paired by stamp.
#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <string>

#include <ros/package.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tabletop_msgs/TrackedTargets.h>

#include "hand_tracking/mpf_tracker.h"
#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_common/cli_args.h"
#include "tabletop_sim/ros/sim_truth_msgs.h"
#include "tabletop_common/running_stats.h"
#include "tabletop_sim/simulated_rig.h"
#include "tabletop_sim/tracking_evaluator.h"

namespace {

namespace sim = tabletop_sim;

void usage() {
  std::fprintf(stderr,
               "usage: track_eval [--scenario NAME] [--script NAME] [--frames N] [--seed N] [--out DIR]\n"
               "       track_eval --bag FILE [--out DIR]\n"
               "  --scenario NAME  simulated world: default, a preset or random-SEED (demo.sh --help)\n"
               "  --script NAME  simulated motion script (default all; see demo.sh --help)\n"
               "  --frames N     frame sets after the 25 empty ones (default: the whole script)\n"
               "  --seed N       sensor noise and tracker seed (default 1)\n"
               "  --out DIR      where tracking_error.png and tracking_summary.txt go (default .)\n"
               "  --bag FILE     evaluate a recording instead of running the simulated rig\n");
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

sim::TruthPoints truthOf(const sim::GroundTruth& g) {
  sim::TruthPoints t;
  t.position = {g.left_hand_skin, g.right_hand_skin, g.head};  // the MPF's targets
  t.visible = {g.person_present && g.left_hand_in_workspace,
               g.person_present && g.right_hand_in_workspace,
               g.person_present && g.head_in_workspace};
  sim::setHandAxes(g.wrist, &t);  // the hand target's error splits along wrist -> hand
  return t;
}

int runSim(const std::string& scenario, const std::string& script, int frames, int seed,
           sim::TrackingEvaluator* ev,
           tabletop_common::RunningStats* mpf_ms, tabletop_common::RunningStats* psfs_ms) {
  sim::SimOptions so;
  so.script = script;
  so.scenario = scenario;
  so.seed = static_cast<uint64_t>(seed);
  sim::SimulatedRig rig(so);
  const int total = frames > 0 ? so.empty_frames + frames : rig.scriptFrames();
  const std::string config = ros::package::getPath("psfs_reconstruction") + "/config";
  psfs::Reconstructor recon(psfs::GaussianMixture2D::load(config + "/skin_gmm.yaml"),
                            psfs::ReconstructorParams());
  hand_tracking::MpfTracker tracker(hand_tracking::MpfParams(), static_cast<uint64_t>(seed));
  const double dt = 1.0 / so.fps;
  const auto t0 = std::chrono::steady_clock::now();
  int skipped = 0;
  tabletop_common::RunningStats stage_ms[3];  // classify, fusion, background update
  for (int f = 0; f < total; ++f) {
    const sim::SimFrame frame = rig.render(f);
    const psfs::FrameResult r = recon.process(frame.images, rig.rig().cameras);
    if (r.learning_skipped && ++skipped <= 3)
      std::fprintf(stderr, "\n[track_eval] frame %d: changed against the background learned so far "
                   "(%d frames): not learned\n", f, r.background_frames);
    if (r.status == psfs::FrameResult::Status::kReconstructed) {
      psfs_ms->add(r.times.total);
      stage_ms[0].add(r.times.classify);
      if (std::getenv("TRACK_EVAL_DEBUG") && f % 10 == 0) {
        std::fprintf(stderr, "\nframe %d mean P(F):", f);
        for (const auto& st : r.stats) std::fprintf(stderr, " %.3f", st.mean_foreground);
      }
      stage_ms[1].add(r.times.body + r.times.skin);
      stage_ms[2].add(r.times.background);
      tracker.update(r.skin, r.body, dt);
      mpf_ms->add(tracker.lastTimes().total_ms);
      ev->add(f * dt, toPoints(tracker.targets()), truthOf(frame.truth));
    }
    if (f % 25 == 0 || f + 1 == total) {  // progress bar
      const int width = 40, done = (f + 1) * width / total;
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::fprintf(stderr, "\r[track_eval] [%s%s] %d/%d frame sets, %.0f s", std::string(done, '#').c_str(),
                   std::string(width - done, '.').c_str(), f + 1, total, s);
    }
  }
  std::fprintf(stderr, "\n");
  if (stage_ms[0].count() > 0)
    std::fprintf(stderr, "[track_eval] pSfS stages (ms, mean): classify %.1f, fusion %.1f, "
                 "background update %.1f\n", stage_ms[0].mean(), stage_ms[1].mean(), stage_ms[2].mean());
  return total;
}

int runBag(const std::string& path, sim::TrackingEvaluator* ev) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  const std::vector<std::string> topics = {"/tabletop/hands/targets", "/tabletop/ground_truth/targets"};
  rosbag::View view(bag, rosbag::TopicQuery(topics));
  std::map<ros::Time, tabletop_msgs::TrackedTargets::ConstPtr> tracked, truth;
  for (const rosbag::MessageInstance& m : view) {
    auto msg = m.instantiate<tabletop_msgs::TrackedTargets>();
    if (!msg) continue;
    (m.getTopic() == topics[0] ? tracked : truth)[msg->header.stamp] = msg;
  }
  int n = 0;
  for (const auto& t : tracked) {
    auto g = truth.find(t.first);
    if (g == truth.end()) continue;
    ev->add(t.first.toSec(), tabletop_sim::toTrackedPoints(*t.second),
            tabletop_sim::toTruthPoints(*g->second));
    ++n;
  }
  if (n == 0)
    throw std::runtime_error(path + ": no stamps with both /tabletop/hands/targets and "
                             "/tabletop/ground_truth/targets");
  return n;
}

}  // namespace

int main(int argc, char** argv) {
  std::string script = "all", scenario = "default", out = ".", bag;
  int frames = 0, seed = 1;
  tabletop_common::CliArgs args("track_eval", argc, argv, usage);
  while (args.next()) {
    if (args.is("--script")) script = args.text();
    else if (args.is("--scenario")) scenario = args.text();
    else if (args.is("--frames")) frames = static_cast<int>(args.integer(0));
    else if (args.is("--seed")) seed = static_cast<int>(args.integer());
    else if (args.is("--out")) out = args.text();
    else if (args.is("--bag")) bag = args.text();
    else if (args.help()) {
      usage();
      return 0;
    } else {
      args.unknown();
    }
  }
  ::mkdir(out.c_str(), 0755);
  sim::TrackingEvaluator ev;
  tabletop_common::RunningStats mpf_ms, psfs_ms;
  std::string source;
  try {
    if (bag.empty()) {
      const int n = runSim(scenario, script, frames, seed, &ev, &mpf_ms, &psfs_ms);
      source = "simulated rig, scenario '" + scenario + "', script '" + script + "', " + std::to_string(n) + " frame sets, seed " +
               std::to_string(seed);
    } else {
      runBag(bag, &ev);
      source = "bag " + bag;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "track_eval: %s\n", e.what());
    return 1;
  }
  std::string text = "==== hand/head tracking vs ground truth ====\n" + source + ", " +
                     std::to_string(ev.frames()) + " frames scored\n" + ev.summary();
  if (mpf_ms.count() > 0) {
    char buf[200];
    std::snprintf(buf, sizeof(buf), "  MPF update %.2f ms mean (max %.2f); pSfS %.1f ms mean\n",
                  mpf_ms.mean(), mpf_ms.max(), psfs_ms.mean());
    text += buf;
  }
  const std::string png = out + "/tracking_error.png";
  if (ev.writePlot(png)) text += "  plot: " + png + "\n";
  std::printf("%s", text.c_str());
  std::ofstream(out + "/tracking_summary.txt") << text;
  return 0;
}
