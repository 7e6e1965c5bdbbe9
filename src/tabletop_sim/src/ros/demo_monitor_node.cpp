// Demo monitor: watches the pipeline on /tabletop, prints a live status line, and when the run
// ends writes a contact sheet of the camera views (with the ground truth projected) and a
// summary (frames, rate, end-to-end latency, per-stage times from /diagnostics). When the pSfS
// stage runs it also scores psfs/body_volume and psfs/skin_volume against the simulated rig's
// oracle volumes (ground_truth/*_volume, same stamps) and writes volumes.png: the latest
// reconstruction beside the truth as top, front and side projections; body/volume (the body
// tracker's body volume with its model as a prior) is scored the same way. When a hand tracker
// publishes hands/targets, its targets are scored against ground_truth/targets (same stamps)
// with TrackingEvaluator: errors, losses, identity switches in the summary and
// tracking_error.png. When the body tracker publishes body/pose, its head, hands, elbows and
// shoulders are scored against ground_truth/body_pose, and the contact sheet shows its stick
// skeleton and the outlines of its silhouette masks (cam<i>/body_mask) over each view.
//
// Parameters (private):
//   ~frames        frame sets to wait for before finishing (0 = until Ctrl-C)       [0]
//   ~hold_file     while this file exists, do not finish after ~frames (at most 120 s more;
//                  demo.sh --browser keeps the room alive until its browser check is done) [""]
//   ~idle_timeout  finish when no frame set arrived for this long after the first  [5.0 s]
//   ~start_timeout give up (exit code 1) if no frame set arrives within this        [60 s]
//   ~output_dir    where contact_sheet.png and summary.txt go                       [./output]
//   ~sheet_columns views per row of the contact sheet                               [4]
//   ~live_status_line  overwrite one status line (terminal) instead of a line every 5 s
//                      [stdout is a tty]
//   ~volume_threshold  a voxel is "in the volume" above this probability (the fusion's t)  [0.75]
//   ~digests       write digests.txt: per frame set what pSfS did with it (psfs/processed),
//                  the CRC-32 of the body, skin and hand volumes and the tracked targets, to
//                  compare two runs of one bag; when the bag is played again within one run
//                  (psfs/processed stamps go back), each further pass goes to
//                  digests_play<k>.txt (k = 2, 3, ...)                                 [false]
//   ~image_transport  plugin the body tracker's silhouettes (cam<i>/body_mask) come through [raw]
//
// The summary also follows a frame set through the stages (sets in and out of each, from
// their /diagnostics counters), the one place that drops them (pSfS), load shedding, and which
// stage is the bottleneck (the largest time per set).
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <map>
#include <mutex>
#include <sstream>

#include <boost/crc.hpp>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <image_transport/image_transport.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <ros/ros.h>
#include <std_msgs/Header.h>

#include <sensor_msgs/Image.h>
#include <tabletop_msgs/BodyPose.h>
#include <tabletop_msgs/HandVolumes.h>
#include <tabletop_msgs/MultiViewFrame.h>
#include <tabletop_msgs/TrackedTargets.h>
#include <tabletop_msgs/VoxelVolume.h>

#include "tabletop_capture/ros/conversions.h"
#include "tabletop_sim/ros/sim_truth_msgs.h"
#include "tabletop_common/running_stats.h"
#include "tabletop_sim/tracking_evaluator.h"

