#include "cvephands_bridge/eval/sim_hand_volumes.h"

#include <cmath>
#include <stdexcept>

#include "psfs_reconstruction/gaussian_mixture.h"

namespace cvephands {

void visitSimHandFrames(const SimHandVolumeOptions& o,
                        const std::function<void(const SimHandFrame&)>& visit) {
  namespace sim = tabletop_sim;
  if (o.first_frame < 0 || o.frames < 0)
    throw std::invalid_argument("visitSimHandFrames: first_frame and frames must be >= 0");
  if (o.every < 1) throw std::invalid_argument("visitSimHandFrames: every must be >= 1");
  sim::SimOptions so;
  so.scenario = o.scenario;
  so.script = o.script;
  so.seed = static_cast<uint64_t>(o.seed);
  so.num_cameras = o.cameras;
  so.short_sleeves = o.short_sleeves;
  sim::SimulatedRig rig(so);
  psfs::ReconstructorParams rp;
  rp.hand_roi_edge = o.hand_edge;
  rp.hand_roi_voxels = o.hand_voxels;
  rp.hand_roi_clip_floor = o.clip_floor;
  psfs::Reconstructor recon(psfs::GaussianMixture2D::load(o.skin_model), rp);

  const int begin = so.empty_frames + o.first_frame;
  const int end = o.frames > 0 ? begin + o.frames : rig.scriptFrames();
  SimHandFrame out;
  out.rig = &rig;
  out.count = end > begin ? (end - begin + o.every - 1) / o.every : 0;
  for (int f = 0; f < end; ++f) {
    const bool wanted = f >= begin && (f - begin) % o.every == 0;
    if (f >= so.empty_frames && !wanted) continue;  // background learned; skipped frames
    const sim::SimFrame frame = rig.render(f);
    std::vector<Eigen::Vector3d> rois;
    out.sides.clear();
    if (frame.truth.person_present) {
      if (frame.truth.left_hand_in_workspace)
        rois.push_back(frame.truth.left_hand), out.sides.push_back(0);
      if (frame.truth.right_hand_in_workspace)
        rois.push_back(frame.truth.right_hand), out.sides.push_back(1);
    }
    const psfs::FrameResult res = recon.process(frame.images, rig.rig().cameras, rois);
    if (!wanted || res.status != psfs::FrameResult::Status::kReconstructed) continue;
    out.sim = &frame;
    out.rig_frame = f;
    out.result = &res;
    visit(out);
    ++out.index;
  }
}

std::vector<SimHandVolume> recordSimHandVolumes(const SimHandVolumeOptions& o) {
  std::vector<SimHandVolume> out;
  visitSimHandFrames(o, [&](const SimHandFrame& f) {
    const int empty = f.rig->options().empty_frames;
    for (size_t h = 0; h < f.sides.size(); ++h) {
      const psfs::ProbabilityVolume& vol = f.result->hands[h];
      SimHandVolume v;
      v.frame = f.rig_frame - empty;
      v.side = f.sides[h];
      v.time = f.sim->time;
      v.origin = vol.grid.origin;
      v.voxel_size = vol.grid.voxel_size;
      v.dims = vol.grid.dims;
      v.data = vol.data;
      out.push_back(std::move(v));
    }
  });
  return out;
}

HandFrame toHandFrame(SimHandVolume&& v) {
  HandFrame f;
  f.target_id = uint32_t(v.side);
  f.stamp_sec = uint32_t(v.time);
  f.stamp_nsec = uint32_t(std::lround((v.time - std::floor(v.time)) * 1e9)) % 1000000000u;
  f.origin = v.origin;
  f.voxel_size = v.voxel_size;
  f.dims = v.dims;
  f.data = std::move(v.data);
  return f;
}

}  // namespace cvephands
