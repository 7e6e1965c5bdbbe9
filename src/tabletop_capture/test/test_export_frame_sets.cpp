// exportFrameSets (ros/frame_set_export.h) on bags written here (rosbag::Bag writes the file, no
// ROS master): 5 sets of 3 cameras (rgb8, bgr8, bayer_rggb8), set 2 degraded (cam1 empty), set 4
// with an image cam2 cannot convert, and an unrelated raw camera topic.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <rosbag/bag.h>
#include <sensor_msgs/Image.h>
#include <tabletop_msgs/MultiViewFrame.h>

#include "tabletop_capture/ros/frame_set_export.h"

namespace fs = std::filesystem;
using tabletop_capture::exportFrameSets;
using tabletop_capture::FrameSetExportOptions;
using tabletop_capture::FrameSetExportResult;

namespace {

constexpr int kW = 8, kH = 6, kSets = 5;
const cv::Vec3b kBayerRgb(200, 100, 50);  // the flat colour of cam2's mosaic, R,G,B

sensor_msgs::Image image(const std::string& encoding, int bpp) {
  sensor_msgs::Image m;
  m.encoding = encoding;
  m.width = kW;
  m.height = kH;
  m.step = kW * bpp;
  m.data.resize(m.step * kH);
  return m;
}

tabletop_msgs::MultiViewFrame frameSet(int i) {
  tabletop_msgs::MultiViewFrame f;
  f.header.stamp = ros::Time(100, i * 100000000u);
  f.header.frame_id = "world";
  f.camera_names = {"cam0", "cam1", "cam2"};
  // cam0 rgb8: R = 10 + x + i, G = 20 + y, B = 30
  sensor_msgs::Image rgb = image("rgb8", 3);
  // cam1 bgr8: R = 60 + x, G = 50 + y, B = 40 + i (stored B,G,R)
  sensor_msgs::Image bgr = image("bgr8", 3);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      uint8_t* p = &rgb.data[y * rgb.step + 3 * x];
      p[0] = 10 + x + i, p[1] = 20 + y, p[2] = 30;
      uint8_t* q = &bgr.data[y * bgr.step + 3 * x];
      q[0] = 40 + i, q[1] = 50 + y, q[2] = 60 + x;
    }
  // cam2 bayer_rggb8 of a flat colour
  sensor_msgs::Image bayer = image("bayer_rggb8", 1);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      bayer.data[y * bayer.step + x] = kBayerRgb[(y % 2) + (x % 2)];  // r g / g b
  if (i == 2) bgr = sensor_msgs::Image();  // degraded set: cam1 delivered nothing
  if (i == 4) bayer.encoding = "mono16";   // cannot be converted
  f.images = {rgb, bgr, bayer};
  f.camera_infos.resize(3);
  f.camera_poses.resize(3);
  return f;
}