namespace tabletop_sim {

class DemoMonitor {
 public:
  DemoMonitor() : pnh_("~") {
    pnh_.param("frames", expected_, 0);
    pnh_.param("hold_file", hold_file_, std::string());
    pnh_.param("idle_timeout", idle_timeout_, 5.0);
    pnh_.param("start_timeout", start_timeout_, 60.0);
    pnh_.param("output_dir", output_dir_, std::string("output"));
    pnh_.param("sheet_columns", columns_, 4);
    // One self-overwriting status line on a terminal, a line every 5 s in logs. roslaunch
    // pipes our stdout, so the caller says which via ~live_status_line.
    pnh_.param("live_status_line", tty_, static_cast<bool>(isatty(fileno(stdout))));
    double t = 0.75;
    pnh_.param("volume_threshold", t, t);
    threshold_byte_ = static_cast<uint8_t>(std::max(0.0, std::min(255.0, std::floor(255.0 * t))));
    pnh_.param("digests", digests_, false);
    if (digests_) {
      boost::function<void(const tabletop_msgs::HandVolumes::ConstPtr&)> on_hands =
          [this](const tabletop_msgs::HandVolumes::ConstPtr& m) {
            std::string d;
            for (size_t i = 0; i < m->volumes.size(); ++i)
              d += " " + std::to_string(i < m->target_ids.size() ? m->target_ids[i] : 0) + ":" +
                   crcOf(m->volumes[i].data);
            std::lock_guard<std::mutex> lock(mutex_);
            digest_[{pass_, m->header.stamp}]["hands"] = d;
          };
      hands_sub_ = nh_.subscribe<tabletop_msgs::HandVolumes>("psfs/hand_volumes", 300, on_hands);
      boost::function<void(const std_msgs::Header::ConstPtr&)> on_processed =
          [this](const std_msgs::Header::ConstPtr& h) {
            std::lock_guard<std::mutex> lock(mutex_);
            if (!last_processed_.isZero() && h->stamp < last_processed_) ++pass_;
            last_processed_ = h->stamp;
            digest_[{pass_, h->stamp}]["psfs"] = h->frame_id;
          };
      processed_sub_ = nh_.subscribe<std_msgs::Header>("psfs/processed", 1000, on_processed);
    }
    for (int k = 0; k < kVolumeKinds; ++k) {
      const std::string kind = k == 1 ? "skin" : "body";
      boost::function<void(const tabletop_msgs::VoxelVolume::ConstPtr&)> on_rec =
          [this, k](const tabletop_msgs::VoxelVolume::ConstPtr& m) { onVolume(k, false, m); };
      boost::function<void(const tabletop_msgs::VoxelVolume::ConstPtr&)> on_truth =
          [this, k](const tabletop_msgs::VoxelVolume::ConstPtr& m) { onVolume(k, true, m); };
      volume_subs_.push_back(nh_.subscribe<tabletop_msgs::VoxelVolume>(
          k == 2 ? std::string("body/volume") : "psfs/" + kind + "_volume", 300, on_rec));
      volume_subs_.push_back(
          nh_.subscribe<tabletop_msgs::VoxelVolume>("ground_truth/" + kind + "_volume", 8, on_truth));
    }
    if (digests_) {
      // The synchroniser holds the first sets until its `frames` subscribers are there, and we
      // are one of them: listen on `frames` only once psfs/processed is connected, so that no
      // digest of the first sets is lost to a connection still being made.
      const ros::WallTime asked = ros::WallTime::now();
      boost::function<void(const ros::WallTimerEvent&)> when_connected = [this, asked](const ros::WallTimerEvent&) {
        const bool connected = processed_sub_.getNumPublishers() > 0 && hands_sub_.getNumPublishers() > 0;
        if (!connected && (ros::WallTime::now() - asked).toSec() < 10.0) return;  // no pSfS: go on
        frames_sub_ = nh_.subscribe("frames", 10, &DemoMonitor::onFrame, this);
        subscribe_timer_.stop();
      };
      subscribe_timer_ = nh_.createWallTimer(ros::WallDuration(0.02), when_connected);
    } else {
      frames_sub_ = nh_.subscribe("frames", 10, &DemoMonitor::onFrame, this);
    }
    truth_sub_ = nh_.subscribe("ground_truth/targets", 50, &DemoMonitor::onTruth, this);
    tracked_sub_ = nh_.subscribe("hands/targets", 300, &DemoMonitor::onTracked, this);
    body_sub_ = nh_.subscribe("body/pose", 300, &DemoMonitor::onBodyPose, this);
    body_truth_sub_ = nh_.subscribe("ground_truth/body_pose", 50, &DemoMonitor::onBodyTruth, this);
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
    if (mask_subs_.empty() && body_sub_.getNumPublishers() > 0) {
      // The body tracker draws its silhouettes only while someone listens: the sheet's overlay.
      for (size_t i = 0; i < msg->camera_names.size(); ++i) {
        boost::function<void(const sensor_msgs::Image::ConstPtr&)> cb =
            [this, i](const sensor_msgs::Image::ConstPtr& m) { onBodyMask(i, m); };
        // image_transport: ~image_transport (default raw) names the plugin.
        image_transport::ImageTransport it(nh_);
        try {
          mask_subs_.push_back(it.subscribe(msg->camera_names[i] + "/body_mask", 5, cb, ros::VoidPtr(),
                                            image_transport::TransportHints("raw", ros::TransportHints(), pnh_)));
        } catch (const image_transport::TransportLoadException& e) {
          ROS_ERROR_ONCE("demo monitor: no silhouette overlay: %s", e.what());
        }
      }
    }
    // Keep the latest frame that shows the person (ground truth says a target is active) for
    // the contact sheet; fall back to the latest frame.
    auto it = truth_.find(msg->header.stamp);
    const bool person = it != truth_.end() && it->second;
    if (person || !sheet_person_) {
      sheet_ = msg;
      sheet_person_ = person;
    }
  }

