// pSfS nodelet: frame sets (`frames`, MultiViewFrame) in, probabilistic volumes out.
// A thin wrapper around psfs::Reconstructor: it converts the bundle to images and camera models
// without copying the pixels (the images are read in place, inside the same nodelet manager the
// bundle itself arrives zero-copy), collects hand ROIs from `hands/targets`, publishes
//   psfs/body_volume, psfs/skin_volume   (tabletop_msgs/VoxelVolume, every reconstructed set)
//   psfs/hand_volumes                    (tabletop_msgs/HandVolumes, when ROIs are requested)
//   psfs/body_cloud, psfs/skin_cloud     (sensor_msgs/PointCloud2, only while subscribed)
//   psfs/processed                       (std_msgs/Header per frame set taken in: its stamp, and
//                                         frame_id learned | reconstructed | rejected | dropped;
//                                         what a lockstep source such as the SimRig paces on)
// and reports rate, per-stage times, learning progress, rejected and dropped sets, load
// shedding and switched-off cameras on /diagnostics.
// Service ~relearn_background (std_srvs/Trigger): forget the background model and learn it
// again from the next learning_frames sets (the workspace must be empty then), e.g. after the
// lighting or the room changed.
// Live tuning (dynamic_reconfigure, cfg/PsfsTuning.cfg): body_threshold, skin_threshold and
// hand_threshold, applied from the next frame set on.
//
// Frame sets wait in a PipelineGate (tabletop_common/pipeline_gate.h) and are processed on the
// nodelet's own thread: this is the pipeline's one drop point (live: the oldest waiting set goes
// when nodelet/queue_size is exceeded; offline: a large queue_size keeps every set), and the
// closed loop's lockstep (the next set waits for the tracker's targets of the last one).
//
// Private parameters:
//   ~config_file          the YAML with every parameter   [$(find psfs_reconstruction)/config/psfs.yaml]
//   ~<key>                any key of the file, as its path (~fusion/body/threshold), overrides
//                         it (tabletop_common/ros/config_overrides.h); an unknown one is an error
//   ~threads, ~queue_size, ~wait_for_tracker, ~tracker_timeout, ~load_shedding,
//   ~background_load_dir, ~background_save_dir
//                         short names of the nodelet/ keys of the file
//   ~body_threshold, ~skin_threshold, ~hand_threshold
//                         short names of fusion/*/threshold, also live (dynamic_reconfigure)
//   ~world_frame          frame of the volumes                               [world]
#include <array>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <sys/stat.h>

#include <boost/make_shared.hpp>
#include <diagnostic_updater/diagnostic_updater.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/package.h>
#include <ros/ros.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>
#include <std_srvs/Trigger.h>

#include <tabletop_msgs/HandVolumes.h>
#include <tabletop_msgs/MultiViewFrame.h>
#include <tabletop_msgs/TrackedTargets.h>
#include <tabletop_msgs/VoxelVolume.h>

#include "psfs_reconstruction/PsfsTuningConfig.h"  // generated from cfg/PsfsTuning.cfg
#include "psfs_reconstruction/reconstructor.h"
#include "psfs_reconstruction/cuda_device.h"
#include "psfs_reconstruction/reconstructor_config.h"
#include "psfs_reconstruction/ros/volume_msgs.h"
#include "tabletop_common/pipeline_gate.h"
#include "tabletop_capture/ros/frame_set_view.h"
#include "tabletop_common/ros/config_overrides.h"
#include "tabletop_common/ros/live_tuning.h"
#include "tabletop_common/ros/periodic_diagnostics.h"
#include "tabletop_common/running_stats.h"

namespace psfs {

using tabletop_common::RunningStats;

class PsfsNodelet : public nodelet::Nodelet {
 public:
  ~PsfsNodelet() override {
    tuning_.reset();  // no tuning callback while the rest goes
    {
      std::lock_guard<std::mutex> lock(gate_mutex_);
      running_ = false;
    }
    gate_cv_.notify_all();
    if (worker_.joinable()) worker_.join();
  }

 private:
  using FramePtr = tabletop_msgs::MultiViewFrame::ConstPtr;
  // Why the worker starts over before the next set: time went back, or relearn_background.
  enum class StartOver { kNone, kTimeJump, kRelearn };

