// MPF nodelet: psfs/skin_volume + psfs/body_volume (same stamp) in; hands/targets
// (TrackedTargets: head + 2 hand slots, inactive ones flagged), tf frames hand_<id> and head,
// hands/markers (boxes, labels, optionally the particles) and diagnostics out. The pSfS nodelet
// takes the active hands of hands/targets as the ROIs of its high-resolution hand volumes (the
// closed loop of thesis 4.3). A thin wrapper around hand_tracking::MpfTracker.
//
// Parameters: ~config_file (default $(find hand_tracking)/config/mpf.yaml, every key documented
// there) read strictly, then any private parameter named like a key overrides it; an unknown
// one stops the stage (tabletop_common/ros/config_overrides.h). Live tuning (dynamic_reconfigure,
// cfg/MpfTuning.cfg): head_noise, hand_noise_ar1..3.
#include <map>
#include <memory>
#include <mutex>

#include <boost/make_shared.hpp>
#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/TransformStamped.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/package.h>
#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <tabletop_msgs/TrackedTargets.h>
#include <tabletop_msgs/VoxelVolume.h>

#include "hand_tracking/MpfTuningConfig.h"  // generated from cfg/MpfTuning.cfg
#include "hand_tracking/mpf_config.h"
#include "hand_tracking/mpf_tracker.h"
#include "psfs_reconstruction/ros/volume_msgs.h"
#include "psfs_reconstruction/ros/volume_pairing.h"
#include "tabletop_common/ros/config_overrides.h"
#include "tabletop_common/ros/live_tuning.h"
#include "tabletop_common/ros/periodic_diagnostics.h"
#include "tabletop_common/running_stats.h"

namespace hand_tracking {
namespace {

}  // namespace

class MpfNodelet : public nodelet::Nodelet {
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    diag_ = std::make_unique<tabletop_common::PeriodicDiagnostics>(
        nh, pnh, getName(), "mpf", "mpf hand tracking",
        [this](diagnostic_updater::DiagnosticStatusWrapper& stat) { diagnose(stat); });
    MpfConfig cfg;
    try {
      tabletop_common::ConfigSchema schema;
      addMpfKeys(&cfg, &schema);
      const std::string file = tabletop_common::loadConfigWithOverrides(
          pnh, ros::package::getPath("hand_tracking") + "/config/mpf.yaml", schema, {});
      finishMpfConfig(file + " (with the private parameters): ", &cfg);
      tracker_ = std::make_unique<MpfTracker>(cfg.params, static_cast<uint64_t>(cfg.nodelet.seed));
    } catch (const std::exception& e) {
      fatal_ = e.what();
      NODELET_FATAL("mpf: not started: bad parameters: %s", e.what());
      return;
    }
    const int seed = cfg.nodelet.seed;
    publish_particles_ = cfg.nodelet.publish_particles;
    world_frame_ = cfg.nodelet.world_frame;
    tf_prefix_ = cfg.nodelet.tf_prefix;
    targets_pub_ = nh.advertise<tabletop_msgs::TrackedTargets>("hands/targets", 5);
    markers_pub_ = nh.advertise<visualization_msgs::MarkerArray>("hands/markers", 2);
    tf_ = std::make_unique<tf2_ros::TransformBroadcaster>();
    // Sets are dropped only at the pSfS gate (which also waits for our targets before the next
    // set): these queues never fill, whatever the machine's speed.
    skin_sub_ = nh.subscribe("psfs/skin_volume", 10, &MpfNodelet::onSkin, this);
    body_sub_ = nh.subscribe("psfs/body_volume", 10, &MpfNodelet::onBody, this);
    MpfTuningConfig live;
    live.head_noise = cfg.params.head_noise;
    live.hand_noise_ar1 = cfg.params.hand_noise_ar1;
    live.hand_noise_ar2 = cfg.params.hand_noise_ar2;
    live.hand_noise_ar3 = cfg.params.hand_noise_ar3;
    tuning_ = std::make_unique<tabletop_common::LiveTuning<MpfTuningConfig>>(
        pnh, live,
        [this](const MpfTuningConfig& c) {
          std::lock_guard<std::mutex> lock(mutex_);
          tracker_->setProcessNoise(c.head_noise, c.hand_noise_ar1, c.hand_noise_ar2, c.hand_noise_ar3);
        },
        "mpf");
    NODELET_INFO("mpf: tracking on %s + %s, %d particles per hand, %d for the head, seed %d",
                 skin_sub_.getTopic().c_str(), body_sub_.getTopic().c_str(),
                 tracker_->params().hand_particles, tracker_->params().head_particles, seed);
  }

