#include "psfs_reconstruction/reconstructor_config.h"

#include <functional>
#include <map>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace psfs {
namespace {

// Reads a YAML map whose keys must all be known: each key maps to a setter.
class Section {
 public:
  Section(const YAML::Node& node, const std::string& where) : node_(node), where_(where) {}
  template <class T>
  Section& field(const std::string& key, T* out) {
    setters_[key] = [this, key, out](const YAML::Node& n) {
      try {
        *out = n.as<T>();
      } catch (const YAML::Exception&) {
        throw std::runtime_error(where_ + key + ": wrong type");
      }
    };
    return *this;
  }
  Section& vector3(const std::string& key, Eigen::Vector3d* out) {
    setters_[key] = [this, key, out](const YAML::Node& n) { *out = readVec<double>(n, key); };
    return *this;
  }
  Section& vector3i(const std::string& key, Eigen::Vector3i* out) {
    setters_[key] = [this, key, out](const YAML::Node& n) { *out = readVec<int>(n, key); };
    return *this;
  }
  Section& child(const std::string& key, std::function<void(const YAML::Node&, const std::string&)> f) {
    setters_[key] = [this, key, f](const YAML::Node& n) { f(n, where_ + key + "/"); };
    return *this;
  }
  void read() {
    if (!node_) return;
    if (!node_.IsMap()) throw std::runtime_error(where_ + ": expected a map");
    for (const auto& kv : node_) {
      const std::string key = kv.first.as<std::string>();
      auto it = setters_.find(key);
      if (it == setters_.end()) throw std::runtime_error(where_ + key + ": unknown key");
      it->second(kv.second);
    }
  }

 private:
  template <class T>
  Eigen::Matrix<T, 3, 1> readVec(const YAML::Node& n, const std::string& key) const {
    if (!n.IsSequence() || n.size() != 3)
      throw std::runtime_error(where_ + key + ": expected a list of 3 numbers");
    try {
      return Eigen::Matrix<T, 3, 1>(n[0].as<T>(), n[1].as<T>(), n[2].as<T>());
    } catch (const YAML::Exception&) {
      throw std::runtime_error(where_ + key + ": expected a list of 3 numbers");
    }
  }
  YAML::Node node_;
  std::string where_;
  std::map<std::string, std::function<void(const YAML::Node&)>> setters_;
};

void readFusion(const YAML::Node& n, const std::string& where, PsfsOptions* o) {
  Section(n, where)
      .field("threshold", &o->threshold)
      .field("occluded_views", &o->occluded_views)
      .field("drop_threshold", &o->drop_threshold)
      .field("min_views", &o->min_views)
      .field("multi_projection", &o->multi_projection)
      .read();
}

std::string directoryOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : path.substr(0, slash);
}

}  // namespace

