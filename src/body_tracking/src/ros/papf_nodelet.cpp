// Body tracker nodelet: psfs/body_volume + psfs/skin_volume (same stamp) in, and /frames for the
// camera models of the silhouette masks. Out, at each volume's stamp:
//   body/pose          tabletop_msgs/BodyPose (18 DOF, hands, head, shoulders, elbows, wrists)
//   body/joint_states  sensor_msgs/JointState (the 18 state values by name, body_state.h)
//   body/hand_targets  tabletop_msgs/TrackedTargets (head + two hands, the MPF's layout), which
//                      psfs can take as its hand ROIs instead of hands/targets (its hand_roi
//                      topic parameter)
//   body/markers       visualization_msgs/MarkerArray: the quadrics and a stick skeleton
//   body/volume        tabletop_msgs/VoxelVolume: psfs/body_volume with the tracked model as a
//                      prior (model_prior.h), less its phantom volume; the input unchanged
//                      while no pose is tracked (optional, publish_volume)
//   <camera>/body_mask sensor_msgs/Image mono8: the model's silhouettes, dilated (optional)
//   tf                 <tf_prefix><part> for each body part
// A thin wrapper around body_tracking::Papf. Parameters: ~config_file (default
// $(find body_tracking)/config/papf.yaml, every key documented there) read strictly, then any
// private parameter named like a key overrides it.
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
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <tf2_ros/transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <tabletop_msgs/BodyPose.h>
#include <tabletop_msgs/MultiViewFrame.h>
#include <tabletop_msgs/TrackedTargets.h>
#include <tabletop_msgs/VoxelVolume.h>

#include "body_tracking/model_prior.h"
#include "body_tracking/papf.h"
#include "body_tracking/papf_config.h"
#include "body_tracking/silhouette_mask.h"
#include "psfs_reconstruction/ros/volume_msgs.h"
#include "psfs_reconstruction/ros/volume_pairing.h"
#include "tabletop_capture/ros/conversions.h"
#include "tabletop_common/ros/config_overrides.h"
#include "tabletop_common/ros/periodic_diagnostics.h"
#include "tabletop_common/running_stats.h"

