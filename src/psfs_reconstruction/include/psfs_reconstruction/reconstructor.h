// One frame set in, the pSfS volumes out: the whole per-frame pipeline of thesis chapter 4 as a
// ROS-free object (the nodelet is a thin wrapper around it, tests drive it directly).
//
//   optional noise filter on every image (image_prefilter.h; all the stages below see it)
//   -> background learning (first learning_frames sets, or a loaded model; a set that shows a
//   change against the sets learned so far, e.g. a person sitting down, is not learned)
//   -> pixel classification (P'(F|c), P'(F,S|c) per camera, one pass)
//   -> view evidence (log terms, bilinear pairs) for the body and the skin class
//   -> body volume and skin volume on the workspace grid (shared projection table)
//   -> hand sub-volumes around requested ROIs (skin class, moving grids projected on the fly)
//   -> selective background update with the foreground mask: the back-projection of the body
//      volume, or masks the caller supplies (the body tracker, later).
//
// Bad input never corrupts the state: process() validates the whole frame set first and throws
// std::invalid_argument naming the camera and the problem (count, encoding, size, calibration),
// leaving the models as they were. A rig that changes on purpose (another camera count or image
// size) resets the background models and relearns them; a calibration change only rebuilds the
// projection tables. Cameras that deliver an (almost) all-dark image are switched off for the
// frame and reported, so a covered lens degrades the volume instead of carving it. An empty image
// (a camera missing from a degraded frame set) switches its camera off the same way, and such a
// set is not learned into the background.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "psfs_reconstruction/background_model.h"
#include "psfs_reconstruction/clothing_colour.h"
#include "psfs_reconstruction/gaussian_mixture.h"
#include "psfs_reconstruction/image_prefilter.h"
#include "psfs_reconstruction/pixel_classifier.h"
#include "psfs_reconstruction/probability_volume.h"
#include "psfs_reconstruction/projection_table.h"
#include "psfs_reconstruction/psfs_fusion.h"
#include "psfs_reconstruction/view_evidence.h"
#include "psfs_reconstruction/voxel_grid.h"
#include "tabletop_capture/camera_model.h"

