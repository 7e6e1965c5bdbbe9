#include "psfs_reconstruction/reconstructor.h"

#include <algorithm>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <omp.h>

#include <opencv2/imgproc.hpp>

#include "cpu_dispatch.h"
#include "gpu_frame_path.h"
#include "psfs_reconstruction/cuda_device.h"
#include "psfs_reconstruction/image_checks.h"
#include "psfs_reconstruction/occluder_depth.h"
#include "tabletop_capture/rig_description.h"

namespace psfs {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

bool sameCamera(const tabletop_capture::CameraModel& a, const tabletop_capture::CameraModel& b) {
  return a.name == b.name && a.width == b.width && a.height == b.height && a.fx == b.fx &&
         a.fy == b.fy && a.cx == b.cx && a.cy == b.cy && a.distortion == b.distortion &&
         a.world_T_camera.matrix() == b.world_T_camera.matrix();
}

std::string percent(double fraction) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.0f %%", 100.0 * fraction);
  return buf;
}

// The hand sub-volumes' fusion options: nothing below the workspace's floor (the desk top) when
// hand_roi_clip_floor is set (or below the options' own floor, if higher); over the desk no
// camera sees there, and without the floor the voxels under a hand resting on it take the
// hand's evidence. The CPU fusion, the GPU frame path and live tuning all take these.
PsfsOptions handFusionOptions(const ReconstructorParams& params, PsfsOptions hand) {
  if (params.hand_roi_clip_floor)
    hand.floor_z = std::max(hand.floor_z, params.workspace.min_corner.z());
  return hand;
}

}  // namespace

void ReconstructorParams::validate() const {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("psfs::ReconstructorParams: " + what);
  };
  if (!(dims.minCoeff() >= 1)) fail("dims must be >= 1 along every axis");
  workspaceGrid(workspace, dims).validate();
  if (!(hull_occupancy_foreground > 0 && hull_occupancy_foreground < 1))
    fail("hull_occupancy_foreground must lie in (0, 1)");
  if (!(hull_occupancy_skin > 0 && hull_occupancy_skin <= hull_occupancy_foreground))
    fail("hull_occupancy_skin must lie in (0, hull_occupancy_foreground]");
  if (!(hand_roi_edge > 0 && std::isfinite(hand_roi_edge))) fail("hand_roi_edge must be > 0");
  if (hand_roi_voxels < 2 || hand_roi_voxels > 512) fail("hand_roi_voxels must lie in [2, 512]");
  if (!(hand_occlusion_margin >= 0 && std::isfinite(hand_occlusion_margin)))
    fail("hand_occlusion_margin must be finite and >= 0");
  if (mask_margin_px < 0 || mask_margin_px > 50) fail("mask_margin_px must lie in [0, 50]");
  if (!(dark_camera_fraction > 0 && dark_camera_fraction <= 1))
    fail("dark_camera_fraction must lie in (0, 1]");
  if (!(learning_max_occupied_litres >= 0 && std::isfinite(learning_max_occupied_litres)))
    fail("learning_max_occupied_litres must be finite and >= 0");
  if (!(saturated_warning_fraction > 0 && saturated_warning_fraction <= 1))
    fail("saturated_warning_fraction must lie in (0, 1]");
  if (threads < 0) fail("threads must be >= 0");
  if (hand.footprint) fail("hand.footprint is not supported (hand tables are projected on the fly)");
  if (hand.skip_empty_below != 0.0 && hand.multi_projection)
    fail("hand.skip_empty_below needs the single projection (hand.multi_projection false): the "
         "multi-projection bound is derived once per table, and a hand's cube moves every frame");
  if (body.footprint != skin.footprint)
    fail("body.footprint and skin.footprint must agree (one shared workspace table)");
  for (const FootprintFilter* f : {&body_footprint, &skin_footprint})
    if (f->levels < 2 || f->levels > ProjectionTable::kMaxFootprintLevels)
      fail("footprint levels must lie in [2, 3]");
  if (!(footprint_scale > 0 && std::isfinite(footprint_scale))) fail("footprint_scale must be > 0");
  clothing.validate();
  prefilter.validate();
}

