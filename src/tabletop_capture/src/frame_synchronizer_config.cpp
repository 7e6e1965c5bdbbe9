#include "tabletop_capture/frame_synchronizer_config.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tabletop_capture {

FrameSetAssemblerConfig FrameSynchronizerConfig::assembler() const {
  auto fail = [](const std::string& key, const std::string& what) {
    throw std::invalid_argument(key + ": " + what);
  };
  if (num_cameras < 1 || num_cameras > 64) fail("num_cameras", "must lie in [1, 64]");
  if (camera_prefix.empty()) fail("camera_prefix", "must not be empty");
  if (image_transport.empty()) fail("image_transport", "must not be empty (raw, compressed, ...)");
  if (!(tolerance >= 0.0 && std::isfinite(tolerance))) fail("tolerance", "must be finite and >= 0");
  if (!(timeout > 0.0)) fail("timeout", "must be > 0");
  if (max_pending < 1) fail("max_pending", "must be >= 1");
  if (max_missing_cameras < 0) fail("max_missing_cameras", "must be >= 0");
  if (absent_after < 1) fail("absent_after", "must be >= 1");
  if (!(time_jump_threshold > 0.0)) fail("time_jump_threshold", "must be > 0");
  if (world_frame.empty()) fail("world_frame", "must not be empty");
  if (!(tf_timeout >= 0.0 && tf_timeout <= 10.0)) fail("tf_timeout", "must lie in [0, 10] s");
  if (queue_size < 1) fail("queue_size", "must be >= 1");
  if (image_queue_size < 1) fail("image_queue_size", "must be >= 1");
  if (hold_until_subscribers < 0) fail("hold_until_subscribers", "must be >= 0");
  if (max_held < 1) fail("max_held", "must be >= 1");
  FrameSetAssemblerConfig a;
  a.num_cameras = num_cameras;
  a.tolerance = tolerance;
  a.timeout = timeout;
  a.max_pending = static_cast<std::size_t>(max_pending);
  // pSfS needs two views: a set keeps at least two cameras (all of them on a 1-camera rig).
  a.max_missing = std::min(max_missing_cameras, std::max(0, num_cameras - 2));
  a.absent_after = absent_after;
  return a;
}

void addFrameSynchronizerKeys(FrameSynchronizerConfig* c, tabletop_common::ConfigSchema* s) {
  s->add("num_cameras", &c->num_cameras)
      .add("camera_prefix", &c->camera_prefix)
      .add("image_transport", &c->image_transport)
      .add("tolerance", &c->tolerance)
      .add("timeout", &c->timeout)
      .add("max_pending", &c->max_pending)
      .add("max_missing_cameras", &c->max_missing_cameras)
      .add("absent_after", &c->absent_after)
      .add("time_jump_threshold", &c->time_jump_threshold)
      .add("world_frame", &c->world_frame)
      .add("tf_timeout", &c->tf_timeout)
      .add("queue_size", &c->queue_size)
      .add("image_queue_size", &c->image_queue_size)
      .add("hold_until_subscribers", &c->hold_until_subscribers)
      .add("max_held", &c->max_held);
}

FrameSynchronizerConfig loadFrameSynchronizerConfig(const std::string& path) {
  FrameSynchronizerConfig c;
  tabletop_common::ConfigSchema schema;
  addFrameSynchronizerKeys(&c, &schema);
  schema.loadFile(path);
  try {
    c.assembler();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  return c;
}

}  // namespace tabletop_capture
