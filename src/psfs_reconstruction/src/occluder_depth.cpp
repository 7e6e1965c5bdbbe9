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
    const int np = cam.width * cam.height;
    // Distances in float from the camera's centre: millimetres matter here, not nanometres.
    const Eigen::Vector3d o = g.origin - cam.center();
    const float ox = float(o.x()), oy = float(o.y()), oz = float(o.z()), s = float(g.voxel_size);
    float nearest = std::numeric_limits<float>::infinity();
    int u0 = cam.width, v0 = cam.height, u1 = -1, v1 = -1;  // the drawn pixels' box
    for (const Eigen::Vector3i& v : occupied) {
      int idx;
      if (use_table) {  // the stored table's entry (footprint level removed), as voxelCentrePixel reads it
        const size_t row = size_t(v.y()) + size_t(g.dims.y()) * size_t(v.z());
        const uint32_t packed = table->rowCentres(row, nullptr)[size_t(c) * table->paddedRowLength() + v.x()];
        idx = PackedUV::pixelIndex(table->footprintLevels() > 0 ? table->withoutLevel(c, packed) : packed, cam.width);
        if (idx >= np) continue;  // not observed
      } else {
        idx = voxelCentrePixel(g, cam, c, nullptr, v.x(), v.y(), v.z());
        if (idx < 0) continue;
      }
      const float dx = ox + s * (float(v.x()) + 0.5f), dy = oy + s * (float(v.y()) + 0.5f),
                  dz = oz + s * (float(v.z()) + 0.5f);
      const float dist = std::sqrt(dx * dx + dy * dy + dz * dz);
      px[idx] = std::min(px[idx], dist);
      nearest = std::min(nearest, dist);
      const int pu = idx % cam.width, pv = idx / cam.width;
      u0 = std::min(u0, pu), u1 = std::max(u1, pu), v0 = std::min(v0, pv), v1 = std::max(v1, pv);
    }
    if (!std::isfinite(nearest)) continue;
    const int r = static_cast<int>(std::ceil(half_diag * std::max(cam.fx, cam.fy) / std::max(0.05, double(nearest))));
    spreadNearest(&d, r, cv::Rect(u0, v0, u1 - u0 + 1, v1 - v0 + 1));
  }
  return depth;
}

void spreadNearest(cv::Mat* depth, int radius, const cv::Rect& drawn) {
  if (!depth || depth->type() != CV_32F) throw std::invalid_argument("spreadNearest: depth must be CV_32F");
  if (radius <= 0 || drawn.empty()) return;
  // Only pixels within the radius of a drawn one can change: filter that part (the filter reads
  // the +infinity around it from the whole image, as a filter of the whole image would).
  const cv::Rect part = (drawn + cv::Size(2 * radius, 2 * radius) - cv::Point(radius, radius)) &
                        cv::Rect(0, 0, depth->cols, depth->rows);
  if (part.empty()) return;
  cv::Mat roi = (*depth)(part);
  cv::erode(roi, roi, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * radius + 1, 2 * radius + 1)),
            cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(std::numeric_limits<float>::infinity()));
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