  static std::string crcOf(const std::vector<uint8_t>& data) {
    boost::crc_32_type crc;
    crc.process_bytes(data.data(), data.size());
    char buf[16];
    std::snprintf(buf, sizeof(buf), "%08x", crc.checksum());
    return buf;
  }

  // Tracker output and truth are paired by stamp, whichever arrives first.
  void onTracked(const tabletop_msgs::TrackedTargets::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (digests_) {
      std::string d;
      char buf[128];
      for (const auto& t : msg->targets) {
        std::snprintf(buf, sizeof(buf), " %u%s:%.6f,%.6f,%.6f", t.id, t.active ? "" : "(off)",
                      t.position.x, t.position.y, t.position.z);
        d += buf;
      }
      digest_[{pass_, msg->header.stamp}]["targets"] = d;
    }
    tracked_[msg->header.stamp] = msg;
    while (tracked_.size() > 100) tracked_.erase(tracked_.begin());
    scoreTracking(msg->header.stamp);
  }

  void scoreTracking(const ros::Time& stamp) {
    auto t = tracked_.find(stamp);
    auto g = truth_msgs_.find(stamp);
    if (t == tracked_.end() || g == truth_msgs_.end()) return;
    tracking_.add(stamp.toSec(), toTrackedPoints(*t->second), toTruthPoints(*g->second));
    scored_tracked_[stamp] = t->second;  // for the contact sheet
    while (scored_tracked_.size() > 100) scored_tracked_.erase(scored_tracked_.begin());
    tracked_.erase(t);
  }

  // Body tracker output and truth, paired by stamp.
  void onBodyPose(const tabletop_msgs::BodyPose::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    body_tracked_[msg->header.stamp] = msg;
    while (body_tracked_.size() > 100) body_tracked_.erase(body_tracked_.begin());
    scoreBody(msg->header.stamp);
  }
  void onBodyTruth(const tabletop_msgs::BodyPose::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    body_truth_[msg->header.stamp] = msg;
    while (body_truth_.size() > 200) body_truth_.erase(body_truth_.begin());
    scoreBody(msg->header.stamp);
  }
  void scoreBody(const ros::Time& stamp) {
    auto t = body_tracked_.find(stamp);
    auto g = body_truth_.find(stamp);
    if (t == body_tracked_.end() || g == body_truth_.end()) return;
    scored_body_[stamp] = t->second;
    while (scored_body_.size() > 100) scored_body_.erase(scored_body_.begin());
    const auto& a = *t->second;
    const auto& b = *g->second;
    if (b.valid) {
      ++body_person_frames_;
      if (a.valid) {
        auto d = [](const geometry_msgs::Point& p, const geometry_msgs::Point& q) {
          return 1e3 * std::sqrt((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) + (p.z - q.z) * (p.z - q.z));
        };
        body_err_[0].add(d(a.head, b.head));
        body_err_[1].add(0.5 * (d(a.left_hand, b.left_hand) + d(a.right_hand, b.right_hand)));
        body_err_[2].add(0.5 * (d(a.left_elbow, b.left_elbow) + d(a.right_elbow, b.right_elbow)));
        body_err_[3].add(0.5 * (d(a.left_shoulder, b.left_shoulder) + d(a.right_shoulder, b.right_shoulder)));
      }
    } else if (a.valid) {
      ++body_false_frames_;
    }
    body_tracked_.erase(t);
  }
  void onBodyMask(size_t camera, const sensor_msgs::Image::ConstPtr& m) {
    if (m->encoding != "mono8" || m->data.size() < size_t(m->step) * m->height) return;
    std::lock_guard<std::mutex> lock(mutex_);
    auto& masks = body_masks_[camera];
    masks[m->header.stamp] = m;
    while (masks.size() > 30) masks.erase(masks.begin());
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
    scoreTracking(msg->header.stamp);
  }

