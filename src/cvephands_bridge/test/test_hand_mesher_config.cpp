// config/hand_mesher.yaml through the strict loader: the shipped file holds the defaults, a bad
// file names itself and the key, and the byte iso level is the half-integer of the thesis' 0.6.
#include <string>

#include <gtest/gtest.h>

#include "cvephands_bridge/mesh/hand_mesher_config.h"
#include "tabletop_common/config_test_support.h"

namespace cvephands {
namespace {

std::string errorOf(const std::string& text) {
  return tabletop_common::config_test::errorOf([](const std::string& p) { loadHandMesherConfig(p); }, text);
}

TEST(HandMesherConfig, ShippedFileHoldsTheDefaults) {
  const std::string path = std::string(CVEPHANDS_CONFIG_DIR) + "/hand_mesher.yaml";
  const HandMesherConfig c = loadHandMesherConfig(path), d;
  tabletop_common::ConfigSchema schema;
  HandMesherConfig scratch;
  addHandMesherKeys(&scratch, &schema);
  EXPECT_TRUE(tabletop_common::config_test::keysMissingFrom(schema, path).empty());
  EXPECT_EQ(c.iso, d.iso);
  EXPECT_EQ(c.mode, d.mode);
  EXPECT_EQ(c.close_at_border, d.close_at_border);
  EXPECT_EQ(c.min_component_triangles, d.min_component_triangles);
  EXPECT_EQ(c.keep_radius, d.keep_radius);
  EXPECT_EQ(c.threads, d.threads);
  EXPECT_EQ(c.publish_markers, d.publish_markers);
  EXPECT_EQ(c.marker_color, d.marker_color);
  EXPECT_EQ(c.world_frame, d.world_frame);
  // floor(255 * 0.6) + 0.5: no uint8 sample equals the level.
  EXPECT_FLOAT_EQ(marchingCubesOptions(c).iso, 153.5f);
  EXPECT_EQ(marchingCubesOptions(c).mode, MeshingMode::kProbabilistic);
}

TEST(HandMesherConfig, BadFilesNameTheFileAndTheKey) {
  EXPECT_NE(errorOf("isolevel: 0.5\n").find("isolevel: unknown key"), std::string::npos);
  EXPECT_NE(errorOf("iso: 1.5\n").find("iso: must be a probability"), std::string::npos);
  EXPECT_NE(errorOf("iso: high\n").find("iso: wrong type"), std::string::npos);
  EXPECT_NE(errorOf("mode: smooth\n").find("mode: must be"), std::string::npos);
  EXPECT_NE(errorOf("keep_radius: -0.1\n").find("keep_radius: must be >= 0"), std::string::npos);
  EXPECT_NE(errorOf("marker_color: [1, 0, 0]\n").find("marker_color: expected a list of 4"), std::string::npos);
  EXPECT_NE(errorOf("marker_color: [1, 0, 0, 2]\n").find("marker_color: each of"), std::string::npos);
  EXPECT_THROW(isoByteLevel(0.0), std::invalid_argument);
  EXPECT_FLOAT_EQ(isoByteLevel(0.999), 254.5f);  // below the top byte value
}

}  // namespace
}  // namespace cvephands
