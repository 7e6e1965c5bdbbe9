#include "psfs_reconstruction/reconstructor_config.h"

#include <stdexcept>

namespace psfs {
namespace {

void addFusionKeys(const std::string& section, PsfsOptions* o, tabletop_common::ConfigSchema* s) {
  const std::string k = "fusion/" + section + "/";
  s->add(k + "skip_empty_below", &o->skip_empty_below)
      .add(k + "threshold", &o->threshold)
      .add(k + "occluded_views", &o->occluded_views)
      .add(k + "drop_threshold", &o->drop_threshold)
      .add(k + "min_views", &o->min_views)
      .add(k + "multi_projection", &o->multi_projection)
      .add(k + "footprint", &o->footprint);
}

std::string directoryOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : path.substr(0, slash);
}

}  // namespace

void addReconstructorKeys(ReconstructorConfig* c, tabletop_common::ConfigSchema* s) {
  ReconstructorParams& p = c->params;
  s->add("pixel_classifier/prefilter", &c->prefilter_name)
      .add("pixel_classifier/prefilter_size", &p.prefilter.size);
  s->add("pixel_classifier/skin_model", &c->skin_model_path)
      .add("pixel_classifier/foreground_outlier", &p.classifier.foreground_outlier)
      .add("pixel_classifier/skin_outlier", &p.classifier.skin_outlier)
      .add("pixel_classifier/shadow_suppression", &p.classifier.shadow_suppression)
      .add("pixel_classifier/shadow_chroma_radius", &p.classifier.shadow_chroma_radius)
      .add("pixel_classifier/shadow_min_intensity_ratio", &p.classifier.shadow_min_intensity_ratio)
      .add("pixel_classifier/shadow_max_intensity_ratio", &p.classifier.shadow_max_intensity_ratio)
      .add("pixel_classifier/min_chroma_intensity", &p.classifier.min_chroma_intensity)
      .add("pixel_classifier/intensity_model", &p.classifier.intensity_model)
      .add("pixel_classifier/shadow_weight", &p.classifier.shadow_weight)
      .add("pixel_classifier/gain_tolerance", &p.classifier.gain_tolerance)
      .add("pixel_classifier/gain_compensation", &p.classifier.gain_compensation);
  s->add("background_model/learning_frames", &p.background.learning_frames)
      .add("background_model/learning_rate", &p.background.learning_rate)
      .add("background_model/min_sigma_rg", &p.background.min_sigma_rg)
      .add("background_model/min_sigma_intensity", &p.background.min_sigma_intensity)
      .add("background_model/learning_change_sigmas", &p.background.learning_change_sigmas)
      .add("background_model/learning_change_fraction", &p.background.learning_change_fraction)
      .add("background_model/min_learning_frames", &p.background.min_learning_frames)
      .add("background_model/learning_max_occupied_litres", &p.learning_max_occupied_litres)
      .add("background_model/update", &p.update_background)
      .add("background_model/mask_margin_px", &p.mask_margin_px);
  s->add("clothing_colour/enabled", &p.clothing.enabled)
      .add("clothing_colour/weight", &p.clothing.weight)
      .add("clothing_colour/band_top", &p.clothing.band_top)
      .add("clothing_colour/band_bottom", &p.clothing.band_bottom)
      .add("clothing_colour/core_radius", &p.clothing.core_radius)
      .add("clothing_colour/hand_exclusion_radius", &p.clothing.hand_exclusion_radius)
      .add("clothing_colour/trim_radius", &p.clothing.trim_radius)
      .add("clothing_colour/min_inlier_fraction", &p.clothing.min_inlier_fraction)
      .add("clothing_colour/min_samples", &p.clothing.min_samples)
      .add("clothing_colour/min_sd", &p.clothing.min_sd)
      .add("clothing_colour/update_rate", &p.clothing.update_rate);
  s->add("volume/workspace_min", &p.workspace.min_corner)
      .add("volume/workspace_size", &p.workspace.size)
      .add("volume/dims", &p.dims)
      .add("volume/hull_occupancy_foreground", &p.hull_occupancy_foreground)
      .add("volume/hull_occupancy_skin", &p.hull_occupancy_skin);
  addFusionKeys("body", &p.body, s);
  addFusionKeys("skin", &p.skin, s);
  addFusionKeys("hand", &p.hand, s);
  s->add("fusion/footprint_scale", &p.footprint_scale);
  s->add("hand_volumes/edge", &p.hand_roi_edge)
      .add("hand_volumes/voxels", &p.hand_roi_voxels)
      .add("hand_volumes/clip_below_floor", &p.hand_roi_clip_floor)
      .add("hand_volumes/occlusion_masks", &p.hand_occlusion_masks)
      .add("hand_volumes/occlusion_margin", &p.hand_occlusion_margin)
      .add("hand_volumes/topic", &c->nodelet.hand_roi_topic)
      .add("hand_volumes/max_age", &c->nodelet.hand_roi_max_age)
      .add("hand_volumes/max_hands", &c->nodelet.max_hand_rois);
  s->add("camera_checks/dark_camera_fraction", &p.dark_camera_fraction)
      .add("camera_checks/saturated_warning_fraction", &p.saturated_warning_fraction);
  s->add("compute/backend", &c->backend_name);
  s->add("nodelet/threads", &p.threads)
      .add("nodelet/queue_size", &c->nodelet.queue_size)
      .add("nodelet/wait_for_tracker", &c->nodelet.wait_for_tracker)
      .add("nodelet/tracker_timeout", &c->nodelet.tracker_timeout)
      .add("nodelet/load_shedding", &c->nodelet.load_shedding)
      .add("nodelet/shed_drop_fraction", &c->nodelet.shed_drop_fraction)
      .add("nodelet/foreground_mask_topics", &c->nodelet.foreground_mask_topics)
      .add("nodelet/foreground_mask_topic", &c->nodelet.foreground_mask_topic)
      .add("nodelet/foreground_mask_transport", &c->nodelet.foreground_mask_transport)
      .add("nodelet/foreground_mask_max_age", &c->nodelet.foreground_mask_max_age)
      .add("nodelet/background_load_dir", &c->nodelet.background_load_dir)
      .add("nodelet/background_save_dir", &c->nodelet.background_save_dir)
      .add("nodelet/publish_clouds", &c->nodelet.publish_clouds);
  // The short names the nodelet has always taken as private parameters, and the live ones
  // (cfg/Psfs.cfg).
  s->alias("backend", "compute/backend");
  for (const char* k : {"threads", "queue_size", "wait_for_tracker", "tracker_timeout", "load_shedding",
                        "background_load_dir", "background_save_dir"})
    s->alias(k, std::string("nodelet/") + k);
  for (const char* v : {"body", "skin", "hand"})
    s->alias(std::string(v) + "_threshold", std::string("fusion/") + v + "/threshold");
}

