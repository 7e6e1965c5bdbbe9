// Where a capture nodelet's frames come from: a V4L2 camera (v4l2_frame_source.h) or a file
// posing as one (file_frame_source.h: a video file or an image-sequence pattern, paced at the
// configured fps). ROS-free. One source per camera, used from one thread.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace tabletop_capture {

struct FrameSourceSettings {
  // "/dev/video0", a stable "/dev/v4l/by-id/..." path, or "file:<video file or pattern>"
  // (pattern: printf-style index, e.g. "file:frames/img_%04d.png").
  std::string device;
  int width = 640;  // requested size (a file delivers its own; a difference is reported)
  int height = 480;
  double fps = 25.0;   // requested rate; files are paced at it
  std::string fourcc;  // requested pixel format, e.g. "YUYV", "MJPG", "BA81"; "" = device's
  // Fixed exposure / gain / white balance (K) with the auto modes off; < 0 = leave the device's.
  double exposure = -1, gain = -1, white_balance = -1;
  // The device's data as it comes (OpenCV's RGB conversion off), e.g. raw Bayer as one channel.
  bool raw = false;
  bool loop = true;               // files: start over at the end
  bool external_trigger = false;  // V4L2: ask for the device's trigger mode
  // Stamps (s) taken right after grab(), before decoding. Default: the system clock.
  std::function<double()> clock;
};

struct CapturedFrame {
  cv::Mat image;       // BGR (CV_8UC3) or one channel (CV_8UC1: mono, or raw Bayer)
  double stamp = 0.0;  // settings.clock() right after grab()
};

enum class ReadResult {
  kFrame,   // *frame filled
  kEnd,     // a file ended and loop is off: nothing more will come
  kFailed,  // the source failed or vanished (*why says how): close() and open() again later
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  // Opens (again); false with what OpenCV says in *why. Refills accepted() and differences().
  virtual bool open(std::string* why) = 0;
  virtual void close() = 0;
  virtual bool isOpen() const = 0;
  // Blocks until the next frame (the device's pace, or the file's pacing at fps).
  virtual ReadResult read(CapturedFrame* frame, std::string* why) = 0;
  // "V4L2 camera /dev/video0", "image sequence frames/img_%04d.png", ...
  virtual std::string describe() const = 0;

  // What the source accepted after open(): (setting, value) pairs, e.g. ("fps", "25").
  const std::vector<std::pair<std::string, std::string>>& accepted() const { return accepted_; }
  // Requested settings the source did not take, one line each, e.g.
  // "fps: asked 25, device gives 30" or "exposure: the device has no exposure control".
  const std::vector<std::string>& differences() const { return differences_; }
  // The rate frames should come at after open(): what the device accepted (or the file's
  // pacing); the nominal rate for counting dropped frames.
  double nominalFps() const { return nominal_fps_; }

 protected:
  double nominal_fps_ = 0.0;
  std::vector<std::pair<std::string, std::string>> accepted_;
  std::vector<std::string> differences_;
};

// True for "file:..." devices.
bool isFileDevice(const std::string& device);

// The source for settings.device (not opened yet). Throws std::invalid_argument for an empty
// device, "file:" without a path, or a non-positive fps.
std::unique_ptr<FrameSource> makeFrameSource(const FrameSourceSettings& settings);

// Decodes a FOURCC code (CAP_PROP_FOURCC) into its four characters ("" for 0).
std::string fourccToString(double code);

// The settings' clock, or the system clock (s since the epoch) when none is set.
std::function<double()> clockOf(const FrameSourceSettings& settings);

}  // namespace tabletop_capture
