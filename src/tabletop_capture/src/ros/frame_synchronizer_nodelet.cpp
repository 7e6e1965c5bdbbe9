// Frame synchroniser nodelet: bundles the N camera streams (cam<i>/image_raw, received through
// image_transport, + camera_info) into synchronised MultiViewFrame sets on `frames`, converting
// every image to rgb8.
// Grouping, ordering and drop policy live in FrameSetAssembler (ROS-free, unit-tested);
// image validation and debayering in convertToRgb8.
// Parameters: ~config_file (default $(find tabletop_capture)/config/frame_synchronizer.yaml,
// every key documented there) read strictly, then any private parameter named like a key
// overrides it; an unknown one stops the stage (tabletop_common/ros/config_overrides.h).
// Live tuning (dynamic_reconfigure, cfg/FrameSynchronizerTuning.cfg): tolerance, timeout.
#include <cmath>
#include <deque>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>

#include <boost/function.hpp>
#include <diagnostic_updater/diagnostic_updater.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/package.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <tabletop_msgs/MultiViewFrame.h>

#include "tabletop_capture/FrameSynchronizerTuningConfig.h"  // generated from cfg/FrameSynchronizerTuning.cfg
#include "tabletop_capture/frame_set_assembler.h"
#include "tabletop_capture/frame_synchronizer_config.h"
#include "tabletop_capture/image_conversion.h"
#include "tabletop_capture/ros/conversions.h"
#include "tabletop_common/ros/config_overrides.h"
#include "tabletop_common/ros/live_tuning.h"
#include "tabletop_common/ros/periodic_diagnostics.h"
#include "tabletop_capture/ros/published_frames.h"
#include "tabletop_common/running_stats.h"

namespace tabletop_capture {

class FrameSynchronizerNodelet : public nodelet::Nodelet {
  using ImagePtr = sensor_msgs::ImageConstPtr;

