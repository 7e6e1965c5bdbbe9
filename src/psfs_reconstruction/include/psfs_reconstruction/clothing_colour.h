// The person's clothing colour, learned from the trunk, as a second colour in the skin
// classifier's non-skin density p(c|notS) (pixel_classifier.h).
//
// Why: the thesis' skin model has a uniform p(c|notS), so a shirt whose chroma lies inside the
// skin cluster (tan, brown, wood: a quarter of the generated scenarios) is skin in every view,
// the skin volume holds the torso, and the hands' blobs join it (docs/benchmarks.md, "pSfS:
// the clothing colour"). The trunk is clothing in every scenario and the body volume finds it
// reliably. Its chroma is a narrow Gaussian q (one fabric, one light); p(c|notS) = 1 + weight q
// lowers P(S|c) for that colour only. The uniform part stays: taking mass from it would raise
// P(S|c) for every other colour, skin-coloured clutter included.
//
// The trunk, from the body volume at the body threshold (z up from the desk):
//  1. the upper body's axis: the median x, y of the occupied voxels less than 0.55 m below the
//     highest one (arms stretched forward are fewer voxels than the trunk);
//  2. its top: the highest occupied voxel within core_radius of the axis (the head's top);
//  3. the chest band: those within core_radius, band_top .. band_bottom below that top, and
//     farther than hand_exclusion_radius from every hand the tracker reports.
// At most 400 band voxels (every k-th; ~0.3 ms a set) are projected into every active camera;
// a pixel's chroma is a sample unless it is too dark for a chroma or saturated. The estimate is
// the samples within trim_radius of their median (hair and arms in front are outliers): their
// mean and covariance plus min_sd^2, if min_samples or more were taken and at least
// min_inlier_fraction are inliers (a patterned top gives none). Sets blend in at update_rate.
// Deterministic: a pure function of the sets in order.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "psfs_reconstruction/colour_gaussian.h"
#include "psfs_reconstruction/probability_volume.h"
#include "tabletop_capture/camera_model.h"

namespace psfs {

struct ClothingColourParams {
  bool enabled = true;
  // Weight of the clothing colour's Gaussian q in p(c|notS) = 1 + weight q(c) (dimensionless,
  // >= 0; q peaks at 1 / (2 pi sd^2), ~1600 for an sd of 0.01). 0 leaves the thesis' uniform
  // density.
  double weight = 0.5;
  // The chest band, metres below the top of the trunk's column, and the column's radius (m).
  double band_top = 0.30;
  double band_bottom = 0.55;
  double core_radius = 0.12;
  // Band voxels this close to a tracked hand (m) are not sampled: a hand raised to the chest is
  // skin, not clothing.
  double hand_exclusion_radius = 0.15;
  // Robust estimate: inliers lie within trim_radius (normalised rg) of the samples' median.
  double trim_radius = 0.03;
  double min_inlier_fraction = 0.6;
  int min_samples = 200;
  // Standard deviation floor added to the estimate (normalised rg): a perfectly uniform fabric
  // would otherwise give a spike that misses its own noisy pixels.
  double min_sd = 0.005;
  // Weight of a frame's estimate in the running one (1 = the last frame only).
  double update_rate = 0.2;
  // Throws std::invalid_argument naming the field.
  void validate() const;
  bool active() const { return enabled && weight > 0.0; }  // learned and used at all
};

// One frame set's measurement of the trunk's colour.
struct TrunkColourSample {
  bool valid = false;  // enough samples, enough of them inliers
  ColourGaussian colour;
  int samples = 0;               // pixel samples taken
  double inlier_fraction = 0.0;  // of those, within trim_radius of the median
  int band_voxels = 0;           // occupied voxels in the chest band
};

// rgb: rgb8 images (CV_8UC3), one per camera (empty or another type: not sampled); active: the
// cameras that count (a camera past its end counts); hands: tracked hand centres (world, m);
// occupied_byte: voxels above it are occupied; min_intensity: darker pixels ((R+G+B)/3, 8-bit
// levels) have no chroma.
TrunkColourSample measureTrunkColour(const ProbabilityVolume& body, uint8_t occupied_byte,
                                     const std::vector<cv::Mat>& rgb,
                                     const std::vector<tabletop_capture::CameraModel>& cameras,
                                     const std::vector<bool>& active,
                                     const std::vector<Eigen::Vector3d>& hands,
                                     float min_intensity, const ClothingColourParams& params);

// The running estimate over frames.
class ClothingColourModel {
 public:
  explicit ClothingColourModel(const ClothingColourParams& params = {});
  // Blends a valid sample in (an invalid one leaves the model as it was): the mixture's mean
  // and covariance, spread between the means included.
  void update(const TrunkColourSample& sample);
  void reset() { valid_ = false; }
  bool valid() const { return valid_; }
  const ColourGaussian& colour() const { return colour_; }
  const ClothingColourParams& params() const { return params_; }

 private:
  ClothingColourParams params_;
  bool valid_ = false;
  ColourGaussian colour_;
};

}  // namespace psfs
