#include "tabletop_capture/camera_capture_config.h"

#include <cmath>
#include <stdexcept>

namespace tabletop_capture {

void CameraCaptureConfig::validate() const {
  auto fail = [](const std::string& key, const std::string& what) {
    throw std::invalid_argument(key + ": " + what);
  };
  if (device.empty() || device == "file:") fail("device", "must be a device path or file:<path>");
  if (camera_name.empty() || camera_name.find('/') != std::string::npos)
    fail("camera_name", "must be a plain name such as cam0");
  if (!rig_file.empty() && !camera_info_file.empty())
    fail("camera_info_file", "set either rig_file or camera_info_file, not both");
  if (width <= 0 || height <= 0) fail(width <= 0 ? "width" : "height", "must be > 0");
  if (!(fps > 0 && fps <= 1000)) fail("fps", "must lie in (0, 1000]");
  if (!fourcc.empty() && fourcc.size() != 4) fail("fourcc", "must be empty or four characters");
  BayerPattern p;
  if (!parseBayerPattern(bayer, &p)) fail("bayer", "must be none, rggb, bggr, gbrg or grbg");
  if (half_resolution && p == BayerPattern::kNone)
    fail("half_resolution", "needs a Bayer pattern (bayer: rggb, bggr, gbrg or grbg)");
  if (half_resolution && (width % 2 != 0 || height % 2 != 0))
    fail("half_resolution", "needs an even width and height (whole 2x2 quads)");
  if (trigger != "none" && trigger != "external") fail("trigger", "must be none or external");
  if (!(reopen_interval > 0 && reopen_interval <= 3600)) fail("reopen_interval", "must lie in (0, 3600] s");
  if (queue_size < 1) fail("queue_size", "must be >= 1");
  for (double v : {exposure, gain, white_balance})
    if (!std::isfinite(v)) fail("exposure/gain/white_balance", "must be finite (-1 = the device's)");
}

BayerPattern CameraCaptureConfig::bayerPattern() const {
  BayerPattern p = BayerPattern::kNone;
  parseBayerPattern(bayer, &p);
  return p;
}

FrameSourceSettings CameraCaptureConfig::sourceSettings() const {
  FrameSourceSettings s;
  s.device = device;
  s.width = width;
  s.height = height;
  s.fps = fps;
  s.fourcc = fourcc;
  s.exposure = exposure;
  s.gain = gain;
  s.white_balance = white_balance;
  s.raw = bayerPattern() != BayerPattern::kNone;
  s.loop = loop;
  s.external_trigger = trigger == "external";
  return s;
}

void addCameraCaptureKeys(CameraCaptureConfig* c, tabletop_common::ConfigSchema* s) {
  s->add("device", &c->device)
      .add("camera_name", &c->camera_name)
      .add("rig_file", &c->rig_file)
      .add("camera_info_file", &c->camera_info_file)
      .add("width", &c->width)
      .add("height", &c->height)
      .add("fps", &c->fps)
      .add("fourcc", &c->fourcc)
      .add("exposure", &c->exposure)
      .add("gain", &c->gain)
      .add("white_balance", &c->white_balance)
      .add("bayer", &c->bayer)
      .add("half_resolution", &c->half_resolution)
      .add("loop", &c->loop)
      .add("trigger", &c->trigger)
      .add("reopen_interval", &c->reopen_interval)
      .add("queue_size", &c->queue_size);
}

CameraCaptureConfig loadCameraCaptureConfig(const std::string& path) {
  CameraCaptureConfig c;
  tabletop_common::ConfigSchema schema;
  addCameraCaptureKeys(&c, &schema);
  schema.loadFile(path);
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  return c;
}

std::string checkRigCameraSize(const CameraModel& camera, const CameraCaptureConfig& c,
                               const std::string& source) {
  if (camera.width == c.outputWidth() && camera.height == c.outputHeight()) return "";
  std::string s = source + ": camera '" + camera.name + "' is calibrated for " +
                  std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                  " but the nodelet publishes " + std::to_string(c.outputWidth()) + "x" +
                  std::to_string(c.outputHeight());
  if (c.half_resolution)
    s += " (half_resolution: " + std::to_string(c.width) + "x" + std::to_string(c.height) +
         " Bayer debayered to half size; the rig must describe the half-size images)";
  return s;
}

}  // namespace tabletop_capture