namespace {
// The parameters with the background models tagged by the images' filter (saved with them).
ReconstructorParams withFilterTag(const ReconstructorParams& params) {
  params.validate();
  ReconstructorParams p = params;
  p.background.image_filter = describeImagePrefilter(p.prefilter);
  return p;
}
}  // namespace

Reconstructor::Reconstructor(const GaussianMixture2D& skin_model, const ReconstructorParams& params)
    : params_(withFilterTag(params)),
      classifier_(skin_model, params.classifier),
      clothing_(params.clothing),
      body_fusion_(params.body),
      skin_fusion_(params.skin),
      hand_fusion_(handFusionOptions(params, params.hand)) {
  // Background parameters are checked by constructing a model with them.
  BackgroundModel probe(1, 1, params_.background);
  (void)probe;
  if (params.backend == ReconstructorParams::Backend::kCuda) {
    const cuda::DeviceInfo& d = cuda::device();
    if (!d.usable) {
      backend_warning_ = "backend cuda: " + d.describe() + "; running on the CPU";
    } else {
      try {
        ReconstructorParams device_params = params_;
        device_params.hand = handFusionOptions(params, params.hand);
        gpu_ = std::make_unique<GpuFramePath>(skin_model, device_params);
        active_backend_ = ReconstructorParams::Backend::kCuda;
      } catch (const std::runtime_error& e) {
        backend_warning_ = std::string("backend cuda: ") + e.what() + "; running on the CPU";
      }
    }
  }
}

void Reconstructor::dropGpu(const std::string& what, std::vector<std::string>* warnings) {
  std::string models = "";
  try {
    gpu_->syncModels(&backgrounds_);
  } catch (const std::exception& e) {
    models = " (the background updates since the models were uploaded are lost: " +
             std::string(e.what()) + ")";
  }
  gpu_.reset();
  active_backend_ = ReconstructorParams::Backend::kCpu;
  warnings->push_back("backend cuda failed: " + what + "; running on the CPU from now on" + models);
}

Reconstructor::~Reconstructor() = default;

void Reconstructor::setFusionThresholds(double body, double skin, double hand) {
  PsfsOptions b = params_.body, s = params_.skin, h = params_.hand;
  b.threshold = body;
  s.threshold = skin;
  h.threshold = hand;
  PsfsFusion fb(b), fs(s), fh(handFusionOptions(params_, h));  // each checks its options first
  body_fusion_ = fb;
  skin_fusion_ = fs;
  hand_fusion_ = fh;
  if (gpu_) gpu_->setFusion(b, s, fh.options());
  params_.body = b;
  params_.skin = s;
  params_.hand = h;
}

bool Reconstructor::backgroundReady() const {
  if (backgrounds_.empty()) return false;
  for (const auto& b : backgrounds_)
    if (!b.ready()) return false;
  return true;
}

void Reconstructor::resetBackground() {
  if (gpu_) {
    try {
      gpu_->syncModels(&backgrounds_);
    } catch (const std::runtime_error& e) {
      std::vector<std::string> ignored;  // the next frame set finds the GPU path gone
      dropGpu(e.what(), &ignored);
    }
    if (gpu_) gpu_->modelsChanged();
  }
  if (backgroundReady()) previous_backgrounds_ = backgrounds_;
  for (auto& b : backgrounds_) b = BackgroundModel(b.width(), b.height(), params_.background);
  learning_skips_ = 0;
  clothing_.reset();  // perhaps another person, or another light
  setClothingColour(nullptr);
}

void Reconstructor::setClothingColour(const ColourGaussian* colour) {
  classifier_.setClothingColour(colour, params_.clothing.weight);
  if (gpu_) gpu_->setClothingColour(colour, params_.clothing.weight);
}

void Reconstructor::learnClothingColour(const std::vector<cv::Mat>& rgb,
                                        const std::vector<Eigen::Vector3d>& hands, FrameResult* r) {
  if (!params_.clothing.active()) return;
  r->trunk_colour = measureTrunkColour(r->body, thresholdByte(params_.body.threshold), rgb,
                                       cameras_, r->camera_active, hands,
                                       params_.classifier.min_chroma_intensity, params_.clothing);
  clothing_.update(r->trunk_colour);
  if (clothing_.valid()) setClothingColour(&clothing_.colour());
}