  struct Camera {
    std::string name;
    image_transport::Subscriber image_sub;
    ros::Subscriber info_sub;
    sensor_msgs::CameraInfoConstPtr info;  // latest valid camera_info
    std::string info_error;                // why the latest camera_info was rejected
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    bool have_pose = false;
    std::string pose_frame;   // the optical frame the pose is of
    ros::WallTime pose_time;  // when the pose was last looked up
    bool hasPoseOf(const std::string& frame) const { return have_pose && pose_frame == frame; }
    // A valid camera_info and the pose of the frame it names.
    bool calibrated() const { return info && hasPoseOf(info->header.frame_id); }
    // Its last complete calibration (camera_info with a pose for its frame): fills its slot in
    // a set it is missing from.
    sensor_msgs::CameraInfoConstPtr published_info;
    geometry_msgs::Transform published_pose;
    uint64_t images = 0, rejected = 0;
    double last_stamp = -1e300;  // of its last image (time-jump detection)
    bool before_jump = false;    // no image from after the last time jump yet
  };

  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    diag_ = std::make_unique<tabletop_common::PeriodicDiagnostics>(
        nh, pnh, getName(), "frame_synchronizer", "frame synchronizer",
        [this](diagnostic_updater::DiagnosticStatusWrapper& stat) { diagnose(stat); });
    FrameSynchronizerConfig cfg;
    FrameSetAssemblerConfig timing;
    try {
      tabletop_common::ConfigSchema schema;
      addFrameSynchronizerKeys(&cfg, &schema);
      tabletop_common::loadConfigWithOverrides(
          pnh, ros::package::getPath("tabletop_capture") + "/config/frame_synchronizer.yaml", schema, {});
      timing = cfg.assembler();
      assembler_ = std::make_unique<FrameSetAssembler<ImagePtr>>(timing);
    } catch (const std::exception& e) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        fatal_ = std::string("bad parameters: ") + e.what();
      }
      NODELET_FATAL("frame synchroniser: not started: bad parameters: %s", e.what());
      return;
    }
    const int num_cameras = cfg.num_cameras;
    const std::string& prefix = cfg.camera_prefix;
    world_frame_ = cfg.world_frame;
    tf_timeout_ = cfg.tf_timeout;
    hold_until_subscribers_ = cfg.hold_until_subscribers;
    max_held_ = cfg.max_held;
    time_jump_threshold_ = cfg.time_jump_threshold;
    const int queue_size = cfg.queue_size, image_queue_size = cfg.image_queue_size;
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh);
    cameras_.resize(num_cameras);
    image_transport::ImageTransport it(nh);
    for (int i = 0; i < num_cameras; ++i) {
      Camera& c = cameras_[i];
      c.name = prefix + std::to_string(i);
      boost::function<void(const ImagePtr&)> on_image = [this, i](const ImagePtr& m) {
        onImage(i, m);
      };
      boost::function<void(const sensor_msgs::CameraInfoConstPtr&)> on_info =
          [this, i](const sensor_msgs::CameraInfoConstPtr& m) { onInfo(i, m); };
      try {
        c.image_sub = it.subscribe(c.name + "/image_raw", std::max(1, image_queue_size), on_image,
                                   ros::VoidPtr(), image_transport::TransportHints(cfg.image_transport));
      } catch (const image_transport::TransportLoadException& e) {
        std::lock_guard<std::mutex> lock(mutex_);
        fatal_ = "image_transport '" + cfg.image_transport + "' is not available (" + e.what() + ")";
        assembler_.reset();
        cameras_.clear();
        NODELET_FATAL("frame synchroniser: not started: %s", fatal_.c_str());
        return;
      }
      c.info_sub = nh.subscribe<sensor_msgs::CameraInfo>(c.name + "/camera_info",
                                                         std::max(1, image_queue_size), on_info);
    }
    pub_ = nh.advertise<tabletop_msgs::MultiViewFrame>("frames", queue_size);
    boost::function<void(const ros::WallTimerEvent&)> on_tick = [this](const ros::WallTimerEvent&) {
      onTick();
    };
    tick_ = nh.createWallTimer(ros::WallDuration(0.05), on_tick);
    NODELET_INFO("frame synchroniser: %d cameras (%s0..%s%d, %s transport), tolerance %.4f s, "
                 "timeout %.3f s, sets published without up to %d camera(s)",
                 num_cameras, prefix.c_str(), prefix.c_str(), num_cameras - 1,
                 cfg.image_transport.c_str(), timing.tolerance, timing.timeout, timing.max_missing);
    tabletop_capture::FrameSynchronizerTuningConfig live;
    live.tolerance = timing.tolerance;
    live.timeout = timing.timeout;
    tuning_ = std::make_unique<tabletop_common::LiveTuning<tabletop_capture::FrameSynchronizerTuningConfig>>(
        pnh, live,
        [this](const tabletop_capture::FrameSynchronizerTuningConfig& c) {
          std::lock_guard<std::mutex> lock(mutex_);
          assembler_->setTiming(c.tolerance, c.timeout);
        },
        "frame synchroniser");
  }

  void onInfo(int i, const sensor_msgs::CameraInfoConstPtr& msg) {
    CameraModel model;
    std::string why;
    const bool ok = fromCameraInfo(*msg, &model, &why);
    std::lock_guard<std::mutex> lock(mutex_);
    Camera& c = cameras_[i];
    if (ok) {
      c.info = msg;
      c.info_error.clear();
    } else {
      c.info_error = why;
      NODELET_ERROR_THROTTLE(5.0, "frame synchroniser: %s: invalid camera_info ignored: %s",
                             c.name.c_str(), why.c_str());
    }
  }

  void onImage(int i, const ImagePtr& msg) {
    const ros::WallTime t0 = ros::WallTime::now();
    sensor_msgs::CameraInfoConstPtr info;
    std::string info_error;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++cameras_[i].images;
      info = cameras_[i].info;
      info_error = cameras_[i].info_error;
    }
    const std::string& name = cameras_[i].name;
    if (!info) {
      reject(i, "no valid camera_info yet (" +
                    (info_error.empty() ? "nothing on " + name + "/camera_info" : info_error) +
                    "): image dropped");
      return;
    }
    RawImageView view;
    view.encoding = msg->encoding;
    view.width = static_cast<int>(msg->width);
    view.height = static_cast<int>(msg->height);
    view.step = msg->step;
    view.data = msg->data.data();
    view.size = msg->data.size();
    // rgb8 input is kept as the received message (no conversion, no copy yet).
    ImagePtr rgb = msg;
    if (msg->encoding != "rgb8" || msg->width != info->width || msg->height != info->height ||
        msg->step < msg->width * 3 || msg->data.size() < size_t(msg->step) * msg->height) {
      // (No source name: reject() puts the camera's name in front.)
      ImageConversionResult r =
          convertToRgb8(view, static_cast<int>(info->width), static_cast<int>(info->height), "");
      if (!r.ok) {
        reject(i, r.error);
        return;
      }
      sensor_msgs::ImagePtr out(new sensor_msgs::Image);
      toImageMsg(r.rgb, "rgb8", out.get());
      out->header = msg->header;
      rgb = out;
    }
    const double ms = (ros::WallTime::now() - t0).toSec() * 1e3;
    refreshPose(i, info->header.frame_id);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      convert_ms_.add(ms);
      if (!checkTimeJump(i, msg->header.stamp.toSec())) {
        NODELET_WARN_THROTTLE(5.0, "frame synchroniser: %s: image %.3f from before the time jump "
                              "dropped", name.c_str(), msg->header.stamp.toSec());
        return;
      }
      const Losses missing_before = losses();
      const AddResult r = assembler_->add(i, msg->header.stamp.toSec(), rgb);
      newest_arrival_ = ros::WallTime::now();
      newest_stamp_ = std::max(newest_stamp_, msg->header.stamp.toSec());
      if (r == AddResult::kLate)
        NODELET_WARN_THROTTLE(5.0, "frame synchroniser: %s: late image (stamp %.3f) dropped",
                              name.c_str(), msg->header.stamp.toSec());
      else if (r == AddResult::kDuplicate)
        NODELET_WARN_THROTTLE(5.0, "frame synchroniser: %s: two images for one set, second dropped",
                              name.c_str());
      warnDropped(missing_before);
      // Published under the lock so that sets leave in stamp order whichever thread completed them.
      for (auto& set : assembler_->takeCompleted()) publishSet(set);
    }
  }

  // Called with mutex_ held. One camera's images arrive in stamp order (one topic), so a stamp
  // more than time_jump_threshold before that camera's last one means its clock went back: a
  // bag played again or in a loop (rosbag play -l). Pending sets and the watermark are
  // forgotten, so the replay is assembled like a first play instead of being dropped as late.
  // Returns false for an image that is still from before the jump (in a loop, another camera's
  // last images of the previous pass can come after the first camera's jump).
  bool checkTimeJump(int i, double stamp) {
    Camera& cam = cameras_[i];
    if (cam.before_jump) {
      if (stamp > jump_stamp_ + time_jump_threshold_) return false;
      cam.before_jump = false;
      cam.last_stamp = stamp;
      return true;
    }
    const double back = cam.last_stamp - stamp;
    cam.last_stamp = stamp;
    if (!(back > time_jump_threshold_)) return true;
    NODELET_WARN("frame synchroniser: time went back by %.3f s on %s (a bag played again or "
                 "looped?): %zu pending frame set(s) dropped, assembling from %.3f on",
                 back, cameras_[i].name.c_str(), assembler_->pendingCount(), stamp);
    assembler_->reset();
    for (size_t c = 0; c < cameras_.size(); ++c) cameras_[c].before_jump = static_cast<int>(c) != i;
    jump_stamp_ = stamp;
    newest_stamp_ = stamp;
    ++time_jumps_;
    return true;
  }

  // What warnDropped compares: the counters before an add() or expire().
  struct Losses {
    std::vector<uint64_t> missing;
    uint64_t dropped = 0;
  };
  Losses losses() const {
    return {assembler_->counters().missing_per_camera, assembler_->counters().incomplete()};
  }

  // Called with mutex_ held: names the cameras missing from the sets just dropped or published
  // without them.
  void warnDropped(const Losses& before) {
    const Losses after = losses();
    std::string names;
    for (size_t c = 0; c < after.missing.size(); ++c)
      if (after.missing[c] > before.missing[c]) names += (names.empty() ? "" : ", ") + cameras_[c].name;
    if (names.empty()) return;
    if (after.dropped > before.dropped)
      NODELET_WARN_THROTTLE(5.0, "frame synchroniser: incomplete frame set dropped, missing: %s",
                            names.c_str());
    else
      NODELET_WARN_THROTTLE(5.0, "frame synchroniser: frame set published without %s (no image "
                            "within the timeout): those views are left out", names.c_str());
  }

  void reject(int i, const std::string& why) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++cameras_[i].rejected;
    NODELET_ERROR_THROTTLE(5.0, "frame synchroniser: %s: %s", cameras_[i].name.c_str(),
                           why.c_str());
  }

  void onTick() {
    // A camera whose images stopped (or never came) still needs a pose for its empty slot in
    // degraded sets: look it up here, outside the lock (a lookup may wait tf_timeout).
    std::vector<std::pair<int, std::string>> unposed;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (size_t i = 0; i < cameras_.size(); ++i) {
        const Camera& c = cameras_[i];
        if (c.info && !c.calibrated() &&
            (ros::WallTime::now() - c.pose_time).toSec() >= 1.0)
          unposed.emplace_back(static_cast<int>(i), c.info->header.frame_id);
      }
    }
    for (const auto& u : unposed) refreshPose(u.first, u.second);
    std::lock_guard<std::mutex> lock(mutex_);
    if (!assembler_ || newest_arrival_.isZero()) return;
    const Losses missing_before = losses();
    // Stamps may come from a camera clock: advance the newest stamp by the wall time since it
    // arrived instead of comparing stamps with the system clock.
    assembler_->expire(newest_stamp_ + (ros::WallTime::now() - newest_arrival_).toSec());
    warnDropped(missing_before);
    for (auto& set : assembler_->takeCompleted()) publishSet(set);
    flushHeld();
  }

  // Called with mutex_ held. The first sets of a recording are the background-learning sets:
  // until hold_until_subscribers stages listen on `frames` (a nodelet that loads late, a
  // recording that starts at once), sets are held here instead of being lost.
  void emit(const tabletop_msgs::MultiViewFrameConstPtr& out) {
    held_.push_back(out);
    while (static_cast<int>(held_.size()) > std::max(1, max_held_)) {
      held_.pop_front();
      ++held_dropped_;
      NODELET_WARN_THROTTLE(5.0, "frame synchroniser: nobody listens on %s: oldest held frame "
                            "set dropped (max_held %d)", pub_.getTopic().c_str(), max_held_);
    }
    flushHeld();
  }

  void flushHeld() {
    if (held_.empty()) return;
    if (static_cast<int>(pub_.getNumSubscribers()) < hold_until_subscribers_) return;
    if (held_.size() > 1)
      NODELET_INFO("frame synchroniser: %zu frame sets held until %d subscriber(s) listened: "
                   "publishing them", held_.size(), hold_until_subscribers_);
    for (const auto& m : held_) pub_.publish(m);
    held_.clear();
    hold_until_subscribers_ = 0;  // only at start-up: later, a live pipeline must not stall
  }

  // Called with mutex_ held. Copies each image once, into the bundle. A camera missing from
  // the set, or whose image has no pose (refreshPose() said why), gets an empty slot
  // (MultiViewFrame.msg) with its current calibration or, lacking one (no tf for the frame its
  // images name now), that of its last published image; the set is dropped if that leaves more
  // than max_missing slots empty or a slot without any calibration.
  void publishSet(FrameSet<ImagePtr>& set) {
    const ros::WallTime t0 = ros::WallTime::now();
    const size_t n = cameras_.size();
    std::vector<bool> usable(n);
    int empty_slots = 0;
    for (size_t i = 0; i < n; ++i) {
      Camera& c = cameras_[i];
      const bool calibrated = c.calibrated();
      if (calibrated) {
        c.published_info = c.info;
        c.published_pose = toTransform(c.pose);
      }
      usable[i] = set.present[i] && calibrated;
      if (usable[i]) continue;
      ++empty_slots;
      if (!c.published_info || empty_slots > assembler_->config().max_missing) {
        ++tf_failures_;
        return;
      }
    }
    tabletop_msgs::MultiViewFramePtr out(new tabletop_msgs::MultiViewFrame);
    // The earliest image stamp, taken from the messages (set.stamp is a double: it would
    // lose nanoseconds).
    bool first = true;
    for (size_t i = 0; i < n; ++i)
      if (usable[i] && (first || set.frames[i]->header.stamp < out->header.stamp)) {
        out->header.stamp = set.frames[i]->header.stamp;
        first = false;
      }
    out->header.frame_id = world_frame_;
    out->camera_names.resize(n);
    out->images.resize(n);
    out->camera_infos.resize(n);
    out->camera_poses.resize(n);
    for (size_t i = 0; i < n; ++i) {
      Camera& c = cameras_[i];
      out->camera_names[i] = c.name;
      sensor_msgs::Image& image = out->images[i];
      if (usable[i]) {
        image = *set.frames[i];  // the one copy: into the bundle
      } else {
        image.header.stamp = out->header.stamp;
        image.header.frame_id = c.published_info->header.frame_id;
      }
      image.encoding = "rgb8";
      out->camera_infos[i] = *c.published_info;
      out->camera_infos[i].header.stamp = image.header.stamp;
      out->camera_poses[i] = c.published_pose;
    }
    if (empty_slots > 0) ++partial_;
    notePublishedFrame(out.get());
    emit(out);
    bundle_ms_.add((ros::WallTime::now() - t0).toSec() * 1e3);
    ++published_;
  }

  // Called WITHOUT mutex_: a tf lookup can wait up to tf_timeout, and every camera callback
  // needs mutex_. The rig is static: the pose is looked up again once a second, and a failed
  // lookup keeps the last known pose (or, without one, the camera's sets are dropped).
  void refreshPose(int i, const std::string& frame_id) {
    const ros::WallTime now = ros::WallTime::now();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const Camera& c = cameras_[i];
      if (c.hasPoseOf(frame_id) && (now - c.pose_time).toSec() < 1.0) return;
    }
    Eigen::Isometry3d pose;
    std::string error;
    try {
      const geometry_msgs::TransformStamped t =
          tf_buffer_.lookupTransform(world_frame_, frame_id, ros::Time(0), ros::Duration(tf_timeout_));
      if (!fromTransform(t.transform, &pose)) error = "the transform is not finite";
    } catch (const tf2::TransformException& e) {
      error = e.what();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    Camera& c = cameras_[i];
    // With a pose, a failure is retried after a second, not on every image; without one, at
    // the next image (the static tf may simply not have arrived yet).
    c.pose_time = now;
    if (error.empty()) {
      if (c.hasPoseOf(frame_id)) {
        const double moved_mm = (pose.translation() - c.pose.translation()).norm() * 1e3;
        const double turned_deg =
            Eigen::AngleAxisd(pose.linear() * c.pose.linear().transpose()).angle() * 180.0 / M_PI;
        if (moved_mm > 1.0 || turned_deg > 0.1)
          NODELET_WARN("frame synchroniser: %s: its tf changed (%.1f mm, %.2f deg): the new pose is "
                       "used from now on", c.name.c_str(), moved_mm, turned_deg);
      }
      c.pose = pose;
      c.pose_frame = frame_id;
      c.have_pose = true;
    } else if (!c.hasPoseOf(frame_id)) {
      c.have_pose = false;
      NODELET_ERROR_THROTTLE(5.0, "frame synchroniser: %s: no tf %s -> %s (%s): its images are "
                             "left out of the sets (or the sets dropped)", c.name.c_str(),
                             world_frame_.c_str(), frame_id.c_str(), error.c_str());
    } else {
      NODELET_WARN_THROTTLE(5.0, "frame synchroniser: %s: tf %s -> %s lost (%s): keeping its last "
                            "pose (a static rig)", c.name.c_str(), world_frame_.c_str(),
                            frame_id.c_str(), error.c_str());
    }
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!assembler_) {
      if (fatal_.empty())
        stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "starting");
      else
        stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "not started: " + fatal_);
      return;
    }
    const ros::WallTime now = ros::WallTime::now();
    const double dt = last_diag_.isZero() ? 0.0 : (now - last_diag_).toSec();
    const double rate = dt > 0 ? (published_ - published_at_last_diag_) / dt : 0.0;
    const FrameSetCounters& k = assembler_->counters();
    const uint64_t problems = k.incomplete() + k.late + tf_failures_;
    uint64_t inputs = 0;
    std::string no_info;
    for (const Camera& c : cameras_) {
      inputs += c.images;
      if (!c.info) no_info += (no_info.empty() ? "" : ", ") + c.name;
    }
    if (inputs > 0 && !no_info.empty())
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "no camera_info from " + no_info);
    else if (inputs > 0 && rate == 0 && dt > 0 && published_ == published_at_last_diag_)
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "images arrive but no complete set");
    else if (problems > problems_at_last_diag_)
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "dropping frame sets");
    else if (partial_ > partial_at_last_diag_)
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "publishing frame sets without some cameras");
    else
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "ok");
    last_diag_ = now;
    published_at_last_diag_ = published_;
    problems_at_last_diag_ = problems;
    partial_at_last_diag_ = partial_;
    stat.add("rate (Hz)", rate);
    stat.add("sets published", published_);
    stat.add("sets incomplete (dropped)", k.incomplete());
    stat.add("sets without some cameras (published)", partial_);
    stat.add("late images (dropped)", k.late);
    stat.add("duplicate images (dropped)", k.duplicate);
    stat.add("sets without tf (dropped)", tf_failures_);
    stat.add("time jumps back (reset)", time_jumps_);
    stat.add("convert time mean (ms)", convert_ms_.mean());
    stat.add("bundle time mean (ms)", bundle_ms_.mean());
    stat.add("pending sets", assembler_->pendingCount());
    stat.add("sets held for subscribers", held_.size());
    stat.add("held sets dropped (nobody listened)", held_dropped_);
    for (size_t c = 0; c < cameras_.size(); ++c) {
      std::ostringstream v;
      v << cameras_[c].images << " received, " << cameras_[c].rejected << " rejected, "
        << k.missing_per_camera[c] << " sets missed" << (assembler_->absent(c) ? ", absent" : "");
      stat.add(cameras_[c].name, v.str());
    }
  }

  std::unique_ptr<FrameSetAssembler<ImagePtr>> assembler_;
  std::string fatal_;  // why the nodelet did not start
  std::vector<Camera> cameras_;
  ros::Publisher pub_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<tabletop_common::PeriodicDiagnostics> diag_;
  ros::WallTimer tick_;
  std::string world_frame_;
  double tf_timeout_ = 0.05;
  int hold_until_subscribers_ = 1, max_held_ = 100;
  std::deque<tabletop_msgs::MultiViewFrameConstPtr> held_;
  uint64_t held_dropped_ = 0;
  std::mutex mutex_;
  ros::WallTime newest_arrival_, last_diag_;
  double newest_stamp_ = 0;
  // A camera's stamp this far (s) before its last one is a time jump (see checkTimeJump).
  double time_jump_threshold_ = 1.0;
  uint64_t time_jumps_ = 0;
  double jump_stamp_ = 0;  // the first stamp after the last jump
  tabletop_common::RunningStats convert_ms_, bundle_ms_;
  uint64_t published_ = 0, published_at_last_diag_ = 0, problems_at_last_diag_ = 0,
           tf_failures_ = 0, partial_ = 0, partial_at_last_diag_ = 0;
  // Last: destroyed first, so that no tuning callback meets a half-destroyed nodelet.
  std::unique_ptr<tabletop_common::LiveTuning<tabletop_capture::FrameSynchronizerTuningConfig>> tuning_;
};

}  // namespace tabletop_capture

PLUGINLIB_EXPORT_CLASS(tabletop_capture::FrameSynchronizerNodelet, nodelet::Nodelet)
