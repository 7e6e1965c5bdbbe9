// Private: the Reconstructor's GPU path (ReconstructorParams::backend = kCuda, issue 20): the
// pixel stage (classification, evidence, background update: GpuPixelStage) and the three
// fusions (GpuPsfsFusion) on one device, with the bookkeeping of which side holds the newest
// background models. The Reconstructor keeps every decision (learning, camera checks, masks,
// warnings) on the host and calls this where the CPU path would classify, build evidence, fuse
// or update; any CUDA failure throws std::runtime_error and the Reconstructor falls back.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "psfs_reconstruction/background_model.h"
#include "psfs_reconstruction/gpu_pixel_stage.h"
#include "psfs_reconstruction/gpu_psfs_fusion.h"
#include "psfs_reconstruction/reconstructor.h"
#include "empty_space_bound.h"

namespace psfs {

class GpuFramePath {
 public:
  // Throws std::runtime_error (with the reason) when the device or a part of the backend is
  // not usable, std::invalid_argument like the CPU classes for bad parameters. params.body,
  // .skin and .hand are the fusion options as the CPU path runs them (the Reconstructor sets
  // the hand's floor_z); so are setFusion's.
  GpuFramePath(const GaussianMixture2D& skin, const ReconstructorParams& params);

  void setPriors(const ClassPriors& priors) { pixels_.setPriors(priors); }
  void setClothingColour(const ColourGaussian* colour, double weight) {
    pixels_.setClothingColour(colour, weight);
  }
  void setFusion(const PsfsOptions& body, const PsfsOptions& skin, const PsfsOptions& hand);

  // The host's models changed (learned, relearned, loaded, another rig): upload them before
  // the next frame.
  void modelsChanged() { device_current_ = false, device_newer_ = false; }
  // Copies the device's models into `models` if the device updated them since they were
  // uploaded (and then the host's are current again).
  void syncModels(std::vector<BackgroundModel>* models);
  // The same into a copy, leaving the bookkeeping alone (saving from a const Reconstructor).
  void copyModels(std::vector<BackgroundModel>* models) const;

  // One frame, in the CPU path's order. classify uploads `models` first when they changed.
  std::vector<ClassificationStats> classify(const std::vector<cv::Mat>& rgb,
                                            const std::vector<BackgroundModel>& models,
                                            std::vector<cv::Mat>* likelihoods);
  void buildEvidence(const std::vector<bool>& camera_active, const std::vector<cv::Mat>& likelihoods,
                     bool with_skin);
  void fuseBody(const ProjectionTable& table, ProbabilityVolume* out);
  void fuseSkin(const ProjectionTable& table, ProbabilityVolume* out);
  // Returns the share of the voxels the CPU path skips (set to 0 here, as there).
  double fuseHand(const ProjectionTable& table, ProbabilityVolume* out);
  void updateBackground(const std::vector<cv::Mat>& masks, const std::vector<bool>& camera_active);

 private:
  GpuPixelStage pixels_;
  GpuPsfsFusion body_, skin_, hand_;
  bool body_bilinear_, skin_bilinear_;
  std::vector<cv::Mat> off_masks_;   // all-zero masks of switched-off views, kept per camera
  // Empty-space skipping (PsfsOptions::skip_empty_below): the device fuses every voxel; the
  // chunks the CPU path skips are set to its fill from the host likelihoods' bounds.
  detail::EmptySkipCache body_skip_, skin_skip_, hand_skip_;
  std::vector<ViewImage> skin_views_;  // this frame's skin likelihoods and masks, on the host
  bool device_current_ = false;      // the device holds the host's models (or newer ones)
  bool device_newer_ = false;        // the device updated them since they were uploaded
};

}  // namespace psfs