void Reconstructor::validateFrame(const std::vector<cv::Mat>& rgb,
                                  const std::vector<tabletop_capture::CameraModel>& cameras) const {
  if (cameras.empty()) throw std::invalid_argument("frame set has no cameras");
  if (rgb.size() != cameras.size())
    throw std::invalid_argument("frame set has " + std::to_string(rgb.size()) + " images but " +
                                std::to_string(cameras.size()) + " cameras");
  if (std::all_of(rgb.begin(), rgb.end(), [](const cv::Mat& m) { return m.empty(); }))
    throw std::invalid_argument("frame set has no image (every camera missing)");
  for (size_t i = 0; i < cameras.size(); ++i) {
    const auto& cam = cameras[i];
    const std::string name = cam.name.empty() ? "camera " + std::to_string(i) : cam.name;
    try {
      tabletop_capture::validateCamera(cam, "frame set", static_cast<int>(i));
    } catch (const std::exception& e) {
      throw std::invalid_argument(name + ": invalid calibration: " + e.what());
    }
    if (!rgb[i].empty() && (rgb[i].cols != cam.width || rgb[i].rows != cam.height))
      throw std::invalid_argument(name + ": image is " + std::to_string(rgb[i].cols) + "x" +
                                  std::to_string(rgb[i].rows) + " but its calibration says " +
                                  std::to_string(cam.width) + "x" + std::to_string(cam.height));
    if (!rgb[i].empty()) checkRgb8(rgb[i], cam.width, cam.height, name);
  }
}

void Reconstructor::adoptRig(const std::vector<tabletop_capture::CameraModel>& cameras,
                             std::vector<std::string>* warnings) {
  bool layout_changed = cameras.size() != cameras_.size();
  bool calibration_changed = layout_changed;
  for (size_t i = 0; !layout_changed && i < cameras.size(); ++i) {
    layout_changed = cameras[i].width != cameras_[i].width ||
                     cameras[i].height != cameras_[i].height || cameras[i].name != cameras_[i].name;
    calibration_changed = calibration_changed || !sameCamera(cameras[i], cameras_[i]);
  }
  if (layout_changed) {
    if (!cameras_.empty())
      warnings->push_back("the rig changed (" + std::to_string(cameras_.size()) + " -> " +
                          std::to_string(cameras.size()) +
                          " cameras, or other names/image sizes): relearning the background from "
                          "the next " + std::to_string(params_.background.learning_frames) +
                          " frame sets");
    backgrounds_.clear();
    previous_backgrounds_.clear();
    clothing_.reset();  // seen through other cameras' white balance
    setClothingColour(nullptr);
    for (const auto& c : cameras)
      backgrounds_.emplace_back(c.width, c.height, params_.background);
    // A model loaded from files is used if it was saved for exactly these cameras.
    if (!loaded_backgrounds_.empty() && loaded_names_.size() == cameras.size()) {
      bool match = true;
      for (size_t i = 0; i < cameras.size(); ++i)
        match = match && loaded_names_[i] == cameras[i].name &&
                loaded_backgrounds_[i].width() == cameras[i].width &&
                loaded_backgrounds_[i].height() == cameras[i].height;
      if (match) {
        backgrounds_ = loaded_backgrounds_;
        for (auto& b : backgrounds_) b.setParams(params_.background);
      } else {
        warnings->push_back("the loaded background model was saved for other cameras: learning it");
      }
    }
    classifier_.setPriors(ClassPriors::fromOccupancy(params_.hull_occupancy_foreground,
                                                     params_.hull_occupancy_skin,
                                                     static_cast<int>(cameras.size())));
    if (gpu_) {
      gpu_->setPriors(classifier_.priors());
      gpu_->modelsChanged();
    }
    likelihoods_.assign(cameras.size(), cv::Mat());
  }
  if (calibration_changed) {
    cameras_ = cameras;
    const VoxelGrid grid = workspaceGrid(params_.workspace, params_.dims);
    ProjectionTableOptions o;
    o.multi_projection = params_.body.multi_projection || params_.skin.multi_projection;
    o.threads = params_.threads;
    if (params_.body.footprint || params_.skin.footprint) {
      o.footprint_levels = std::min(params_.body_footprint.levels, params_.skin_footprint.levels);
      o.footprint_scale = params_.footprint_scale;
    }
    if (!table_)
      table_ = std::make_unique<ProjectionTable>(grid, cameras_, o);
    else
      table_->update(grid, cameras_);
  }
}

