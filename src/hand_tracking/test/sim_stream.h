// Test input: one scripted sequence of the simulated rig (tabletop_capture), rendered and
// reconstructed by the real pipeline (psfs::Reconstructor: background learning from the empty
// frames, pixel classification, pSfS fusion of the body and skin volumes), streamed frame by
// frame with the ground truth. Nothing is kept: the pSfS volumes are dense (~196 KB each, every
// byte non-zero), so a test runs all the trackers it needs on one pass instead.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_sim/simulated_rig.h"

namespace hand_tracking_test {

namespace sim = tabletop_sim;

constexpr int kLearnFrames = 25;  // empty frames the background model learns from

struct FrameTruth {
  bool person = false;
  Eigen::Vector3d left = Eigen::Vector3d::Zero(), right = Eigen::Vector3d::Zero(),
                  head = Eigen::Vector3d::Zero();
  bool left_in = false, right_in = false, head_in = false;

  const Eigen::Vector3d& hand(int h) const { return h == 0 ? left : right; }  // 0 left, 1 right
  bool handIn(int h) const { return person && (h == 0 ? left_in : right_in); }
};

struct StreamFrame {
  int rig_frame = 0;  // index into the rig's frames
  int k = 0;          // reconstructed frames before this one
  double time = 0;    // k * dt (s)
  double dt = 0.04;
  FrameTruth truth;
  const psfs::ProbabilityVolume* skin = nullptr;
  const psfs::ProbabilityVolume* body = nullptr;
  const sim::SimulatedRig* rig = nullptr;
};

// The reconstructor's defaults on 2 threads; `footprint`: the footprint-filtered body and skin
// evidence (psfs.yaml fusion/{body,skin}/footprint) instead of the multi-projection.
inline psfs::ReconstructorParams streamParams(bool footprint = false) {
  psfs::ReconstructorParams rp;
  rp.threads = 2;
  if (footprint) {
    rp.body.multi_projection = rp.skin.multi_projection = false;
    rp.body.footprint = rp.skin.footprint = true;
  }
  return rp;
}

// Renders and reconstructs `script` (after kLearnFrames + extra_empty empty frames; with
// extra_empty > 0 the stream starts with extra_empty reconstructed empty frames) with `rp` and
// calls fn(const StreamFrame&) for each reconstructed frame, at most max_frames (< 0: all).
// Returns the number of frames streamed.
template <typename Fn>
int streamSequence(const psfs::ReconstructorParams& rp, const std::string& script, int extra_empty,
                   int max_frames, Fn&& fn) {
  const auto t0 = std::chrono::steady_clock::now();
  sim::SimOptions o;
  o.script = script;
  o.empty_frames = kLearnFrames + extra_empty;
  sim::SimulatedRig rig(o);
  psfs::Reconstructor rec(psfs::GaussianMixture2D::load(HAND_TRACKING_SKIN_MODEL), rp);
  StreamFrame s;
  std::string grid = "no volumes";
  s.dt = 1.0 / o.fps;
  s.rig = &rig;
  for (int f = 0; f < rig.scriptFrames() && (max_frames < 0 || s.k < max_frames); ++f) {
    const sim::SimFrame frame = rig.render(f);
    const psfs::FrameResult r = rec.process(frame.images, rig.rig().cameras);
    if (r.status != psfs::FrameResult::Status::kReconstructed) continue;
    FrameTruth& t = s.truth;
    t = FrameTruth();
    t.person = frame.truth.person_present;
    if (t.person) {
      t.left = frame.truth.left_hand;
      t.right = frame.truth.right_hand;
      t.head = frame.truth.head;
    }
    t.left_in = frame.truth.left_hand_in_workspace;
    t.right_in = frame.truth.right_hand_in_workspace;
    t.head_in = frame.truth.head_in_workspace;
    s.rig_frame = f;
    s.time = s.k * s.dt;
    s.skin = &r.skin;
    s.body = &r.body;
    if (s.k == 0) grid = r.skin.grid.describe();
    fn(static_cast<const StreamFrame&>(s));
    ++s.k;
  }
  s.skin = s.body = nullptr;
  std::printf("[ sim      ] %s: %d reconstructed frames (%s) in %.1f s (render + reconstruct + "
              "track)\n", script.c_str(), s.k, grid.c_str(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return s.k;
}

template <typename Fn>
int streamSequence(const std::string& script, int extra_empty, int max_frames, Fn&& fn) {
  return streamSequence(streamParams(), script, extra_empty, max_frames, std::forward<Fn>(fn));
}

}  // namespace hand_tracking_test
