// Demo monitor: watches the pipeline on /tabletop, prints a live status line, and when the run
// ends writes a contact sheet of the camera views (with the ground truth projected) and a
// summary (frames, rate, end-to-end latency, per-stage times from /diagnostics).
//
// Parameters (private):
//   ~frames        frame sets to wait for before finishing (0 = until Ctrl-C)       [0]
//   ~idle_timeout  finish when no frame set arrived for this long after the first  [5.0 s]
//   ~start_timeout give up (exit code 1) if no frame set arrives within this        [60 s]
//   ~output_dir    where contact_sheet.png and summary.txt go                       [./output]
//   ~sheet_columns views per row of the contact sheet                               [4]
//   ~live_status_line  overwrite one status line (terminal) instead of a line every 5 s
//                      [stdout is a tty]
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <ros/ros.h>

#include <tabletop_msgs/MultiViewFrame.h>
#include <tabletop_msgs/TrackedTargets.h>

#include "tabletop_capture/ros/conversions.h"
#include "tabletop_capture/running_stats.h"

namespace tabletop_capture {

class DemoMonitor {
 public:
  DemoMonitor() : pnh_("~") {
    pnh_.param("frames", expected_, 0);
    pnh_.param("idle_timeout", idle_timeout_, 5.0);
    pnh_.param("start_timeout", start_timeout_, 60.0);
    pnh_.param("output_dir", output_dir_, std::string("output"));
    pnh_.param("sheet_columns", columns_, 4);
    // One self-overwriting status line on a terminal, a line every 5 s in logs. roslaunch
    // pipes our stdout, so the caller says which via ~live_status_line.
    pnh_.param("live_status_line", tty_, static_cast<bool>(isatty(fileno(stdout))));
    frames_sub_ = nh_.subscribe("frames", 4, &DemoMonitor::onFrame, this);
    truth_sub_ = nh_.subscribe("ground_truth/targets", 50, &DemoMonitor::onTruth, this);
    diag_sub_ = nh_.subscribe("/diagnostics", 50, &DemoMonitor::onDiagnostics, this);
    timer_ = nh_.createWallTimer(ros::WallDuration(0.5), &DemoMonitor::onTimer, this);
    start_ = ros::WallTime::now();
  }

  int exitCode() const { return exit_code_; }

 private:
  void onFrame(const tabletop_msgs::MultiViewFrame::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    const double latency_ms = (ros::Time::now() - msg->header.stamp).toSec() * 1e3;
    latency_ms_.add(latency_ms);
    if (received_ == 0) first_ = ros::WallTime::now();
    last_ = ros::WallTime::now();
    ++received_;
    // Keep the latest frame that shows the person (ground truth says a target is active) for
    // the contact sheet; fall back to the latest frame.
    auto it = truth_.find(msg->header.stamp);
    const bool person = it != truth_.end() && it->second;
    if (person || !sheet_person_) {
      sheet_ = msg;
      sheet_person_ = person;
    }
  }

  void onTruth(const tabletop_msgs::TrackedTargets::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    bool any = false;
    for (const auto& t : msg->targets) any = any || t.active;
    truth_[msg->header.stamp] = any;
    truth_msgs_[msg->header.stamp] = msg;
    while (truth_.size() > 200) {
      truth_.erase(truth_.begin());
      truth_msgs_.erase(truth_msgs_.begin());
    }
  }

  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    // Every stage reports its rate and times here (each later stage too).
    for (const auto& st : msg->status) {
      for (const auto& kv : st.values) stages_[st.name][kv.key] = kv.value;
    }
  }

