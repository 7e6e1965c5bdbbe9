#include "cvephands_bridge/mesh/hand_mesher_config.h"

#include <cmath>
#include <stdexcept>

namespace cvephands {

void addHandMesherKeys(HandMesherConfig* c, tabletop_common::ConfigSchema* s) {
  s->add("iso", &c->iso)
      .add("mode", &c->mode)
      .add("close_at_border", &c->close_at_border)
      .add("min_component_triangles", &c->min_component_triangles)
      .add("keep_radius", &c->keep_radius)
      .add("threads", &c->threads)
      .add("publish_markers", &c->publish_markers)
      .add("marker_color", &c->marker_color)
      .add("world_frame", &c->world_frame);
}

float isoByteLevel(double iso) {
  if (!std::isfinite(iso) || !(iso > 0.0) || !(iso < 1.0))
    throw std::invalid_argument("iso: must be a probability in (0, 1)");
  const float level = static_cast<float>(std::floor(255.0 * iso) + 0.5);
  return level >= 255.0f ? 254.5f : level;
}

MarchingCubesOptions marchingCubesOptions(const HandMesherConfig& c) {
  MarchingCubesOptions o;
  o.iso = isoByteLevel(c.iso);
  if (c.mode == "binary")
    o.mode = MeshingMode::kBinary;
  else if (c.mode != "probabilistic")
    throw std::invalid_argument("mode: must be 'probabilistic' or 'binary', not '" + c.mode + "'");
  o.close_at_border = c.close_at_border;
  if (c.threads < 0) throw std::invalid_argument("threads: must be >= 0");
  o.threads = c.threads;
  if (c.min_component_triangles < 0) throw std::invalid_argument("min_component_triangles: must be >= 0");
  if (!(std::isfinite(c.keep_radius) && c.keep_radius >= 0.0))
    throw std::invalid_argument("keep_radius: must be >= 0 m (0 keeps every component)");
  if (!(c.marker_color.minCoeff() >= 0.0 && c.marker_color.maxCoeff() <= 1.0))
    throw std::invalid_argument("marker_color: each of r, g, b, a must lie in [0, 1]");
  if (c.world_frame.empty()) throw std::invalid_argument("world_frame: must not be empty");
  return o;
}

HandMesherConfig loadHandMesherConfig(const std::string& path) {
  HandMesherConfig c;
  tabletop_common::ConfigSchema schema;
  addHandMesherKeys(&c, &schema);
  schema.loadFile(path);
  try {
    marchingCubesOptions(c);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  return c;
}

}  // namespace cvephands
