// Camera capture nodelet (one instance per camera): grabs frames from a V4L2 camera or a file
// posing as one (FrameSource) on its own thread and publishes <camera_name>/image_raw with
// <camera_name>/camera_info (the rig's calibration, same stamp), meeting the camera contract
// of DESIGN.md section 3. Raw Bayer data is published as bayer_<pattern>8 or, with
// half_resolution, debayered 2x2 -> rgb8 at half size (thesis 4.1).
// A device that fails or vanishes is reported (ERROR naming the device and what OpenCV says,
// at most every 10 s per camera) and opened again every reopen_interval; the capture thread
// waits for it alone, so other nodelets of the manager are not blocked.
// Parameters: ~config_file (default $(find tabletop_capture)/config/camera_capture.yaml,
// every key documented there) read strictly, then any private parameter named like a key
// overrides it; an unknown one stops the nodelet (tabletop_common/ros/config_overrides.h).
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include <boost/make_shared.hpp>
#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/package.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "tabletop_capture/camera_calibration_file.h"
#include "tabletop_capture/camera_capture_config.h"
#include "tabletop_capture/capture_stats.h"
#include "tabletop_capture/frame_source.h"
#include "tabletop_capture/half_resolution_debayer.h"
#include "tabletop_capture/rig_description.h"
#include "tabletop_capture/ros/conversions.h"
#include "tabletop_common/ros/config_overrides.h"
#include "tabletop_common/ros/periodic_diagnostics.h"

namespace tabletop_capture {

class CameraCaptureNodelet : public nodelet::Nodelet {
 public:
  ~CameraCaptureNodelet() override {
    diag_.reset();  // no diagnostics callback from here on (it reads what goes below)
    {
      std::lock_guard<std::mutex> lock(stop_mutex_);
      running_ = false;
    }
    stop_cv_.notify_all();
    // A V4L2 grab() in progress returns within the device's timeout; files within a period.
    if (thread_.joinable()) thread_.join();
  }

 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    diag_ = std::make_unique<tabletop_common::PeriodicDiagnostics>(
        nh, pnh, getName(), "camera_capture", "camera capture",
        [this](diagnostic_updater::DiagnosticStatusWrapper& stat) { diagnose(stat); });
    try {
      tabletop_common::ConfigSchema schema;
      addCameraCaptureKeys(&cfg_, &schema);
      tabletop_common::loadConfigWithOverrides(
          pnh, ros::package::getPath("tabletop_capture") + "/config/camera_capture.yaml", schema, {});
      cfg_.validate();
      loadCameraInfo();
      FrameSourceSettings settings = cfg_.sourceSettings();
      settings.clock = [] { return ros::Time::now().toSec(); };
      source_ = makeFrameSource(settings);
      stats_ = std::make_unique<CaptureStats>(cfg_.fps);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      fatal_ = e.what();
      source_.reset();
      NODELET_FATAL("camera capture: not started: %s", e.what());
      return;
    }
    name_ = cfg_.camera_name;
    if (!have_info_)
      NODELET_WARN("camera capture %s: no rig_file (nor camera_info_file): no camera_info is published on %s/camera_info "
                   "(the RigPublisher nodelet or another source must publish it)",
                   name_.c_str(), name_.c_str());
    image_pub_ = nh.advertise<sensor_msgs::Image>(name_ + "/image_raw", cfg_.queue_size);
    if (have_info_)
      info_pub_ = nh.advertise<sensor_msgs::CameraInfo>(name_ + "/camera_info", cfg_.queue_size);
    const std::string raw = cfg_.bayer == "none" ? "" : ", raw Bayer " + cfg_.bayer;
    NODELET_INFO("camera capture %s: %s, %dx%d at %.2f fps%s%s -> %s/image_raw (%dx%d %s)",
                 name_.c_str(), source_->describe().c_str(), cfg_.width, cfg_.height, cfg_.fps,
                 raw.c_str(),
                 cfg_.trigger == "external" ? ", external trigger" : "", name_.c_str(),
                 cfg_.outputWidth(), cfg_.outputHeight(), outputEncoding().c_str());
    running_ = true;
    thread_ = std::thread([this] { run(); });
  }

