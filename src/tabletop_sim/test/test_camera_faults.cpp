// The fault-injection commands of the simulated rig (camera_faults.h): parsing, timing,
// per-camera effects, clear, and clear errors for bad commands.
#include <gtest/gtest.h>

#include <stdexcept>

#include "tabletop_sim/camera_faults.h"

namespace tabletop_sim {
namespace {

TEST(CameraFaults, CommandsApplyToTheirCameraForTheirTime) {
  CameraFaults f(4);
  f.command("stop 2 2.0", 10.0);
  f.command("encoding 1 bgr8 1", 10.0);
  f.command("size all 160 120 0.5", 10.0);
  f.command("nan_info 3 0", 10.0);  // until clear
  f.command("brightness 1.4 3", 11.0);
  EXPECT_TRUE(f.effect(2, 11.9).drop);
  EXPECT_FALSE(f.effect(2, 12.0).drop);  // [start, start + 2 s)
  EXPECT_FALSE(f.effect(0, 11.0).drop);
  EXPECT_EQ(f.effect(1, 10.5).encoding, "bgr8");
  EXPECT_EQ(f.effect(1, 11.5).encoding, "");
  EXPECT_EQ(f.effect(0, 10.2).width, 160);
  EXPECT_EQ(f.effect(3, 10.2).height, 120);
  EXPECT_EQ(f.effect(3, 10.6).width, 0);
  EXPECT_TRUE(f.effect(3, 1000.0).nan_info);
  EXPECT_FALSE(f.effect(2, 1000.0).nan_info);
  EXPECT_DOUBLE_EQ(f.effect(0, 10.9).gain, 1.0);  // not yet
  EXPECT_DOUBLE_EQ(f.effect(0, 11.0).gain, 1.4);
  EXPECT_DOUBLE_EQ(f.effect(2, 13.99).gain, 1.4);
  EXPECT_FALSE(f.effect(0, 20.0).any());
  EXPECT_EQ(f.describe(11.5), "stop cam2, nan_info cam3, brightness");
  f.command("clear", 12.0);
  EXPECT_FALSE(f.effect(3, 12.0).any());
  EXPECT_EQ(f.describe(12.0), "");
}

TEST(CameraFaults, FrameTfAndClockFaults) {
  CameraFaults f(4);
  f.command("frame 1 cam1_unknown_frame 2", 10.0);
  f.command("tf 2 0.01 -0.02 0 1", 10.0);
  f.command("clock -30 0", 10.5);
  EXPECT_EQ(f.effect(1, 11.0).frame_id, "cam1_unknown_frame");
  EXPECT_EQ(f.effect(1, 12.0).frame_id, "");
  EXPECT_EQ(f.effect(0, 11.0).frame_id, "");
  EXPECT_TRUE(f.effect(2, 10.5).tfShifted());
  EXPECT_DOUBLE_EQ(f.effect(2, 10.5).tf_shift[1], -0.02);
  EXPECT_FALSE(f.effect(2, 11.0).tfShifted());
  EXPECT_FALSE(f.effect(2, 10.5).any());  // not an image fault
  EXPECT_DOUBLE_EQ(f.clockOffset(10.4), 0.0);
  EXPECT_DOUBLE_EQ(f.clockOffset(100.0), -30.0);  // until clear
  EXPECT_EQ(f.describe(10.6), "frame cam1, tf cam2, clock");
  f.command("clear", 101.0);
  EXPECT_DOUBLE_EQ(f.clockOffset(101.0), 0.0);
}

TEST(CameraFaults, BadCommandsAreRefusedWithTheReason) {
  CameraFaults f(2);
  const auto refused = [&](const char* c, const char* why) {
    try {
      f.command(c, 0.0);
      ADD_FAILURE() << "accepted: " << c;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  refused("", "empty");
  refused("explode 0 1", "unknown command");
  refused("stop 2 1", "camera must be 0..1");
  refused("stop -1 1", "camera must be");
  refused("stop 0", "missing seconds");
  refused("stop 0 x", "bad seconds");
  refused("stop 0 -1", ">= 0");
  refused("encoding 0 yuv422 1", "encoding must be");
  refused("size 0 0 10 1", "size out of range");
  refused("brightness 0 1", "gain must be");
  refused("brightness nan 1", "bad gain");
  refused("frame 0", "missing frame_id");
  refused("tf 0 0 0 1", "missing seconds");
  refused("tf 0 11 0 0 1", "within 10 m");
  refused("clock x 1", "bad offset");
  refused("stop 0 1 extra", "unexpected");
  EXPECT_FALSE(f.effect(0, 0.5).any());  // nothing half-applied
}

}  // namespace
}  // namespace tabletop_sim
