// Peer comparison (issue: pSfS benchmarks): foreground-class pSfS, our binary SfS and Open3D
// 0.16's VoxelGrid::CarveSilhouette on the same frame, cameras and grids, with time and IoU
// against the simulated rig's occupancy oracle.
//
// Workload: the default 8-camera rig at 320x240 WITHOUT lens distortion (Open3D's pinhole
// camera has none), the waving person of the simulated rig; likelihood images are the rendered
// person masks with classifier-like noise bounded by the outlier model
// (test::classifierLikelihood), silhouettes are those likelihoods > 0.5 and go to both binary
// methods. Times are the median of --reps runs on 2 threads (Open3D's carving is serial).
//
//   bench_carving [--reps 7] [--open3d-4mm]   (Open3D at 3.9 mm takes minutes: off by default)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <open3d/camera/PinholeCameraParameters.h>
#include <open3d/geometry/Image.h>
#include <open3d/geometry/VoxelGrid.h>

#include "../test/fusion_test_utils.h"
#include "psfs_reconstruction/binary_sfs.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "tabletop_sim/simulated_rig.h"

namespace {

using namespace psfs;
namespace sim = tabletop_sim;
using Clock = std::chrono::steady_clock;

template <class F>
double medianMs(int reps, F&& f) {
  std::vector<double> t;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = Clock::now();
    f();
    t.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

double iou(const std::vector<uint8_t>& in, const std::vector<uint8_t>& truth) {
  size_t both = 0, either = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    both += in[i] && truth[i];
    either += in[i] || truth[i];
  }
  return either ? double(both) / either : 1.0;
}

std::vector<uint8_t> above(const ProbabilityVolume& v, uint8_t t) {
  std::vector<uint8_t> out(v.data.size());
  for (size_t i = 0; i < v.data.size(); ++i) out[i] = v.data[i] > t;
  return out;
}

// Open3D: dense grid over the same box, carved by every view; the surviving voxels mapped back
// onto our grid by their centres.
std::vector<uint8_t> carveOpen3d(const VoxelGrid& g,
                                 const std::vector<tabletop_capture::CameraModel>& cams,
                                 const std::vector<cv::Mat>& silhouettes) {
  const Eigen::Vector3d size = g.voxel_size * g.dims.cast<double>();
  // In 0.16 CreateDense's `origin` is the grid's min corner (despite its doc comment).
  auto grid = open3d::geometry::VoxelGrid::CreateDense(g.origin, Eigen::Vector3d(1, 1, 1),
                                                       g.voxel_size, size.x(), size.y(), size.z());
  for (size_t c = 0; c < cams.size(); ++c) {
    // CarveSilhouette reads the mask with Image::FloatValueAt, which only accepts 1-channel
    // float images (a uint8 mask reads as "outside the image" everywhere and carves nothing).
    open3d::geometry::Image mask;
    mask.Prepare(cams[c].width, cams[c].height, 1, 4);
    for (int v = 0; v < cams[c].height; ++v)
      for (int u = 0; u < cams[c].width; ++u)
        *mask.PointerAt<float>(u, v) = silhouettes[c].at<uint8_t>(v, u) ? 1.0f : 0.0f;
    open3d::camera::PinholeCameraParameters p;
    p.intrinsic_.SetIntrinsics(cams[c].width, cams[c].height, cams[c].fx, cams[c].fy, cams[c].cx, cams[c].cy);
    p.extrinsic_ = cams[c].cameraTWorld().matrix();
    grid->CarveSilhouette(mask, p, /*keep_voxels_outside_image=*/true);
  }
  std::vector<uint8_t> out(g.numVoxels(), 0);
  for (const auto& v : grid->GetVoxels()) {
    Eigen::Vector3i idx;
    if (g.voxelOf(grid->GetVoxelCenterCoordinate(v.grid_index_), &idx))
      out[g.index(idx.x(), idx.y(), idx.z())] = 1;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 7;
  bool open3d_4mm = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--open3d-4mm")) open3d_4mm = true;
    else {
      std::fprintf(stderr, "usage: bench_carving [--reps N] [--open3d-4mm]\n");
      return 2;
    }
  }
  sim::SimOptions so;
  so.script = "wave";
  so.empty_frames = 0;
  so.distortion = false;
  so.render_masks = true;
  sim::SimulatedRig rig(so);
  const int frame = rig.scriptFrames() / 2;
  const sim::SimFrame f = rig.render(frame);
  const auto& cams = rig.rig().cameras;
  std::vector<ViewImage> views(cams.size());
  std::vector<cv::Mat> silhouettes(cams.size());
  for (size_t c = 0; c < cams.size(); ++c) {
    views[c].likelihood = test::classifierLikelihood(f.person_masks[c], true, 100 + c);
    silhouettes[c] = views[c].likelihood > 127;
  }
  std::printf("bench_carving: 8 undistorted 320x240 views of the simulated rig (wave, frame %d), "
              "median of %d runs, pSfS/binary on 2 threads, Open3D serial\n", frame, reps);
  std::printf("%-28s %10s %8s %10s\n", "method @ grid", "time (ms)", "IoU", "voxels in");
  for (Resolution r : {Resolution::k16mm, Resolution::k8mm, Resolution::k4mm}) {
    const VoxelGrid g = referenceGrid(r);
    const char* label = r == Resolution::k16mm ? "64x64x48" : r == Resolution::k8mm ? "128x128x96" : "256x256x192";
    std::vector<uint8_t> truth;
    rig.oracle(frame).sampleGrid(g.origin, g.voxel_size, g.dims, &truth, nullptr);
    const bool multi = r == Resolution::k16mm;
    ProjectionTableOptions to;
    to.multi_projection = multi;
    to.threads = 2;
    ProjectionTable table(g, cams, to);
    ViewEvidence ev;
    ev.set(views, multi, 2);
    PsfsOptions po;
    po.multi_projection = multi;
    po.threads = 2;
    PsfsFusion psfs(po);
    ProbabilityVolume vp;
    const double tp = medianMs(reps, [&] { psfs.fuse(table, ev, &vp); });
    const auto in_p = above(vp, thresholdByte(po.threshold));
    BinarySfsOptions bo;
    bo.threads = 2;
    BinarySfs bin(bo);
    ProbabilityVolume vb;
    const double tb = medianMs(reps, [&] { bin.fuse(table, ev, &vb); });
    const auto in_b = above(vb, 127);
    auto count = [](const std::vector<uint8_t>& v) { return std::count(v.begin(), v.end(), 1); };
    std::printf("%-28s %10.2f %8.3f %10ld\n", (std::string("pSfS @ ") + label).c_str(), tp, iou(in_p, truth), count(in_p));
    std::printf("%-28s %10.2f %8.3f %10ld\n", (std::string("binary SfS @ ") + label).c_str(), tb, iou(in_b, truth), count(in_b));
    if (r != Resolution::k4mm || open3d_4mm) {
      std::vector<uint8_t> in_o;
      const double to3 = medianMs(r == Resolution::k4mm ? 1 : std::min(reps, 3),
                                  [&] { in_o = carveOpen3d(g, cams, silhouettes); });
      std::printf("%-28s %10.2f %8.3f %10ld\n", (std::string("Open3D carve @ ") + label).c_str(), to3,
                  iou(in_o, truth), count(in_o));
    } else {
      std::printf("%-28s %10s %8s %10s\n", (std::string("Open3D carve @ ") + label).c_str(), "skipped", "-", "(--open3d-4mm)");
    }
    std::printf("%-28s %10s %8s %10ld\n", (std::string("oracle @ ") + label).c_str(), "", "", count(truth));
    std::fflush(stdout);
  }
  return 0;
}
