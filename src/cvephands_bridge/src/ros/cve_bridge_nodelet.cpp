// CveBridge nodelet: streams the local user's hands into a room of the collaborative virtual
// environment (thesis 6.5 "Infrastructure"). psfs/hand_volumes in; per tracked hand a
// HandStreamEncoder message (band-coded sub-volume, hand_stream_codec.h) sent through a
// RoomClient (WebSocket, ws:// or with tls wss://) to the room server, which relays it to the
// other participants.
// The connection is (re)made from a wall timer, never from the volume callback, so a missing or
// slow server costs the pipeline nothing: hands are dropped (counted) while disconnected.
// With face_video on it also sends the user's face (thesis 7.5): frames + hands/targets in, a
// JPEG crop around the tracked head from the camera facing the user (face_video.h), at most
// face_video_fps per second.
//
// Parameters: ~config_file (default $(find cvephands_bridge)/config/cve_bridge.yaml, every key
// documented there) read strictly, then any private parameter named like a key overrides it; an
// unknown one stops the stage (tabletop_common/ros/config_overrides.h).
#include <atomic>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/package.h>
#include <ros/ros.h>

#include <tabletop_msgs/HandVolumes.h>
#include <tabletop_msgs/MultiViewFrame.h>
#include <tabletop_msgs/TrackedTargets.h>

#include "cvephands_bridge/room/reconnect_backoff.h"
#include "cvephands_bridge/room/room_client.h"
#include "cvephands_bridge/stream/hand_stream_codec.h"
#include "cvephands_bridge/video/face_video.h"
#include "tabletop_capture/ros/frame_set_view.h"
#include "tabletop_common/ros/config_overrides.h"
#include "tabletop_common/ros/periodic_diagnostics.h"
#include "tabletop_common/running_stats.h"

namespace cvephands {

class CveBridgeNodelet : public nodelet::Nodelet {
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    diag_ = std::make_unique<tabletop_common::PeriodicDiagnostics>(
        nh, pnh, getName(), "cve_bridge", "cve bridge",
        [this](diagnostic_updater::DiagnosticStatusWrapper& stat) { diagnose(stat); });