Reconstructor::LearningVerdict Reconstructor::checkLearningFrame(
    const std::vector<cv::Mat>& rgb, std::vector<std::string>* warnings) {
  const int learned = backgrounds_[0].learnedFrames();
  const BackgroundModelParams& bp = params_.background;
  // After a relearn or a time jump the models used before still know the empty workspace: a
  // set in which they see a body is not empty, even if the person sits still (which the
  // change test below cannot see) or is there from the first learning set on.
  if (previous_backgrounds_.size() == backgrounds_.size()) {
    const double litres = occupiedLitresAgainstPrevious(rgb);
    if (litres > params_.learning_max_occupied_litres) {
      char what[160];
      std::snprintf(what, sizeof what, "the background model used before sees %.1f litres occupied "
                    "in the workspace (a person in view?)", litres);
      return skipLearningFrame(what, warnings);
    }
  }
  if (learned < 1) return LearningVerdict::kLearn;
  double worst = 0;
  size_t worst_camera = 0;
  for (size_t i = 0; i < backgrounds_.size(); ++i) {
    const double f = backgrounds_[i].changedFraction(rgb[i]);
    if (f > worst) worst = f, worst_camera = i;
  }
  if (worst <= bp.learning_change_fraction) {
    learning_skips_ = 0;
    return LearningVerdict::kLearn;
  }
  const std::string what = percent(worst) + " of " + cameras_[worst_camera].name +
                           "'s pixels changed against the " + std::to_string(learned) +
                           " empty frame sets learned so far";
  if (learned >= std::min(bp.min_learning_frames, bp.learning_frames)) {
    warnings->push_back("background learning ended after " + std::to_string(learned) + " of " +
                        std::to_string(bp.learning_frames) + " frame sets: " + what +
                        " (a person came into view); reconstructing from here");
    learning_skips_ = 0;
    return LearningVerdict::kEndLearning;
  }
  return skipLearningFrame(what + " (a person in view?)", warnings);
}

// A learning set that shows something in the workspace. After learning_frames of them in a
// row, the models used before are taken back if there are any (a relearn or a time jump with
// the person in view); else learning starts over (the few sets learned first were the odd ones
// out), until the workspace is empty.
Reconstructor::LearningVerdict Reconstructor::skipLearningFrame(const std::string& why,
                                                                std::vector<std::string>* warnings) {
  warnings->push_back("frame set not learned into the background: " + why);
  if (++learning_skips_ < params_.background.learning_frames) return LearningVerdict::kSkip;
  if (previous_backgrounds_.size() == backgrounds_.size()) {
    warnings->push_back("the workspace was not empty for " + std::to_string(learning_skips_) +
                        " frame sets (a person in view): using the background model learned "
                        "before again; relearn with an empty workspace for a fresh one");
    backgrounds_ = previous_backgrounds_;
    learning_skips_ = 0;
    return LearningVerdict::kEndLearning;
  }
  warnings->push_back("the scene differed from the first " +
                      std::to_string(backgrounds_[0].learnedFrames()) + " learned frame sets for " +
                      std::to_string(learning_skips_) +
                      " sets: learning the background again from scratch (it needs an empty "
                      "workspace)");
  resetBackground();  // (and the count of skips)
  return LearningVerdict::kSkip;
}

