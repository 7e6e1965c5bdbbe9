#include "tabletop_capture/frame_source.h"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "tabletop_capture/file_frame_source.h"
#include "tabletop_capture/v4l2_frame_source.h"

namespace tabletop_capture {

bool isFileDevice(const std::string& device) { return device.rfind("file:", 0) == 0; }

std::unique_ptr<FrameSource> makeFrameSource(const FrameSourceSettings& settings) {
  if (settings.device.empty()) throw std::invalid_argument("device: empty (a /dev path or file:<path>)");
  if (settings.device == "file:") throw std::invalid_argument("device: 'file:' without a path");
  if (!(settings.fps > 0) || !std::isfinite(settings.fps))
    throw std::invalid_argument("fps: must be > 0");
  if (isFileDevice(settings.device)) return std::make_unique<FileFrameSource>(settings);
  return std::make_unique<V4l2FrameSource>(settings);
}

std::string fourccToString(double code) {
  const auto c = static_cast<unsigned>(std::llround(code));
  if (c == 0) return "";
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char ch = static_cast<char>((c >> (8 * i)) & 0xFF);
    s += (ch >= 32 && ch < 127) ? ch : '?';
  }
  return s;
}

std::function<double()> clockOf(const FrameSourceSettings& settings) {
  if (settings.clock) return settings.clock;
  return [] {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  };
}

}  // namespace tabletop_capture
