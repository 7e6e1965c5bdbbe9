// Simulated rig nodelet: renders the scripted scene and publishes exactly the camera-input
// contract of DESIGN.md section 3 (cam<i>/image_raw, cam<i>/camera_info, static tf), plus
// ground_truth/targets and ground_truth/body_pose, and (every ~truth_volume_every frames) the
// oracle's occupancy as ground_truth/body_volume and ground_truth/skin_volume for evaluating
// the reconstruction. All rendering lives in SimulatedRig.
//
// Lockstep (~lockstep = K > 0): the rig renders a frame only while fewer than K of its frames
// wait for their ack on ~lockstep_topic (psfs/processed), so it never outruns the pipeline it
// feeds: on a slow machine it renders at the rate the pipeline sustains (reported as the rig's
// rate) instead of starving it of CPU and making it drop sets. Before the first frame it waits
// for the ack topic's publisher, so the first (background-learning) sets are not missed. An ack
// that does not come within ~lockstep_timeout seconds is counted and waited for no longer.
#include <array>
#include <atomic>
#include <limits>
#include <condition_variable>
#include <set>
#include <memory>
#include <mutex>
#include <thread>

#include <boost/make_shared.hpp>
#include <opencv2/imgproc.hpp>

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/TransformStamped.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <std_msgs/String.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "tabletop_capture/rig_description.h"
#include "tabletop_capture/ros/conversions.h"
#include "tabletop_common/ros/config_overrides.h"
#include "tabletop_common/ros/periodic_diagnostics.h"
#include "tabletop_sim/ros/sim_truth_msgs.h"
#include "tabletop_common/running_stats.h"
#include "tabletop_sim/camera_faults.h"
#include "tabletop_sim/simulated_rig.h"

namespace tabletop_sim {


class SimRigNodelet : public nodelet::Nodelet {
 public:
  ~SimRigNodelet() override {
    running_ = false;
    ack_cv_.notify_all();
    if (worker_.joinable()) worker_.join();
  }

 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    SimOptions o;
    int seed = static_cast<int>(o.seed);
    std::string rig_file;
    std::string lockstep_topic = "psfs/processed";
    // Oracle volumes: every N-th frame (0 = never), on the workspace box at these dims.
    Eigen::Vector3i dims(64, 64, 48);
    max_frames_ = 0;
    start_delay_ = 1.0;
    realtime_ = true;
    lockstep_ = 0;
    lockstep_timeout_ = 5.0;
    truth_every_ = 0;
    // No file: the private parameters alone, through the strict loader every stage uses (an
    // unknown name is an error, not a silent default).
    tabletop_common::ConfigSchema schema;
    schema.add("num_cameras", &o.num_cameras)
        .add("width", &o.width)
        .add("height", &o.height)
        .add("distortion", &o.distortion)
        .add("fps", &o.fps)
        .add("script", &o.script)
        .add("empty_frames", &o.empty_frames)
        .add("seed", &seed)
        .add("noise_sigma", &o.noise_sigma)
        .add("bayer", &o.bayer)
        .add("scenario", &o.scenario)
        .add("short_sleeves", &o.short_sleeves)
        .add("shadows", &o.shadows)
        .add("threads", &o.threads)
        .add("rig_file", &rig_file)
        .add("max_frames", &max_frames_)
        .add("start_delay", &start_delay_)
        .add("realtime", &realtime_)
        .add("lockstep", &lockstep_)
        .add("lockstep_timeout", &lockstep_timeout_)
        .add("lockstep_topic", &lockstep_topic)
        .add("truth_volume_every", &truth_every_)
        .add("truth_volume_dims", &dims);
    try {
      tabletop_common::applyPrivateOverrides(pnh, schema, {});
      if (seed < 0) throw std::runtime_error("~seed: must be >= 0");
      if (!(dims.minCoeff() > 0)) throw std::runtime_error("~truth_volume_dims: must be 3 positive integers");
    } catch (const std::exception& e) {
      NODELET_FATAL("simulated rig: not started: bad parameters: %s", e.what());
      return;
    }
    o.seed = static_cast<uint64_t>(seed);
    truth_dims_ = dims;