// Classification, view evidence and the two workspace volumes of one set against `backgrounds`
// (the cameras missing from the set and the dark ones switched off). Fills r's stats,
// camera_active, body, skin (with_skin), their times and warnings.
void Reconstructor::fuseWorkspace(const std::vector<cv::Mat>& rgb,
                                  const std::vector<BackgroundModel>& backgrounds, FrameResult* r,
                                  bool with_skin, bool gpu) {
  const int n = static_cast<int>(cameras_.size());
  std::vector<int> seen;
  for (int i = 0; i < n; ++i)
    if (!rgb[i].empty()) seen.push_back(i);
  // --- classification
  auto t0 = Clock::now();
  if (gpu) {
    r->stats = gpu_->classify(rgb, backgrounds, &likelihoods_);
  } else {
    std::vector<cv::Mat> seen_rgb, seen_likelihoods;
    std::vector<const BackgroundModel*> bg;
    for (int i : seen) {
      // Headers that share likelihoods_[i]'s buffer: classify() writes into it.
      likelihoods_[i].create(rgb[i].rows, rgb[i].cols, CV_8UC2);
      seen_rgb.push_back(rgb[i]);
      seen_likelihoods.push_back(likelihoods_[i]);
      bg.push_back(&backgrounds[i]);
    }
    const std::vector<ClassificationStats> stats =
        classifier_.classify(seen_rgb, bg, seen_likelihoods, params_.threads);
    r->stats.assign(n, ClassificationStats());
    for (size_t k = 0; k < seen.size(); ++k) r->stats[seen[k]] = stats[k];
  }
  r->times.classify = msSince(t0);

  // --- evidence (dark cameras switched off)
  t0 = Clock::now();
  r->camera_active.assign(n, true);
  std::vector<ViewImage> body_views(n), skin_views(n);
  for (int i = 0; i < n; ++i) {
    const auto& s = r->stats[i];
    if (rgb[i].empty()) {  // missing from this set: no evidence either way
      r->camera_active[i] = false;
      likelihoods_[i].create(cameras_[i].height, cameras_[i].width, CV_8UC2);
      likelihoods_[i].setTo(0);
    } else if (s.darkFraction() > params_.dark_camera_fraction) {
      r->camera_active[i] = false;
      r->warnings.push_back(cameras_[i].name + ": " + percent(s.darkFraction()) +
                            " of the image is too dark for colour (covered lens or camera off?): "
                            "the view is left out of this frame");
    } else if (s.saturatedFraction() > params_.saturated_warning_fraction) {
      r->warnings.push_back(cameras_[i].name + ": " + percent(s.saturatedFraction()) +
                            " of the pixels are saturated (overexposed): colours are unreliable");
    }
    body_views[i].likelihood = likelihoods_[i];
    body_views[i].channel = 0;
    skin_views[i].likelihood = likelihoods_[i];
    skin_views[i].channel = 1;
    if (!r->camera_active[i]) {
      const cv::Mat off = cv::Mat::zeros(likelihoods_[i].size(), CV_8UC1);
      body_views[i].active = off;
      skin_views[i].active = off;
    }
  }
  if (gpu) {
    gpu_->buildEvidence(r->camera_active, likelihoods_, with_skin);
  } else {
    body_evidence_.set(body_views, params_.body.multi_projection, params_.threads,
                       params_.body.footprint ? params_.body_footprint : FootprintFilter());
    if (with_skin)
      skin_evidence_.set(skin_views, params_.skin.multi_projection, params_.threads,
                         params_.skin.footprint ? params_.skin_footprint : FootprintFilter());
  }
  r->times.evidence = msSince(t0);

  // --- workspace volumes
  t0 = Clock::now();
  if (gpu)
    gpu_->fuseBody(*table_, &r->body);
  else
    body_fusion_.fuse(*table_, body_evidence_, &r->body);
  r->times.body = msSince(t0);
  if (!with_skin) return;
  t0 = Clock::now();
  if (gpu)
    gpu_->fuseSkin(*table_, &r->skin);
  else
    skin_fusion_.fuse(*table_, skin_evidence_, &r->skin);
  r->times.skin = msSince(t0);
}

