// A file posing as a camera: a video file (cv::CAP_FFMPEG) or an image-sequence pattern
// (cv::CAP_IMAGES, e.g. frames/img_%04d.png), delivered at the configured fps (absolute
// deadlines, so the rate does not drift), optionally looping. Used for tests and offline runs.
// A file that vanishes (moved, renamed) fails like an unplugged camera: read() says kFailed
// and a later open() finds it again.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include <opencv2/videoio.hpp>

#include "tabletop_capture/frame_source.h"

namespace tabletop_capture {

class FileFrameSource : public FrameSource {
 public:
  explicit FileFrameSource(FrameSourceSettings settings);
  bool open(std::string* why) override;
  void close() override;
  bool isOpen() const override { return cap_.isOpened(); }
  ReadResult read(CapturedFrame* frame, std::string* why) override;
  std::string describe() const override;

  bool isPattern() const { return path_.find('%') != std::string::npos; }

 private:
  bool openCapture(std::string* why);
  void pace();

  FrameSourceSettings settings_;
  std::function<double()> clock_;
  std::string path_;  // without "file:"
  cv::VideoCapture cap_;
  std::uint64_t frames_since_open_ = 0;
  double frame_count_ = 0;  // as the backend counts it at open(); 0 = unknown
  std::chrono::steady_clock::time_point next_due_{};
  bool paced_ = false;
};

}  // namespace tabletop_capture
