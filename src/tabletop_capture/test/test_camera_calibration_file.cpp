// camera_calibration's YAML as a camera_info source: read, and refused naming file and field.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "tabletop_capture/camera_calibration_file.h"
#include "tabletop_capture/rig_description.h"

using namespace tabletop_capture;

namespace {

const char* const kGood = R"(image_width: 320
image_height: 240
camera_name: some_camera
camera_matrix:
  rows: 3
  cols: 3
  data: [300.5, 0, 161.25, 0, 301.5, 119.75, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.1, 0.02, 0.001, -0.002, 0.0005]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [300.5, 0, 161.25, 0, 0, 301.5, 119.75, 0, 0, 0, 1, 0]
)";

std::string write(const std::string& text) {
  const std::string path = "/tmp/test_calib_" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(path) << text;
  return path;
}

std::string errorOf(const std::string& text) {
  const std::string path = write(text);
  std::string what;
  try {
    loadCameraCalibrationYaml(path, "cam0");
  } catch (const RigError& e) {
    what = e.what();
    EXPECT_EQ(what.rfind(path, 0), 0u) << what;
  }
  std::remove(path.c_str());
  return what;
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const size_t at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

}  // namespace

TEST(CameraCalibrationFile, ReadsCameraCalibrationsFormat) {
  const std::string path = write(kGood);
  for (const std::string& p : {path, "file://" + path}) {
    const CameraModel c = loadCameraCalibrationYaml(p, "cam3");
    EXPECT_EQ(c.name, "cam3");
    EXPECT_EQ(c.frame_id, "cam3_optical_frame");
    EXPECT_EQ(c.width, 320);
    EXPECT_EQ(c.height, 240);
    EXPECT_EQ(c.fx, 300.5);
    EXPECT_EQ(c.fy, 301.5);
    EXPECT_EQ(c.cx, 161.25);
    EXPECT_EQ(c.cy, 119.75);
    EXPECT_EQ(c.distortion[0], -0.1);
    EXPECT_EQ(c.distortion[4], 0.0005);
  }
  std::remove(path.c_str());
}

TEST(CameraCalibrationFile, BadFilesNameTheFileAndTheField) {
  EXPECT_NE(errorOf(replaced(kGood, "image_width: 320\n", "")).find("'image_width': missing"), std::string::npos);
  EXPECT_NE(errorOf(replaced(kGood, "data: [300.5, 0, 161.25, 0, 301.5, 119.75, 0, 0, 1]", "data: [1, 2]"))
                .find("'camera_matrix/data': expected a list of 9"),
            std::string::npos);
  EXPECT_NE(errorOf(replaced(kGood, "data: [300.5, 0, 161.25, 0, 301.5, 119.75, 0, 0, 1]",
                             "data: [0, 0, 161.25, 0, 301.5, 119.75, 0, 0, 1]"))
                .find("fx"),
            std::string::npos);
  EXPECT_NE(errorOf(replaced(kGood, "plumb_bob", "equidistant")).find("'distortion_model'"), std::string::npos);
  EXPECT_NE(errorOf("[1, 2]\n").find("expected a map"), std::string::npos);
  EXPECT_NE(errorOf(replaced(kGood, "data: [-0.1, 0.02, 0.001, -0.002, 0.0005]", "data: [-0.1]"))
                .find("distortion_coefficients/data"),
            std::string::npos);
}