  // The rig camera named camera_name (or the camera_info_file), checked against the published
  // size. Throws.
  void loadCameraInfo() {
    frame_id_ = cfg_.camera_name + "_optical_frame";
    if (!cfg_.camera_info_file.empty()) {
      const CameraModel cam = loadCameraCalibrationYaml(cfg_.camera_info_file, cfg_.camera_name);
      const std::string size_error = checkRigCameraSize(cam, cfg_, cfg_.camera_info_file);
      if (!size_error.empty()) throw std::runtime_error(size_error);
      info_ = toCameraInfo(cam);
      have_info_ = true;
      return;
    }
    if (cfg_.rig_file.empty()) return;
    const RigDescription rig = loadRigYaml(cfg_.rig_file);
    const int i = rig.findCamera(cfg_.camera_name);
    if (i < 0) {
      std::string names;
      for (const CameraModel& c : rig.cameras) names += (names.empty() ? "" : ", ") + c.name;
      throw std::runtime_error(cfg_.rig_file + ": no camera named '" + cfg_.camera_name +
                               "' (it has: " + names + ")");
    }
    const CameraModel& cam = rig.cameras[i];
    const std::string size_error = checkRigCameraSize(cam, cfg_, cfg_.rig_file);
    if (!size_error.empty()) throw std::runtime_error(size_error);
    info_ = toCameraInfo(cam);
    frame_id_ = cam.frame_id;
    have_info_ = true;
  }

  std::string outputEncoding() const {
    if (cfg_.half_resolution) return "rgb8";
    if (cfg_.bayerPattern() != BayerPattern::kNone) return bayerEncoding(cfg_.bayerPattern());
    return "bgr8 or mono8";
  }