  // Pairs reconstruction and truth by stamp (either may arrive first) and scores the pair.
  void onVolume(int kind, bool truth, const tabletop_msgs::VoxelVolume::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto& mine = truth ? truth_volumes_[kind] : recon_volumes_[kind];
    auto& other = truth ? recon_volumes_[kind] : truth_volumes_[kind];
    if (!truth) ++volumes_received_[kind];
    if (!truth && digests_ && kind < 2)
      digest_[{pass_, msg->header.stamp}][kind == 0 ? "body" : "skin"] = crcOf(msg->data);
    auto it = other.find(msg->header.stamp);
    if (it == other.end()) {
      mine[msg->header.stamp] = msg;
      while (mine.size() > 60) mine.erase(mine.begin());
      return;
    }
    const auto rec = truth ? it->second : msg;
    const auto tru = truth ? msg : it->second;
    other.erase(it);
    if (rec->size_x != tru->size_x || rec->size_y != tru->size_y || rec->size_z != tru->size_z ||
        std::abs(rec->voxel_size - tru->voxel_size) > 1e-9 || rec->data.size() != tru->data.size()) {
      grid_mismatch_ = true;
      return;
    }
    size_t both = 0, either = 0;
    for (size_t i = 0; i < rec->data.size(); ++i) {
      const bool a = rec->data[i] > threshold_byte_, b = tru->data[i] > 127;
      both += a && b;
      either += a || b;
    }
    if (either == 0) return;  // empty scene: nothing to score
    iou_[kind].add(double(both) / either);
    scored_[kind] = {rec, tru};
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
      // The last sets are still in the later stages: give them a moment.
      if (all_received_.isZero()) all_received_ = now;
      const double since = (now - all_received_).toSec();
      const bool held = !hold_file_.empty() && ::access(hold_file_.c_str(), F_OK) == 0 && since < 120;
      if (held && !hold_announced_) {
        hold_announced_ = true;
        std::printf("\n[demo] %d frame sets done; going on while %s exists (browser check)\n",
                    received_, hold_file_.c_str());
      }
      done = since >= 1.5 && !held;
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
            kv.first.find("incomplete") == std::string::npos &&
            kv.first.find("rejected") == std::string::npos &&
            kv.first.find("(%)") == std::string::npos && kv.first.find("timeouts") == std::string::npos &&
            kv.first.find("switched off") == std::string::npos)
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
    s << pipelineSummary();
    if (body_person_frames_ > 0 || body_false_frames_ > 0) {
      std::snprintf(buf, sizeof(buf),
                    "body tracker (PAPF)   tracked %llu of %llu frames with the person, %llu without; "
                    "mean error head %.1f mm, hands %.1f mm, elbows %.1f mm, shoulders %.1f mm\n",
                    static_cast<unsigned long long>(body_err_[0].count()),
                    static_cast<unsigned long long>(body_person_frames_),
                    static_cast<unsigned long long>(body_false_frames_), body_err_[0].mean(),
                    body_err_[1].mean(), body_err_[2].mean(), body_err_[3].mean());
      s << buf;
    }
    for (int k = 0; k < kVolumeKinds; ++k) {
      static const char* const kNames[kVolumeKinds] = {"body volume", "skin volume", "body/volume"};
      if (iou_[k].count() > 0) {
        std::snprintf(buf, sizeof(buf),
                      "%s IoU        mean %.3f, min %.3f over %llu frames (vs the oracle, p > %.2f)%s\n",
                      kNames[k], iou_[k].mean(), iou_[k].min(),
                      static_cast<unsigned long long>(iou_[k].count()), threshold_byte_ / 255.0,
                      k == 2 ? "; the body tracker's model as a prior on the body volume" : "");
        s << buf;
      } else if (volumes_received_[k] > 0) {
        static const char* const kCounted[kVolumeKinds] = {"body volumes          ", "skin volumes          ",
                                                           "body/volume volumes   "};
        s << kCounted[k] << volumes_received_[k]
          << (grid_mismatch_ ? " (not scored: grid differs from the oracle's)\n"
                             : " (not scored: no oracle volumes; simulated rig only)\n");
      }
    }
    if (scored_[0].first) {
      const std::string path = output_dir_ + "/volumes.png";
      if (writeVolumeImage(path)) s << "volume image          " << path << "\n";
    }
    if (tracking_.frames() > 0) {
      s << "hand/head tracking vs ground truth (" << tracking_.frames() << " frames):\n"
        << tracking_.summary();
      const std::string path = output_dir_ + "/tracking_error.png";
      if (tracking_.writePlot(path)) s << "tracking error plot   " << path << "\n";
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
    if (digests_) {
      std::ofstream out;
      int open_pass = -1;
      for (const auto& d : digest_) {
        if (d.first.first != open_pass) {
          open_pass = d.first.first;
          out.close();
          out.open(output_dir_ + (open_pass == 0 ? std::string("/digests.txt")
                                                 : "/digests_play" + std::to_string(open_pass + 1) + ".txt"));
        }
        const ros::Time& stamp = d.first.second;
        out << stamp.sec << "." << std::setw(9) << std::setfill('0') << stamp.nsec
            << std::setfill(' ');
        for (const char* k : {"psfs", "body", "skin", "targets", "hands"}) {
          auto it = d.second.find(k);
          if (it != d.second.end()) out << " " << k << " " << it->second;
        }
        out << "\n";
      }
    }
    std::fflush(stdout);
  }