namespace body_tracking {
namespace {

geometry_msgs::Point point(const Eigen::Vector3d& p) {
  geometry_msgs::Point q;
  q.x = p.x(), q.y = p.y(), q.z = p.z();
  return q;
}

geometry_msgs::Point nanPoint() {
  const double n = std::numeric_limits<double>::quiet_NaN();
  return point(Eigen::Vector3d::Constant(n));
}

geometry_msgs::Pose pose(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose p;
  p.position = point(T.translation());
  const Eigen::Quaterniond q(T.linear());
  p.orientation.x = q.x(), p.orientation.y = q.y(), p.orientation.z = q.z(), p.orientation.w = q.w();
  return p;
}

bool sameCamera(const tabletop_capture::CameraModel& a, const tabletop_capture::CameraModel& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
         a.cx == b.cx && a.cy == b.cy && a.distortion == b.distortion &&
         a.world_T_camera.isApprox(b.world_T_camera, 1e-12);
}

}  // namespace

class PapfNodelet : public nodelet::Nodelet {
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    diag_ = std::make_unique<tabletop_common::PeriodicDiagnostics>(
        nh, pnh, getName(), "papf", "papf body tracking",
        [this](diagnostic_updater::DiagnosticStatusWrapper& stat) { diagnose(stat); });
    try {
      tabletop_common::ConfigSchema schema;
      addPapfKeys(&cfg_, &schema);
      const std::string file = tabletop_common::loadConfigWithOverrides(
          pnh, ros::package::getPath("body_tracking") + "/config/papf.yaml", schema, {});
      finishPapfConfig(file + " (with the private parameters): ", &cfg_);
      const std::string profile_file = cfg_.nodelet.body_profile_file.empty()
          ? ros::package::getPath("body_tracking") + "/config/body_profile.yaml"
          : cfg_.nodelet.body_profile_file;
      profile_ = BodyProfile::fromYamlFile(profile_file);
      papf_ = std::make_unique<Papf>(profile_, cfg_.params);
      if (papf_->gpuWeightsActive()) NODELET_INFO("papf: particle weights on the GPU");
      reportGpuWarning();
    } catch (const std::exception& e) {
      fatal_ = e.what();
      NODELET_FATAL("papf: not started: bad parameters: %s", e.what());
      return;
    }
    pose_pub_ = nh.advertise<tabletop_msgs::BodyPose>("body/pose", 5);
    joints_pub_ = nh.advertise<sensor_msgs::JointState>("body/joint_states", 5);
    targets_pub_ = nh.advertise<tabletop_msgs::TrackedTargets>("body/hand_targets", 5);
    markers_pub_ = nh.advertise<visualization_msgs::MarkerArray>("body/markers", 2);
    if (cfg_.nodelet.publish_volume) volume_pub_ = nh.advertise<tabletop_msgs::VoxelVolume>("body/volume", 2);
    tf_ = std::make_unique<tf2_ros::TransformBroadcaster>();
    // getNodeHandle(): this nodelet's callbacks run one at a time in arrival order, so the
    // volumes of a set (body, then skin) pair up and sets are tracked in stamp order.
    const int q = cfg_.nodelet.queue_size;
    body_sub_ = nh.subscribe("psfs/body_volume", q, &PapfNodelet::onBody, this);
    if (cfg_.nodelet.use_skin_volume)
      skin_sub_ = nh.subscribe("psfs/skin_volume", q, &PapfNodelet::onSkin, this);
    if (cfg_.nodelet.publish_masks)
      frames_sub_ = nh.subscribe("frames", 2, &PapfNodelet::onFrameSet, this);
    NODELET_INFO("papf: tracking the upper body on %s%s, %d particles x %d layers, seed %llu%s",
                 body_sub_.getTopic().c_str(),
                 cfg_.nodelet.use_skin_volume ? (" + " + skin_sub_.getTopic()).c_str() : "",
                 cfg_.params.particles, cfg_.params.layers,
                 static_cast<unsigned long long>(cfg_.params.seed),
                 cfg_.nodelet.publish_masks ? ", silhouette masks on <camera>/body_mask" : "");
  }

  // ---- inputs --------------------------------------------------------------------------------
  void onFrameSet(const tabletop_msgs::MultiViewFrame::ConstPtr& f) {
    std::vector<tabletop_capture::CameraModel> cams;
    if (f->camera_infos.size() != f->camera_names.size() ||
        f->camera_poses.size() != f->camera_names.size()) {
      NODELET_WARN_THROTTLE(10.0, "papf: frame set with inconsistent camera arrays: no masks");
      return;
    }
    for (size_t i = 0; i < f->camera_names.size(); ++i) {
      tabletop_capture::CameraModel c;
      std::string why;
      if (!tabletop_capture::fromCameraInfo(f->camera_infos[i], &c, &why) ||
          !tabletop_capture::fromTransform(f->camera_poses[i], &c.world_T_camera)) {
        NODELET_WARN_THROTTLE(10.0, "papf: camera %s unusable (%s): no masks for it",
                              f->camera_names[i].c_str(), why.c_str());
        c.width = 0;
      }
      c.name = f->camera_names[i];
      cams.push_back(c);
    }
    std::lock_guard<std::mutex> lock(camera_mutex_);
    bool same = cams.size() == projectors_.size();
    for (size_t i = 0; same && i < cams.size(); ++i)
      same = projectors_[i] && cams[i].width > 0 && sameCamera(projectors_[i]->camera(), cams[i]);
    if (same) return;
    // Cameras are static: the per-pixel rays are computed once per rig (tens of ms).
    projectors_.clear();
    mask_pubs_.clear();
    for (const auto& c : cams) {
      projectors_.push_back(c.width > 0 ? std::make_unique<SilhouetteProjector>(c) : nullptr);
      mask_pubs_.push_back(getNodeHandle().advertise<sensor_msgs::Image>(c.name + "/body_mask", 2));
    }
  }

  void onSkin(const tabletop_msgs::VoxelVolume::ConstPtr& m) { pair(m, true); }
  void onBody(const tabletop_msgs::VoxelVolume::ConstPtr& m) {
    if (!cfg_.nodelet.use_skin_volume) {
      process(nullptr, *m);
      return;
    }
    pair(m, false);
  }