class ExportFrameSets : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/test_export_frame_sets_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    bag_ = dir_ + "/sets.bag";
    rosbag::Bag bag(bag_, rosbag::bagmode::Write);
    for (int i = 0; i < kSets; ++i) {
      const auto f = frameSet(i);
      bag.write("/tabletop/frames", f.header.stamp, f);
      bag.write("/camera/cam0/image_raw", f.header.stamp, f.images[0]);
    }
  }
  void TearDown() override { fs::remove_all(dir_); }

  static std::string readFile(const std::string& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  static std::string errorOf(const std::string& bag, const std::string& out,
                             const FrameSetExportOptions& o) {
    try {
      exportFrameSets(bag, out, o);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "(no error)";
  }

  std::string dir_, bag_;
};

TEST_F(ExportFrameSets, WritesOneFilePerCameraAndSetWithRightColours) {
  const std::string out = dir_ + "/out";
  std::vector<std::string> log;
  const FrameSetExportResult r =
      exportFrameSets(bag_, out, FrameSetExportOptions(), [&](const std::string& l) { log.push_back(l); });
  EXPECT_EQ(r.sets_read, 5);
  EXPECT_EQ(r.sets_written, 5);
  ASSERT_EQ(r.cameras.size(), 3u);
  EXPECT_EQ(r.cameras[0].name, "cam0");
  EXPECT_EQ(r.cameras[0].written, 5);
  EXPECT_EQ(r.cameras[1].written, 4);
  EXPECT_EQ(r.cameras[1].missing, 1);
  EXPECT_EQ(r.cameras[2].written, 4);
  EXPECT_EQ(r.cameras[2].failed, 1);
  EXPECT_EQ(r.conversion_failures, 1);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("set 4, camera cam2"), std::string::npos) << r.warnings[0];
  ASSERT_EQ(log.size(), 1u);  // the warning; no progress line below 50 sets
  EXPECT_EQ(log[0], "WARNING: " + r.warnings[0]);

  for (int i = 0; i < kSets; ++i) {
    char name[16];
    std::snprintf(name, sizeof name, "%05d.png", i);
    EXPECT_TRUE(fs::exists(out + "/cam0/" + name)) << name;
    EXPECT_EQ(fs::exists(out + "/cam1/" + name), i != 2) << name;
    EXPECT_EQ(fs::exists(out + "/cam2/" + name), i != 4) << name;
  }
  EXPECT_FALSE(fs::exists(out + "/camera"));  // the other topic is not read

  // Colour order: PNGs read back as B,G,R.
  const cv::Mat c0 = cv::imread(out + "/cam0/00003.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(c0.type(), CV_8UC3);
  ASSERT_EQ(c0.size(), cv::Size(kW, kH));
  const cv::Mat c1 = cv::imread(out + "/cam1/00003.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(c1.type(), CV_8UC3);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      EXPECT_EQ(c0.at<cv::Vec3b>(y, x), cv::Vec3b(30, 20 + y, 10 + x + 3)) << x << "," << y;
      EXPECT_EQ(c1.at<cv::Vec3b>(y, x), cv::Vec3b(40 + 3, 50 + y, 60 + x)) << x << "," << y;
    }
  // The Bayer mosaic of a flat colour is demosaiced to that colour.
  const cv::Mat c2 = cv::imread(out + "/cam2/00000.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(c2.type(), CV_8UC3);
  ASSERT_EQ(c2.size(), cv::Size(kW, kH));
  const cv::Vec3b bgr(kBayerRgb[2], kBayerRgb[1], kBayerRgb[0]);
  for (int y = 2; y < kH - 2; ++y)
    for (int x = 2; x < kW - 2; ++x) EXPECT_EQ(c2.at<cv::Vec3b>(y, x), bgr) << x << "," << y;

  EXPECT_EQ(readFile(out + "/stamps.csv"),
            "index,stamp,cameras\n"
            "0,100.000000000,cam0 cam1 cam2\n"
            "1,100.100000000,cam0 cam1 cam2\n"
            "2,100.200000000,cam0 cam2\n"
            "3,100.300000000,cam0 cam1 cam2\n"
            "4,100.400000000,cam0 cam1\n");
}

TEST_F(ExportFrameSets, EveryNthSetAndCameraFilterKeepTheSetIndex) {
  const std::string out = dir_ + "/every2";
  FrameSetExportOptions o;
  o.every = 2;
  o.cameras = {"cam2", "cam0"};
  const auto r = exportFrameSets(bag_, out, o);
  EXPECT_EQ(r.sets_read, 5);
  EXPECT_EQ(r.sets_written, 3);
  ASSERT_EQ(r.cameras.size(), 2u);
  EXPECT_EQ(r.cameras[0].name, "cam0");
  EXPECT_EQ(r.cameras[1].name, "cam2");
  EXPECT_FALSE(fs::exists(out + "/cam1"));
  for (const char* f : {"00000.png", "00002.png", "00004.png"})
    EXPECT_TRUE(fs::exists(out + "/cam0/" + f)) << f;
  for (const char* f : {"00001.png", "00003.png"}) EXPECT_FALSE(fs::exists(out + "/cam0/" + f)) << f;
  EXPECT_TRUE(fs::exists(out + "/cam2/00002.png"));
  EXPECT_FALSE(fs::exists(out + "/cam2/00004.png"));  // conversion failure
  EXPECT_EQ(readFile(out + "/stamps.csv"),
            "index,stamp,cameras\n"
            "0,100.000000000,cam0 cam2\n"
            "2,100.200000000,cam0 cam2\n"
            "4,100.400000000,cam0\n");

  FrameSetExportOptions m;
  m.every = 2;
  m.max_sets = 2;
  const auto r2 = exportFrameSets(bag_, dir_ + "/max2", m);
  EXPECT_EQ(r2.sets_written, 2);
  EXPECT_TRUE(fs::exists(dir_ + "/max2/cam0/00002.png"));
  EXPECT_FALSE(fs::exists(dir_ + "/max2/cam0/00004.png"));
}

TEST_F(ExportFrameSets, ErrorsNameTheCause) {
  const FrameSetExportOptions o;
  EXPECT_NE(errorOf(dir_ + "/absent.bag", dir_ + "/o", o).find("cannot read bag"), std::string::npos);

  FrameSetExportOptions wrong;
  wrong.topic = "/frames";
  const std::string absent = errorOf(bag_, dir_ + "/o", wrong);
  EXPECT_NE(absent.find("no topic /frames"), std::string::npos) << absent;
  EXPECT_NE(absent.find("/tabletop/frames  tabletop_msgs/MultiViewFrame  (5 messages)"), std::string::npos)
      << absent;
  EXPECT_NE(absent.find("/camera/cam0/image_raw  sensor_msgs/Image"), std::string::npos) << absent;

  wrong.topic = "/camera/cam0/image_raw";
  const std::string type = errorOf(bag_, dir_ + "/o", wrong);
  EXPECT_NE(type.find("is of type sensor_msgs/Image, not tabletop_msgs/MultiViewFrame"), std::string::npos)
      << type;
  EXPECT_NE(type.find("/tabletop/frames  tabletop_msgs/MultiViewFrame"), std::string::npos) << type;

  FrameSetExportOptions cams;
  cams.cameras = {"cam0", "cam9"};
  const std::string cam = errorOf(bag_, dir_ + "/o", cams);
  EXPECT_NE(cam.find("no camera 'cam9'"), std::string::npos) << cam;
  EXPECT_FALSE(fs::exists(dir_ + "/o"));  // nothing written on an error found before writing

  std::ofstream(dir_ + "/file") << "x";  // a file where a folder must be created
  const std::string unwritable = errorOf(bag_, dir_ + "/file/out", o);
  EXPECT_NE(unwritable.find("cannot create output folder"), std::string::npos) << unwritable;

  const std::string empty_bag = dir_ + "/no_sets.bag";
  {
    rosbag::Bag b(empty_bag, rosbag::bagmode::Write);
    b.write("/camera/cam0/image_raw", ros::Time(1), frameSet(0).images[0]);
  }
  EXPECT_NE(errorOf(empty_bag, dir_ + "/o", o).find("no topic /tabletop/frames"), std::string::npos);
}

}  // namespace
