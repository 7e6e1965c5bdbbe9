// HandMesher nodelet: psfs/hand_volumes (HandVolumes, one high-resolution skin sub-volume per
// tracked hand) in; per hand a triangle mesh by marching cubes on the probability field (thesis
// 6.5) out, as cve/hand_mesh_data (HandMeshes, for machines: the CVE bridge) and cve/hand_meshes
// (MarkerArray: one TRIANGLE_LIST marker per hand id, deleted when that hand is no longer
// meshed). A thin wrapper around cvephands::MarchingCubes.
//
// Parameters: ~config_file (default $(find cvephands_bridge)/config/hand_mesher.yaml, every key
// documented there) read strictly, then any private parameter named like a key overrides it; an
// unknown one stops the stage (tabletop_common/ros/config_overrides.h). Live tuning
// (dynamic_reconfigure, cfg/HandMesherTuning.cfg): iso.
// Bad input (data size not matching the dims, non-finite geometry, ids and volumes of different
// counts) is reported (throttled) and counted in the diagnostics; the other hands of the message
// are still meshed.
#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <boost/make_shared.hpp>
#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/package.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include <tabletop_msgs/HandMeshes.h>
#include <tabletop_msgs/HandVolumes.h>

#include "cvephands_bridge/HandMesherTuningConfig.h"  // generated from cfg/HandMesherTuning.cfg
#include "cvephands_bridge/mesh/hand_mesher_config.h"
#include "cvephands_bridge/mesh/marching_cubes.h"
#include "cvephands_bridge/mesh/mesh_components.h"
#include "cvephands_bridge/ros/mesh_conversions.h"
#include "tabletop_common/ros/config_overrides.h"
#include "tabletop_common/ros/live_tuning.h"
#include "tabletop_common/ros/periodic_diagnostics.h"
#include "tabletop_common/running_stats.h"

namespace cvephands {

class HandMesherNodelet : public nodelet::Nodelet {
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    diag_ = std::make_unique<tabletop_common::PeriodicDiagnostics>(
        nh, pnh, getName(), "hand_mesher", "hand meshing",
        [this](diagnostic_updater::DiagnosticStatusWrapper& stat) { diagnose(stat); });
    HandMesherConfig cfg;
    try {
      tabletop_common::ConfigSchema schema;
      addHandMesherKeys(&cfg, &schema);
      tabletop_common::loadConfigWithOverrides(
          pnh, ros::package::getPath("cvephands_bridge") + "/config/hand_mesher.yaml", schema, {});
      mc_ = std::make_unique<MarchingCubes>(marchingCubesOptions(cfg));
    } catch (const std::exception& e) {
      fatal_ = e.what();
      NODELET_FATAL("hand_mesher: not started: bad parameters: %s", e.what());
      return;
    }
    publish_markers_ = cfg.publish_markers;
    min_component_triangles_ = cfg.min_component_triangles;
    keep_radius_ = float(cfg.keep_radius);
    world_frame_ = cfg.world_frame;
    color_.r = float(cfg.marker_color[0]), color_.g = float(cfg.marker_color[1]);
    color_.b = float(cfg.marker_color[2]), color_.a = float(cfg.marker_color[3]);
    cvephands_bridge::HandMesherTuningConfig live;
    live.iso = cfg.iso;
    tuning_ = std::make_unique<tabletop_common::LiveTuning<cvephands_bridge::HandMesherTuningConfig>>(
        pnh, live,
        [this](const cvephands_bridge::HandMesherTuningConfig& c) {
          MarchingCubesOptions o = mc_->options();
          o.iso = isoByteLevel(c.iso);  // throws for a value out of (0, 1)
          auto mc = std::make_unique<MarchingCubes>(o);
          std::lock_guard<std::mutex> lock(mutex_);
          mc_ = std::move(mc);
        },
        "hand_mesher");
    mesh_pub_ = nh.advertise<tabletop_msgs::HandMeshes>("cve/hand_mesh_data", 5);
    marker_pub_ = nh.advertise<visualization_msgs::MarkerArray>("cve/hand_meshes", 2);
    // Sets are dropped only at the pSfS gate; later stages queue enough never to drop one.
    sub_ = nh.subscribe("psfs/hand_volumes", 10, &HandMesherNodelet::onVolumes, this);
    NODELET_INFO("hand_mesher: %s -> %s + %s, iso %.1f/255, %s",
                 sub_.getTopic().c_str(), mesh_pub_.getTopic().c_str(),
                 marker_pub_.getTopic().c_str(), mc_->options().iso,
                 mc_->options().mode == MeshingMode::kBinary ? "binary" : "probabilistic");
  }

