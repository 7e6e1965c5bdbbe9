// Test helper: the real pipeline on the simulated rig, for the empty-space skipping tests.
// Script 'wave', the background learned from its 25 empty sets (classifier, skin model and
// parameters as given), then 4 person frames spread over the script; with_hands: hand
// sub-volumes at the true hands.
#pragma once

#include <gtest/gtest.h>

#include <vector>

#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_sim/simulated_rig.h"
#include "test_data_path.h"

namespace psfs_test {

inline std::vector<psfs::FrameResult> pipelineFrames(const psfs::ReconstructorParams& params, bool with_hands) {
  tabletop_sim::SimOptions so;
  so.script = "wave";
  so.empty_frames = 25;
  tabletop_sim::SimulatedRig rig(so);
  psfs::Reconstructor r(psfs::GaussianMixture2D::load(configDir() + "/skin_gmm.yaml"), params);
  for (int f = 0; f < 25; ++f) r.process(rig.render(f).images, rig.rig().cameras);
  EXPECT_TRUE(r.backgroundReady());
  std::vector<psfs::FrameResult> results;
  const int n = rig.scriptFrames();
  for (int f : {25 + 5, 25 + (n - 25) / 3, 25 + 2 * (n - 25) / 3, n - 3}) {
    const tabletop_sim::SimFrame frame = rig.render(f);
    std::vector<Eigen::Vector3d> hands;
    if (with_hands) hands = {frame.truth.left_hand, frame.truth.right_hand};
    results.push_back(r.process(frame.images, rig.rig().cameras, hands));
    EXPECT_EQ(results.back().status, psfs::FrameResult::Status::kReconstructed);
    EXPECT_EQ(results.back().hands.size(), hands.size());
  }
  return results;
}

}  // namespace psfs_test
