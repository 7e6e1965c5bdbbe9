#include "gpu_frame_path.h"

#include <stdexcept>

#include "volume_fusion.h"

namespace psfs {

GpuFramePath::GpuFramePath(const GaussianMixture2D& skin, const ReconstructorParams& params)
    : pixels_(skin, params.classifier),
      body_(params.body),
      skin_(params.skin),
      hand_(params.hand),
      body_bilinear_(params.body.multi_projection),
      skin_bilinear_(params.skin.multi_projection) {
  if (!pixels_.usable()) throw std::runtime_error(pixels_.reason());
  if (!body_.usable()) throw std::runtime_error(body_.reason());
  if (params.body.footprint || params.skin.footprint)
    throw std::runtime_error("footprint-filtered evidence (fusion/*/footprint) is CPU-only");
}

void GpuFramePath::setFusion(const PsfsOptions& body, const PsfsOptions& skin, const PsfsOptions& hand) {
  // Live tuning is rare: new objects (their tables are uploaded again with the next frame).
  body_ = GpuPsfsFusion(body);
  skin_ = GpuPsfsFusion(skin);
  hand_ = GpuPsfsFusion(hand);
}

void GpuFramePath::syncModels(std::vector<BackgroundModel>* models) {
  if (!device_newer_) return;
  copyModels(models);
  device_newer_ = false;
}

void GpuFramePath::copyModels(std::vector<BackgroundModel>* models) const {
  if (!device_newer_) return;
  std::vector<BackgroundModel*> m;
  for (auto& b : *models) m.push_back(&b);
  pixels_.downloadBackgrounds(m);
}

std::vector<ClassificationStats> GpuFramePath::classify(const std::vector<cv::Mat>& rgb,
                                                        const std::vector<BackgroundModel>& models,
                                                        std::vector<cv::Mat>* likelihoods) {
  if (!device_current_) {
    std::vector<const BackgroundModel*> m;
    for (const auto& b : models) m.push_back(&b);
    pixels_.uploadBackgrounds(m);
    device_current_ = true;
    device_newer_ = false;
  }
  return pixels_.classify(rgb, likelihoods);
}

void GpuFramePath::buildEvidence(const std::vector<bool>& camera_active,
                                 const std::vector<cv::Mat>& likelihoods, bool with_skin) {
  // Switched-off views (dark, missing) get an all-zero mask, as on the CPU path.
  std::vector<cv::Mat> active(camera_active.size());
  off_masks_.resize(camera_active.size());
  for (size_t i = 0; i < camera_active.size(); ++i) {
    if (camera_active[i]) continue;
    cv::Mat& off = off_masks_[i];
    if (off.size() != likelihoods[i].size()) off = cv::Mat::zeros(likelihoods[i].size(), CV_8UC1);
    active[i] = off;
  }
  pixels_.buildEvidence(active, body_bilinear_, skin_bilinear_, with_skin);
  // The hand sub-volumes' skipping reads the skin likelihoods on the host (centre_space_bound.h).
  skin_views_.assign(likelihoods.size(), ViewImage{});
  for (size_t i = 0; i < likelihoods.size() && with_skin; ++i) skin_views_[i] = ViewImage{likelihoods[i], 1, active[i]};
  // The bounds of the CPU path's skipping, from the same likelihoods and masks.
  for (int kind = 0; kind < (with_skin ? 2 : 1); ++kind) {
    const PsfsOptions& o = (kind ? skin_ : body_).options();
    if (!detail::skipsEmptySpace(o)) continue;
    std::vector<ViewImage> views(likelihoods.size());
    for (size_t i = 0; i < views.size(); ++i) views[i] = ViewImage{likelihoods[i], kind, active[i]};
    detail::tileMaxImages(views, o.threads, &(kind ? skin_skip_ : body_skip_).tiles);
  }
}

void GpuFramePath::fuseBody(const ProjectionTable& table, ProbabilityVolume* out) {
  body_.fuse(table, pixels_.bodyEvidence(), out);
  if (detail::skipsEmptySpace(body_.options()))
    detail::fillSkipped(body_.options(), table, &body_skip_, out);
}
void GpuFramePath::fuseSkin(const ProjectionTable& table, ProbabilityVolume* out) {
  skin_.fuse(table, pixels_.skinEvidence(), out);
  if (detail::skipsEmptySpace(skin_.options()))
    detail::fillSkipped(skin_.options(), table, &skin_skip_, out);
}
double GpuFramePath::fuseHand(const ProjectionTable& table, ProbabilityVolume* out) {
  hand_.fuse(table, pixels_.skinEvidence(), out);
  const PsfsOptions& o = hand_.options();
  if (!detail::skipsCentreSpace(o)) return 0.0;
  // The device fused every voxel: zero what PsfsFusion skips.
  std::vector<uint8_t> flags;
  const double skipped = hand_skip_.centre.skippableChunks(table, skin_views_, detail::psfsRowParams(o, table),
                                                           o.occluded_views, o.skip_empty_below, o.threads, &flags);
  detail::zeroChunks(table, flags, out);
  return skipped;
}

void GpuFramePath::updateBackground(const std::vector<cv::Mat>& masks,
                                    const std::vector<bool>& camera_active) {
  pixels_.updateBackground(masks, camera_active);
  device_newer_ = true;
}

}  // namespace psfs