    int port = 8765, bits = 2, keyframes = 25, queue = 16;
    double reconnect = 2.0, reconnect_max = 30.0;
    options_.host = "127.0.0.1";
    options_.join.room = "tabletop";
    options_.join.name = "rig";
    options_.connect_timeout = 1.0;
    face_video_ = true;
    face_fps_ = 10.0;
    try {
      tabletop_common::ConfigSchema schema;
      schema.add("server_host", &options_.host)
          .add("server_port", &port)
          .add("room", &options_.join.room)
          .add("name", &options_.join.name)
          .add("token", &options_.join.token)
          .add("tls", &options_.tls)
          .add("tls_ca_file", &options_.tls_ca_file)
          .add("send_queue", &queue)
          .add("connect_timeout", &options_.connect_timeout)
          .add("code_bits", &bits)
          .add("keyframe_interval", &keyframes)
          .add("reconnect_interval", &reconnect)
          .add("reconnect_max_interval", &reconnect_max)
          .add("face_video", &face_video_)
          .add("face_video_fps", &face_fps_)
          .add("face_video_size", &face_options_.size)
          .add("face_video_quality", &face_options_.jpeg_quality);
      tabletop_common::loadConfigWithOverrides(
          pnh, ros::package::getPath("cvephands_bridge") + "/config/cve_bridge.yaml", schema, {});
    } catch (const std::exception& e) {
      fatal_ = e.what();
      NODELET_FATAL("cve_bridge: not started: bad parameters: %s", e.what());
      return;
    }
    options_.port = static_cast<uint16_t>(port);
    options_.send_queue_length = static_cast<size_t>(std::max(1, queue));
    options_.join.role = room::Role::kRig;
    // Someone joined (or left): the newcomer has no reference frames, send key frames next.
    options_.on_participants = [this](const std::vector<room::ParticipantInfo>&) {
      key_frames_needed_ = true;
    };
    encoder_options_.bits = bits;
    encoder_options_.keyframe_interval = keyframes;
    try {
      encoder_options_.validate();
      if (port < 1 || port > 65535) throw std::invalid_argument("server_port must be in 1..65535");
      if (!options_.tls_ca_file.empty()) {
        if (!options_.tls)
          throw std::invalid_argument("tls_ca_file is set but tls is false (the CA would not be used)");
        std::error_code ec;
        if (!std::filesystem::is_regular_file(options_.tls_ca_file, ec))
          throw std::invalid_argument("tls_ca_file " + options_.tls_ca_file + ": no such file");
      }
      if (!(reconnect > 0.0)) throw std::invalid_argument("reconnect_interval must be > 0");
      if (!(reconnect_max >= reconnect))
        throw std::invalid_argument("reconnect_max_interval must be >= reconnect_interval");
      backoff_ = std::make_unique<ReconnectBackoff>(reconnect, reconnect_max);
      if (queue < 1) throw std::invalid_argument("send_queue must be >= 1");
      if (!(options_.connect_timeout > 0.0)) throw std::invalid_argument("connect_timeout must be > 0");
      face_options_.validate();
      if (!(face_fps_ > 0.0 && face_fps_ <= 60.0)) throw std::invalid_argument("face_video_fps must be in (0, 60]");
    } catch (const std::exception& e) {
      fatal_ = e.what();
      NODELET_FATAL("cve_bridge: not started: bad parameters: %s", e.what());
      return;
    }
    boost::function<void(const ros::WallTimerEvent&)> on_connect = [this](const ros::WallTimerEvent&) {
      ensureConnected();
    };
    // The timer ticks at the first interval; after failures, ticks are skipped until the
    // back-off's next attempt (reconnect_interval doubling up to reconnect_max_interval).
    connect_timer_ = nh.createWallTimer(ros::WallDuration(reconnect), on_connect);
    // Sets are dropped only at the pSfS gate; later stages queue enough never to drop one.
    sub_ = nh.subscribe("psfs/hand_volumes", 10, &CveBridgeNodelet::onVolumes, this);
    if (face_video_) {
      targets_sub_ = nh.subscribe("hands/targets", 2, &CveBridgeNodelet::onTargets, this);
      frames_sub_ = nh.subscribe("frames", 1, &CveBridgeNodelet::onFrames, this);
    }
    NODELET_INFO("cve_bridge: %s -> %s://%s:%d%s room '%s' as '%s', %d-bit band codes%s%s",
                 sub_.getTopic().c_str(), options_.tls ? "wss" : "ws", options_.host.c_str(), port,
                 options_.path.c_str(), options_.join.room.c_str(), options_.join.name.c_str(), bits,
                 options_.tls ? ", server certificate checked against " : "",
                 !options_.tls ? "" : options_.tls_ca_file.empty() ? "the system's CAs" : options_.tls_ca_file.c_str());
  }