  void onVolumes(const tabletop_msgs::HandVolumes::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++frames_;
    if (msg->target_ids.size() != msg->volumes.size()) {
      ++rejected_;
      NODELET_WARN_THROTTLE(5.0, "hand_mesher: %zu target ids for %zu volumes: message ignored",
                            msg->target_ids.size(), msg->volumes.size());
      return;
    }
    auto meshes = boost::make_shared<tabletop_msgs::HandMeshes>();
    meshes->header = msg->header;
    meshes->header.frame_id = world_frame_;
    const bool markers = publish_markers_ && marker_pub_.getNumSubscribers() > 0;
    visualization_msgs::MarkerArray array;
    std::set<uint32_t> present;
    for (size_t i = 0; i < msg->volumes.size(); ++i) {
      const uint32_t id = msg->target_ids[i];
      try {
        const ProbabilityGridView grid = gridView(msg->volumes[i]);
        const ros::WallTime t0 = ros::WallTime::now();
        mc_->extract(grid, &mesh_);
        keepHandComponents(&mesh_, grid.boxCentre().cast<float>(),
                           size_t(std::max(0, min_component_triangles_)), keep_radius_);
        mesh_ms_.add((ros::WallTime::now() - t0).toSec() * 1e3);
      } catch (const std::exception& e) {
        ++rejected_;
        NODELET_WARN_THROTTLE(5.0, "hand_mesher: hand %u: volume rejected: %s", id, e.what());
        continue;
      }
      triangles_.add(double(mesh_.numTriangles()));
      tabletop_msgs::HandMesh m;
      m.header = meshes->header;
      m.target_id = id;
      toMessage(mesh_, &m);
      meshes->meshes.push_back(std::move(m));
      present.insert(id);
      if (markers) {
        visualization_msgs::Marker mk;
        toMarker(mesh_, "hand_meshes", int(id), color_, &mk);
        mk.header = meshes->header;
        array.markers.push_back(std::move(mk));
      }
    }
    // Hands meshed last time but not now: lost, or their volume was rejected.
    for (uint32_t id : last_ids_) {
      if (present.count(id)) continue;
      visualization_msgs::Marker del;
      del.header = meshes->header;
      del.ns = "hand_meshes";
      del.id = int(id);
      del.action = visualization_msgs::Marker::DELETE;
      array.markers.push_back(del);
    }
    last_ids_ = present;
    meshed_ += meshes->meshes.size();
    mesh_pub_.publish(meshes);
    if (publish_markers_ && !array.markers.empty()) marker_pub_.publish(array);
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    if (!fatal_.empty()) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "not started: " + fatal_);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    const double rate = rate_.rate(frames_);
    const bool rejecting = rejections_.grew(rejected_);
    if (frames_ == 0)
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "waiting for hand volumes");
    else if (rejecting)
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "rejecting hand volumes (see the log)");
    else
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::OK, "meshing %zu hand(s)", last_ids_.size());
    stat.add("rate (Hz)", rate);
    stat.add("frames", frames_);
    stat.add("meshes", meshed_);
    stat.add("meshing per hand (ms)", mesh_ms_.mean());
    stat.add("meshing per hand, max (ms)", mesh_ms_.count() ? mesh_ms_.max() : 0.0);
    stat.add("triangles per hand", triangles_.mean());
    stat.add("volumes rejected", rejected_);
  }

  std::unique_ptr<MarchingCubes> mc_;
  TriangleMesh mesh_;
  std::string fatal_, world_frame_;
  bool publish_markers_ = true;
  int min_component_triangles_ = 64;
  float keep_radius_ = 0.08f;
  std_msgs::ColorRGBA color_;
  ros::Subscriber sub_;
  ros::Publisher mesh_pub_, marker_pub_;
  std::unique_ptr<tabletop_common::PeriodicDiagnostics> diag_;
  std::mutex mutex_;  // guards mc_ (live tuning replaces it) and everything below
  std::unique_ptr<tabletop_common::LiveTuning<cvephands_bridge::HandMesherTuningConfig>> tuning_;
  std::set<uint32_t> last_ids_;
  tabletop_common::RateMeter rate_;
  tabletop_common::GrowthMeter rejections_;
  uint64_t frames_ = 0, rejected_ = 0, meshed_ = 0;
  tabletop_common::RunningStats mesh_ms_, triangles_;
};

}  // namespace cvephands

PLUGINLIB_EXPORT_CLASS(cvephands::HandMesherNodelet, nodelet::Nodelet)