  // The two volumes of a frame set arrive one after the other (body first); pair them by stamp.
  void onSkin(const tabletop_msgs::VoxelVolume::ConstPtr& m) { pair(m, true); }
  void onBody(const tabletop_msgs::VoxelVolume::ConstPtr& m) { pair(m, false); }

  void pair(const tabletop_msgs::VoxelVolume::ConstPtr& m, bool skin) {
    tabletop_msgs::VoxelVolume::ConstPtr skin_msg, body_msg;
    if (!pairing_.add(m, skin, &skin_msg, &body_msg)) return;
    process(*skin_msg, *body_msg);
  }

  void process(const tabletop_msgs::VoxelVolume& skin_msg, const tabletop_msgs::VoxelVolume& body_msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string why;
    if (!psfs::fromVoxelVolumeMsg(skin_msg, &skin_, &why) ||
        !psfs::fromVoxelVolumeMsg(body_msg, &body_, &why)) {
      ++rejected_;
      NODELET_ERROR_THROTTLE(5.0, "mpf: volume at %.3f ignored: %s", skin_msg.header.stamp.toSec(),
                             why.c_str());
      return;
    }
    const ros::Time stamp = skin_msg.header.stamp;
    double dt = last_stamp_.isZero() ? tracker_->params().reference_dt : (stamp - last_stamp_).toSec();
    if (dt <= 0.0) {
      // Volumes come in stamp order: time went back (a bag played again or looped). The tracker
      // starts over as constructed (same seed), so a replay gives what the first play gave.
      NODELET_WARN("mpf: volume at %.3f is not newer than the last one (%.3f): time went back "
                   "(a bag played again or looped?): the tracker starts over", stamp.toSec(),
                   last_stamp_.toSec());
      tracker_->reset();
      ++time_jumps_;
      dt = tracker_->params().reference_dt;
    }
    // A gap (dropped sets, a paused bag) must not let the dynamics extrapolate wildly.
    dt = std::min(dt, 0.5);
    try {
      tracker_->update(skin_, body_, dt);
    } catch (const std::exception& e) {
      ++rejected_;
      NODELET_ERROR_THROTTLE(5.0, "mpf: %s", e.what());
      return;
    }
    last_stamp_ = stamp;
    ++frames_;
    const auto& t = tracker_->lastTimes();
    total_ms_.add(t.total_ms);
    integral_ms_.add(t.integral_ms);
    weights_ms_.add(t.weights_ms);
    reconfigure_ms_.add(t.reconfigure_ms);
    const auto& s = tracker_->lastStats();
    births_ += s.births, merges_ += s.merges, splits_ += s.splits, losses_ += s.losses;
    publish(stamp);
  }

