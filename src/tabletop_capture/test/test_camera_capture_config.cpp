// config/camera_capture.yaml through the strict loader: the shipped file holds the defaults,
// bad files name themselves and the key, and the rig camera must have the published size.
#include <string>

#include <gtest/gtest.h>

#include "tabletop_capture/camera_capture_config.h"
#include "tabletop_common/config_test_support.h"

namespace tabletop_capture {
namespace {

std::string errorOf(const std::string& text) {
  return tabletop_common::config_test::errorOf([](const std::string& p) { loadCameraCaptureConfig(p); },
                                               text);
}

TEST(CameraCaptureConfig, ShippedFileHoldsTheDefaults) {
  const std::string path = std::string(TABLETOP_CAPTURE_CONFIG_DIR) + "/camera_capture.yaml";
  const CameraCaptureConfig c = loadCameraCaptureConfig(path), d;
  tabletop_common::ConfigSchema schema;
  CameraCaptureConfig scratch;
  addCameraCaptureKeys(&scratch, &schema);
  EXPECT_TRUE(tabletop_common::config_test::keysMissingFrom(schema, path).empty());
  EXPECT_EQ(c.device, d.device);
  EXPECT_EQ(c.camera_name, d.camera_name);
  EXPECT_EQ(c.rig_file, d.rig_file);
  EXPECT_EQ(c.camera_info_file, d.camera_info_file);
  EXPECT_EQ(c.width, d.width);
  EXPECT_EQ(c.height, d.height);
  EXPECT_EQ(c.fps, d.fps);
  EXPECT_EQ(c.fourcc, d.fourcc);
  EXPECT_EQ(c.exposure, d.exposure);
  EXPECT_EQ(c.gain, d.gain);
  EXPECT_EQ(c.white_balance, d.white_balance);
  EXPECT_EQ(c.bayer, d.bayer);
  EXPECT_EQ(c.half_resolution, d.half_resolution);
  EXPECT_EQ(c.loop, d.loop);
  EXPECT_EQ(c.trigger, d.trigger);
  EXPECT_EQ(c.reopen_interval, d.reopen_interval);
  EXPECT_EQ(c.queue_size, d.queue_size);
}

TEST(CameraCaptureConfig, BadFilesNameTheFileAndTheKey) {
  EXPECT_NE(errorOf("devise: /dev/video0\n").find("devise: unknown key"), std::string::npos);
  EXPECT_NE(errorOf("fps: 0\n").find("fps: must"), std::string::npos);
  EXPECT_NE(errorOf("width: wide\n").find("width: wrong type"), std::string::npos);
  EXPECT_NE(errorOf("bayer: rgbg\n").find("bayer: must be"), std::string::npos);
  EXPECT_NE(errorOf("half_resolution: true\n").find("half_resolution: needs a Bayer"), std::string::npos);
  EXPECT_NE(errorOf("bayer: rggb\nhalf_resolution: true\nwidth: 641\n").find("even"), std::string::npos);
  EXPECT_NE(errorOf("trigger: hardware\n").find("trigger: must be none or external"), std::string::npos);
  EXPECT_NE(errorOf("fourcc: YUV\n").find("fourcc"), std::string::npos);
  EXPECT_NE(errorOf("reopen_interval: 0\n").find("reopen_interval"), std::string::npos);
  EXPECT_NE(errorOf("camera_name: a/b\n").find("camera_name"), std::string::npos);
  EXPECT_NE(errorOf("rig_file: a.yaml\ncamera_info_file: b.yaml\n").find("not both"), std::string::npos);
}

TEST(CameraCaptureConfig, RigCameraMustHaveThePublishedSize) {
  CameraCaptureConfig c;
  c.bayer = "rggb";
  c.half_resolution = true;
  CameraModel cam;
  cam.name = "cam0";
  cam.width = 320;
  cam.height = 240;
  EXPECT_EQ(checkRigCameraSize(cam, c, "rig.yaml"), "");
  cam.width = 640;
  cam.height = 480;
  const std::string e = checkRigCameraSize(cam, c, "rig.yaml");
  EXPECT_NE(e.find("rig.yaml: camera 'cam0' is calibrated for 640x480 but the nodelet publishes 320x240"),
            std::string::npos) << e;
  EXPECT_NE(e.find("half_resolution"), std::string::npos) << e;
  c.half_resolution = false;
  EXPECT_EQ(checkRigCameraSize(cam, c, "rig.yaml"), "");
}

TEST(CameraCaptureConfig, SourceSettingsFollowTheConfig) {
  CameraCaptureConfig c;
  c.device = "file:/tmp/x_%04d.png";
  c.bayer = "gbrg";
  c.trigger = "external";
  c.validate();
  const FrameSourceSettings s = c.sourceSettings();
  EXPECT_TRUE(s.raw);
  EXPECT_TRUE(s.external_trigger);
  EXPECT_EQ(s.device, c.device);
  EXPECT_EQ(c.bayerPattern(), BayerPattern::kGBRG);
}

}  // namespace
}  // namespace tabletop_capture
