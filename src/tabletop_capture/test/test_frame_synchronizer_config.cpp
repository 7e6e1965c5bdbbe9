// config/frame_synchronizer.yaml through the strict loader: the shipped file holds the
// defaults, a bad file names itself and the key, and live tuning changes only the timing.
#include <string>

#include <gtest/gtest.h>

#include "tabletop_capture/frame_synchronizer_config.h"
#include "tabletop_common/config_test_support.h"

namespace tabletop_capture {
namespace {

std::string errorOf(const std::string& text) {
  return tabletop_common::config_test::errorOf([](const std::string& p) { loadFrameSynchronizerConfig(p); },
                                               text);
}

TEST(FrameSynchronizerConfig, ShippedFileHoldsTheDefaults) {
  const std::string path = std::string(TABLETOP_CAPTURE_CONFIG_DIR) + "/frame_synchronizer.yaml";
  const FrameSynchronizerConfig c = loadFrameSynchronizerConfig(path), d;
  tabletop_common::ConfigSchema schema;
  FrameSynchronizerConfig scratch;
  addFrameSynchronizerKeys(&scratch, &schema);
  EXPECT_TRUE(tabletop_common::config_test::keysMissingFrom(schema, path).empty());
  EXPECT_EQ(c.num_cameras, d.num_cameras);
  EXPECT_EQ(c.camera_prefix, d.camera_prefix);
  EXPECT_EQ(c.image_transport, d.image_transport);
  EXPECT_EQ(c.tolerance, d.tolerance);
  EXPECT_EQ(c.timeout, d.timeout);
  EXPECT_EQ(c.max_pending, d.max_pending);
  EXPECT_EQ(c.max_missing_cameras, d.max_missing_cameras);
  EXPECT_EQ(c.absent_after, d.absent_after);
  EXPECT_EQ(c.time_jump_threshold, d.time_jump_threshold);
  EXPECT_EQ(c.world_frame, d.world_frame);
  EXPECT_EQ(c.tf_timeout, d.tf_timeout);
  EXPECT_EQ(c.queue_size, d.queue_size);
  EXPECT_EQ(c.image_queue_size, d.image_queue_size);
  EXPECT_EQ(c.hold_until_subscribers, d.hold_until_subscribers);
  EXPECT_EQ(c.max_held, d.max_held);
}

TEST(FrameSynchronizerConfig, BadFilesNameTheFileAndTheKey) {
  EXPECT_NE(errorOf("tolerence: 0.01\n").find("tolerence: unknown key"), std::string::npos);
  EXPECT_NE(errorOf("tolerance: -0.01\n").find("tolerance: must be"), std::string::npos);
  EXPECT_NE(errorOf("num_cameras: eight\n").find("num_cameras: wrong type"), std::string::npos);
  EXPECT_NE(errorOf("max_pending: 0\n").find("max_pending: must be >= 1"), std::string::npos);
  EXPECT_NE(errorOf("camera_prefix: \"\"\n").find("camera_prefix"), std::string::npos);
  EXPECT_NE(errorOf("max_missing_cameras: -1\n").find("max_missing_cameras: must be >= 0"),
            std::string::npos);
  EXPECT_NE(errorOf("absent_after: 0\n").find("absent_after: must be >= 1"), std::string::npos);
}

// Degraded output keeps at least two views: max_missing_cameras is clamped to num_cameras - 2.
TEST(FrameSynchronizerConfig, MissingCamerasLeaveAtLeastTwoViews) {
  FrameSynchronizerConfig c;
  c.num_cameras = 8;
  c.max_missing_cameras = 2;
  EXPECT_EQ(c.assembler().max_missing, 2);
  c.num_cameras = 3;
  EXPECT_EQ(c.assembler().max_missing, 1);
  c.num_cameras = 2;
  EXPECT_EQ(c.assembler().max_missing, 0);
  c.num_cameras = 1;
  EXPECT_EQ(c.assembler().max_missing, 0);
}

// With a 15 ms tolerance, images 10 ms apart make one set; tuned to 0 (hardware sync) the next
// ones must have equal stamps. A refused value leaves the timing as it was.
TEST(FrameSynchronizerConfig, TimingIsTunedLive) {
  FrameSetAssemblerConfig a;
  a.num_cameras = 2;
  a.tolerance = 0.015;
  a.timeout = 1.0;
  FrameSetAssembler<int> asm2(a);
  asm2.add(0, 10.00, 1);
  asm2.add(1, 10.01, 2);
  EXPECT_EQ(asm2.takeCompleted().size(), 1u);
  asm2.setTiming(0.0, 1.0);
  EXPECT_THROW(asm2.setTiming(-1.0, 1.0), std::invalid_argument);
  EXPECT_EQ(asm2.config().tolerance, 0.0);
  asm2.add(0, 10.04, 3);
  asm2.add(1, 10.04, 4);
  EXPECT_EQ(asm2.takeCompleted().size(), 1u);
  asm2.add(0, 10.08, 5);
  asm2.add(1, 10.09, 6);  // within the old tolerance, not within the new one
  EXPECT_TRUE(asm2.takeCompleted().empty());
}

}  // namespace
}  // namespace tabletop_capture