// The body volume (litres at the body threshold) that the previous models see in a learning
// set: an empty workspace shows next to none, a person several litres. The skin volume is
// not needed for that (it was about 16 ms of a learning set's cost on the default rig).
double Reconstructor::occupiedLitresAgainstPrevious(const std::vector<cv::Mat>& rgb) {
  FrameResult probe;
  fuseWorkspace(rgb, previous_backgrounds_, &probe, /*with_skin=*/false);
  const uint8_t t = thresholdByte(params_.body.threshold);
  const size_t occupied = static_cast<size_t>(
      std::count_if(probe.body.data.begin(), probe.body.data.end(), [t](uint8_t v) { return v > t; }));
  const double edge = probe.body.grid.voxel_size;
  return occupied * edge * edge * edge * 1e3;
}

FrameResult Reconstructor::process(const std::vector<cv::Mat>& rgb_in,
                                   const std::vector<tabletop_capture::CameraModel>& cameras,
                                   const std::vector<Eigen::Vector3d>& hand_rois,
                                   const std::vector<cv::Mat>& foreground_masks) {
  const auto t_start = Clock::now();
  validateFrame(rgb_in, cameras);
  for (const auto& c : hand_rois)
    if (!c.allFinite()) throw std::invalid_argument("hand ROI centre is not finite");
  // Every image through the noise filter first: learning, classification, the update and the
  // clothing colour all see the filtered pixels (image_prefilter.h).
  const bool filter = params_.prefilter.type != ImagePrefilter::kNone;
  const auto t_filter = Clock::now();
  if (filter) prefilterImages(rgb_in, params_.prefilter, &filtered_, params_.threads);
  const std::vector<cv::Mat>& rgb = filter ? filtered_ : rgb_in;

  FrameResult r;
  r.times.prefilter = msSince(t_filter);
  if (!backend_warning_.empty()) {  // once: the nodelet logs it
    r.warnings.push_back(backend_warning_);
    backend_warning_.clear();
  }
  r.backend = active_backend_;
  adoptRig(cameras, &r.warnings);
  const int n = static_cast<int>(cameras_.size());

  std::string missing;  // the cameras without an image in this set (a degraded set)
  for (int i = 0; i < n; ++i)
    if (rgb[i].empty()) missing += (missing.empty() ? "" : ", ") + cameras_[i].name;

  if (!backgroundReady()) {
    const auto t0 = Clock::now();
    // Every camera's model learns from the same sets: one without some cameras is not learned.
    const LearningVerdict v = !missing.empty() ? LearningVerdict::kSkip
                                               : checkLearningFrame(rgb, &r.warnings);
    if (!missing.empty())
      r.warnings.push_back("frame set not learned into the background: no image from " + missing);
    if (v != LearningVerdict::kEndLearning) {
      if (v == LearningVerdict::kLearn)
        for (int i = 0; i < n; ++i) backgrounds_[i].addLearningFrame(rgb[i]);
      r.learning_skipped = v == LearningVerdict::kSkip;
      r.times.background = msSince(t0);
      r.background_frames = backgrounds_[0].learnedFrames();
      r.status = FrameResult::Status::kLearningBackground;
      r.times.total = msSince(t_start);
      return r;
    }
    for (auto& b : backgrounds_) b.finishLearning();  // and reconstruct this set below
    if (gpu_) gpu_->modelsChanged();
  }
  r.status = FrameResult::Status::kReconstructed;
  r.background_frames = backgrounds_[0].learnedFrames();
  // A learning that finished no longer needs the models from before it (~20 MB for 8 cameras):
  // the next resetBackground() keeps the ones in use then.
  previous_backgrounds_.clear();

  if (gpu_) {
    const size_t warnings_before = r.warnings.size();
    try {
      reconstruct(rgb, hand_rois, foreground_masks, true, &r);
    } catch (const std::runtime_error& e) {
      r.warnings.resize(warnings_before);  // the CPU run below says them again
      dropGpu(e.what(), &r.warnings);
      reconstruct(rgb, hand_rois, foreground_masks, false, &r);
    }
  } else {
    reconstruct(rgb, hand_rois, foreground_masks, false, &r);
  }
  // After the set, once (a GPU failure above reran it on the CPU with the same colour).
  const auto t_clothing = Clock::now();
  learnClothingColour(rgb, hand_rois, &r);
  r.times.clothing = msSince(t_clothing);
  r.backend = active_backend_;
  r.times.total = msSince(t_start);
  return r;
}