    try {
      if (rig_file.empty()) {
        sim_ = std::make_unique<SimulatedRig>(o);
      } else {
        sim_ = std::make_unique<SimulatedRig>(o, tabletop_capture::loadRigYaml(rig_file));
      }
    } catch (const std::exception& e) {
      NODELET_FATAL("simulated rig: cannot start: %s", e.what());
      return;
    }
    encoding_ = (o.bayer == "none") ? "rgb8" : o.bayer;
    const tabletop_capture::RigDescription& rig = sim_->rig();
    for (const tabletop_capture::CameraModel& cam : rig.cameras) {
      image_pubs_.push_back(nh.advertise<sensor_msgs::Image>(cam.name + "/image_raw", 4));
      info_pubs_.push_back(nh.advertise<sensor_msgs::CameraInfo>(cam.name + "/camera_info", 4));
      infos_.push_back(tabletop_capture::toCameraInfo(cam));
      geometry_msgs::TransformStamped t;
      t.header.stamp = ros::Time::now();
      t.header.frame_id = rig.world_frame;
      t.child_frame_id = cam.frame_id;
      t.transform = tabletop_capture::toTransform(cam.world_T_camera);
      tfs_.push_back(t);
    }
    static_tf_.sendTransform(tfs_);
    tf_shift_.assign(tfs_.size(), {0.0, 0.0, 0.0});
    targets_pub_ = nh.advertise<tabletop_msgs::TrackedTargets>("ground_truth/targets", 10);
    body_pub_ = nh.advertise<tabletop_msgs::BodyPose>("ground_truth/body_pose", 10);
    if (truth_every_ > 0) {
      truth_body_pub_ = nh.advertise<tabletop_msgs::VoxelVolume>("ground_truth/body_volume", 4);
      truth_skin_pub_ = nh.advertise<tabletop_msgs::VoxelVolume>("ground_truth/skin_volume", 4);
    }
    world_frame_ = rig.world_frame;
    if (lockstep_ > 0)
      ack_sub_ = nh.subscribe(lockstep_topic, 100, &SimRigNodelet::onAck, this);
    faults_ = std::make_unique<CameraFaults>(static_cast<int>(rig.cameras.size()));
    fault_sub_ = pnh.subscribe("fault", 10, &SimRigNodelet::onFault, this);

    diag_ = std::make_unique<tabletop_common::PeriodicDiagnostics>(
        nh, pnh, getName(), "simulated_rig", "simulated rig",
        [this](diagnostic_updater::DiagnosticStatusWrapper& stat) { diagnose(stat); });
    NODELET_INFO("simulated rig: %zu cameras %dx%d at %.1f fps, script '%s', %d empty frames, "
                 "seed %d, encoding %s%s",
                 rig.cameras.size(), rig.cameras[0].width, rig.cameras[0].height, o.fps, o.script.c_str(), o.empty_frames,
                 seed, encoding_.c_str(),
                 lockstep_ > 0 ? (", in lockstep with " + lockstep_topic + " (" +
                                  std::to_string(lockstep_) + " sets in flight)").c_str()
                               : "");
    if (o.scenario != "default")
      NODELET_INFO("simulated rig: scenario %s", sim_->scenario().describe().c_str());
    running_ = true;
    worker_ = std::thread(&SimRigNodelet::run, this);
  }

  // Fault injection (camera_faults.h): the fault matrix's commands, on ~fault.
  void onFault(const std_msgs::String::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(fault_mutex_);
    try {
      faults_->command(m->data, ros::WallTime::now().toSec());
      NODELET_WARN("simulated rig: injecting fault '%s'", m->data.c_str());
    } catch (const std::exception& e) {
      NODELET_ERROR("simulated rig: %s", e.what());
    }
  }

  // The image as a fault makes it: resized, brighter, in another encoding (from rgb8 only).
  void applyFault(const CameraFaultEffect& e, const cv::Mat& rendered, cv::Mat* image, std::string* encoding) {
    cv::Mat m = rendered;
    if (e.gain != 1.0) rendered.convertTo(m, rendered.type(), e.gain);  // saturating
    if (e.width > 0) cv::resize(m, m, cv::Size(e.width, e.height), 0, 0, cv::INTER_AREA);
    if (!e.encoding.empty() && *encoding == "rgb8" && m.channels() == 3) {
      if (e.encoding == "bgr8") cv::cvtColor(m, m, cv::COLOR_RGB2BGR);
      if (e.encoding == "mono8") cv::cvtColor(m, m, cv::COLOR_RGB2GRAY);
      if (e.encoding == "rgba8") cv::cvtColor(m, m, cv::COLOR_RGB2RGBA);
      *encoding = e.encoding;
    }
    *image = m;
  }

  void onAck(const std_msgs::Header::ConstPtr& h) {
    {
      std::lock_guard<std::mutex> lock(ack_mutex_);
      if (in_flight_.erase(h->stamp) == 0) return;  // not ours, or already given up on
    }
    ack_cv_.notify_all();
  }