namespace psfs {

struct ReconstructorParams {
  // The noise filter before the background model and the classifier (image_prefilter.h).
  ImagePrefilterParams prefilter;
  PixelClassifierParams classifier;
  BackgroundModelParams background;
  // The person's clothing colour, learned from the trunk of each set's body volume, in the skin
  // classifier's p(c|notS) from the next set on (clothing_colour.h).
  ClothingColourParams clothing;
  // Volume of the body and skin volumes (DESIGN.md section 3 user space) and its resolution.
  // 64x64x48 (15.6 mm) is the tracking resolution of the thesis; a voxel that large spans
  // several pixels, so its evidence must cover its footprint: the body/skin options use the
  // thesis' multi-projection test by default. Footprint-filtered evidence (body/skin.footprint)
  // costs a half to a third of it with a better body hull, but the trackers were tuned on the
  // multi-projection volumes (docs/benchmarks.md, "pSfS footprint-filtered evidence").
  Workspace workspace;
  Eigen::Vector3i dims{64, 64, 48};
  // Expected occupancy of the workspace by the foreground hull P(H_F) and by the skin-coloured
  // hull P(H) (fractions of the volume): they set the classifier's priors
  // P(F) = P(H_F)^(1/C), P(S) = P(H)^(1/C) / P(F) (thesis 4.2.2). A seated person fills about
  // 8 % of the 1 x 1 x 0.75 m box, face and hands about 0.5 %.
  double hull_occupancy_foreground = 0.08;
  double hull_occupancy_skin = 0.005;
  // Fusion of the body volume (P'(F|c)), the skin volume and the hand sub-volumes (P'(F,S|c)).
  // Skin tolerates one occluded view by default: a hand or the face is hidden from some camera
  // in most frames (by the other hand, the head, the monitor), and an AND over views would
  // erase it.
  PsfsOptions body = defaultBody();
  PsfsOptions skin = defaultSkin();
  PsfsOptions hand = defaultHand();
  // Footprint-filtered evidence (used where body.footprint and skin.footprint are set; both
  // or neither, since they share one table): the filters of each class
  // and the workspace table's level choice (ProjectionTableOptions::footprint_scale). Hand
  // sub-volumes always read level 0, the plain terms.
  FootprintFilter body_footprint{3, FootprintStatistic::kMedian};
  FootprintFilter skin_footprint{3, FootprintStatistic::kMean};
  double footprint_scale = 0.7;
  // Hand sub-volumes: cubes of hand_roi_edge metres with hand_roi_voxels per side around each
  // requested ROI centre, snapped to a world lattice (0.30 m / 83 = 3.6 mm voxels, thesis 4.3).
  double hand_roi_edge = 0.30;
  int hand_roi_voxels = 83;
  // Hand sub-volumes hold nothing below the workspace's floor (workspace.min_corner z, the desk
  // top in DESIGN's world frame). A hand on the desk puts half its cube under the desk top;
  // over the desk those voxels are hidden from every camera, project onto the hand above them
  // in all of them and fill with its evidence: a slab of phantom skin under the hand. The hand
  // fusion skips those layers (PsfsOptions::floor_z).
  bool hand_roi_clip_floor = true;
  // Known occlusions of the hand sub-volumes (occluder_depth.h): a camera's pixels where this
  // set's body volume lies nearer to the camera than the hand's ROI centre by more than
  // hand_occlusion_margin (m) give that hand no evidence (the trunk, the other arm or the head
  // hides it there). Off: every pixel counts, and only the hand fusion's occlusion tolerance
  // (hand.occluded_views, then 1) survives a view that sees clothing in front of the hand, at
  // the cost of a hull fattened by the view it drops (docs/benchmarks.md, "Hand sub-volumes:
  // known occlusions"). On the GPU backend the masked hand fusion runs on the CPU.
  bool hand_occlusion_masks = true;
  double hand_occlusion_margin = 0.12;
  // Selective background update after each reconstructed frame (alpha in `background`).
  bool update_background = true;
  // Extra pixels added around the back-projected body volume before it masks the update: the
  // volume is coarse (a 16 mm voxel is ~3 px) and its edge must not leak the person into the
  // background model.
  int mask_margin_px = 2;
  // A camera whose image has more than this fraction of too-dark pixels (see
  // PixelClassifierParams::min_chroma_intensity) is switched off for the frame.
  double dark_camera_fraction = 0.9;
  // Saturated-pixel fraction above which a camera is reported as overexposed (it still counts).
  double saturated_warning_fraction = 0.3;
  // Relearning (a relearn request, a time jump) with models learned before: a learning set in
  // which those models see more body volume than this (litres, at the body threshold) is not
  // empty and is not learned. An empty workspace shows well under 0.1 l; a hand ~0.4 l.
  double learning_max_occupied_litres = 0.3;
  int threads = 0;  // OpenMP threads for every stage (0 = OpenMP default)
  // Where classification, fusion and the background update run: kCpu, or kCuda (the GPU
  // backend, cuda_device.h; the same results). kCuda falls back to the CPU, reported once in
  // FrameResult::warnings, where the backend is not compiled in, no device is usable, or a
  // CUDA call fails.
  enum class Backend { kCpu, kCuda };
  Backend backend = Backend::kCpu;