  // The last /diagnostics values of the stage whose status name ends with `task`.
  // Stages of this monitor's own rig (namespace) first: a second participant's pipeline
  // reports the same tasks under its namespace.
  const std::map<std::string, std::string>* stage(const std::string& task) const {
    std::string own = nh_.getNamespace();
    while (!own.empty() && own.front() == '/') own.erase(own.begin());
    const std::map<std::string, std::string>* any = nullptr;
    for (const auto& st : stages_)
      if (st.first.size() >= task.size() &&
          st.first.compare(st.first.size() - task.size(), task.size(), task) == 0) {
        if (!own.empty() && st.first.compare(0, own.size() + 1, own + "/") == 0) return &st.second;
        if (!any) any = &st.second;
      }
    return any;
  }
  static double number(const std::map<std::string, std::string>* st, const std::string& key) {
    if (!st) return std::nan("");
    auto it = st->find(key);
    if (it == st->end()) return std::nan("");
    try {
      return std::stod(it->second);
    } catch (...) {
      return std::nan("");
    }
  }

  // Sets through each stage, the drop point, shedding and the bottleneck (mutex_ held).
  std::string pipelineSummary() const {
    const auto* rig = stage("simulated rig");
    const auto* sync = stage("frame synchronizer");
    const auto* psfs = stage("psfs reconstruction");
    const auto* mpf = stage("mpf hand tracking");
    const auto* papf = stage("papf body tracking");
    const auto* mesher = stage("hand meshing");
    std::ostringstream s;
    char buf[512];
    s << "pipeline, frame sets per stage:";
    if (rig) {
      const double published = number(rig, "frames published"), nominal = number(rig, "nominal rate (Hz)");
      const bool paced = rig->count("lockstep wait mean (ms)") > 0;
      std::snprintf(buf, sizeof(buf), " rig %.0f", published);
      s << buf;
      if (paced && received_ > 1 && (last_ - first_).toSec() > 0) {
        std::snprintf(buf, sizeof(buf), " (paced by the pipeline: %.1f of %.0f fps)",
                      (received_ - 1) / (last_ - first_).toSec(), nominal);
        s << buf;
      }
      s << " ->";
    }
    if (sync) {
      std::snprintf(buf, sizeof(buf), " synchroniser %.0f ->", number(sync, "sets published"));
      s << buf;
    }
    if (psfs) {
      const double in = number(psfs, "frame sets received"), dropped = number(psfs, "frame sets dropped (pipeline busy)");
      std::snprintf(buf, sizeof(buf), " pSfS %.0f in, %.0f dropped (%.1f %%), %.0f reconstructed",
                    in, dropped, in > 0 ? 100.0 * dropped / in : 0.0,
                    number(psfs, "frame sets reconstructed"));
      s << buf;
    }
    if (mpf) {
      std::snprintf(buf, sizeof(buf), " -> MPF %.0f", number(mpf, "frames"));
      s << buf;
    }
    if (mesher) {
      std::snprintf(buf, sizeof(buf), " -> hand meshes for %.0f sets", number(mesher, "frames"));
      s << buf;
    }
    if (papf) {
      std::snprintf(buf, sizeof(buf), "; pSfS -> PAPF %.0f", number(papf, "frames"));
      s << buf;
    }
    s << "\n";
    if (psfs && psfs->count("load shedding"))
      s << "load shedding          " << psfs->at("load shedding") << ", hand volume sets shed "
        << (psfs->count("hand volume sets shed") ? psfs->at("hand volume sets shed") : "0") << "\n";
    // Bottleneck: the stage with the largest time per frame set.
    std::vector<std::pair<double, std::string>> per_set = {
        {number(rig, "render time mean (ms)"), "simulated rig rendering"},
        {number(psfs, "total (ms)"), "pSfS reconstruction"},
        {number(mpf, "mpf total (ms)"), "MPF tracking"},
        {number(papf, "papf total (ms)"), "PAPF body tracking"},
        {2 * number(mesher, "meshing per hand (ms)"), "hand meshing (2 hands)"}};
    std::string list;
    double worst = -1;
    std::string worst_name;
    for (const auto& p : per_set) {
      if (!std::isfinite(p.first)) continue;
      std::snprintf(buf, sizeof(buf), "%s%s %.1f ms", list.empty() ? "" : ", ", p.second.c_str(), p.first);
      list += buf;
      if (p.first > worst) worst = p.first, worst_name = p.second;
    }
    if (!worst_name.empty()) s << "bottleneck             " << worst_name << " (per set: " << list << ")\n";
    return s.str();
  }