  // Lockstep: returns once fewer than lockstep_ frames are in flight (or on timeout).
  void waitForPipeline(int frame) {
    const ros::WallTime t0 = ros::WallTime::now();
    if (frame == 0) {
      while (running_ && ros::ok() && ack_sub_.getNumPublishers() == 0 &&
             (ros::WallTime::now() - t0).toSec() < 6 * lockstep_timeout_)
        ros::WallDuration(0.05).sleep();
      if (ack_sub_.getNumPublishers() == 0)
        NODELET_WARN("simulated rig: nothing publishes %s: rendering without lockstep",
                     ack_sub_.getTopic().c_str());
      return;
    }
    std::unique_lock<std::mutex> lock(ack_mutex_);
    const bool ok = ack_cv_.wait_for(lock, std::chrono::duration<double>(lockstep_timeout_), [&] {
      return !running_ || static_cast<int>(in_flight_.size()) < lockstep_;
    });
    if (!ok) {
      NODELET_WARN_THROTTLE(5.0, "simulated rig: no ack on %s for %.1f s: going on without it",
                            ack_sub_.getTopic().c_str(), lockstep_timeout_);
      in_flight_.erase(in_flight_.begin());
      ++lockstep_timeouts_;
    }
    lock.unlock();
    std::lock_guard<std::mutex> stats_lock(mutex_);
    lockstep_wait_ms_.add((ros::WallTime::now() - t0).toSec() * 1e3);
  }