  void publish(const ros::Time& stamp) {
    auto msg = boost::make_shared<tabletop_msgs::TrackedTargets>();
    msg->header.stamp = stamp;
    msg->header.frame_id = world_frame_;
    visualization_msgs::MarkerArray markers;
    std::vector<geometry_msgs::TransformStamped> tfs;
    active_ = 0;
    int slot = 0;
    for (const Target& t : tracker_->targets()) {
      tabletop_msgs::TrackedTarget m;
      m.id = t.id;
      m.type = t.type == Target::kHead ? tabletop_msgs::TrackedTarget::HEAD
                                       : tabletop_msgs::TrackedTarget::HAND;
      m.position.x = t.position.x();
      m.position.y = t.position.y();
      m.position.z = t.position.z();
      m.weight = t.weight;
      m.active = t.active;
      msg->targets.push_back(m);
      const std::string frame =
          tf_prefix_ + (t.type == Target::kHead ? "head" : "hand_" + std::to_string(t.id));
      visualization_msgs::Marker box;
      box.header = msg->header;
      box.ns = "targets";
      box.id = slot;
      box.type = visualization_msgs::Marker::CUBE;
      box.action = t.active ? visualization_msgs::Marker::ADD : visualization_msgs::Marker::DELETE;
      box.pose.position = m.position;
      box.pose.orientation.w = 1.0;
      const Eigen::Vector3d size =
          t.type == Target::kHead ? tracker_->params().head_box : tracker_->params().hand_box;
      box.scale.x = size.x(), box.scale.y = size.y(), box.scale.z = size.z();
      box.color.a = 0.45f;
      box.color.r = t.type == Target::kHead ? 0.2f : 1.0f;
      box.color.g = t.type == Target::kHead ? 0.6f : 0.8f;
      box.color.b = t.type == Target::kHead ? 1.0f : 0.1f;
      markers.markers.push_back(box);
      visualization_msgs::Marker label = box;
      label.ns = "labels";
      label.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
      label.pose.position.z += 0.5 * size.z() + 0.03;
      label.scale.x = label.scale.y = 0.0;
      label.scale.z = 0.04;
      label.color.r = label.color.g = label.color.b = label.color.a = 1.0f;
      label.text = frame;
      markers.markers.push_back(label);
      if (t.active) {
        ++active_;
        geometry_msgs::TransformStamped tf;
        tf.header = msg->header;
        tf.child_frame_id = frame;
        tf.transform.translation.x = t.position.x();
        tf.transform.translation.y = t.position.y();
        tf.transform.translation.z = t.position.z();
        tf.transform.rotation.w = 1.0;
        tfs.push_back(tf);
      }
      ++slot;
    }
    if (publish_particles_) {
      visualization_msgs::Marker cloud;
      cloud.header = msg->header;
      cloud.ns = "particles";
      cloud.type = visualization_msgs::Marker::POINTS;
      cloud.pose.orientation.w = 1.0;
      cloud.scale.x = cloud.scale.y = 0.004;
      for (const auto& p : tracker_->particles()) {
        if (p.component < 0) continue;
        geometry_msgs::Point q;
        q.x = p.position.x(), q.y = p.position.y(), q.z = p.position.z();
        cloud.points.push_back(q);
        std_msgs::ColorRGBA c;
        c.r = p.component == MpfTracker::kHeadSlot ? 0.2f : 1.0f;
        c.g = 0.8f, c.b = p.component == MpfTracker::kHeadSlot ? 1.0f : 0.1f, c.a = 0.8f;
        cloud.colors.push_back(c);
      }
      markers.markers.push_back(cloud);
    }
    targets_pub_.publish(msg);
    markers_pub_.publish(markers);
    if (!tfs.empty()) tf_->sendTransform(tfs);
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
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "waiting for volumes");
    else if (rejecting)
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "rejecting volumes (see the log)");
    else
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::OK, "tracking %d target(s)", active_);
    stat.add("rate (Hz)", rate);
    stat.add("frames", frames_);
    stat.add("time jumps back (started over)", time_jumps_);
    stat.add("active targets", active_);
    stat.add("mpf total (ms)", total_ms_.mean());
    stat.add("mpf integral volumes (ms)", integral_ms_.mean());
    stat.add("mpf weights (ms)", weights_ms_.mean());
    stat.add("mpf reconfiguration (ms)", reconfigure_ms_.mean());
    stat.add("births", births_);
    stat.add("merges", merges_);
    stat.add("splits", splits_);
    stat.add("losses", losses_);
    stat.add("volumes rejected", rejected_);
  }

  std::unique_ptr<MpfTracker> tracker_;
  std::unique_ptr<tabletop_common::LiveTuning<MpfTuningConfig>> tuning_;  // after tracker_: goes first
  std::string fatal_, world_frame_, tf_prefix_;
  bool publish_particles_ = false;
  ros::Subscriber skin_sub_, body_sub_;
  ros::Publisher targets_pub_, markers_pub_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_;
  std::unique_ptr<tabletop_common::PeriodicDiagnostics> diag_;
  std::mutex mutex_;
  psfs::VolumePairing pairing_;
  psfs::ProbabilityVolume skin_, body_;
  ros::Time last_stamp_;
  uint64_t time_jumps_ = 0;  // under mutex_
  tabletop_common::RateMeter rate_;
  tabletop_common::GrowthMeter rejections_;
  uint64_t frames_ = 0, rejected_ = 0;
  uint64_t births_ = 0, merges_ = 0, splits_ = 0, losses_ = 0;
  int active_ = 0;
  tabletop_common::RunningStats total_ms_, integral_ms_, weights_ms_, reconfigure_ms_;
};

}  // namespace hand_tracking

PLUGINLIB_EXPORT_CLASS(hand_tracking::MpfNodelet, nodelet::Nodelet)