void Reconstructor::reconstruct(const std::vector<cv::Mat>& rgb,
                                const std::vector<Eigen::Vector3d>& hand_rois,
                                const std::vector<cv::Mat>& foreground_masks, bool gpu,
                                FrameResult* out) {
  FrameResult& r = *out;
  const int n = static_cast<int>(cameras_.size());
  fuseWorkspace(rgb, backgrounds_, &r, /*with_skin=*/true, gpu);

  // --- hand sub-volumes (grids move with the hands: projected on the fly)
  auto t0 = Clock::now();
  while (hand_tables_.size() < hand_rois.size()) hand_tables_.emplace_back();
  r.hands.resize(hand_rois.size());
  r.hands_skipped = 0.0;  // (a GPU failure reruns this set on the CPU)
  // Known occlusions: per camera the body's distance, then per hand its masks and evidence (on
  // the CPU, also on the GPU path: the likelihoods are on the host, and the bytes the same).
  std::vector<cv::Mat> occluders;
  if (params_.hand_occlusion_masks && !hand_rois.empty())
    occluders = occluderDepths(r.body, thresholdByte(params_.body.threshold), cameras_, table_.get(),
                               params_.threads);
  for (size_t h = 0; h < hand_rois.size(); ++h) {
    const VoxelGrid grid =
        snappedCubeGrid(hand_rois[h], params_.hand_roi_edge, params_.hand_roi_voxels);
    if (!hand_tables_[h]) {
      ProjectionTableOptions o;
      o.storage = TableStorage::kOnTheFly;
      o.threads = params_.threads;
      hand_tables_[h] = std::make_unique<ProjectionTable>(grid, cameras_, o);
    } else {
      hand_tables_[h]->update(grid, cameras_);
    }
    if (!occluders.empty()) {
      std::vector<ViewImage> views(n);
      for (int i = 0; i < n; ++i) {
        views[i].likelihood = likelihoods_[i];
        views[i].channel = 1;
        views[i].active = r.camera_active[i]
                              ? frontOcclusionMask(occluders[i], cameras_[i], hand_rois[h],
                                                   params_.hand_occlusion_margin)
                              : cv::Mat::zeros(likelihoods_[i].size(), CV_8UC1);
      }
      hand_evidence_.set(views, params_.hand.multi_projection, params_.threads);
      hand_fusion_.fuse(*hand_tables_[h], hand_evidence_, &r.hands[h]);
      r.hands_skipped += hand_fusion_.lastSkippedFraction() / double(hand_rois.size());
    } else if (gpu) {
      r.hands_skipped += gpu_->fuseHand(*hand_tables_[h], &r.hands[h]) / double(hand_rois.size());
    } else {
      hand_fusion_.fuse(*hand_tables_[h], skin_evidence_, &r.hands[h]);
      r.hands_skipped += hand_fusion_.lastSkippedFraction() / double(hand_rois.size());
    }
  }
  r.times.hands = msSince(t0);

  // --- selective background update
  t0 = Clock::now();
  if (params_.update_background) {
    std::vector<cv::Mat> masks = backProject(r.body, thresholdByte(params_.body.threshold),
                                             params_.mask_margin_px);
    for (int i = 0; i < n; ++i) {
      if (i < static_cast<int>(foreground_masks.size()) && !foreground_masks[i].empty() &&
          foreground_masks[i].type() == CV_8UC1 && foreground_masks[i].size() == rgb[i].size())
        cv::bitwise_or(masks[i], foreground_masks[i], masks[i]);
      // A switched-off camera shows no scene: learning from it would poison the model.
      if (!gpu && r.camera_active[i]) backgrounds_[i].update(rgb[i], masks[i], params_.threads);
    }
    if (gpu) gpu_->updateBackground(masks, r.camera_active);
  }
  r.times.background = msSince(t0);
}