void finishReconstructorConfig(const std::string& path, ReconstructorConfig* cfg) {
  ReconstructorConfig& c = *cfg;
  ReconstructorParams& p = c.params;
  const std::string where = path + ": ";
  try {
    p.prefilter.type = parseImagePrefilter(c.prefilter_name);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(where + "pixel_classifier/prefilter: " + e.what());
  }
  // The structs check their own ranges; report those against the file too.
  try {
    p.validate();
    BackgroundModel probe(1, 1, p.background);
    PsfsFusion body(p.body), skin(p.skin), hand(p.hand);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(where + e.what());
  }
  if (c.nodelet.hand_roi_max_age <= 0) throw std::runtime_error(where + "hand_volumes/max_age: must be > 0");
  if (!(c.nodelet.foreground_mask_max_age >= 0))
    throw std::runtime_error(where + "nodelet/foreground_mask_max_age: must be >= 0");
  if (c.nodelet.foreground_mask_topic.empty())
    throw std::runtime_error(where + "nodelet/foreground_mask_topic: must not be empty");
  if (c.nodelet.foreground_mask_transport.empty())
    throw std::runtime_error(where + "nodelet/foreground_mask_transport: must not be empty");
  if (c.nodelet.max_hand_rois < 0 || c.nodelet.max_hand_rois > 8)
    throw std::runtime_error(where + "hand_volumes/max_hands: must lie in [0, 8]");
  if (c.nodelet.queue_size < 1) throw std::runtime_error(where + "nodelet/queue_size: must be >= 1");
  if (!(c.nodelet.tracker_timeout >= 0 && c.nodelet.tracker_timeout <= 600))
    throw std::runtime_error(where + "nodelet/tracker_timeout: must lie in [0, 600] s");
  if (!(c.nodelet.shed_drop_fraction > 0 && c.nodelet.shed_drop_fraction < 1))
    throw std::runtime_error(where + "nodelet/shed_drop_fraction: must lie in (0, 1)");
  if (c.backend_name == "cpu")
    p.backend = ReconstructorParams::Backend::kCpu;
  else if (c.backend_name == "cuda")
    p.backend = ReconstructorParams::Backend::kCuda;
  else
    throw std::runtime_error(where + "compute/backend: '" + c.backend_name + "' is not cpu or cuda");
  const std::string& skin_model = c.skin_model_path;
  if (!skin_model.empty() && skin_model[0] != '/') c.skin_model_path = directoryOf(path) + "/" + skin_model;
}

ReconstructorConfig loadReconstructorConfig(const std::string& path) {
  ReconstructorConfig c;
  tabletop_common::ConfigSchema schema;
  addReconstructorKeys(&c, &schema);
  schema.loadFile(path);
  finishReconstructorConfig(path, &c);
  return c;
}

}  // namespace psfs