 private:
  // Max projections of a volume along one axis (0 = x, 1 = y, 2 = z) into a BGR panel, `scale`
  // pixels per voxel, world z up: body voxels grey, skin voxels orange on top.
  cv::Mat projection(const tabletop_msgs::VoxelVolume& body, const tabletop_msgs::VoxelVolume* skin,
                     int axis, uint8_t body_t, uint8_t skin_t, int scale) const {
    const int n[3] = {int(body.size_x), int(body.size_y), int(body.size_z)};
    const int u_axis = axis == 0 ? 1 : 0, v_axis = axis == 2 ? 1 : 2;
    cv::Mat panel(n[v_axis] * scale, n[u_axis] * scale, CV_8UC3, cv::Scalar(30, 30, 30));
    auto index = [&](int x, int y, int z) { return size_t(x) + size_t(n[0]) * (size_t(y) + size_t(n[1]) * z); };
    for (int v = 0; v < n[v_axis]; ++v)
      for (int u = 0; u < n[u_axis]; ++u) {
        int depth_body = 0, depth_skin = 0;
        for (int w = 0; w < n[axis]; ++w) {
          int c[3];
          c[axis] = w;
          c[u_axis] = u;
          c[v_axis] = v;
          const size_t i = index(c[0], c[1], c[2]);
          depth_body += body.data[i] > body_t;
          if (skin && skin->data.size() == body.data.size()) depth_skin += skin->data[i] > skin_t;
        }
        cv::Scalar colour;
        if (depth_skin > 0)
          colour = cv::Scalar(60, 140, 255);
        else if (depth_body > 0)
          colour = cv::Scalar::all(std::min(255, 110 + 8 * depth_body));
        else
          continue;
        // Image rows go down; world z (or y in the top view) goes up.
        const int row = (n[v_axis] - 1 - v) * scale;
        cv::rectangle(panel, cv::Rect(u * scale, row, scale, scale), colour, cv::FILLED);
      }
    return panel;
  }

