#include "cvephands_bridge/sim_hand_volumes.h"

#include <stdexcept>

#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/reconstructor.h"
#include "tabletop_capture/sim/simulated_rig.h"

namespace cvephands {

std::vector<SimHandVolume> recordSimHandVolumes(const SimHandVolumeOptions& o) {
  namespace sim = tabletop_capture::sim;
  if (o.first_frame < 0 || o.frames < 0)
    throw std::invalid_argument("recordSimHandVolumes: first_frame and frames must be >= 0");
  sim::SimOptions so;
  so.script = o.script;
  so.seed = static_cast<uint64_t>(o.seed);
  so.num_cameras = o.cameras;
  so.short_sleeves = o.short_sleeves;
  sim::SimulatedRig rig(so);
  psfs::ReconstructorParams rp;
  rp.hand_roi_edge = o.hand_edge;
  rp.hand_roi_voxels = o.hand_voxels;
  psfs::Reconstructor recon(psfs::GaussianMixture2D::load(o.skin_model), rp);

  std::vector<SimHandVolume> out;
  const int begin = so.empty_frames + o.first_frame, end = begin + o.frames;
  for (int f = 0; f < end; ++f) {
    if (f >= so.empty_frames && f < begin) continue;  // background learned; skipped frames
    const sim::SimFrame frame = rig.render(f);
    std::vector<Eigen::Vector3d> rois;
    std::vector<int> sides;
    if (frame.truth.person_present) {
      if (frame.truth.left_hand_in_workspace)
        rois.push_back(frame.truth.left_hand), sides.push_back(0);
      if (frame.truth.right_hand_in_workspace)
        rois.push_back(frame.truth.right_hand), sides.push_back(1);
    }
    const psfs::FrameResult res = recon.process(frame.images, rig.rig().cameras, rois);
    if (f < begin || res.status != psfs::FrameResult::Status::kReconstructed) continue;
    for (size_t h = 0; h < rois.size(); ++h) {
      SimHandVolume v;
      v.frame = f - so.empty_frames;
      v.side = sides[h];
      v.time = frame.time;
      v.origin = res.hands[h].grid.origin;
      v.voxel_size = res.hands[h].grid.voxel_size;
      v.dims = res.hands[h].grid.dims;
      v.data = res.hands[h].data;
      out.push_back(std::move(v));
    }
  }
  return out;
}

}  // namespace cvephands
