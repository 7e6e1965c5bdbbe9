#include "tabletop_capture/file_frame_source.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <thread>

#include <opencv2/imgproc.hpp>

namespace tabletop_capture {

FileFrameSource::FileFrameSource(FrameSourceSettings settings)
    : settings_(std::move(settings)), clock_(clockOf(settings_)), path_(settings_.device.substr(5)) {}

std::string FileFrameSource::describe() const {
  return (isPattern() ? "image sequence " : "video file ") + path_;
}

bool FileFrameSource::openCapture(std::string* why) {
  cap_.release();
  frames_since_open_ = 0;
  const int api = isPattern() ? cv::CAP_IMAGES : cv::CAP_FFMPEG;
  bool ok = false;
  try {
    ok = cap_.open(path_, api) && cap_.isOpened();
  } catch (const cv::Exception& e) {
    if (why) *why = std::string("OpenCV: ") + e.what();
    return false;
  }
  if (!ok) {
    std::string reason = std::string("OpenCV's ") + (isPattern() ? "image-sequence" : "FFmpeg") +
                         " backend cannot open it";
    if (!isPattern() && ::access(path_.c_str(), R_OK) != 0)
      reason += ": no such (readable) file";
    else if (isPattern())
      reason += ": no file matches the pattern (moved away?)";
    if (why) *why = reason;
    return false;
  }
  return true;
}

bool FileFrameSource::open(std::string* why) {
  accepted_.clear();
  differences_.clear();
  paced_ = false;
  if (!openCapture(why)) return false;
  const int w = static_cast<int>(cap_.get(cv::CAP_PROP_FRAME_WIDTH));
  const int h = static_cast<int>(cap_.get(cv::CAP_PROP_FRAME_HEIGHT));
  const double file_fps = cap_.get(cv::CAP_PROP_FPS);
  // Exact for a sequence (the backend counts the files); only an estimate for a video file.
  frame_count_ = isPattern() ? std::max(0.0, cap_.get(cv::CAP_PROP_FRAME_COUNT)) : 0.0;
  nominal_fps_ = settings_.fps;
  accepted_.emplace_back("backend", cap_.getBackendName());
  accepted_.emplace_back("width", std::to_string(w));
  accepted_.emplace_back("height", std::to_string(h));
  accepted_.emplace_back("fps", std::to_string(settings_.fps) + " (paced)");
  accepted_.emplace_back("loop", settings_.loop ? "yes" : "no");
  if (w > 0 && w != settings_.width)
    differences_.push_back("width: asked " + std::to_string(settings_.width) + ", file gives " + std::to_string(w));
  if (h > 0 && h != settings_.height)
    differences_.push_back("height: asked " + std::to_string(settings_.height) + ", file gives " + std::to_string(h));
  if (!isPattern() && file_fps > 0 && std::abs(file_fps - settings_.fps) > 1e-3)
    differences_.push_back("fps: the file says " + std::to_string(file_fps) + ", played at " +
                           std::to_string(settings_.fps));
  for (const char* what : {"exposure", "gain", "white_balance"}) {
    const double v = std::string(what) == "exposure" ? settings_.exposure
                     : std::string(what) == "gain"   ? settings_.gain
                                                     : settings_.white_balance;
    if (v >= 0) differences_.push_back(std::string(what) + ": a file has no such control (ignored)");
  }
  if (settings_.external_trigger)
    differences_.push_back("trigger: a file has no trigger: frames are paced at fps");
  return true;
}

void FileFrameSource::close() {
  cap_.release();
  paced_ = false;
}

// Absolute deadlines one period apart; a source that fell more than a period behind (machine
// busy, a reopen) starts a new schedule instead of delivering a burst.
void FileFrameSource::pace() {
  using clock = std::chrono::steady_clock;
  const auto period = std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(1.0 / settings_.fps));
  const auto now = clock::now();
  if (!paced_ || now > next_due_ + period) {
    next_due_ = now;
    paced_ = true;
  }
  std::this_thread::sleep_until(next_due_);
  next_due_ += period;
}

ReadResult FileFrameSource::read(CapturedFrame* frame, std::string* why) {
  if (!cap_.isOpened()) {
    if (why) *why = "not open";
    return ReadResult::kFailed;
  }
  pace();
  // At the known end of a sequence, start over without asking for the file after the last
  // (OpenCV would log a warning for it at every pass).
  const bool at_end = frame_count_ > 0 && frames_since_open_ >= frame_count_;
  bool grabbed = !at_end && cap_.grab();
  if (!grabbed && !at_end && frame_count_ > 0) {
    // A file of a sequence whose length is known went missing: the camera vanished.
    if (why)
      *why = "file " + std::to_string(frames_since_open_ + 1) + " of " +
             std::to_string(static_cast<long>(frame_count_)) +
             " is missing or unreadable (moved away?)";
    return ReadResult::kFailed;
  }
  if (!grabbed && frames_since_open_ > 0) {
    // The end of the file (or the next file of the pattern is missing).
    if (!settings_.loop) return ReadResult::kEnd;
    std::string reopen_why;
    if (!openCapture(&reopen_why)) {
      if (why) *why = "cannot start over at the end: " + reopen_why;
      return ReadResult::kFailed;
    }
    grabbed = cap_.grab();
  }
  if (!grabbed) {
    if (why) *why = "grab() failed: no frame (file missing, empty or unreadable)";
    return ReadResult::kFailed;
  }
  frame->stamp = clock_();  // as early as possible: before retrieve() decodes
  cv::Mat image;
  if (!cap_.retrieve(image) || image.empty()) {
    if (why) *why = "retrieve() gave no image (a file OpenCV cannot decode?)";
    return ReadResult::kFailed;
  }
  ++frames_since_open_;
  // A grey PNG standing in for raw Bayer data may be read as three equal channels.
  if (settings_.raw && image.channels() == 3) cv::extractChannel(image, image, 0);
  frame->image = image;
  return ReadResult::kFrame;
}

}  // namespace tabletop_capture
