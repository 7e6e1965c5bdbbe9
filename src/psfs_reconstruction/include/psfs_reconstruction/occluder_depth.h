// Known occlusions of the hand sub-volumes: per camera, how far away the person's body is at each
// pixel, so that a view where the body hides a hand gives that hand no evidence there.
//
// The hand sub-volumes are skin-class pSfS (4.2.2). A camera that sees the trunk, the other arm
// or the head in front of a hand sees clothing there, not skin, and its low likelihood would carve
// the hand. The thesis tolerates such views blindly (occlusion tolerance k, eq. 4.8: the lowest
// view is dropped wherever it is low), which also drops the one view that rightly carves a
// voxel next to the hand: with 4-6 cameras the hull of the remaining views is a bloated hand
// (docs/benchmarks.md, "Hand meshes"). Instead the occlusion is read from geometry: the body
// volume of the same set (every camera's pixels, as in the thesis' active camera flags but per
// pixel) says where something lies between the camera and the hand.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/projection_table.h"
#include "tabletop_capture/camera_model.h"

namespace psfs {

// Pixel index (v * width + u) of voxel (x, y, z)'s centre in camera c, or -1 where it does not
// project into the camera's image: from `table` when given (a precomputed table of `grid` and
// the cameras; no lens model per voxel), else through the camera model, rounded to the nearest
// pixel. Shared with Reconstructor::backProject, which draws the body volume the same way.
int voxelCentrePixel(const VoxelGrid& grid, const tabletop_capture::CameraModel& camera, int c,
                     const ProjectionTable* table, int x, int y, int z);

// Per camera a CV_32F image of the distance (m) from the camera's centre to the nearest voxel of
// `volume` above `threshold_byte` whose footprint covers the pixel; +infinity where none does.
// Each voxel centre is drawn at its pixel, then spread by a min filter as wide as a voxel's
// half diagonal projects at the nearest occupied voxel's distance (as Reconstructor::backProject
// dilates its masks): a conservative (wide) footprint. `table`, when it is a precomputed table of
// volume's grid and these cameras, gives the centres' pixels without the lens model.
std::vector<cv::Mat> occluderDepths(const ProbabilityVolume& volume, uint8_t threshold_byte,
                                    const std::vector<tabletop_capture::CameraModel>& cameras,
                                    const ProjectionTable* table, int threads = 0);

// The min filter of occluderDepths: each pixel of `depth` (CV_32F, +infinity where nothing is
// drawn) takes the smallest value within `radius` pixels (a square), pixels beyond the image
// counting as +infinity. `drawn` holds every finite pixel; only the pixels within the radius
// of it are filtered (the rest stay +infinity, as a filter of the whole image leaves them).
void spreadNearest(cv::Mat* depth, int radius, const cv::Rect& drawn);

// The active mask (ViewImage::active) of one camera for a sub-volume around `point`: 0 where the
// body lies nearer to the camera than the point by more than `margin` (m), 255 elsewhere. The
// margin keeps the hand's own surface and its wrist (within about 0.1 m of its centre) from
// masking the hand.
cv::Mat frontOcclusionMask(const cv::Mat& depth, const tabletop_capture::CameraModel& camera,
                           const Eigen::Vector3d& point, double margin);

}  // namespace psfs