  void pair(const tabletop_msgs::VoxelVolume::ConstPtr& m, bool skin) {
    tabletop_msgs::VoxelVolume::ConstPtr skin_msg, body_msg;
    if (!pairing_.add(m, skin, &skin_msg, &body_msg)) return;
    process(skin_msg.get(), *body_msg);
  }

  void process(const tabletop_msgs::VoxelVolume* skin_msg, const tabletop_msgs::VoxelVolume& body_msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string why;
    if (!psfs::fromVoxelVolumeMsg(body_msg, &body_, &why) ||
        (skin_msg && !psfs::fromVoxelVolumeMsg(*skin_msg, &skin_, &why))) {
      ++rejected_;
      NODELET_ERROR_THROTTLE(5.0, "papf: volume at %.3f ignored: %s", body_msg.header.stamp.toSec(),
                             why.c_str());
      return;
    }
    const ros::Time stamp = body_msg.header.stamp;
    if (!last_stamp_.isZero() && stamp <= last_stamp_) {
      // Time went back (a bag played again or looped): start over as constructed (same seed),
      // so a replay gives what the first play gave.
      NODELET_WARN("papf: volume at %.3f is not newer than the last one (%.3f): time went back "
                   "(a bag played again or looped?): the tracker starts over", stamp.toSec(),
                   last_stamp_.toSec());
      papf_ = std::make_unique<Papf>(profile_, cfg_.params);
      ++time_jumps_;
    }
    try {
      papf_->update(body_, skin_msg ? &skin_ : nullptr);
      reportGpuWarning();  // a CUDA failure moves the weights to the CPU
    } catch (const std::exception& e) {
      ++rejected_;
      NODELET_ERROR_THROTTLE(5.0, "papf: %s", e.what());
      return;
    }
    last_stamp_ = stamp;
    ++frames_;
    total_ms_.add(papf_->lastTimes().total_ms);
    const BodyEstimate& e = papf_->estimate();
    if (e.started) {
      ++starts_;
      NODELET_INFO("papf: person found, tracking (start %llu)", static_cast<unsigned long long>(starts_));
    }
    if (was_tracking_ && !e.tracking) {
      ++losses_;
      NODELET_WARN("papf: track lost (the fit stayed poor or the person left); restarting when "
                   "a person is seen");
    }
    was_tracking_ = e.tracking;
    publish(stamp, e);
  }