ReconstructorConfig loadReconstructorConfig(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": cannot read: " + e.what());
  }
  ReconstructorConfig c;
  ReconstructorParams& p = c.params;
  std::string skin_model = "skin_gmm.yaml";
  const std::string where = path + ": ";
  try {
    Section(root, where)
        .child("pixel_classifier",
               [&](const YAML::Node& n, const std::string& w) {
                 Section(n, w)
                     .field("skin_model", &skin_model)
                     .field("foreground_outlier", &p.classifier.foreground_outlier)
                     .field("skin_outlier", &p.classifier.skin_outlier)
                     .field("shadow_suppression", &p.classifier.shadow_suppression)
                     .field("shadow_chroma_radius", &p.classifier.shadow_chroma_radius)
                     .field("shadow_min_intensity_ratio", &p.classifier.shadow_min_intensity_ratio)
                     .field("shadow_max_intensity_ratio", &p.classifier.shadow_max_intensity_ratio)
                     .field("min_chroma_intensity", &p.classifier.min_chroma_intensity)
                     .read();
               })
        .child("background_model",
               [&](const YAML::Node& n, const std::string& w) {
                 Section(n, w)
                     .field("learning_frames", &p.background.learning_frames)
                     .field("learning_rate", &p.background.learning_rate)
                     .field("min_sigma_rg", &p.background.min_sigma_rg)
                     .field("min_sigma_intensity", &p.background.min_sigma_intensity)
                     .field("learning_change_sigmas", &p.background.learning_change_sigmas)
                     .field("learning_change_fraction", &p.background.learning_change_fraction)
                     .field("min_learning_frames", &p.background.min_learning_frames)
                     .field("update", &p.update_background)
                     .field("mask_margin_px", &p.mask_margin_px)
                     .read();
               })
        .child("volume",
               [&](const YAML::Node& n, const std::string& w) {
                 Section(n, w)
                     .vector3("workspace_min", &p.workspace.min_corner)
                     .vector3("workspace_size", &p.workspace.size)
                     .vector3i("dims", &p.dims)
                     .field("hull_occupancy_foreground", &p.hull_occupancy_foreground)
                     .field("hull_occupancy_skin", &p.hull_occupancy_skin)
                     .read();
               })
        .child("fusion",
               [&](const YAML::Node& n, const std::string& w) {
                 Section(n, w)
                     .child("body", [&](const YAML::Node& m, const std::string& v) { readFusion(m, v, &p.body); })
                     .child("skin", [&](const YAML::Node& m, const std::string& v) { readFusion(m, v, &p.skin); })
                     .child("hand", [&](const YAML::Node& m, const std::string& v) { readFusion(m, v, &p.hand); })
                     .read();
               })
        .child("hand_volumes",
               [&](const YAML::Node& n, const std::string& w) {
                 Section(n, w)
                     .field("edge", &p.hand_roi_edge)
                     .field("voxels", &p.hand_roi_voxels)
                     .field("topic", &c.nodelet.hand_roi_topic)
                     .field("max_age", &c.nodelet.hand_roi_max_age)
                     .field("max_hands", &c.nodelet.max_hand_rois)
                     .read();
               })
        .child("camera_checks",
               [&](const YAML::Node& n, const std::string& w) {
                 Section(n, w)
                     .field("dark_camera_fraction", &p.dark_camera_fraction)
                     .field("saturated_warning_fraction", &p.saturated_warning_fraction)
                     .read();
               })
        .child("nodelet",
               [&](const YAML::Node& n, const std::string& w) {
                 Section(n, w)
                     .field("threads", &p.threads)
                     .field("queue_size", &c.nodelet.queue_size)
                     .field("wait_for_tracker", &c.nodelet.wait_for_tracker)
                     .field("tracker_timeout", &c.nodelet.tracker_timeout)
                     .field("load_shedding", &c.nodelet.load_shedding)
                     .field("shed_drop_fraction", &c.nodelet.shed_drop_fraction)
                     .field("foreground_mask_topics", &c.nodelet.foreground_mask_topics)
                     .field("background_load_dir", &c.nodelet.background_load_dir)
                     .field("background_save_dir", &c.nodelet.background_save_dir)
                     .field("publish_clouds", &c.nodelet.publish_clouds)
                     .read();
               })
        .read();
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(where + e.what());
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
  if (c.nodelet.max_hand_rois < 0 || c.nodelet.max_hand_rois > 8)
    throw std::runtime_error(where + "hand_volumes/max_hands: must lie in [0, 8]");
  if (c.nodelet.queue_size < 1) throw std::runtime_error(where + "nodelet/queue_size: must be >= 1");
  if (!(c.nodelet.tracker_timeout >= 0 && c.nodelet.tracker_timeout <= 600))
    throw std::runtime_error(where + "nodelet/tracker_timeout: must lie in [0, 600] s");
  if (!(c.nodelet.shed_drop_fraction > 0 && c.nodelet.shed_drop_fraction < 1))
    throw std::runtime_error(where + "nodelet/shed_drop_fraction: must lie in (0, 1)");
  c.skin_model_path = (!skin_model.empty() && skin_model[0] == '/') ? skin_model
                                                                     : directoryOf(path) + "/" + skin_model;
  return c;
}

}  // namespace psfs
