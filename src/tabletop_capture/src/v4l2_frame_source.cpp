#include "tabletop_capture/v4l2_frame_source.h"

#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <sstream>

namespace tabletop_capture {
namespace {

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

V4l2FrameSource::V4l2FrameSource(FrameSourceSettings settings)
    : settings_(std::move(settings)), clock_(clockOf(settings_)) {}

void V4l2FrameSource::request(int property, double value, const std::string& name) {
  if (!cap_.set(property, value)) {
    differences_.push_back(name + ": the device has no such control (OpenCV's V4L2 backend "
                           "refused " + number(value) + ")");
    return;
  }
  const double got = cap_.get(property);
  if (std::fabs(got - value) > 1e-3 * std::max(1.0, std::fabs(value)))
    differences_.push_back(name + ": asked " + number(value) + ", device gives " + number(got));
}

void V4l2FrameSource::report(int property, const std::string& name) {
  const double v = cap_.get(property);
  // OpenCV answers -1 (or 0 on some versions) for a property the device lacks.
  accepted_.emplace_back(name, v == -1 ? std::string("n/a") : number(v));
}

bool V4l2FrameSource::open(std::string* why) {
  accepted_.clear();
  differences_.clear();
  cap_.release();
  const std::string& dev = settings_.device;
  if (!cap_.open(dev, cv::CAP_V4L2)) {
    std::string reason = "OpenCV's V4L2 backend cannot open it";
    if (::access(dev.c_str(), F_OK) != 0)
      reason += ": no such device node (unplugged? check /dev/v4l/by-id/)";
    else if (::access(dev.c_str(), R_OK | W_OK) != 0)
      reason += std::string(": ") + std::strerror(errno) + " (is the user in group 'video'?)";
    else
      reason += " (busy in another program, or not a capture device)";
    if (why) *why = reason;
    return false;
  }
  // The pixel format first: it limits the sizes and rates the device offers.
  if (settings_.fourcc.size() == 4) {
    const std::string& f = settings_.fourcc;
    const double code = cv::VideoWriter::fourcc(f[0], f[1], f[2], f[3]);
    if (!cap_.set(cv::CAP_PROP_FOURCC, code) || fourccToString(cap_.get(cv::CAP_PROP_FOURCC)) != f)
      differences_.push_back("fourcc: asked " + f + ", device gives " +
                             fourccToString(cap_.get(cv::CAP_PROP_FOURCC)));
  }
  request(cv::CAP_PROP_FRAME_WIDTH, settings_.width, "width");
  request(cv::CAP_PROP_FRAME_HEIGHT, settings_.height, "height");
  request(cv::CAP_PROP_FPS, settings_.fps, "fps");
  if (settings_.raw) request(cv::CAP_PROP_CONVERT_RGB, 0, "raw data (convert_rgb off)");
  // Fixed settings for background learning: the auto mode off first, then the value.
  // V4L2's exposure_auto menu: 1 = manual, 3 = aperture priority (OpenCV passes it through).
  if (settings_.exposure >= 0) {
    request(cv::CAP_PROP_AUTO_EXPOSURE, 1, "auto exposure (1 = manual)");
    request(cv::CAP_PROP_EXPOSURE, settings_.exposure, "exposure");
  }
  if (settings_.gain >= 0) request(cv::CAP_PROP_GAIN, settings_.gain, "gain");
  if (settings_.white_balance >= 0) {
    request(cv::CAP_PROP_AUTO_WB, 0, "auto white balance (0 = off)");
    request(cv::CAP_PROP_WB_TEMPERATURE, settings_.white_balance, "white balance");
  }
  if (settings_.external_trigger) {
    // OpenCV's V4L2 backend maps no trigger control (CAP_PROP_TRIGGER is for other backends):
    // set() says whether this device/backend has one.
    if (!cap_.set(cv::CAP_PROP_TRIGGER, 1))
      differences_.push_back("trigger: the device has no trigger control (OpenCV's V4L2 backend "
                             "offers none): it runs free");
  }
  const double device_fps = cap_.get(cv::CAP_PROP_FPS);
  nominal_fps_ = device_fps > 0 ? device_fps : settings_.fps;
  accepted_.emplace_back("backend", cap_.getBackendName());
  accepted_.emplace_back("fourcc", fourccToString(cap_.get(cv::CAP_PROP_FOURCC)));
  report(cv::CAP_PROP_FRAME_WIDTH, "width");
  report(cv::CAP_PROP_FRAME_HEIGHT, "height");
  report(cv::CAP_PROP_FPS, "fps");
  report(cv::CAP_PROP_AUTO_EXPOSURE, "auto exposure");
  report(cv::CAP_PROP_EXPOSURE, "exposure");
  report(cv::CAP_PROP_GAIN, "gain");
  report(cv::CAP_PROP_AUTO_WB, "auto white balance");
  report(cv::CAP_PROP_WB_TEMPERATURE, "white balance");
  return true;
}

ReadResult V4l2FrameSource::read(CapturedFrame* frame, std::string* why) {
  if (!cap_.isOpened()) {
    if (why) *why = "not open";
    return ReadResult::kFailed;
  }
  if (!cap_.grab()) {
    if (why) *why = "grab() failed (unplugged, or the device stopped delivering frames)";
    return ReadResult::kFailed;
  }
  frame->stamp = clock_();  // as early as possible: before retrieve() decodes
  cv::Mat image;
  if (!cap_.retrieve(image) || image.empty()) {
    if (why) *why = "retrieve() gave no image (a format OpenCV cannot decode?)";
    return ReadResult::kFailed;
  }
  // Raw data may come as one row of bytes: a one-channel W x H image if it has that many.
  const int w = static_cast<int>(cap_.get(cv::CAP_PROP_FRAME_WIDTH));
  const int h = static_cast<int>(cap_.get(cv::CAP_PROP_FRAME_HEIGHT));
  if (settings_.raw && image.rows == 1 && image.channels() == 1 && w > 0 && h > 0 &&
      image.total() == static_cast<size_t>(w) * h)
    image = image.reshape(1, h);
  frame->image = image;
  return ReadResult::kFrame;
}

}  // namespace tabletop_capture
