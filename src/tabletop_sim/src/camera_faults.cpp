#include "tabletop_sim/camera_faults.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace tabletop_sim {
namespace {

[[noreturn]] void bad(const std::string& text, const std::string& why) {
  throw std::invalid_argument("camera fault '" + text + "': " + why);
}

double number(std::istringstream& in, const std::string& text, const char* what) {
  std::string w;
  if (!(in >> w)) bad(text, std::string("missing ") + what);
  try {
    size_t used = 0;
    const double v = std::stod(w, &used);
    if (used != w.size() || !std::isfinite(v)) throw std::invalid_argument(w);
    return v;
  } catch (const std::exception&) {
    bad(text, std::string("bad ") + what + " '" + w + "'");
  }
}

}  // namespace

void CameraFaults::command(const std::string& text, double now) {
  std::istringstream in(text);
  std::string kind;
  if (!(in >> kind)) bad(text, "empty command");
  if (kind == "clear") {
    faults_.clear();
    return;
  }
  Fault f;
  f.kind = kind;
  const auto camera = [&] {
    std::string c;
    if (!(in >> c)) bad(text, "missing camera");
    if (c == "all") return -1;
    try {
      size_t used = 0;
      const int i = std::stoi(c, &used);
      if (used != c.size() || i < 0 || i >= num_cameras_) throw std::out_of_range(c);
      return i;
    } catch (const std::exception&) {
      bad(text, "camera must be 0.." + std::to_string(num_cameras_ - 1) + " or all");
    }
  };
  if (kind == "stop" || kind == "nan_info") {
    f.camera = camera();
  } else if (kind == "encoding") {
    f.camera = camera();
    if (!(in >> f.encoding)) bad(text, "missing encoding");
    if (f.encoding != "rgb8" && f.encoding != "bgr8" && f.encoding != "mono8" && f.encoding != "rgba8")
      bad(text, "encoding must be rgb8, bgr8, rgba8 or mono8");
  } else if (kind == "size") {
    f.camera = camera();
    f.width = static_cast<int>(number(in, text, "width"));
    f.height = static_cast<int>(number(in, text, "height"));
    if (f.width < 1 || f.height < 1 || f.width > 4096 || f.height > 4096) bad(text, "size out of range");
  } else if (kind == "brightness") {
    f.gain = number(in, text, "gain");
    if (!(f.gain > 0 && f.gain <= 10)) bad(text, "gain must be in (0, 10]");
  } else if (kind == "frame") {
    f.camera = camera();
    if (!(in >> f.encoding)) bad(text, "missing frame_id");
  } else if (kind == "tf") {
    f.camera = camera();
    for (int k = 0; k < 3; ++k) {
      f.shift[k] = number(in, text, "shift");
      if (std::abs(f.shift[k]) > 10) bad(text, "shift must be within 10 m");
    }
  } else if (kind == "clock") {
    f.shift[0] = number(in, text, "offset");
  } else {
    bad(text, "unknown command (stop, encoding, size, nan_info, brightness, frame, tf, clock, clear)");
  }
  const double seconds = number(in, text, "seconds");
  if (seconds < 0) bad(text, "seconds must be >= 0");
  std::string extra;
  if (in >> extra) bad(text, "unexpected '" + extra + "'");
  f.start = now;
  f.end = seconds > 0 ? now + seconds : now;
  faults_.push_back(f);
}

CameraFaultEffect CameraFaults::effect(int camera, double now) const {
  CameraFaultEffect e;
  for (const Fault& f : faults_) {
    if (!f.activeAt(now) || (f.camera >= 0 && f.camera != camera)) continue;
    if (f.kind == "stop") e.drop = true;
    if (f.kind == "nan_info") e.nan_info = true;
    if (f.kind == "encoding") e.encoding = f.encoding;
    if (f.kind == "size") e.width = f.width, e.height = f.height;
    if (f.kind == "brightness") e.gain = f.gain;
    if (f.kind == "frame") e.frame_id = f.encoding;
    if (f.kind == "tf")
      for (int k = 0; k < 3; ++k) e.tf_shift[k] = f.shift[k];
  }
  return e;
}

double CameraFaults::clockOffset(double now) const {
  double offset = 0;
  for (const Fault& f : faults_)
    if (f.kind == "clock" && f.activeAt(now)) offset = f.shift[0];
  return offset;
}

std::string CameraFaults::describe(double now) const {
  std::string out;
  for (const Fault& f : faults_) {
    if (!f.activeAt(now)) continue;
    if (!out.empty()) out += ", ";
    const bool global = f.kind == "brightness" || f.kind == "clock";
    out += f.kind + (f.camera >= 0 ? " cam" + std::to_string(f.camera) : global ? "" : " all");
  }
  return out;
}

}  // namespace tabletop_sim