  // Waits `seconds` or until the nodelet unloads; false when it unloads.
  bool pause(double seconds) {
    std::unique_lock<std::mutex> lock(stop_mutex_);
    stop_cv_.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return !running_; });
    return running_;
  }

  // Per camera (the NODELET_*_THROTTLE macros throttle per call site, i.e. across cameras).
  bool due(ros::WallTime* last, double seconds) {
    const ros::WallTime now = ros::WallTime::now();
    if (!last->isZero() && (now - *last).toSec() < seconds) return false;
    *last = now;
    return true;
  }

  void run() {
    const std::string dev = source_->describe();
    std::string why;
    bool ever_open = false;
    while (running_) {
      if (!source_->isOpen()) {
        if (!source_->open(&why)) {
          {
            std::lock_guard<std::mutex> lock(mutex_);
            state_ = "unavailable";
            last_error_ = why;
            ++open_failures_;
          }
          if (due(&last_error_log_, 10.0))
            NODELET_ERROR("camera capture %s: cannot open %s: %s; trying again every %.1f s",
                          name_.c_str(), dev.c_str(), why.c_str(), cfg_.reopen_interval);
          pause(cfg_.reopen_interval);
          continue;
        }
        std::ostringstream accepted;
        for (const auto& kv : source_->accepted()) accepted << " " << kv.first << "=" << kv.second;
        {
          std::lock_guard<std::mutex> lock(mutex_);
          if (ever_open) ++reopens_;
          state_ = "capturing";
          last_error_.clear();
          accepted_ = source_->accepted();
          differences_ = source_->differences();
          stats_->restart();
          // Drops are counted against the rate the device accepted.
          if (source_->nominalFps() > 0 && std::abs(source_->nominalFps() - stats_->nominalFps()) > 1e-6)
            stats_ = std::make_unique<CaptureStats>(source_->nominalFps());
        }
        NODELET_INFO("camera capture %s: %s %s; accepted:%s", name_.c_str(), dev.c_str(),
                     ever_open ? "open again" : "open", accepted.str().c_str());
        for (const std::string& d : source_->differences())
          NODELET_WARN("camera capture %s: %s: %s", name_.c_str(), dev.c_str(), d.c_str());
        ever_open = true;
      }
      CapturedFrame frame;
      const ReadResult r = source_->read(&frame, &why);
      if (r == ReadResult::kEnd) {
        {
          std::lock_guard<std::mutex> lock(mutex_);
          state_ = "ended";
        }
        NODELET_INFO("camera capture %s: %s ended (loop off): no more frames", name_.c_str(), dev.c_str());
        while (pause(3600.0)) {
        }
        break;
      }
      if (r == ReadResult::kFailed) {
        {
          std::lock_guard<std::mutex> lock(mutex_);
          state_ = "failed";
          last_error_ = why;
          ++failures_;
        }
        if (due(&last_error_log_, 10.0))
          NODELET_ERROR("camera capture %s: %s failed: %s; re-opening every %.1f s", name_.c_str(),
                        dev.c_str(), why.c_str(), cfg_.reopen_interval);
        source_->close();
        pause(cfg_.reopen_interval);
        continue;
      }
      publish(frame);
    }
  }

  void reject(const std::string& why) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++rejected_;
      last_reject_ = why;
    }
    if (due(&last_reject_log_, 10.0))
      NODELET_ERROR("camera capture %s: frame dropped: %s", name_.c_str(), why.c_str());
  }

  void publish(const CapturedFrame& frame) {
    const cv::Mat& in = frame.image;
    cv::Mat out;
    std::string encoding;
    const BayerPattern pattern = cfg_.bayerPattern();
    if (in.depth() != CV_8U) return reject("the device delivers more than 8 bits per channel");
    if (pattern != BayerPattern::kNone) {
      if (in.channels() != 1)
        return reject("bayer: " + cfg_.bayer + " needs one-channel raw data, the device delivers " +
                      std::to_string(in.channels()) + " channels (set fourcc to its raw Bayer "
                      "format, e.g. BA81, or bayer: none)");
      if (cfg_.half_resolution) {
        std::string error;
        if (!debayerHalfResolution(in, pattern, &out, &error)) return reject(error);
        encoding = "rgb8";
      } else {
        out = in;
        encoding = bayerEncoding(pattern);
      }
    } else if (in.channels() == 3) {
      out = in;
      encoding = "bgr8";
    } else if (in.channels() == 1) {
      out = in;
      encoding = "mono8";
    } else {
      return reject("unsupported image with " + std::to_string(in.channels()) + " channels");
    }
    if (have_info_ && (out.cols != static_cast<int>(info_.width) || out.rows != static_cast<int>(info_.height)))
      return reject("image " + std::to_string(out.cols) + "x" + std::to_string(out.rows) +
                    " does not match the calibration " + std::to_string(info_.width) + "x" +
                    std::to_string(info_.height) + " (" + cfg_.rig_file + cfg_.camera_info_file +
                    "); check width/height" +
                    (cfg_.half_resolution ? " (halved by half_resolution)" : ""));
    const ros::Time stamp(frame.stamp);
    auto image = boost::make_shared<sensor_msgs::Image>();
    toImageMsg(out, encoding, image.get());
    image->header.stamp = stamp;
    image->header.frame_id = frame_id_;
    image_pub_.publish(image);
    if (have_info_) {
      auto info = boost::make_shared<sensor_msgs::CameraInfo>(info_);
      info->header.stamp = stamp;
      info_pub_.publish(info);
    }
    std::lock_guard<std::mutex> lock(mutex_);
    stats_->add(frame.stamp);
    ++published_;
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!source_) {
      if (fatal_.empty())
        stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "starting");
      else
        stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "not started: " + fatal_);
      return;
    }
    const bool rejecting = rejected_growth_.grew(rejected_);
    const bool dropping = stats_->droppedInWindow() > 0;
    if (state_ == "unavailable" || state_ == "failed")
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR,
                   cfg_.device + " " + state_ + ": " + last_error_ + " (re-opening every " +
                       std::to_string(cfg_.reopen_interval) + " s)");
    else if (rejecting)
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "frames dropped: " + last_reject_);
    else if (state_ == "ended")
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "file ended (loop off)");
    else if (dropping)
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "frames missed (gaps > 1.5 periods)");
    else if (!differences_.empty())
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "device differs from the request: " + differences_.front());
    else
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK, state_);
    stat.add("device", cfg_.device);
    stat.add("source", source_->describe());
    stat.add("state", state_);
    stat.add("rate (Hz)", stats_->rate());
    stat.add("nominal rate (Hz)", stats_->nominalFps());
    stat.add("jitter (ms)", stats_->jitterMs());
    stat.add("mean interval (ms)", stats_->meanIntervalMs());
    stat.add("dropped frames (window)", stats_->droppedInWindow());
    stat.add("dropped frames (total)", stats_->droppedTotal());
    stat.add("frames published", published_);
    stat.add("frames rejected", rejected_);
    stat.add("reopens", reopens_);
    stat.add("failures", failures_);
    stat.add("open failures", open_failures_);
    stat.add("last error", last_error_);
    for (const auto& kv : accepted_) stat.add("accepted " + kv.first, kv.second);
    for (size_t i = 0; i < differences_.size(); ++i)
      stat.add("difference " + std::to_string(i + 1), differences_[i]);
  }

  CameraCaptureConfig cfg_;
  std::string name_, frame_id_;
  sensor_msgs::CameraInfo info_;
  bool have_info_ = false;
  std::unique_ptr<FrameSource> source_;  // used by the capture thread only (describe(): any)
  ros::Publisher image_pub_, info_pub_;
  std::unique_ptr<tabletop_common::PeriodicDiagnostics> diag_;
  ros::WallTime last_error_log_, last_reject_log_;  // capture thread only

  std::mutex mutex_;  // guards what follows (capture thread vs diagnostics)
  std::string fatal_, state_ = "opening", last_error_, last_reject_;
  std::unique_ptr<CaptureStats> stats_;
  std::vector<std::pair<std::string, std::string>> accepted_;
  std::vector<std::string> differences_;
  uint64_t published_ = 0, rejected_ = 0, reopens_ = 0, failures_ = 0, open_failures_ = 0;
  tabletop_common::GrowthMeter rejected_growth_;

  std::mutex stop_mutex_;
  std::condition_variable stop_cv_;
  std::atomic<bool> running_{false};
  std::thread thread_;  // last: joined in the destructor before anything above goes
};

}  // namespace tabletop_capture

PLUGINLIB_EXPORT_CLASS(tabletop_capture::CameraCaptureNodelet, nodelet::Nodelet)
