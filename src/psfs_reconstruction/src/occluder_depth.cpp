#include "psfs_reconstruction/occluder_depth.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "cpu_dispatch.h"

namespace psfs {

int voxelCentrePixel(const VoxelGrid& grid, const tabletop_capture::CameraModel& camera, int c,
                     const ProjectionTable* table, int x, int y, int z) {
  if (table) {
    const int p = PackedUV::pixelIndex(table->centre(c, x, y, z), camera.width);
    return p < camera.width * camera.height ? p : -1;  // else not observed
  }
  Eigen::Vector2d px;
  if (!camera.projectWorld(grid.centre(x, y, z), &px)) return -1;
  const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
  return u >= 0 && v >= 0 && u < camera.width && v < camera.height ? v * camera.width + u : -1;
}

std::vector<cv::Mat> occluderDepths(const ProbabilityVolume& volume, uint8_t threshold_byte,
                                    const std::vector<tabletop_capture::CameraModel>& cameras,
                                    const ProjectionTable* table, int threads) {
  const int n = static_cast<int>(cameras.size());
  constexpr float kNone = std::numeric_limits<float>::infinity();
  std::vector<cv::Mat> depth(n);
  for (int c = 0; c < n; ++c) depth[c] = cv::Mat(cameras[c].height, cameras[c].width, CV_32F, cv::Scalar(kNone));
  const VoxelGrid& g = volume.grid;
  if (n == 0 || volume.data.size() != g.numVoxels()) return depth;
  const bool use_table = table && table->precomputed() && table->grid() == g && table->numCameras() == n;
  std::vector<Eigen::Vector3i> occupied;
  for (size_t i = 0; i < volume.data.size(); ++i)
    if (volume.data[i] > threshold_byte) occupied.push_back(g.coords(i));
  if (occupied.empty()) return depth;
  const double half_diag = 0.5 * std::sqrt(3.0) * g.voxel_size;
#pragma omp parallel for num_threads(resolveThreads(threads)) schedule(static)
  for (int c = 0; c < n; ++c) {
    const auto& cam = cameras[c];
    cv::Mat& d = depth[c];
    float* px = d.ptr<float>();
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3i& o : occupied) {
      const int idx = voxelCentrePixel(g, cam, c, use_table ? table : nullptr, o.x(), o.y(), o.z());
      if (idx < 0) continue;
      const double dist = (g.centre(o.x(), o.y(), o.z()) - cam.center()).norm();
      px[idx] = std::min(px[idx], static_cast<float>(dist));
      nearest = std::min(nearest, dist);
    }
    if (!std::isfinite(nearest)) continue;
    const int r = static_cast<int>(std::ceil(half_diag * std::max(cam.fx, cam.fy) / std::max(0.05, nearest)));
    if (r > 0) cv::erode(d, d, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1)),
                         cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(kNone));
  }
  return depth;
}

cv::Mat frontOcclusionMask(const cv::Mat& depth, const tabletop_capture::CameraModel& camera,
                           const Eigen::Vector3d& point, double margin) {
  if (depth.type() != CV_32F) throw std::invalid_argument("frontOcclusionMask: depth must be CV_32F");
  if (!(margin >= 0.0 && std::isfinite(margin)) || !point.allFinite())
    throw std::invalid_argument("frontOcclusionMask: margin must be >= 0 and the point finite");
  const float limit = static_cast<float>((point - camera.center()).norm() - margin);
  cv::Mat active;
  // 255 where the nearest body is at least `limit` away (or absent: +inf), 0 where it is nearer.
  cv::compare(depth, limit, active, cv::CMP_GE);
  return active;
}

}  // namespace psfs