  void ensureConnected() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (client_ && client_->connected()) return;
      if (client_ && !loss_reported_) {
        // Joined before, gone now (the server stopped or the network dropped). Said once per
        // loss: a rejoin that succeeds at its first attempt would otherwise leave no trace.
        NODELET_WARN("cve_bridge: lost room '%s' at %s:%u; rejoining", options_.join.room.c_str(),
                     options_.host.c_str(), options_.port);
        loss_reported_ = true;
      }
    }
    const ros::WallTime now = ros::WallTime::now();
    if (now + ros::WallDuration(0.05) < next_attempt_) return;  // backing off (timer slack)
    auto client = std::make_shared<RoomClient>(options_);
    std::string error;
    if (!client->connect(&error)) {
      const double wait = backoff_->failed();
      next_attempt_ = now + ros::WallDuration(wait);
      NODELET_WARN_THROTTLE(30.0, "cve_bridge: cannot join room '%s' at %s:%u: %s (%d failed "
                            "attempts, next in %.0f s)",
                            options_.join.room.c_str(), options_.host.c_str(), options_.port,
                            error.c_str(), backoff_->failures(), wait);
      std::lock_guard<std::mutex> lock(mutex_);
      last_error_ = error;
      return;
    }
    backoff_->succeeded();
    next_attempt_ = ros::WallTime();
    const room::ParticipantInfo self = client->self();
    NODELET_INFO("cve_bridge: joined room '%s' as participant %u, seat %d",
                 options_.join.room.c_str(), self.id, self.seat);
    std::lock_guard<std::mutex> lock(mutex_);
    client_ = client;
    loss_reported_ = false;
    ++connects_;
    // A new connection: the receivers have no reference frames of ours.
    for (auto& e : encoders_) e.second.requestKeyFrame();
  }

  void onVolumes(const tabletop_msgs::HandVolumes::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++frames_;
    if (msg->target_ids.size() != msg->volumes.size()) {
      ++rejected_;
      NODELET_WARN_THROTTLE(5.0, "cve_bridge: %zu target ids for %zu volumes: message ignored",
                            msg->target_ids.size(), msg->volumes.size());
      return;
    }
    const bool online = client_ && client_->connected();
    if (key_frames_needed_.exchange(false))
      for (auto& e : encoders_) e.second.requestKeyFrame();
    for (size_t i = 0; i < msg->volumes.size(); ++i) {
      const tabletop_msgs::VoxelVolume& v = msg->volumes[i];
      if (!online) {
        ++dropped_offline_;
        continue;
      }
      frame_.target_id = msg->target_ids[i];
      frame_.stamp_sec = msg->header.stamp.sec;
      frame_.stamp_nsec = msg->header.stamp.nsec;
      frame_.origin = Eigen::Vector3d(v.origin.x, v.origin.y, v.origin.z);
      frame_.voxel_size = v.voxel_size;
      frame_.dims = Eigen::Vector3i(int(v.size_x), int(v.size_y), int(v.size_z));
      frame_.data = v.data;  // the encoder reads a HandFrame; 571 kB, ~0.05 ms
      auto it = encoders_.find(frame_.target_id);
      if (it == encoders_.end())
        it = encoders_.emplace(frame_.target_id, HandStreamEncoder(encoder_options_)).first;
      std::vector<uint8_t> message;
      try {
        const ros::WallTime t0 = ros::WallTime::now();
        it->second.encode(frame_, &message);
        encode_ms_.add((ros::WallTime::now() - t0).toSec() * 1e3);
      } catch (const std::exception& e) {
        ++rejected_;
        NODELET_WARN_THROTTLE(5.0, "cve_bridge: hand %u: cannot encode: %s", frame_.target_id, e.what());
        continue;
      }
      message_bytes_.add(double(message.size()));
      bytes_sent_ += message.size();
      client_->send(std::move(message));
      ++sent_;
    }
  }

  void onTargets(const tabletop_msgs::TrackedTargets::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    head_valid_ = false;
    for (const auto& t : msg->targets) {
      if (t.type != tabletop_msgs::TrackedTarget::HEAD || !t.active) continue;
      head_ = Eigen::Vector3d(t.position.x, t.position.y, t.position.z);
      head_valid_ = head_.allFinite();
      head_stamp_ = msg->header.stamp;
    }
  }

  // One face picture per 1 / face_video_fps s, while the head is tracked and the room is joined.
  void onFrames(const tabletop_msgs::MultiViewFrame::ConstPtr& f) {
    Eigen::Vector3d head;
    std::shared_ptr<RoomClient> client;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const ros::WallTime now = ros::WallTime::now();
      // The head of a frame set arrives after it (reconstruction + tracking): use the newest
      // one within half a second; a head that is older than that is lost.
      if (!head_valid_ || std::abs((f->header.stamp - head_stamp_).toSec()) > 0.5) return;
      if (!last_face_.isZero() && (now - last_face_).toSec() < 1.0 / face_fps_) return;
      if (!client_ || !client_->connected()) return;
      last_face_ = now;
      head = head_;
      client = client_;
    }
    std::vector<cv::Mat> images;
    std::vector<tabletop_capture::CameraModel> cams;
    std::string why;
    if (!tabletop_capture::unpackFrameSet(*f, &images, &cams, &why)) {
      NODELET_WARN_THROTTLE(10.0, "cve_bridge: face video: frame set ignored: %s", why.c_str());
      return;
    }
    // Among the cameras that delivered an image (a degraded set has empty slots).
    std::vector<tabletop_capture::CameraModel> seeing;
    std::vector<int> index;
    for (size_t i = 0; i < cams.size(); ++i)
      if (!images[i].empty()) seeing.push_back(cams[i]), index.push_back(static_cast<int>(i));
    const int k = pickFaceCamera(seeing, head);
    if (k < 0) return;
    const int c = index[k];
    std::vector<uint8_t> message;
    try {  // OpenCV or the encoder may throw (memory, a picture over the size limit)
      cv::Mat face;
      if (!cropFace(images[c], cams[c], head, face_options_, &face)) return;
      message = encodeFaceMessage(f->header.stamp.sec, f->header.stamp.nsec, face,
                                  face_options_.jpeg_quality);
    } catch (const std::exception& e) {
      NODELET_WARN_THROTTLE(10.0, "cve_bridge: face video: picture dropped: %s", e.what());
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    face_bytes_ += message.size();
    bytes_sent_ += message.size();
    ++faces_sent_;
    client->send(std::move(message));
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    if (!fatal_.empty()) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "not started: " + fatal_);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    const bool online = client_ && client_->connected();
    if (!online)
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "not connected to the room server" + (last_error_.empty() ? "" : ": " + last_error_));
    else
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::OK, "in room '%s' with %zu participant(s)",
                    options_.join.room.c_str(), client_->participants().size());
    stat.add("connected", online);
    stat.add("connections made", connects_);
    stat.add("hand messages sent", sent_);
    stat.add("hands dropped while disconnected", dropped_offline_);
    stat.add("volumes rejected", rejected_);
    stat.add("send rate (kbit/s)", 8e-3 * byte_rate_.rate(bytes_sent_));
    stat.add("message size, mean (bytes)", message_bytes_.mean());
    stat.add("encode per hand (ms)", encode_ms_.mean());
    stat.add("face pictures sent", faces_sent_);
    stat.add("face video (kbit/s)", 8e-3 * face_rate_.rate(face_bytes_));
    if (client_) {
      const RoomClientStats s = client_->stats();
      stat.add("send queue drops", s.send_dropped);
      stat.add("hand messages received", s.received);
    }
  }

  RoomClientOptions options_;
  HandStreamEncoderOptions encoder_options_;
  std::shared_ptr<RoomClient> client_;
  bool loss_reported_ = false;  // the current client_'s loss has been warned about
  std::map<uint32_t, HandStreamEncoder> encoders_;
  HandFrame frame_;
  std::string fatal_, last_error_;
  std::unique_ptr<ReconnectBackoff> backoff_;
  ros::WallTime next_attempt_;  // timer thread only
  ros::Subscriber sub_;
  std::unique_ptr<tabletop_common::PeriodicDiagnostics> diag_;
  ros::WallTimer connect_timer_;
  std::mutex mutex_;
  std::atomic<bool> key_frames_needed_{false};
  uint64_t frames_ = 0, sent_ = 0, dropped_offline_ = 0, rejected_ = 0, connects_ = 0;
  uint64_t bytes_sent_ = 0, face_bytes_ = 0, faces_sent_ = 0;
  tabletop_common::RateMeter face_rate_;
  // Face video.
  bool face_video_ = true;
  double face_fps_ = 10.0;
  FaceVideoOptions face_options_;
  ros::Subscriber targets_sub_, frames_sub_;
  Eigen::Vector3d head_ = Eigen::Vector3d::Zero();
  bool head_valid_ = false;
  ros::Time head_stamp_;
  ros::WallTime last_face_;
  tabletop_common::RateMeter byte_rate_;
  tabletop_common::RunningStats encode_ms_, message_bytes_;
};

}  // namespace cvephands

PLUGINLIB_EXPORT_CLASS(cvephands::CveBridgeNodelet, nodelet::Nodelet)