  static double steadySeconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  }

  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    pnh.param("world_frame", world_frame_, std::string("world"));
    diag_ = std::make_unique<tabletop_common::PeriodicDiagnostics>(
        nh, pnh, getName(), "psfs", "psfs reconstruction",
        [this](diagnostic_updater::DiagnosticStatusWrapper& stat) { diagnose(stat); });
    std::string config_file;
    try {
      tabletop_common::ConfigSchema schema;
      addReconstructorKeys(&cfg_, &schema);
      config_file = tabletop_common::loadConfigWithOverrides(
          pnh, ros::package::getPath("psfs_reconstruction") + "/config/psfs.yaml", schema,
          {"world_frame"});
      finishReconstructorConfig(config_file, &cfg_);
      tabletop_common::PipelineGateConfig gate;
      gate.capacity = static_cast<size_t>(cfg_.nodelet.queue_size);
      gate.ack_timeout = cfg_.nodelet.tracker_timeout;
      gate_.setConfig(gate);
      const GaussianMixture2D skin = GaussianMixture2D::load(cfg_.skin_model_path);
      recon_ = std::make_unique<Reconstructor>(skin, cfg_.params);
      if (cfg_.params.backend == ReconstructorParams::Backend::kCuda &&
          recon_->activeBackend() == ReconstructorParams::Backend::kCuda)
        NODELET_INFO("psfs: backend cuda on %s", cuda::device().describe().c_str());
    } catch (const std::exception& e) {
      fatal_ = e.what();
      NODELET_FATAL("psfs: not started: %s", e.what());
      return;
    }
    body_pub_ = nh.advertise<tabletop_msgs::VoxelVolume>("psfs/body_volume", 2);
    skin_pub_ = nh.advertise<tabletop_msgs::VoxelVolume>("psfs/skin_volume", 2);
    hands_pub_ = nh.advertise<tabletop_msgs::HandVolumes>("psfs/hand_volumes", 2);
    body_cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("psfs/body_cloud", 1);
    skin_cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("psfs/skin_cloud", 1);
    processed_pub_ = nh.advertise<std_msgs::Header>("psfs/processed", 50);
    relearn_srv_ = pnh.advertiseService("relearn_background", &PsfsNodelet::onRelearn, this);
    psfs_reconstruction::PsfsTuningConfig live;
    live.body_threshold = cfg_.params.body.threshold;
    live.skin_threshold = cfg_.params.skin.threshold;
    live.hand_threshold = cfg_.params.hand.threshold;
    tuning_ = std::make_unique<tabletop_common::LiveTuning<psfs_reconstruction::PsfsTuningConfig>>(
        pnh, live, [this](const psfs_reconstruction::PsfsTuningConfig& c) { onTuning(c); }, "psfs");
    roi_sub_ = nh.subscribe(cfg_.nodelet.hand_roi_topic, 5, &PsfsNodelet::onTargets, this);
    running_ = true;
    worker_ = std::thread(&PsfsNodelet::work, this);
    // The callback only queues the set in the gate: the ROS queue must never be what drops.
    frames_sub_ = nh.subscribe("frames", 50, &PsfsNodelet::onFrameSet, this);
    NODELET_INFO("psfs: %s volumes from the frame sets on %s; config %s; %s",
                 workspaceGrid(cfg_.params.workspace, cfg_.params.dims).describe().c_str(),
                 frames_sub_.getTopic().c_str(), config_file.c_str(),
                 cfg_.nodelet.queue_size > 1000
                     ? "every frame set is processed (offline)"
                     : ("live: up to " + std::to_string(cfg_.nodelet.queue_size) +
                        " set(s) wait, older ones are dropped" +
                        (cfg_.nodelet.load_shedding ? ", load shedding on" : ""))
                           .c_str());
  }

  // ---- the gate: queue, drop, lockstep --------------------------------------------------
  void onFrameSet(const FramePtr& msg) {
    std::deque<FramePtr> dropped;
    {
      std::lock_guard<std::mutex> lock(gate_mutex_);
      checkTimeJump(msg->header.stamp);
      // The learning sets are the recording's first ones: they are never dropped.
      const bool keep = learning_sets_queued_ < cfg_.params.background.learning_frames &&
                        !background_ready_;
      learning_sets_queued_ += keep;
      dropped = gate_.push(msg, keep);
      recent_drops_.push_back(!dropped.empty());
      while (recent_drops_.size() > kShedWindow) recent_drops_.pop_front();
      updateShedding();
    }
    gate_cv_.notify_one();
    for (const auto& d : dropped) {
      NODELET_WARN_THROTTLE(5.0, "%s: falling behind the cameras: frame set %.3f dropped "
                            "(queue_size %d; the later stages get every set that goes on)",
                            getName().c_str(), d->header.stamp.toSec(), cfg_.nodelet.queue_size);
      publishProcessed(d->header.stamp, "dropped");
    }
  }

  // Called with gate_mutex_ held. The synchroniser sends sets in stamp order, so a set that is
  // not newer than the last one means time went back: a bag played again or in a loop. The
  // recording starts over with its empty workspace, so everything learned from the last pass
  // goes (queue, background model, hand ROIs, shedding) and the replay gives what a first play
  // gives. The models are reset by the worker before it processes the next set (see work()).
  void checkTimeJump(const ros::Time& stamp) {
    const ros::Time last = last_in_;
    last_in_ = stamp;
    if (last.isZero() || stamp > last) return;
    const std::deque<FramePtr> forgotten = gate_.clear();
    NODELET_WARN("psfs: frame set %.3f is not newer than the last one (%.3f): time went back (a "
                 "bag played again or looped?); %zu queued set(s) dropped, the background is "
                 "learned again", stamp.toSec(), last.toSec(), forgotten.size());
    for (const auto& d : forgotten) publishProcessed(d->header.stamp, "dropped");
    recent_drops_.clear();
    shed_every_ = 1;
    requestStartOver(StartOver::kTimeJump);
    ++time_jumps_;
  }

  // Called with gate_mutex_ held: the next sets are learning sets again, and the worker resets
  // the models before it processes the next one (a relearn request is not weakened by a time
  // jump that follows it before the next set).
  void requestStartOver(StartOver kind) {
    learning_sets_queued_ = 0;
    background_ready_ = false;
    start_over_ = std::max(start_over_, kind);
  }

  // Called with gate_mutex_ held. Load shedding is a step controller with hysteresis: while
  // more than shed_drop_fraction of the recent sets are dropped, hand volumes are computed on
  // one set in 2, then 3, then 4; after a full window without a drop, one step back. Each step
  // starts a fresh window, so it is judged on what it achieved.
  void updateShedding() {
    if (!cfg_.nodelet.load_shedding) return;
    size_t drops = 0;
    for (bool d : recent_drops_) drops += d;
    const int was = shed_every_;
    if (recent_drops_.size() >= kShedWindow / 2 &&
        drops > cfg_.nodelet.shed_drop_fraction * recent_drops_.size())
      shed_every_ = std::min(kMaxShedEvery, shed_every_ + 1);
    else if (drops == 0 && recent_drops_.size() >= kShedWindow)
      shed_every_ = std::max(1, shed_every_ - 1);
    if (shed_every_ == was) return;
    recent_drops_.clear();
    if (shed_every_ > 1)
      NODELET_WARN("psfs: load shedding: hand volumes (and meshes) on 1 of every %d frame sets "
                   "only: the machine cannot keep up with the cameras", shed_every_);
    else
      NODELET_WARN("psfs: load shedding off: the machine keeps up again");
  }

  void work() {
    std::unique_lock<std::mutex> lock(gate_mutex_);
    while (running_) {
      const double now = steadySeconds();
      std::optional<FramePtr> next;
      StartOver start_over = StartOver::kNone;
      if (outcome_) {
        // The last set's `processed` ack. A reconstructed set's waits for the tracker's answer,
        // so a lockstep source counts the whole closed loop as in flight; and the next set is
        // taken out of the queue before the ack goes, so the set the source sends on it never
        // finds the queue full.
        if (gate_.waiting(now)) {
          gate_cv_.wait_for(lock, std::chrono::duration<double>(gate_.secondsUntilTimeout(now) + 1e-3));
          continue;
        }
        next = gate_.pop(now);
        if (next) start_over = std::exchange(start_over_, StartOver::kNone);
        const std::pair<ros::Time, std::string> done = *outcome_;
        outcome_.reset();
        lock.unlock();
        publishProcessed(done.first, done.second.c_str());
        lock.lock();
        if (!next) continue;  // a set pushed meanwhile is popped at once, not after a wait
      } else {
        next = gate_.pop(now);
        if (!next) {  // popped and waited under one lock hold: a push always wakes us
          gate_cv_.wait_for(lock, std::chrono::duration<double>(0.2));
          continue;
        }
        start_over = std::exchange(start_over_, StartOver::kNone);
      }
      const int shed_every = shed_every_;
      lock.unlock();
      // Popped under the same lock as the flag was read: a set of the last pass is never taken
      // for the first of the replay.
      if (start_over != StartOver::kNone) startOver(start_over == StartOver::kRelearn);
      applyTuning();
      process(*next, shed_every);
      lock.lock();
    }
  }

  // dynamic_reconfigure thread: checked here (a refused value never reaches the worker), applied
  // by the worker before its next set, so that a set is fused with one set of thresholds. cfg_
  // keeps the values read at start (only read after onInit); the thresholds in force are the
  // reconstructor's.
  void onTuning(const psfs_reconstruction::PsfsTuningConfig& c) {
    PsfsOptions o = cfg_.params.body;
    for (const double t : {c.body_threshold, c.skin_threshold, c.hand_threshold}) {
      o.threshold = t;
      PsfsFusion check(o);  // throws std::invalid_argument for a value out of range
    }
    std::lock_guard<std::mutex> lock(tuning_mutex_);
    pending_thresholds_ = {c.body_threshold, c.skin_threshold, c.hand_threshold};
  }

  // Worker thread.
  void applyTuning() {
    std::optional<std::array<double, 3>> t;
    {
      std::lock_guard<std::mutex> lock(tuning_mutex_);
      t = std::exchange(pending_thresholds_, std::nullopt);
    }
    if (!t) return;
    const ReconstructorParams& now = recon_->params();
    if (now.body.threshold == (*t)[0] && now.skin.threshold == (*t)[1] && now.hand.threshold == (*t)[2]) return;
    try {
      recon_->setFusionThresholds((*t)[0], (*t)[1], (*t)[2]);
    } catch (const std::invalid_argument& e) {
      NODELET_WARN("psfs: live tuning not applied: %s", e.what());
      return;
    }
    NODELET_INFO("psfs: live tuning: thresholds body %.3f, skin %.3f, hand %.3f from the next set",
                 (*t)[0], (*t)[1], (*t)[2]);
  }

  bool onRelearn(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
    {
      std::lock_guard<std::mutex> lock(gate_mutex_);
      requestStartOver(StartOver::kRelearn);
    }
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      learning_ = true;  // reported at once; the models are reset before the next set
      learned_ = 0;
    }
    res.success = true;
    res.message = "the background is learned again from the next " +
                  std::to_string(cfg_.params.background.learning_frames) +
                  " frame sets: keep the workspace empty";
    NODELET_WARN("psfs: relearn_background called: %s", res.message.c_str());
    return true;
  }

  // Worker thread: after a time jump or a relearn request, the state a fresh nodelet has (a
  // relearn learns the background; it does not load it again from background_load_dir).
  void startOver(bool relearn) {
    recon_->resetBackground();
    shed_counter_ = 0;
    {
      std::lock_guard<std::mutex> lock(roi_mutex_);
      targets_.reset();
    }
    std::lock_guard<std::mutex> lock(stats_mutex_);
    load_tried_ = relearn;
    announced_ready_ = false;
    learning_ = true;
    learned_ = 0;
  }

  // The fate of the set being processed; work() publishes it on psfs/processed.
  void finish(const ros::Time& stamp, const char* what) {
    std::lock_guard<std::mutex> lock(gate_mutex_);
    outcome_ = std::make_pair(stamp, std::string(what));
  }

  void publishProcessed(const ros::Time& stamp, const char* what) {
    auto h = boost::make_shared<std_msgs::Header>();
    h->stamp = stamp;
    h->frame_id = what;
    processed_pub_.publish(h);
  }

  // ---- inputs ---------------------------------------------------------------------------
  void onTargets(const tabletop_msgs::TrackedTargets::ConstPtr& msg) {
    {
      std::lock_guard<std::mutex> lock(roi_mutex_);
      targets_ = msg;
    }
    {
      std::lock_guard<std::mutex> lock(gate_mutex_);
      gate_.ack(msg->header.stamp.toNSec());
    }
    gate_cv_.notify_one();
  }

  void onMask(size_t camera, const sensor_msgs::Image::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(roi_mutex_);
    if (camera >= masks_.size()) return;
    auto& history = masks_[camera];
    history[msg->header.stamp] = msg;
    while (history.size() > 5) history.erase(history.begin());
  }

  std::vector<std::pair<uint32_t, Eigen::Vector3d>> currentRois(const ros::Time& stamp) {
    std::vector<std::pair<uint32_t, Eigen::Vector3d>> rois;
    std::lock_guard<std::mutex> lock(roi_mutex_);
    if (!targets_ || std::abs((targets_->header.stamp - stamp).toSec()) > cfg_.nodelet.hand_roi_max_age)
      return rois;
    for (const auto& t : targets_->targets) {
      if (!t.active || t.type != tabletop_msgs::TrackedTarget::HAND) continue;
      const Eigen::Vector3d p(t.position.x, t.position.y, t.position.z);
      if (!p.allFinite()) continue;
      if (static_cast<int>(rois.size()) >= cfg_.nodelet.max_hand_rois) break;
      rois.emplace_back(t.id, p);
    }
    return rois;
  }

  std::vector<cv::Mat> currentMasks(const tabletop_msgs::MultiViewFrame& f) {
    std::vector<cv::Mat> out;
    if (!cfg_.nodelet.foreground_mask_topics) return out;
    std::lock_guard<std::mutex> lock(roi_mutex_);
    if (mask_subs_.size() != f.camera_names.size()) {  // (re)subscribe for this rig
      mask_subs_.clear();
      masks_.assign(f.camera_names.size(), {});
      for (size_t i = 0; i < f.camera_names.size(); ++i) {
        boost::function<void(const sensor_msgs::Image::ConstPtr&)> cb =
            [this, i](const sensor_msgs::Image::ConstPtr& m) { onMask(i, m); };
        try {
          image_transport::ImageTransport it(getNodeHandle());
          mask_subs_.push_back(it.subscribe(f.camera_names[i] + "/" + cfg_.nodelet.foreground_mask_topic, 2,
                                            cb, ros::VoidPtr(),
                                            image_transport::TransportHints(cfg_.nodelet.foreground_mask_transport)));
        } catch (const image_transport::TransportLoadException& e) {
          NODELET_ERROR("psfs: foreground masks off: image_transport '%s' is not available (%s)",
                        cfg_.nodelet.foreground_mask_transport.c_str(), e.what());
          cfg_.nodelet.foreground_mask_topics = false;
          mask_subs_.clear();
          masks_.clear();
          return out;
        }
      }
    }
    out.resize(masks_.size());
    for (size_t i = 0; i < masks_.size(); ++i) {
      // The newest mask not newer than the set, if recent enough (the tracker's are of the
      // previous set).
      auto it = masks_[i].upper_bound(f.header.stamp);
      if (it == masks_[i].begin()) continue;
      const auto& m = std::prev(it)->second;
      if ((f.header.stamp - m->header.stamp).toSec() > cfg_.nodelet.foreground_mask_max_age) continue;
      if (m->encoding == "mono8" && m->data.size() >= size_t(m->step) * m->height)
        out[i] = cv::Mat(m->height, m->width, CV_8UC1, const_cast<uint8_t*>(m->data.data()), m->step);
    }
    return out;
  }

  // ---- per frame set --------------------------------------------------------------------
  // shed_every: load shedding's step; this set gets hand volumes only if it is the 1st of
  // every shed_every sets (1 = every set).
  void process(const FramePtr& msg, int shed_every) {
    const ros::WallTime t0 = ros::WallTime::now();
    std::vector<cv::Mat> rgb;
    std::vector<tabletop_capture::CameraModel> cams;
    std::string why;
    if (!tabletop_capture::unpackFrameSet(*msg, &rgb, &cams, &why)) {
      reject("frame set " + std::to_string(msg->header.stamp.toSec()) + " dropped: " + why);
      finish(msg->header.stamp, "rejected");
      return;
    }
    if (!load_tried_ && !cfg_.nodelet.background_load_dir.empty()) {
      load_tried_ = true;
      try {
        recon_->loadBackground(cfg_.nodelet.background_load_dir, cams);
        NODELET_INFO("psfs: background model loaded from %s",
                     cfg_.nodelet.background_load_dir.c_str());
      } catch (const std::exception& e) {
        NODELET_ERROR("psfs: %s; learning the background from the next %d frame sets instead",
                      e.what(), cfg_.params.background.learning_frames);
      }
    }
    auto rois = currentRois(msg->header.stamp);
    const bool skip_hands = shed_every > 1 && (shed_counter_++ % shed_every != 0);
    if (skip_hands) {
      hands_shed_ += !rois.empty();
      rois.clear();
    }
    std::vector<Eigen::Vector3d> centres;
    for (const auto& r : rois) centres.push_back(r.second);
    FrameResult r;
    try {
      r = recon_->process(rgb, cams, centres, currentMasks(*msg));
    } catch (const std::exception& e) {
      reject("frame set " + std::to_string(msg->header.stamp.toSec()) + " dropped: " + e.what());
      finish(msg->header.stamp, "rejected");
      return;
    }
    for (const auto& w : r.warnings) warnThrottled(w);
    if (r.status == FrameResult::Status::kReconstructed) {
      std::lock_guard<std::mutex> lock(gate_mutex_);
      background_ready_ = true;
    }

    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++processed_;
    learned_ = r.background_frames;
    learning_ = r.status == FrameResult::Status::kLearningBackground;
    if (learning_) {
      if (r.background_frames == 1 || r.background_frames % 10 == 0)
        NODELET_INFO("psfs: learning the background: %d/%d frame sets", r.background_frames,
                     cfg_.params.background.learning_frames);
      finish(msg->header.stamp, "learned");
      return;
    }
    if (!announced_ready_) {
      announced_ready_ = true;
      NODELET_INFO("psfs: background model ready (%d frame sets); reconstructing",
                   r.background_frames);
      saveBackground();
    }
    cameras_off_ = 0;
    for (bool a : r.camera_active) cameras_off_ += !a;
    trunk_colour_ = describeTrunkColour(r.trunk_colour);
    clothing_in_use_ = describeClothing(recon_->clothingColour());
    clothing_ms_.add(r.times.clothing);
    // Closed loop: the next set waits for the tracker's answer to this one. Noted before the
    // volumes go out, so an ack can never come before the gate expects it.
    if (cfg_.nodelet.wait_for_tracker && roi_sub_.getNumPublishers() > 0 &&
        body_pub_.getNumSubscribers() > 0) {
      std::lock_guard<std::mutex> gate_lock(gate_mutex_);
      gate_.expectAck(msg->header.stamp.toNSec(), steadySeconds());
    }
    publish(*msg, r, rois);
    finish(msg->header.stamp, "reconstructed");
    const StageTimes& t = r.times;
    prefilter_ms_.add(t.prefilter);
    classify_ms_.add(t.classify);
    evidence_ms_.add(t.evidence);
    body_ms_.add(t.body);
    skin_ms_.add(t.skin);
    hands_ms_.add(t.hands);
    if (!r.hands.empty()) hands_skipped_.add(100.0 * r.hands_skipped);
    background_ms_.add(t.background);
    total_ms_.add((ros::WallTime::now() - t0).toSec() * 1e3);
    ++reconstructed_;
  }

  // rois: the ROIs the hand volumes were computed for (their ids label the volumes).
  void publish(const tabletop_msgs::MultiViewFrame& f, const FrameResult& r,
               const std::vector<std::pair<uint32_t, Eigen::Vector3d>>& rois) {
    const ros::Time stamp = f.header.stamp;
    auto body = boost::make_shared<tabletop_msgs::VoxelVolume>();
    toVoxelVolumeMsg(r.body, stamp, world_frame_, body.get());
    body_pub_.publish(body);
    auto skin = boost::make_shared<tabletop_msgs::VoxelVolume>();
    toVoxelVolumeMsg(r.skin, stamp, world_frame_, skin.get());
    skin_pub_.publish(skin);
    if (!r.hands.empty()) {
      auto hands = boost::make_shared<tabletop_msgs::HandVolumes>();
      hands->header.stamp = stamp;
      hands->header.frame_id = world_frame_;
      for (size_t h = 0; h < r.hands.size(); ++h) {
        hands->target_ids.push_back(rois[h].first);
        hands->volumes.emplace_back();
        toVoxelVolumeMsg(r.hands[h], stamp, world_frame_, &hands->volumes.back());
      }
      hands_pub_.publish(hands);
    }
    if (cfg_.nodelet.publish_clouds && body_cloud_pub_.getNumSubscribers() > 0) {
      auto c = boost::make_shared<sensor_msgs::PointCloud2>();
      toCloudMsg(r.body, thresholdByte(recon_->params().body.threshold), stamp, world_frame_, c.get());
      body_cloud_pub_.publish(c);
    }
    if (cfg_.nodelet.publish_clouds && skin_cloud_pub_.getNumSubscribers() > 0) {
      auto c = boost::make_shared<sensor_msgs::PointCloud2>();
      toCloudMsg(r.skin, thresholdByte(recon_->params().skin.threshold), stamp, world_frame_, c.get());
      skin_cloud_pub_.publish(c);
    }
  }

  void saveBackground() {
    const std::string& dir = cfg_.nodelet.background_save_dir;
    if (dir.empty()) return;
    try {
      ::mkdir(dir.c_str(), 0755);
      recon_->saveBackground(dir);
      NODELET_INFO("psfs: background model saved to %s", dir.c_str());
    } catch (const std::exception& e) {
      NODELET_ERROR("psfs: could not save the background model: %s", e.what());
    }
  }

  void reject(const std::string& what) {
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      ++rejected_;
      last_error_ = what;
    }
    NODELET_ERROR_THROTTLE(5.0, "psfs: %s", what.c_str());
  }

  // One line per distinct message every 5 s (the throttle macros would merge them all).
  // Throttled per kind of warning: numbers that stand alone (percentages, litres, stamps) do
  // not make a new kind, camera names (cam3) do.
  void warnThrottled(const std::string& w) {
    std::string key;
    for (size_t i = 0; i < w.size(); ++i) {
      const bool number_start = std::isdigit(static_cast<unsigned char>(w[i])) &&
                                (i == 0 || !std::isalpha(static_cast<unsigned char>(w[i - 1])));
      if (!number_start) {
        key += w[i];
        continue;
      }
      key += '#';
      while (i + 1 < w.size() && (std::isdigit(static_cast<unsigned char>(w[i + 1])) || w[i + 1] == '.')) ++i;
    }
    const ros::WallTime now = ros::WallTime::now();
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++warnings_;
    auto it = warned_.find(key);
    if (it != warned_.end() && (now - it->second).toSec() < 5.0) return;
    warned_[key] = now;
    if (warned_.size() > 256) warned_.clear();
    NODELET_WARN("psfs: %s", w.c_str());
  }

  // ---- diagnostics ----------------------------------------------------------------------
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    if (!fatal_.empty()) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "not started: " + fatal_);
      return;
    }
    tabletop_common::PipelineGateCounters gate;
    size_t pending = 0;
    int shed_every = 1;
    uint64_t time_jumps = 0;
    {
      std::lock_guard<std::mutex> lock(gate_mutex_);
      gate = gate_.counters();
      pending = gate_.pendingCount();
      shed_every = shed_every_;
      time_jumps = time_jumps_;
    }
    std::lock_guard<std::mutex> lock(stats_mutex_);
    const double rate = rate_.rate(reconstructed_);
    const bool dropping = drops_growth_.grew(gate.dropped);
    const bool rejecting = rejections_.grew(rejected_);
    const bool warning = warnings_growth_.grew(warnings_);
    if (processed_ == 0)
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "waiting for frame sets");
    else if (learning_)
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK,
                   "learning the background (" + std::to_string(learned_) + "/" +
                       std::to_string(cfg_.params.background.learning_frames) + ")");
    else if (rejecting)
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "rejecting frame sets: " + last_error_);
    else if (shed_every > 1)
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                    "load shedding: hand volumes on 1 of every %d frame sets (cannot keep up)",
                    shed_every);
    else if (dropping)
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "dropping frame sets: the machine cannot keep up with the cameras");
    else if (warning || cameras_off_ > 0)
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "degraded input (see the log)");
    else
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "ok");
    stat.add("rate (Hz)", rate);
    stat.add("frame sets reconstructed", reconstructed_);
    stat.add("frame sets rejected", rejected_);
    stat.add("frame sets received", gate.pushed);
    stat.add("frame sets dropped (pipeline busy)", gate.dropped);
    stat.add("time jumps back (started over)", time_jumps);
    stat.add("drop rate (%)", gate.pushed ? 100.0 * gate.dropped / gate.pushed : 0.0);
    stat.add("frame sets waiting", pending);
    stat.add("load shedding", shed_every > 1 ? "on (hand volumes on 1 of every " +
                                                   std::to_string(shed_every) + " sets)"
                                             : std::string("off"));
    stat.add("hand volume sets shed", hands_shed_.load());
    stat.add("tracker acks", gate.acks);
    stat.add("tracker ack timeouts", gate.ack_timeouts);
    stat.add("cameras switched off", cameras_off_);
    stat.add("prefilter", describeImagePrefilter(cfg_.params.prefilter));
    stat.add("prefilter (ms)", prefilter_ms_.mean());
    stat.add("classify (ms)", classify_ms_.mean());
    stat.add("evidence (ms)", evidence_ms_.mean());
    stat.add("body fusion (ms)", body_ms_.mean());
    stat.add("skin fusion (ms)", skin_ms_.mean());
    stat.add("hand volumes (ms)", hands_ms_.mean());
    stat.add("hand volumes skipped (%)", hands_skipped_.mean());
    stat.add("background update (ms)", background_ms_.mean());
    stat.add("total (ms)", total_ms_.mean());
    stat.add("total max (ms)", total_ms_.max());
    stat.add("volume", workspaceGrid(cfg_.params.workspace, cfg_.params.dims).describe());
    stat.add("clothing colour (in use)", clothing_in_use_);
    stat.add("clothing colour (last set)", trunk_colour_);
    stat.add("clothing colour (ms)", clothing_ms_.mean());
  }

  // The clothing colour for the diagnostics (clothing_colour.h): the one in use, and this set's
  // measurement.
  static std::string describeColour(const ColourGaussian& c) {
    char b[64];
    std::snprintf(b, sizeof(b), "rg (%.3f, %.3f), sd (%.3f, %.3f)", c.mean.x(), c.mean.y(),
                  std::sqrt(c.covariance(0, 0)), std::sqrt(c.covariance(1, 1)));
    return b;
  }
  std::string describeClothing(const ClothingColourModel& m) const {
    if (!cfg_.params.clothing.active()) return "off";
    return m.valid() ? describeColour(m.colour()) : "none yet";
  }
  std::string describeTrunkColour(const TrunkColourSample& t) const {
    if (!cfg_.params.clothing.active()) return "off";
    char b[96];
    std::snprintf(b, sizeof(b), "%s %d trunk voxels, %d samples, %.0f %% inliers",
                  t.valid ? "" : "not measured:", t.band_voxels, t.samples,
                  100.0 * t.inlier_fraction);
    return t.valid ? describeColour(t.colour) + "," + b : std::string(b);
  }

  static constexpr size_t kShedWindow = 50;  // recent sets the shedding decision looks at
  static constexpr int kMaxShedEvery = 4;     // hand volumes on at least 1 set in 4

  ReconstructorConfig cfg_;
  std::unique_ptr<Reconstructor> recon_;

  // The gate and its worker thread; gate_mutex_ guards everything in this block.
  std::mutex gate_mutex_;
  std::condition_variable gate_cv_;
  tabletop_common::PipelineGate<FramePtr> gate_;
  std::thread worker_;
  bool running_ = false, background_ready_ = false;
  int shed_every_ = 1;  // load shedding: hand volumes on 1 of every shed_every_ sets
  int learning_sets_queued_ = 0;
  std::deque<bool> recent_drops_;
  std::optional<std::pair<ros::Time, std::string>> outcome_;  // for psfs/processed, see work()
  uint64_t shed_counter_ = 0;           // worker thread only
  ros::Time last_in_;                   // stamp of the last set taken in (time-jump detection)
  StartOver start_over_ = StartOver::kNone;  // see requestStartOver()
  ros::ServiceServer relearn_srv_;
  std::mutex tuning_mutex_;
  std::optional<std::array<double, 3>> pending_thresholds_;  // from onTuning(), for the worker
  std::unique_ptr<tabletop_common::LiveTuning<psfs_reconstruction::PsfsTuningConfig>> tuning_;
  uint64_t time_jumps_ = 0;
  std::atomic<uint64_t> hands_shed_{0};  // hand volume sets given up by load shedding
  ros::Publisher processed_pub_;

  std::string world_frame_, fatal_;
  ros::Subscriber frames_sub_, roi_sub_;
  std::vector<image_transport::Subscriber> mask_subs_;
  ros::Publisher body_pub_, skin_pub_, hands_pub_, body_cloud_pub_, skin_cloud_pub_;
  std::unique_ptr<tabletop_common::PeriodicDiagnostics> diag_;

  std::mutex roi_mutex_;
  tabletop_msgs::TrackedTargets::ConstPtr targets_;
  std::vector<std::map<ros::Time, sensor_msgs::Image::ConstPtr>> masks_;  // per camera, newest 5

  std::mutex stats_mutex_;
  bool load_tried_ = false, announced_ready_ = false, learning_ = true;
  int learned_ = 0, cameras_off_ = 0;
  std::string trunk_colour_ = "no set yet", clothing_in_use_ = "none yet";
  uint64_t processed_ = 0, reconstructed_ = 0, rejected_ = 0, warnings_ = 0;
  tabletop_common::RateMeter rate_;
  tabletop_common::GrowthMeter rejections_, warnings_growth_, drops_growth_;
  std::string last_error_;
  std::map<std::string, ros::WallTime> warned_;
  // Per-stage times over the whole run (the demo's summary reads the means).
  RunningStats classify_ms_, evidence_ms_, body_ms_, skin_ms_, hands_ms_, background_ms_, total_ms_;
  RunningStats hands_skipped_;  // % of the hand sub-volumes' voxels empty-space skipping left out
  RunningStats clothing_ms_, prefilter_ms_;
};

}  // namespace psfs

PLUGINLIB_EXPORT_CLASS(psfs::PsfsNodelet, nodelet::Nodelet)