  // Empty space skipped below 0.5 (PsfsOptions::skip_empty_below): the hull and every voxel
  // at or above 0.5 as without it, at about 0.4 of the multi-projection's cost on the default
  // rig; over 96 generated scenarios the volumes, heads and IoUs unchanged, the hands' medians
  // within 0.6 mm (docs/benchmarks.md, "pSfS: empty-space skipping in the multi-projection test" and
  // "... by chunks of 8 voxels").
  static PsfsOptions defaultBody() {
    PsfsOptions o;
    o.multi_projection = true;
    o.skip_empty_below = 0.5;
    return o;
  }
  static PsfsOptions defaultSkin() {
    PsfsOptions o;
    o.multi_projection = true;
    o.occluded_views = 1;
    o.skip_empty_below = 0.5;
    return o;
  }
  // No tolerated view: the hands' known occlusions are masked instead (hand_occlusion_masks;
  // without the masks, 1 keeps a hand that the trunk hides in one view). Empty space skipped
  // below 0.5 with a strict bound and a margin of two voxels: the voxels at or above 0.5 and
  // those within 2 of them (all that marching cubes at an iso above 0.5 reads, normals
  // included) as without it (src/centre_space_bound.h; docs/benchmarks.md, "pSfS: empty-space
  // skipping in the hand sub-volumes").
  static PsfsOptions defaultHand() {
    PsfsOptions o;
    o.occluded_views = 0;
    o.skip_empty_below = 0.5;
    return o;
  }
  // Throws std::invalid_argument naming the field.
  void validate() const;
};

struct StageTimes {  // wall time per stage of the last frame (ms)
  double classify = 0, evidence = 0, body = 0, skin = 0, hands = 0, background = 0, total = 0;
  double clothing = 0;  // measuring the clothing colour (clothing_colour.h)
  double prefilter = 0;  // the images' noise filter (image_prefilter.h)
};

struct FrameResult {
  enum class Status {
    kLearningBackground,  // the frame went into the background model; no volumes yet
    kReconstructed,
  };
  Status status = Status::kLearningBackground;
  int background_frames = 0;  // learned so far (== learning_frames once ready)
  // While learning: the set showed a change against the sets learned so far (a person in
  // view) and was not learned (see BackgroundModelParams::learning_change_fraction).
  bool learning_skipped = false;
  ProbabilityVolume body, skin;
  std::vector<ProbabilityVolume> hands;  // one per requested ROI, same order
  // Share of the hand sub-volumes' voxels that empty-space skipping left out (mean over the
  // hands; 0 without hands or skipping; hand.skip_empty_below).
  double hands_skipped = 0.0;
  std::vector<ClassificationStats> stats;
  // The trunk's colour measured in this set (clothing_colour.h; valid false when off or not
  // found); the classifier uses the running estimate from the next set on.
  TrunkColourSample trunk_colour;
  std::vector<bool> camera_active;  // false = switched off this frame (dark, or no image)
  StageTimes times;
  // Things the caller should report (throttled): dark or overexposed cameras, rig changes.
  std::vector<std::string> warnings;
  // Where this frame set ran (ReconstructorParams::backend, after any fallback).
  ReconstructorParams::Backend backend = ReconstructorParams::Backend::kCpu;
};

class GpuFramePath;  // private (src/gpu_frame_path.h)

class Reconstructor {
 public:
  // Throws std::invalid_argument for an empty skin model or invalid parameters.
  Reconstructor(const GaussianMixture2D& skin_model, const ReconstructorParams& params);
  ~Reconstructor();

  const ReconstructorParams& params() const { return params_; }
  // The clothing colour the next set's classification uses (valid() false: none yet).
  const ClothingColourModel& clothingColour() const { return clothing_; }

  // One frame set: rgb8 images in the cameras' order (an empty Mat: that camera is missing). hand_rois: centres (world, m) of the hand
  // sub-volumes wanted this frame. foreground_masks: optional CV_8UC1 per camera (nonzero =
  // foreground, e.g. the body tracker's silhouettes, which also cover the person outside the
  // grid) that mask the background update together with the volume's back-projection (their
  // union: a model's silhouettes alone miss hair, fingers and misplaced limbs, which were then
  // learned, carved from the volume and missed again: a runaway, test_body_loop); empty or
  // wrongly sized masks leave the back-projection alone.
  // Throws std::invalid_argument (nothing changed) for an invalid frame set.
  FrameResult process(const std::vector<cv::Mat>& rgb,
                      const std::vector<tabletop_capture::CameraModel>& cameras,
                      const std::vector<Eigen::Vector3d>& hand_rois = {},
                      const std::vector<cv::Mat>& foreground_masks = {});

  // Live tuning: the in-hull thresholds t of the three volumes from the next frame set on.
  // Throws std::invalid_argument (nothing changed) for a value PsfsFusion rejects.
  void setFusionThresholds(double body, double skin, double hand);

  bool backgroundReady() const;
  int numCameras() const { return static_cast<int>(cameras_.size()); }
  // The backend frames run on now: params().backend, or kCpu after a fallback.
  ReconstructorParams::Backend activeBackend() const { return active_backend_; }
  // Drops the background models: the next frames are learned again. If the scene is not empty
  // for learning_frames sets in a row, the models dropped here are used again (reported).
  void resetBackground();
  // Saves each camera's model as <directory>/<camera name>.bgm. Throws std::runtime_error if
  // the model is not ready or a file cannot be written.
  void saveBackground(const std::string& directory) const;
  // Loads <directory>/<name>.bgm for each camera; they are used once a frame set with these
  // cameras (names and sizes) arrives. Throws std::runtime_error naming the file that is
  // missing or invalid, or that was learned through another image prefilter than this
  // reconstructor's (BackgroundModelParams::image_filter); then nothing is loaded and the
  // background is learned as usual.
  void loadBackground(const std::string& directory,
                      const std::vector<tabletop_capture::CameraModel>& cameras);