  void onTimer(const ros::WallTimerEvent&) {
    std::unique_lock<std::mutex> lock(mutex_);
    const ros::WallTime now = ros::WallTime::now();
    const double elapsed = received_ ? (last_ - first_).toSec() : 0.0;
    const double rate = (received_ > 1 && elapsed > 0) ? (received_ - 1) / elapsed : 0.0;
    char line[256];
    std::snprintf(line, sizeof(line),
                  "[demo] frame sets %d%s | %.1f fps | latency %.1f ms (max %.1f) | %.0f s",
                  received_, expected_ ? ("/" + std::to_string(expected_)).c_str() : "", rate,
                  latency_ms_.mean(), latency_ms_.max(), (now - start_).toSec());
    if (tty_) {
      std::printf("\r%s   ", line);
      std::fflush(stdout);
    } else if ((now - last_print_).toSec() >= 5.0) {
      std::printf("%s\n", line);
      std::fflush(stdout);
      last_print_ = now;
    }
    bool done = false;
    if (received_ == 0 && (now - start_).toSec() > start_timeout_) {
      std::printf("\n[demo] ERROR: no frame set on %s within %.0f s: is the rig running?\n",
                  frames_sub_.getTopic().c_str(), start_timeout_);
      exit_code_ = 1;
      done = true;
    } else if (expected_ > 0 && received_ >= expected_) {
      done = true;
    } else if (received_ > 0 && (now - last_).toSec() > idle_timeout_) {
      std::printf("\n[demo] no frame set for %.0f s: the rig stopped\n", idle_timeout_);
      done = true;
    }
    if (done) {
      lock.unlock();
      finish();
      ros::shutdown();
    }
  }

 public:

