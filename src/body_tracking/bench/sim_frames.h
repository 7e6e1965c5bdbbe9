// The PAPF benchmarks' input: 40 consecutive frames of the simulated rig's reach_targets
// script in short sleeves, rendered and reconstructed by psfs::Reconstructor (64x64x48 body and
// skin volumes), prepared once (~3 s).
#pragma once

#include <utility>
#include <vector>

#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_sim/simulated_rig.h"

namespace body_tracking {

struct Frames {
  std::vector<psfs::ProbabilityVolume> skin, body;
  std::vector<tabletop_capture::CameraModel> cameras;
  Frames() {
    namespace sim = tabletop_sim;
    constexpr int kLearn = 25, kFrames = 40, kSkip = 60;  // start mid-reach
    sim::SimOptions o;
    o.script = "reach_targets";
    o.short_sleeves = true;
    o.empty_frames = kLearn;
    sim::SimulatedRig rig(o);
    cameras = rig.rig().cameras;
    psfs::ReconstructorParams rp;
    psfs::Reconstructor rec(psfs::GaussianMixture2D::load(BODY_TRACKING_SKIN_MODEL), rp);
    for (int f = 0; f < kLearn; ++f) rec.process(rig.render(f).images, rig.rig().cameras);
    for (int f = kLearn + kSkip; f < kLearn + kSkip + kFrames; ++f) {
      psfs::FrameResult r = rec.process(rig.render(f).images, rig.rig().cameras);
      skin.push_back(std::move(r.skin));
      body.push_back(std::move(r.body));
    }
  }
  // Back and forth: 0, 1, ..., n-1, n-2, ..., 1, 0, 1, ...
  size_t at(size_t i) const {
    const size_t n = body.size(), p = 2 * (n - 1);
    const size_t k = i % p;
    return k < n ? k : p - k;
  }
};

inline const Frames& frames() {
  static const Frames f;
  return f;
}

}  // namespace body_tracking