std::vector<cv::Mat> Reconstructor::backProject(const ProbabilityVolume& volume,
                                                uint8_t threshold_byte, int margin_px) const {
  const int n = static_cast<int>(cameras_.size());
  std::vector<cv::Mat> masks(n);
  for (int c = 0; c < n; ++c) masks[c] = cv::Mat::zeros(cameras_[c].height, cameras_[c].width, CV_8UC1);
  if (n == 0 || volume.data.size() != volume.grid.numVoxels()) return masks;
  const VoxelGrid& g = volume.grid;
  const Eigen::Vector3d centre = g.origin + 0.5 * g.voxel_size * g.dims.cast<double>();
  const bool use_table = table_ && table_->grid() == g && table_->precomputed();
  // The occupied voxels once (a few percent of the grid), then each camera draws only those.
  std::vector<Eigen::Vector3i> occupied;
  for (size_t i = 0; i < volume.data.size(); ++i)
    if (volume.data[i] > threshold_byte) occupied.push_back(g.coords(i));
#pragma omp parallel for num_threads(resolveThreads(params_.threads)) schedule(static)
  for (int c = 0; c < n; ++c) {
    const auto& cam = cameras_[c];
    cv::Mat& m = masks[c];
    // Each voxel is drawn as its centre pixel, then the mask is dilated by the footprint of a
    // voxel (half its diagonal) at the nearest distance of the grid to this camera, plus margin.
    for (const Eigen::Vector3i& o : occupied) {
      // The stored projections when they fit: no lens model per voxel.
      const int p = voxelCentrePixel(g, cam, c, use_table ? table_.get() : nullptr, o.x(), o.y(), o.z());
      if (p >= 0) m.data[p] = 255;
    }
    const double half_diag = 0.5 * std::sqrt(3.0) * g.voxel_size;
    const double grid_radius = 0.5 * g.voxel_size * g.dims.cast<double>().norm();
    const double nearest = std::max(0.1, (cam.center() - centre).norm() - grid_radius);
    const int r = static_cast<int>(std::ceil(half_diag * std::max(cam.fx, cam.fy) / nearest)) + margin_px;
    if (r > 0)
      cv::dilate(m, m, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1)));
  }
  return masks;
}

void Reconstructor::saveBackground(const std::string& directory) const {
  if (!backgroundReady())
    throw std::runtime_error("background model is not learned yet: nothing to save");
  std::vector<BackgroundModel> models = backgrounds_;
  if (gpu_) gpu_->copyModels(&models);  // the device's updates since the upload
  for (size_t i = 0; i < models.size(); ++i)
    models[i].save(directory + "/" + cameras_[i].name + ".bgm");
}

void Reconstructor::loadBackground(const std::string& directory,
                                   const std::vector<tabletop_capture::CameraModel>& cameras) {
  std::vector<BackgroundModel> models;
  std::vector<std::string> names;
  for (const auto& c : cameras) {
    const std::string path = directory + "/" + c.name + ".bgm";
    try {
      models.push_back(BackgroundModel::load(path, c.width, c.height));
    } catch (const std::exception& e) {
      throw std::runtime_error("background model " + path + ": " + e.what());
    }
    // Its variances are those of the pixels it learned from: under another filter every pixel
    // would be judged against the wrong noise.
    // A version-1 file does not say: it is taken as learned from raw pixels, the only case
    // before the filter existed.
    const std::string& learned = models.back().params().image_filter;
    const std::string& ours = params_.background.image_filter;
    if (learned == kUnrecordedImageFilter && params_.prefilter.type != ImagePrefilter::kNone)
      throw std::runtime_error("background model " + path + " (format version 1) does not record the "
                               "prefilter it was learned through, and pixel_classifier/prefilter and "
                               "prefilter_size give '" + ours + "': learn it again");
    if (learned != kUnrecordedImageFilter && learned != ours)
      throw std::runtime_error("background model " + path + " was learned from images through the "
                               "prefilter '" + learned + "', but pixel_classifier/prefilter and "
                               "prefilter_size give '" + ours +
                               "': learn it again, or set the filter it was learned with");
    names.push_back(c.name);
  }
  loaded_backgrounds_ = std::move(models);
  loaded_names_ = std::move(names);
  cameras_.clear();  // the next frame adopts the rig and, if it matches, the loaded models
  backgrounds_.clear();
}

}  // namespace psfs