  // ---- outputs -------------------------------------------------------------------------------
  void publish(const ros::Time& stamp, const BodyEstimate& e) {
    const std::string& world = cfg_.nodelet.world_frame;
    auto pose_msg = boost::make_shared<tabletop_msgs::BodyPose>();
    pose_msg->header.stamp = stamp;
    pose_msg->header.frame_id = world;
    pose_msg->valid = e.tracking;
    const BodyFrames& f = e.frames;
    if (e.tracking) {
      for (int i = 0; i < dof::COUNT; ++i) pose_msg->state[i] = e.state[i];
      pose_msg->left_hand = point(e.hands.position[0]);
      pose_msg->right_hand = point(e.hands.position[1]);
      pose_msg->head = point(f.head_centre);
      pose_msg->left_shoulder = point(f.shoulder[0]);
      pose_msg->right_shoulder = point(f.shoulder[1]);
      pose_msg->left_elbow = point(f.elbow[0]);
      pose_msg->right_elbow = point(f.elbow[1]);
      pose_msg->left_wrist = point(f.wrist[0]);
      pose_msg->right_wrist = point(f.wrist[1]);
    } else {
      pose_msg->state.fill(std::numeric_limits<double>::quiet_NaN());
      for (auto* p : {&pose_msg->left_hand, &pose_msg->right_hand, &pose_msg->head,
                      &pose_msg->left_shoulder, &pose_msg->right_shoulder, &pose_msg->left_elbow,
                      &pose_msg->right_elbow, &pose_msg->left_wrist, &pose_msg->right_wrist})
        *p = nanPoint();
    }
    pose_pub_.publish(pose_msg);

    if (e.tracking) {
      auto js = boost::make_shared<sensor_msgs::JointState>();
      js->header = pose_msg->header;
      for (int i = 0; i < dof::COUNT; ++i) {
        js->name.push_back(dofName(i));
        js->position.push_back(e.state[i]);
      }
      joints_pub_.publish(js);
    }

    auto targets = boost::make_shared<tabletop_msgs::TrackedTargets>();
    targets->header = pose_msg->header;
    for (int k = 0; k < 3; ++k) {
      tabletop_msgs::TrackedTarget t;
      t.id = k;
      t.type = k == 0 ? tabletop_msgs::TrackedTarget::HEAD : tabletop_msgs::TrackedTarget::HAND;
      t.position = k == 0 ? pose_msg->head : (k == 1 ? pose_msg->left_hand : pose_msg->right_hand);
      t.weight = e.tracking ? e.score : 0.0;
      t.active = e.tracking;
      targets->targets.push_back(t);
    }
    targets_pub_.publish(targets);

    visualization_msgs::MarkerArray markers;
    const BodyParts parts = buildParts(papf_->profile(), f);  // with its online shape
    std::vector<geometry_msgs::TransformStamped> tfs;
    for (int i = 0; i < kNumParts; ++i) {
      const TruncatedQuadric& q = parts[i];
      visualization_msgs::Marker m;
      m.header = pose_msg->header;
      m.ns = "body_parts";
      m.id = i;
      m.action = e.tracking ? visualization_msgs::Marker::ADD : visualization_msgs::Marker::DELETE;
      Eigen::Isometry3d T = q.frame;
      if (q.shape == TruncatedQuadric::Shape::CYLINDER) {
        // rviz cylinders run along their z axis, centred: turn local y onto z, move to the middle.
        m.type = visualization_msgs::Marker::CYLINDER;
        T = q.frame * Eigen::Translation3d(0, 0.5 * q.length, 0) *
            Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX());
        m.scale.x = 2 * q.semi.x(), m.scale.y = 2 * q.semi.z(), m.scale.z = q.length;
      } else {
        m.type = visualization_msgs::Marker::SPHERE;
        m.scale.x = 2 * q.semi.x(), m.scale.y = 2 * q.semi.y(), m.scale.z = 2 * q.semi.z();
      }
      m.pose = pose(T);
      const bool skin = isSkinPart(static_cast<Part>(i));
      m.color.r = skin ? 1.0f : 0.3f, m.color.g = skin ? 0.7f : 0.6f, m.color.b = skin ? 0.5f : 1.0f;
      m.color.a = 0.35f;
      markers.markers.push_back(m);
      if (e.tracking) {
        geometry_msgs::TransformStamped tf;
        tf.header = pose_msg->header;
        tf.child_frame_id = cfg_.nodelet.tf_prefix + partName(static_cast<Part>(i));
        const geometry_msgs::Pose p = pose(q.frame);
        tf.transform.translation.x = p.position.x;
        tf.transform.translation.y = p.position.y;
        tf.transform.translation.z = p.position.z;
        tf.transform.rotation = p.orientation;
        tfs.push_back(tf);
      }
    }
    visualization_msgs::Marker sk;
    sk.header = pose_msg->header;
    sk.ns = "skeleton";
    sk.id = 0;
    sk.type = visualization_msgs::Marker::LINE_LIST;
    sk.action = e.tracking ? visualization_msgs::Marker::ADD : visualization_msgs::Marker::DELETE;
    sk.pose.orientation.w = 1.0;
    sk.scale.x = 0.012;
    sk.color.r = 1.0f, sk.color.g = 1.0f, sk.color.b = 0.2f, sk.color.a = 1.0f;
    if (e.tracking) {
      const Eigen::Vector3d neck = f.head.translation();
      auto bone = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
        sk.points.push_back(point(a));
        sk.points.push_back(point(b));
      };
      bone(f.pelvis.translation(), f.chest.translation());
      bone(f.chest.translation(), neck);
      bone(neck, f.head_centre);
      for (int s = 0; s < 2; ++s) {
        bone(neck, f.shoulder[s]);
        bone(f.shoulder[s], f.elbow[s]);
        bone(f.elbow[s], f.wrist[s]);
        bone(f.wrist[s], e.hands.position[s]);
      }
    }
    markers.markers.push_back(sk);
    markers_pub_.publish(markers);
    if (!tfs.empty()) tf_->sendTransform(tfs);
    if (e.tracking && cfg_.nodelet.publish_masks) publishMasks(pose_msg->header, parts);
    if (cfg_.nodelet.publish_volume && volume_pub_.getNumSubscribers() > 0) {
      const psfs::ProbabilityVolume* v = &body_;
      if (e.tracking) {
        applyModelPrior(body_, priorSolids(papf_->profile(), f, cfg_.nodelet.volume_prior),
                        cfg_.nodelet.volume_prior, &prior_volume_);
        v = &prior_volume_;
      }
      auto msg = boost::make_shared<tabletop_msgs::VoxelVolume>();
      psfs::toVoxelVolumeMsg(*v, stamp, world, msg.get());
      volume_pub_.publish(msg);
    }
  }

  void publishMasks(const std_msgs::Header& header, const BodyParts& parts) {
    std::lock_guard<std::mutex> lock(camera_mutex_);
    for (size_t i = 0; i < projectors_.size(); ++i) {
      if (!projectors_[i] || mask_pubs_[i].getNumSubscribers() == 0) continue;
      cv::Mat mask;
      projectors_[i]->draw(parts, cfg_.nodelet.mask_margin_px, &mask);
      auto img = boost::make_shared<sensor_msgs::Image>();
      img->header = header;
      img->header.frame_id = projectors_[i]->camera().frame_id;
      img->height = mask.rows;
      img->width = mask.cols;
      img->encoding = "mono8";
      img->step = mask.cols;
      img->data.assign(mask.datastart, mask.dataend);
      mask_pubs_[i].publish(img);
    }
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
    else if (!was_tracking_)
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "no person");
    else
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::OK, "tracking, fit %.2f", papf_->estimate().score);
    stat.add("rate (Hz)", rate);
    stat.add("frames", frames_);
    stat.add("starts", starts_);
    stat.add("losses", losses_);
    stat.add("time jumps back (started over)", time_jumps_);
    stat.add("papf total (ms)", total_ms_.mean());
    // The online shape in use (papf.yaml shape/*; 1 = the body profile as given). The timer may
    // fire before onInit has built the tracker.
    if (papf_) {
      stat.add("trunk girth factor", papf_->estimate().trunk_girth);
      stat.add("arm length factor", papf_->estimate().arm_length);
      stat.add("upper arm, forearm (m)", std::to_string(papf_->profile().upper_arm) + ", " +
                                             std::to_string(papf_->profile().forearm));
    }
    stat.add("volumes rejected", rejected_);
  }

  PapfConfig cfg_;
  BodyProfile profile_;
  std::unique_ptr<Papf> papf_;
  // gpu_weights without a usable GPU (or after a CUDA failure): said once per reason.
  void reportGpuWarning() {
    const std::string& w = papf_->gpuWarning();
    if (w.empty() || w == reported_gpu_warning_) return;
    NODELET_WARN("papf: %s", w.c_str());
    reported_gpu_warning_ = w;
  }
  std::string reported_gpu_warning_;
  std::string fatal_;
  ros::Subscriber body_sub_, skin_sub_, frames_sub_;
  ros::Publisher pose_pub_, joints_pub_, targets_pub_, markers_pub_, volume_pub_;
  std::vector<ros::Publisher> mask_pubs_;
  std::vector<std::unique_ptr<SilhouetteProjector>> projectors_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_;
  std::unique_ptr<tabletop_common::PeriodicDiagnostics> diag_;
  std::mutex mutex_, camera_mutex_;
  psfs::VolumePairing pairing_;
  psfs::ProbabilityVolume skin_, body_, prior_volume_;
  ros::Time last_stamp_;
  bool was_tracking_ = false;
  tabletop_common::RateMeter rate_;
  tabletop_common::GrowthMeter rejections_;
  uint64_t frames_ = 0, rejected_ = 0, starts_ = 0, losses_ = 0, time_jumps_ = 0;
  tabletop_common::RunningStats total_ms_;
};

}  // namespace body_tracking

PLUGINLIB_EXPORT_CLASS(body_tracking::PapfNodelet, nodelet::Nodelet)