  // The likelihood images of the last reconstructed frame set, one CV_8UC2 per camera
  // (pixel_classifier.h: P'(F|c), P'(F,S|c)); for tools and diagnostics.
  const std::vector<cv::Mat>& lastLikelihoods() const { return likelihoods_; }

  // The back-projection of a volume into each camera (255 = some voxel above threshold_byte
  // lands within the voxel's footprint + margin_px), using this reconstructor's cameras and the
  // volume's own grid. What the background update uses when no masks are supplied.
  std::vector<cv::Mat> backProject(const ProbabilityVolume& volume, uint8_t threshold_byte,
                                   int margin_px) const;

 private:
  void validateFrame(const std::vector<cv::Mat>& rgb,
                     const std::vector<tabletop_capture::CameraModel>& cameras) const;
  void adoptRig(const std::vector<tabletop_capture::CameraModel>& cameras,
                std::vector<std::string>* warnings);
  // Learning only from empty frame sets (BackgroundModelParams::learning_change_*).
  enum class LearningVerdict { kLearn, kSkip, kEndLearning };
  LearningVerdict checkLearningFrame(const std::vector<cv::Mat>& rgb,
                                     std::vector<std::string>* warnings);
  LearningVerdict skipLearningFrame(const std::string& why, std::vector<std::string>* warnings);
  // with_skin false: the body volume only (r->skin left empty), for the relearn check.
  // gpu: on the GPU path (backgrounds must be backgrounds_).
  void fuseWorkspace(const std::vector<cv::Mat>& rgb, const std::vector<BackgroundModel>& backgrounds,
                     FrameResult* r, bool with_skin = true, bool gpu = false);
  // Volumes, hand sub-volumes and the background update of a set whose models are ready.
  void reconstruct(const std::vector<cv::Mat>& rgb, const std::vector<Eigen::Vector3d>& hand_rois,
                   const std::vector<cv::Mat>& foreground_masks, bool gpu, FrameResult* r);
  // After a GPU failure: the CPU from now on, with the device's newest models if it still
  // gives them, reported in `warnings`.
  void dropGpu(const std::string& what, std::vector<std::string>* warnings);
  double occupiedLitresAgainstPrevious(const std::vector<cv::Mat>& rgb);
  // The clothing colour from this set's body volume, for the next set's classification.
  void learnClothingColour(const std::vector<cv::Mat>& rgb,
                           const std::vector<Eigen::Vector3d>& hands, FrameResult* r);
  void setClothingColour(const ColourGaussian* colour);

  ReconstructorParams params_;
  PixelClassifier classifier_;
  ClothingColourModel clothing_;
  PsfsFusion body_fusion_, skin_fusion_, hand_fusion_;
  std::vector<tabletop_capture::CameraModel> cameras_;
  std::vector<BackgroundModel> backgrounds_;
  std::vector<BackgroundModel> loaded_backgrounds_;  // waiting for their rig
  // The models in use when resetBackground() was last called: taken back when the new learning
  // never sees an empty scene (a relearn or a time jump with the person in view); dropped once
  // a learning finishes.
  std::vector<BackgroundModel> previous_backgrounds_;
  std::vector<std::string> loaded_names_;
  std::unique_ptr<ProjectionTable> table_;          // workspace grid (body and skin)
  std::vector<std::unique_ptr<ProjectionTable>> hand_tables_;
  std::vector<cv::Mat> likelihoods_;
  std::vector<cv::Mat> filtered_;  // this set's images after the prefilter (reused buffers)
  ViewEvidence body_evidence_, skin_evidence_;
  ViewEvidence hand_evidence_;  // skin evidence with one hand's occlusion masks (reused)
  int learning_skips_ = 0;  // changed learning sets in a row
  ReconstructorParams::Backend active_backend_ = ReconstructorParams::Backend::kCpu;
  std::unique_ptr<GpuFramePath> gpu_;  // the GPU path while active_backend_ is kCuda
  std::string backend_warning_;  // a fallback to report with the next frame set
};

}  // namespace psfs