  void run() {
    ros::WallDuration(start_delay_).sleep();
    const double period = 1.0 / sim_->options().fps;
    ros::WallTime next = ros::WallTime::now();
    for (int frame = 0; running_ && ros::ok(); ++frame) {
      if (max_frames_ > 0 && frame >= max_frames_) {
        NODELET_INFO_ONCE("simulated rig: published all %d frames", max_frames_);
        break;
      }
      if (lockstep_ > 0) waitForPipeline(frame);
      double clock_offset = 0;
      {
        std::lock_guard<std::mutex> lock(fault_mutex_);
        clock_offset = faults_->clockOffset(ros::WallTime::now().toSec());
      }
      const ros::Time stamp = ros::Time::now() + ros::Duration(clock_offset);
      if (lockstep_ > 0 && ack_sub_.getNumPublishers() > 0) {
        std::lock_guard<std::mutex> lock(ack_mutex_);
        in_flight_.insert(stamp);
      }
      const ros::WallTime t0 = ros::WallTime::now();
      SimFrame f = sim_->render(frame);
      const double render_ms = (ros::WallTime::now() - t0).toSec() * 1e3;
      publish(f, stamp);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        render_ms_.add(render_ms);
        published_ = frame + 1;
      }
      if (realtime_) {
        next += ros::WallDuration(period);
        const ros::WallTime now = ros::WallTime::now();
        if (next > now) {
          (next - now).sleep();
        } else {
          if ((now - next).toSec() > period) {
            std::lock_guard<std::mutex> lock(mutex_);
            ++overruns_;
          }
          next = now;  // fell behind: do not try to catch up with a burst
        }
      }
    }
  }

  void publish(const SimFrame& f, const ros::Time& stamp) {
    const double now = ros::WallTime::now().toSec();
    for (size_t i = 0; i < f.images.size(); ++i) {
      CameraFaultEffect fault;
      {
        std::lock_guard<std::mutex> lock(fault_mutex_);
        fault = faults_->effect(static_cast<int>(i), now);
      }
      updateTf(i, fault);
      if (fault.drop) continue;
      cv::Mat image = f.images[i];
      std::string encoding = encoding_;
      if (fault.any()) applyFault(fault, f.images[i], &image, &encoding);
      sensor_msgs::ImagePtr img(new sensor_msgs::Image);
      tabletop_capture::toImageMsg(image, encoding, img.get());
      img->header.stamp = stamp;
      img->header.frame_id = fault.frame_id.empty() ? infos_[i].header.frame_id : fault.frame_id;
      img->header.seq = f.index;
      sensor_msgs::CameraInfoPtr info(new sensor_msgs::CameraInfo(infos_[i]));
      info->header.stamp = stamp;
      info->header.seq = f.index;
      if (fault.nan_info) info->K[0] = info->K[4] = std::numeric_limits<double>::quiet_NaN();
      info->header.frame_id = img->header.frame_id;
      info_pubs_[i].publish(info);
      image_pubs_[i].publish(img);
    }
    targets_pub_.publish(toTargetsMsg(f.truth, stamp, world_frame_));
    body_pub_.publish(toBodyPoseMsg(f.truth, stamp, world_frame_));
    if (truth_every_ > 0 && f.index % truth_every_ == 0) {
      auto body = boost::make_shared<tabletop_msgs::VoxelVolume>();
      auto skin = boost::make_shared<tabletop_msgs::VoxelVolume>();
      const auto& o = sim_->options();
      toTruthVolumeMsgs(sim_->oracle(f.index), o.workspace_min, o.workspace_size, truth_dims_,
                        stamp, world_frame_, body.get(), skin.get());
      truth_body_pub_.publish(body);
      truth_skin_pub_.publish(skin);
    }
  }

  // A tf fault: camera i's static tf re-broadcast shifted, or true again once it ends.
  void updateTf(size_t i, const CameraFaultEffect& fault) {
    const std::array<double, 3> shift{fault.tf_shift[0], fault.tf_shift[1], fault.tf_shift[2]};
    if (shift == tf_shift_[i]) return;
    geometry_msgs::TransformStamped t = tfs_[i];
    t.header.stamp = ros::Time::now();
    t.transform.translation.x += shift[0];
    t.transform.translation.y += shift[1];
    t.transform.translation.z += shift[2];
    static_tf_.sendTransform(t);  // replaces the camera's entry in /tf_static
    tf_shift_[i] = shift;
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    std::lock_guard<std::mutex> lock(mutex_);
    const double rate = rate_.rate(static_cast<uint64_t>(published_));
    if (!sim_) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "not started (see log)");
      return;
    }
    const double fps = sim_->options().fps;
    if (lockstep_ > 0 && published_ > 0 && rate > 0 && rate < 0.95 * fps)
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::OK,
                    "paced by the pipeline: %.1f of %.1f fps", rate, fps);
    else if (realtime_ && published_ > 0 && rate > 0 && rate < 0.8 * fps)
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "rendering below %.1f fps", fps);
    else
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "rendering");
    stat.add("frames published", published_);
    {
      std::lock_guard<std::mutex> fault_lock(fault_mutex_);
      const std::string active = faults_ ? faults_->describe(ros::WallTime::now().toSec()) : "";
      stat.add("injected faults", active.empty() ? "none" : active);
    }
    stat.add("rate (Hz)", rate);
    stat.add("render time mean (ms)", render_ms_.mean());
    stat.add("render time max (ms)", render_ms_.max());
    stat.add("deadline overruns", overruns_);
    stat.add("nominal rate (Hz)", fps);
    if (lockstep_ > 0) {
      stat.add("lockstep wait mean (ms)", lockstep_wait_ms_.mean());
      stat.add("lockstep timeouts", lockstep_timeouts_.load());
    }
  }

  std::unique_ptr<SimulatedRig> sim_;
  std::unique_ptr<CameraFaults> faults_;  // under fault_mutex_
  std::mutex fault_mutex_;
  ros::Subscriber fault_sub_;
  std::vector<ros::Publisher> image_pubs_, info_pubs_;
  std::vector<sensor_msgs::CameraInfo> infos_;
  ros::Publisher targets_pub_, body_pub_, truth_body_pub_, truth_skin_pub_;
  int truth_every_ = 0;
  Eigen::Vector3i truth_dims_{64, 64, 48};
  tf2_ros::StaticTransformBroadcaster static_tf_;
  std::vector<geometry_msgs::TransformStamped> tfs_;  // the rig's true camera poses
  std::vector<std::array<double, 3>> tf_shift_;       // the shift broadcast per camera (m)
  std::unique_ptr<tabletop_common::PeriodicDiagnostics> diag_;
  std::string encoding_, world_frame_;
  int max_frames_ = 0;
  double start_delay_ = 1.0;
  bool realtime_ = true;
  int lockstep_ = 0;
  double lockstep_timeout_ = 5.0;
  ros::Subscriber ack_sub_;
  std::mutex ack_mutex_;  // guards in_flight_
  std::condition_variable ack_cv_;
  std::set<ros::Time> in_flight_;  // stamps published and not yet acked
  std::atomic<uint64_t> lockstep_timeouts_{0};
  tabletop_common::RunningStats lockstep_wait_ms_;  // under mutex_
  std::thread worker_;
  std::atomic<bool> running_{false};
  std::mutex mutex_;
  tabletop_common::RunningStats render_ms_;
  int published_ = 0;
  tabletop_common::RateMeter rate_;
  uint64_t overruns_ = 0;
};

}  // namespace tabletop_sim

PLUGINLIB_EXPORT_CLASS(tabletop_sim::SimRigNodelet, nodelet::Nodelet)