  // Writes the summary and the contact sheet once (on the end condition or on Ctrl-C).
  void finish() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) return;
    finished_ = true;
    if (tty_) std::printf("\n");
    ::mkdir(output_dir_.c_str(), 0755);
    std::ostringstream s;
    const double elapsed = received_ ? (last_ - first_).toSec() : 0.0;
    const double rate = (received_ > 1 && elapsed > 0) ? (received_ - 1) / elapsed : 0.0;
    s << "==== tabletop hands demo summary ====\n";
    char buf[256];
    std::snprintf(buf, sizeof(buf), "frame sets received   %d in %.1f s (%.2f fps)\n", received_,
                  elapsed, rate);
    s << buf;
    std::snprintf(buf, sizeof(buf),
                  "end-to-end latency    mean %.1f ms, max %.1f ms (capture stamp -> monitor)\n",
                  latency_ms_.mean(), latency_ms_.max());
    s << buf;
    s << "per-stage figures (from /diagnostics):\n";
    for (const auto& st : stages_) {
      std::string fields;
      for (const auto& kv : st.second) {
        if (kv.first.find("(ms)") == std::string::npos && kv.first.find("(Hz)") == std::string::npos &&
            kv.first.find("dropped") == std::string::npos && kv.first.find("late") == std::string::npos &&
            kv.first.find("incomplete") == std::string::npos)
          continue;
        std::string v = kv.second;
        try {
          size_t used = 0;
          const double x = std::stod(v, &used);
          if (used == v.size() && x == std::floor(x) && std::abs(x) < 1e15)
            std::snprintf(buf, sizeof(buf), "%.0f", x);  // counters stay integers
          else
            std::snprintf(buf, sizeof(buf), "%.2f", x);
          v = buf;
        } catch (...) {
        }
        fields += (fields.empty() ? " " : ", ") + kv.first + " " + v;
      }
      if (!fields.empty()) s << "  " << st.first << ":" << fields << "\n";
    }
    if (sheet_) {
      const std::string path = output_dir_ + "/contact_sheet.png";
      if (writeContactSheet(*sheet_, path))
        s << "contact sheet         " << path << (sheet_person_ ? "" : " (no person in view)")
          << "\n";
    }
    const std::string text = s.str();
    std::printf("%s", text.c_str());
    std::ofstream(output_dir_ + "/summary.txt") << text;
    std::fflush(stdout);
  }

 private:
  bool writeContactSheet(const tabletop_msgs::MultiViewFrame& f, const std::string& path) {
    const size_t n = f.images.size();
    if (n == 0) return false;
    int cell_w = 0, cell_h = 0;
    for (const auto& im : f.images) {
      cell_w = std::max<int>(cell_w, im.width);
      cell_h = std::max<int>(cell_h, im.height);
    }
    const int cols = std::max(1, std::min<int>(columns_, n));
    const int rows = (n + cols - 1) / cols;
    cv::Mat sheet(rows * cell_h, cols * cell_w, CV_8UC3, cv::Scalar(40, 40, 40));
    tabletop_msgs::TrackedTargets::ConstPtr truth;
    auto it = truth_msgs_.find(f.header.stamp);
    if (it != truth_msgs_.end()) truth = it->second;
    for (size_t i = 0; i < n; ++i) {
      const auto& im = f.images[i];
      if (im.encoding != "rgb8" || im.data.size() < size_t(im.step) * im.height) continue;
      cv::Mat rgb(im.height, im.width, CV_8UC3, const_cast<uint8_t*>(im.data.data()), im.step);
      cv::Mat cell = sheet(cv::Rect((i % cols) * cell_w, (i / cols) * cell_h, im.width, im.height));
      cv::cvtColor(rgb, cell, cv::COLOR_RGB2BGR);
      const std::string name = i < f.camera_names.size() ? f.camera_names[i] : std::to_string(i);
      cv::putText(cell, name, cv::Point(5, 15), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                  cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
      // Ground truth projected with the frame's own calibration: a visual check that images,
      // camera_info and tf agree (crosses land on the hands and the head).
      CameraModel cam;
      if (truth && i < f.camera_infos.size() && i < f.camera_poses.size() &&
          fromCameraInfo(f.camera_infos[i], &cam, nullptr) &&
          fromTransform(f.camera_poses[i], &cam.world_T_camera)) {
        for (const auto& t : truth->targets) {
          if (!t.active) continue;
          Eigen::Vector2d px;
          if (!cam.projectWorld(Eigen::Vector3d(t.position.x, t.position.y, t.position.z), &px))
            continue;
          const cv::Scalar colour = t.type == tabletop_msgs::TrackedTarget::HEAD
                                        ? cv::Scalar(255, 200, 0)
                                        : cv::Scalar(0, 255, 0);
          cv::drawMarker(cell, cv::Point(std::lround(px.x()), std::lround(px.y())), colour,
                         cv::MARKER_CROSS, 10, 1);
        }
      }
    }
    return cv::imwrite(path, sheet);
  }

  ros::NodeHandle nh_, pnh_;
  ros::Subscriber frames_sub_, truth_sub_, diag_sub_;
  ros::WallTimer timer_;
  std::mutex mutex_;
  int expected_ = 0, columns_ = 4, received_ = 0, exit_code_ = 0;
  double idle_timeout_ = 5.0, start_timeout_ = 60.0;
  std::string output_dir_;
  bool tty_ = false;
  ros::WallTime start_, first_, last_, last_print_;
  RunningStats latency_ms_;
  tabletop_msgs::MultiViewFrame::ConstPtr sheet_;
  bool sheet_person_ = false, finished_ = false;
  std::map<ros::Time, bool> truth_;
  std::map<ros::Time, tabletop_msgs::TrackedTargets::ConstPtr> truth_msgs_;
  std::map<std::string, std::map<std::string, std::string>> stages_;
};

}  // namespace tabletop_capture

namespace {
volatile std::sig_atomic_t g_interrupted = 0;
void onSigint(int) { g_interrupted = 1; }
}  // namespace

int main(int argc, char** argv) {
  // Own SIGINT handling: roslaunch stops the monitor with SIGINT when the bag or the rig ends,
  // and the summary must still be written.
  ros::init(argc, argv, "demo_monitor", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, onSigint);
  tabletop_capture::DemoMonitor monitor;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  while (ros::ok() && !g_interrupted) ros::WallDuration(0.05).sleep();
  monitor.finish();
  ros::shutdown();
  return monitor.exitCode();
}
