// The constants a ProjectionTable projects with, as plain data (no Eigen, no camera model), so
// that the same projection code (src/voxel_projection.h, __host__ __device__) runs in the CPU
// table build and on a GPU (gpu_psfs_fusion.h), giving the same packed values.
#pragma once

#include <cstdint>

namespace psfs {

// One camera. The float part is the per-voxel projection of the voxel centres (packed as
// PackedUV); the double part the row constants and the multi-projection sample offsets.
struct ProjectionCamera {
  // Centres: camera-frame position of a voxel = camera_R_world (row-major) * (p - position).
  double camera_R_world[9];
  double position[3];
  // PackedUV stores 16 (u + 0.5): U = fx16 * xd + cx16 with fx16 = 16 fx, cx16 = 16 (cx + 0.5).
  float fx16, fy16, cx16, cy16;
  float k1, k2, k3, p1, p2, p1x2, p2x2;  // plumb_bob; p1x2 = 2 p1, p2x2 = 2 p2
  float r2_max;                          // valid range of the lens model (squared normalised radius)
  float u_max, v_max;                    // 16 * width, 16 * height
  uint32_t not_observed;                 // PackedUV::notObserved(height)
  int width, height;
  double focal;                          // sqrt(fx fy), for the footprint levels
  // Sample offsets: camera_T_world = world_T_camera.inverse() (rotation row-major, translation)
  // and the double camera model of tabletop_capture::CameraModel::projectCamera.
  double camera_T_world_R[9], camera_T_world_t[3];
  double fx, fy, cx, cy;
  double distortion[5];                  // k1, k2, p1, p2, k3
};

// The grid and the table options the projection needs.
struct ProjectionGrid {
  double origin[3];
  double voxel_size;
  int nx, ny, nz;
  int nxp;      // nx rounded up to ProjectionTable::kChunk
  int chunks;   // nxp / kChunk
  int footprint_levels;    // 0 or 2..ProjectionTable::kMaxFootprintLevels
  double footprint_scale;
};

}  // namespace psfs
