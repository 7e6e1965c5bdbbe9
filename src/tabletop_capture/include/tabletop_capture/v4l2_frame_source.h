// A V4L2 camera through cv::VideoCapture (cv::CAP_V4L2): size, fps and FOURCC requested, fixed
// exposure / gain / white balance set with the auto modes off where the device has those
// controls, and what the device accepted read back (FrameSource::accepted / differences).
#pragma once

#include <string>

#include <opencv2/videoio.hpp>

#include "tabletop_capture/frame_source.h"

namespace tabletop_capture {

class V4l2FrameSource : public FrameSource {
 public:
  explicit V4l2FrameSource(FrameSourceSettings settings);
  bool open(std::string* why) override;
  void close() override { cap_.release(); }
  bool isOpen() const override { return cap_.isOpened(); }
  ReadResult read(CapturedFrame* frame, std::string* why) override;
  std::string describe() const override { return "V4L2 camera " + settings_.device; }

 private:
  // Sets a property; records a difference when the device refuses it or keeps another value.
  void request(int property, double value, const std::string& name);
  void report(int property, const std::string& name);

  FrameSourceSettings settings_;
  std::function<double()> clock_;
  cv::VideoCapture cap_;
};

}  // namespace tabletop_capture