  bool writeVolumeImage(const std::string& path) const {
    const int scale = 4;
    std::vector<cv::Mat> rows;
    for (int truth = 0; truth < 2; ++truth) {
      const auto& body = truth ? scored_[0].second : scored_[0].first;
      const tabletop_msgs::VoxelVolume* skin = nullptr;
      if (scored_[1].first && scored_[1].first->header.stamp == body->header.stamp)
        skin = (truth ? scored_[1].second : scored_[1].first).get();
      const uint8_t bt = truth ? 127 : threshold_byte_;
      std::vector<cv::Mat> panels = {projection(*body, skin, 2, bt, bt, scale),
                                     projection(*body, skin, 1, bt, bt, scale),
                                     projection(*body, skin, 0, bt, bt, scale)};
      int h = 0, w = 0;
      for (const auto& p : panels) {
        h = std::max(h, p.rows);
        w += p.cols + 8;
      }
      cv::Mat row(h + 22, w + 8, CV_8UC3, cv::Scalar(0, 0, 0));
      int x = 8;
      const char* names[3] = {"top (x right, y up)", "front (x right, z up)", "side (y right, z up)"};
      for (int i = 0; i < 3; ++i) {
        panels[i].copyTo(row(cv::Rect(x, 22, panels[i].cols, panels[i].rows)));
        cv::putText(row, std::string(truth ? "oracle: " : "pSfS: ") + names[i], cv::Point(x, 16),
                    cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
        x += panels[i].cols + 8;
      }
      rows.push_back(row);
    }
    cv::Mat out;
    cv::vconcat(rows, out);
    return cv::imwrite(path, out);
  }

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
    tabletop_msgs::TrackedTargets::ConstPtr truth, tracked;
    auto it = truth_msgs_.find(f.header.stamp);
    if (it != truth_msgs_.end()) truth = it->second;
    auto tr = scored_tracked_.find(f.header.stamp);
    if (tr != scored_tracked_.end()) tracked = tr->second;
    tabletop_msgs::BodyPose::ConstPtr body;
    auto bp = scored_body_.find(f.header.stamp);
    if (bp != scored_body_.end()) body = bp->second;
    for (size_t i = 0; i < n; ++i) {
      const auto& im = f.images[i];
      // (A camera missing from a degraded set has an empty image: its cell stays grey.)
      if (im.encoding != "rgb8" || im.width == 0 || im.height == 0 ||
          im.data.size() < size_t(im.step) * im.height)
        continue;
      cv::Mat rgb(im.height, im.width, CV_8UC3, const_cast<uint8_t*>(im.data.data()), im.step);
      cv::Mat cell = sheet(cv::Rect((i % cols) * cell_w, (i / cols) * cell_h, im.width, im.height));
      cv::cvtColor(rgb, cell, cv::COLOR_RGB2BGR);
      const std::string name = i < f.camera_names.size() ? f.camera_names[i] : std::to_string(i);
      cv::putText(cell, name, cv::Point(5, 15), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                  cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
      // Ground truth projected with the frame's own calibration as crosses (a visual check that
      // images, camera_info and tf agree: they land on the hands and the head), the tracker's
      // targets as circles.
      tabletop_capture::CameraModel cam;
      if (i < f.camera_infos.size() && i < f.camera_poses.size() &&
          tabletop_capture::fromCameraInfo(f.camera_infos[i], &cam, nullptr) &&
          tabletop_capture::fromTransform(f.camera_poses[i], &cam.world_T_camera)) {
        auto draw = [&](const tabletop_msgs::TrackedTargets::ConstPtr& targets, bool is_truth) {
          if (!targets) return;
          for (const auto& t : targets->targets) {
            Eigen::Vector2d px;
            if (!t.active ||
                !cam.projectWorld(Eigen::Vector3d(t.position.x, t.position.y, t.position.z), &px))
              continue;
            const bool head = t.type == tabletop_msgs::TrackedTarget::HEAD;
            const cv::Point at(std::lround(px.x()), std::lround(px.y()));
            if (is_truth)
              cv::drawMarker(cell, at, head ? cv::Scalar(255, 200, 0) : cv::Scalar(0, 255, 0),
                             cv::MARKER_CROSS, 10, 1);
            else
              cv::circle(cell, at, 7, head ? cv::Scalar(255, 0, 255) : cv::Scalar(0, 140, 255), 1,
                         cv::LINE_AA);
          }
        };
        draw(truth, true);
        draw(tracked, false);
        // The body tracker: its silhouette outlines (the masks it publishes for the background
        // update) and its stick skeleton, both of this frame set.
        auto mk = body_masks_.find(i);
        if (mk != body_masks_.end()) {
          auto m = mk->second.find(f.header.stamp);
          if (m != mk->second.end() && m->second->width == im.width && m->second->height == im.height) {
            cv::Mat mask(m->second->height, m->second->width, CV_8UC1,
                         const_cast<uint8_t*>(m->second->data.data()), m->second->step);
            std::vector<std::vector<cv::Point>> contours;
            cv::findContours(mask.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
            cv::drawContours(cell, contours, -1, cv::Scalar(0, 220, 255), 1, cv::LINE_AA);
          }
        }
        if (body && body->valid) {
          auto px = [&](const geometry_msgs::Point& p, cv::Point* out) {
            Eigen::Vector2d q;
            if (!cam.projectWorld(Eigen::Vector3d(p.x, p.y, p.z), &q)) return false;
            *out = cv::Point(std::lround(q.x()), std::lround(q.y()));
            return true;
          };
          auto bone = [&](const geometry_msgs::Point& a, const geometry_msgs::Point& b) {
            cv::Point pa, pb;
            if (px(a, &pa) && px(b, &pb)) cv::line(cell, pa, pb, cv::Scalar(255, 255, 0), 2, cv::LINE_AA);
          };
          geometry_msgs::Point neck;
          neck.x = 0.5 * (body->left_shoulder.x + body->right_shoulder.x);
          neck.y = 0.5 * (body->left_shoulder.y + body->right_shoulder.y);
          neck.z = 0.5 * (body->left_shoulder.z + body->right_shoulder.z);
          bone(neck, body->head);
          bone(body->left_shoulder, body->right_shoulder);
          bone(body->left_shoulder, body->left_elbow);
          bone(body->left_elbow, body->left_wrist);
          bone(body->left_wrist, body->left_hand);
          bone(body->right_shoulder, body->right_elbow);
          bone(body->right_elbow, body->right_wrist);
          bone(body->right_wrist, body->right_hand);
        }
      }
    }
    cv::putText(sheet, body ? "+ ground truth   o tracked   cyan: body skeleton, yellow: body model outline"
                            : "+ ground truth   o tracked", cv::Point(5, sheet.rows - 6),
                cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    return cv::imwrite(path, sheet);
  }

  ros::NodeHandle nh_, pnh_;
  ros::WallTimer subscribe_timer_;
  ros::Subscriber frames_sub_, truth_sub_, diag_sub_, tracked_sub_, hands_sub_, processed_sub_;
  ros::Subscriber body_sub_, body_truth_sub_;
  std::vector<image_transport::Subscriber> mask_subs_;
  std::map<ros::Time, tabletop_msgs::BodyPose::ConstPtr> body_tracked_, body_truth_, scored_body_;
  std::map<size_t, std::map<ros::Time, sensor_msgs::Image::ConstPtr>> body_masks_;
  tabletop_common::RunningStats body_err_[4];  // head, hands, elbows, shoulders (mm)
  uint64_t body_person_frames_ = 0, body_false_frames_ = 0;
  bool digests_ = false;
  // Keyed by (pass over the bag, stamp): a bag played twice in one run has the same stamps twice.
  std::map<std::pair<int, ros::Time>, std::map<std::string, std::string>> digest_;
  int pass_ = 0;              // under mutex_: incremented when psfs/processed stamps go back
  ros::Time last_processed_;  // under mutex_
  std::map<ros::Time, tabletop_msgs::TrackedTargets::ConstPtr> tracked_, scored_tracked_;
  TrackingEvaluator tracking_;
  ros::WallTimer timer_;
  std::mutex mutex_;
  int expected_ = 0, columns_ = 4, received_ = 0, exit_code_ = 0;
  double idle_timeout_ = 5.0, start_timeout_ = 60.0;
  std::string output_dir_;
  bool tty_ = false;
  ros::WallTime start_, first_, last_, last_print_, all_received_;
  std::string hold_file_;
  bool hold_announced_ = false;
  tabletop_common::RunningStats latency_ms_;
  tabletop_msgs::MultiViewFrame::ConstPtr sheet_;
  bool sheet_person_ = false, finished_ = false;
  std::map<ros::Time, bool> truth_;
  std::map<ros::Time, tabletop_msgs::TrackedTargets::ConstPtr> truth_msgs_;
  std::map<std::string, std::map<std::string, std::string>> stages_;
  // [0] psfs/body_volume, [1] psfs/skin_volume, [2] body/volume (the body tracker's, scored
  // against the body oracle): unpaired volumes by stamp, IoU so far, the last scored pair.
  static constexpr int kVolumeKinds = 3;
  std::vector<ros::Subscriber> volume_subs_;
  uint8_t threshold_byte_ = 191;
  std::map<ros::Time, tabletop_msgs::VoxelVolume::ConstPtr> recon_volumes_[kVolumeKinds],
      truth_volumes_[kVolumeKinds];
  tabletop_common::RunningStats iou_[kVolumeKinds];
  uint64_t volumes_received_[kVolumeKinds] = {0, 0, 0};
  bool grid_mismatch_ = false;
  std::pair<tabletop_msgs::VoxelVolume::ConstPtr, tabletop_msgs::VoxelVolume::ConstPtr> scored_[kVolumeKinds];
};

}  // namespace tabletop_sim

namespace {
volatile std::sig_atomic_t g_interrupted = 0;
void onSigint(int) { g_interrupted = 1; }
}  // namespace

int main(int argc, char** argv) {
  // Own SIGINT handling: roslaunch stops the monitor with SIGINT when the bag or the rig ends,
  // and the summary must still be written.
  ros::init(argc, argv, "demo_monitor", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, onSigint);
  tabletop_sim::DemoMonitor monitor;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  while (ros::ok() && !g_interrupted) ros::WallDuration(0.05).sleep();
  monitor.finish();
  ros::shutdown();
  return monitor.exitCode();
}
