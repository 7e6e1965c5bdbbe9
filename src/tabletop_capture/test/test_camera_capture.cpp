// Integration test of the CameraCapture nodelet, hosted in this process (nodelet::Loader), on
// input it writes itself into a temp dir:
//  (a) 25 Bayer (rggb) 640x480 PNGs played as a camera at 25 fps with half_resolution: the
//      rate (within 20 % of 25 fps), strictly increasing stamps, 320x240 rgb8 images with the
//      expected colour of every pixel, and the rig camera's camera_info with the same stamps;
//  (b) the sequence's directory moved away and back: the nodelet reports the failure, opens
//      the camera again and frames resume.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "tabletop_capture/rig_description.h"
#include "tabletop_common/ros/test_support.h"

using namespace tabletop_capture;
using tabletop_common::test_support::waitFor;

namespace {

constexpr int kFrames = 25;  // one second per pass at 25 fps
constexpr double kFps = 25.0;

// Frame i, quad (qx, qy): R = (qx + 3 i) mod 256, G = qy mod 128 and that + 1 (mean rounded
// half up: qy mod 128 + 1), B = 10 i (which tells the frame).
cv::Vec3b expectedRgb(int i, int qx, int qy) {
  return cv::Vec3b(static_cast<uint8_t>((qx + 3 * i) & 255), static_cast<uint8_t>((qy & 127) + 1),
                   static_cast<uint8_t>(10 * i));
}

cv::Mat bayerFrame(int i) {
  cv::Mat m(480, 640, CV_8UC1);
  for (int qy = 0; qy < 240; ++qy)
    for (int qx = 0; qx < 320; ++qx) {
      const cv::Vec3b c = expectedRgb(i, qx, qy);
      m.at<uint8_t>(2 * qy, 2 * qx) = c[0];                                      // R
      m.at<uint8_t>(2 * qy, 2 * qx + 1) = static_cast<uint8_t>(qy & 127);         // G
      m.at<uint8_t>(2 * qy + 1, 2 * qx) = static_cast<uint8_t>((qy & 127) + 1);   // G
      m.at<uint8_t>(2 * qy + 1, 2 * qx + 1) = c[2];                              // B
    }
  return m;
}

CameraModel rigCamera() {
  CameraModel c;
  c.name = "cam0";
  c.frame_id = "cam0_optical_frame";
  c.width = 320;
  c.height = 240;
  c.fx = 300;
  c.fy = 301;
  c.cx = 160;
  c.cy = 120;
  c.distortion = {{-0.1, 0.01, 0.001, -0.002, 0}};
  c.world_T_camera.translation() = Eigen::Vector3d(0, 0, 1);
  return c;
}

struct Received {
  std::mutex m;
  std::vector<sensor_msgs::ImageConstPtr> images;
  std::vector<ros::WallTime> arrival;
  std::map<double, sensor_msgs::CameraInfoConstPtr> infos;  // by stamp
  std::vector<std::string> errors;                         // ERROR log lines of the nodelet
  size_t count() {
    std::lock_guard<std::mutex> l(m);
    return images.size();
  }
};

class CameraCaptureTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char tmpl[] = "/tmp/test_camera_capture_XXXXXX";
    root_ = ::mkdtemp(tmpl);
    dir_ = root_ + "/frames";
    std::filesystem::create_directory(dir_);
    for (int i = 0; i < kFrames; ++i) {
      char name[64];
      std::snprintf(name, sizeof(name), "/img_%04d.png", i);
      ASSERT_TRUE(cv::imwrite(dir_ + name, bayerFrame(i)));
    }
    RigDescription rig;
    rig.cameras.push_back(rigCamera());
    saveRigYaml(rig, root_ + "/rig.yaml");
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(root_); }

  static std::string root_, dir_;
};
std::string CameraCaptureTest::root_, CameraCaptureTest::dir_;

}  // namespace

TEST_F(CameraCaptureTest, BayerSequenceAtHalfResolutionThenVanishAndReturn) {
  Received rx;
  ros::NodeHandle nh;
  boost::function<void(const sensor_msgs::ImageConstPtr&)> on_image = [&rx](const sensor_msgs::ImageConstPtr& m) {
    std::lock_guard<std::mutex> l(rx.m);
    rx.images.push_back(m);
    rx.arrival.push_back(ros::WallTime::now());
  };
  boost::function<void(const sensor_msgs::CameraInfoConstPtr&)> on_info =
      [&rx](const sensor_msgs::CameraInfoConstPtr& m) {
        std::lock_guard<std::mutex> l(rx.m);
        rx.infos[m->header.stamp.toSec()] = m;
      };
  boost::function<void(const rosgraph_msgs::LogConstPtr&)> on_log = [&rx](const rosgraph_msgs::LogConstPtr& m) {
    if (m->level < rosgraph_msgs::Log::ERROR || m->msg.find("camera capture cam0") == std::string::npos) return;
    std::lock_guard<std::mutex> l(rx.m);
    rx.errors.push_back(m->msg);
  };
  ros::Subscriber image_sub = nh.subscribe<sensor_msgs::Image>("/tabletop/cam0/image_raw", 200, on_image);
  ros::Subscriber info_sub = nh.subscribe<sensor_msgs::CameraInfo>("/tabletop/cam0/camera_info", 200, on_info);
  ros::Subscriber log_sub = nh.subscribe<rosgraph_msgs::Log>("/rosout", 200, on_log);
  tabletop_common::test_support::DiagnosticsValues diag("cam0_capture");

  const std::string ns = "/tabletop/cam0_capture/";
  ros::param::set(ns + "device", "file:" + dir_ + "/img_%04d.png");
  ros::param::set(ns + "camera_name", std::string("cam0"));
  ros::param::set(ns + "rig_file", root_ + "/rig.yaml");
  ros::param::set(ns + "fps", kFps);
  ros::param::set(ns + "bayer", std::string("rggb"));
  ros::param::set(ns + "half_resolution", true);
  ros::param::set(ns + "loop", true);
  ros::param::set(ns + "reopen_interval", 0.5);
  ASSERT_TRUE(tabletop_common::test_support::loadNodelet("/tabletop/cam0_capture", "tabletop_capture/CameraCapture"));

  // (a) A little over three passes of the sequence.
  constexpr size_t kWanted = 80;  // 3.2 passes: the files vanish in the middle of a pass
  ASSERT_TRUE(waitFor([&] { return rx.count() >= kWanted; }, 20.0))
      << "only " << rx.count() << " images in 20 s";
  // An image and its camera_info come on two topics: the info of the last images taken may
  // still be on its way (a race of the test, seen once under load), so wait for it a moment.
  waitFor([&] {
    std::lock_guard<std::mutex> l(rx.m);
    for (size_t k = 0; k < kWanted; ++k)
      if (!rx.infos.count(rx.images[k]->header.stamp.toSec())) return false;
    return true;
  }, 5.0);
  std::vector<sensor_msgs::ImageConstPtr> images;
  std::map<double, sensor_msgs::CameraInfoConstPtr> infos;
  {
    std::lock_guard<std::mutex> l(rx.m);
    images.assign(rx.images.begin(), rx.images.begin() + kWanted);
    infos = rx.infos;
  }
  const CameraModel cam = rigCamera();
  int wrong_pixels = 0, missing_info = 0;
  std::set<int> frames_seen;
  for (size_t k = 0; k < images.size(); ++k) {
    const sensor_msgs::Image& im = *images[k];
    ASSERT_EQ(im.encoding, "rgb8");
    ASSERT_EQ(im.width, 320u);
    ASSERT_EQ(im.height, 240u);
    ASSERT_EQ(im.step, 960u);
    ASSERT_EQ(im.data.size(), 960u * 240u);
    EXPECT_EQ(im.header.frame_id, "cam0_optical_frame");
    if (k > 0) {
      EXPECT_GT(im.header.stamp, images[k - 1]->header.stamp) << "image " << k;
    }
    const int i = im.data[2] / 10;  // B of quad (0, 0) tells the frame
    ASSERT_LT(i, kFrames);
    frames_seen.insert(i);
    // Consecutive frames of the sequence (looping), none skipped or repeated.
    if (k > 0) {
      EXPECT_EQ(i, (images[k - 1]->data[2] / 10 + 1) % kFrames) << "image " << k;
    }
    for (int qy = 0; qy < 240; ++qy)
      for (int qx = 0; qx < 320; ++qx) {
        const uint8_t* p = &im.data[qy * 960 + qx * 3];
        const cv::Vec3b e = expectedRgb(i, qx, qy);
        wrong_pixels += p[0] != e[0] || p[1] != e[1] || p[2] != e[2];
      }
    auto it = infos.find(im.header.stamp.toSec());
    if (it == infos.end()) {
      ++missing_info;
      continue;
    }
    const sensor_msgs::CameraInfo& ci = *it->second;
    EXPECT_EQ(ci.header.stamp, im.header.stamp);
    EXPECT_EQ(ci.header.frame_id, "cam0_optical_frame");
    EXPECT_EQ(ci.width, 320u);
    EXPECT_EQ(ci.height, 240u);
    EXPECT_EQ(ci.K[0], cam.fx);
    EXPECT_EQ(ci.K[2], cam.cx);
    EXPECT_EQ(ci.K[4], cam.fy);
    EXPECT_EQ(ci.K[5], cam.cy);
    ASSERT_EQ(ci.D.size(), 5u);
    for (int d = 0; d < 5; ++d) EXPECT_EQ(ci.D[d], cam.distortion[d]);
  }
  EXPECT_EQ(wrong_pixels, 0);
  EXPECT_EQ(missing_info, 0) << "images without a camera_info of the same stamp";
  EXPECT_EQ(frames_seen.size(), static_cast<size_t>(kFrames));
  const double span = (images.back()->header.stamp - images.front()->header.stamp).toSec();
  const double rate = (images.size() - 1) / span;
  EXPECT_NEAR(rate, kFps, 0.2 * kFps) << "measured from the stamps";
  ASSERT_TRUE(waitFor([&] { return !diag.get("rate (Hz)").empty() && !diag.get("jitter (ms)").empty(); }, 5.0));
  std::printf("[capture] stamps: %zu images, %.3f Hz; nodelet diagnostics: rate %s Hz, jitter %s ms, "
              "dropped (total) %s, state %s\n",
              images.size(), rate, diag.get("rate (Hz)").c_str(), diag.get("jitter (ms)").c_str(),
              diag.get("dropped frames (total)").c_str(), diag.get("state").c_str());
  EXPECT_NEAR(std::stod(diag.get("rate (Hz)")), kFps, 0.2 * kFps);
  EXPECT_EQ(diag.get("accepted width"), "640");
  EXPECT_EQ(diag.get("accepted height"), "480");

  // (b) The camera vanishes: its files are moved away.
  const std::string away = root_ + "/frames_away";
  ASSERT_EQ(std::rename(dir_.c_str(), away.c_str()), 0);
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> l(rx.m);
    return !rx.errors.empty();
  }, 10.0)) << "no ERROR from the nodelet about the vanished camera";
  {
    std::lock_guard<std::mutex> l(rx.m);
    std::printf("[capture] reported: %s\n", rx.errors.front().c_str());
    EXPECT_NE(rx.errors.front().find(dir_), std::string::npos) << "names the device: " << rx.errors.front();
  }
  ASSERT_TRUE(waitFor([&] { return diag.get("state") == "unavailable" || diag.get("state") == "failed"; }, 5.0))
      << "state " << diag.get("state");
  EXPECT_NE(diag.message().find("re-opening"), std::string::npos) << diag.message();
  // Nothing is published while it is away (at most a frame already in flight).
  const size_t while_away = rx.count();
  ros::WallDuration(1.0).sleep();
  EXPECT_LE(rx.count(), while_away + 1);

  // It comes back: re-opened (within reopen_interval) and frames resume.
  ASSERT_EQ(std::rename(away.c_str(), dir_.c_str()), 0);
  const size_t before = rx.count();
  ASSERT_TRUE(waitFor([&] { return rx.count() >= before + 25; }, 10.0))
      << "frames did not resume: " << rx.count() - before << " after the files came back";
  ASSERT_TRUE(waitFor([&] { return diag.get("state") == "capturing" && diag.get("reopens") != "0"; }, 5.0))
      << "state " << diag.get("state") << ", reopens " << diag.get("reopens");
  {
    std::lock_guard<std::mutex> l(rx.m);
    for (size_t k = before + 1; k < rx.images.size(); ++k)
      EXPECT_GT(rx.images[k]->header.stamp, rx.images[k - 1]->header.stamp);
    EXPECT_EQ(rx.images.back()->width, 320u);
  }
  std::printf("[capture] after the return: reopens %s, failures %s, rate %s Hz, jitter %s ms\n",
              diag.get("reopens").c_str(), diag.get("failures").c_str(), diag.get("rate (Hz)").c_str(),
              diag.get("jitter (ms)").c_str());
  // Unloaded here, before TearDownTestSuite removes its files.
  tabletop_common::test_support::loader().clear();
}

// A rig that describes the full-size camera cannot calibrate half-resolution images: the
// nodelet refuses to start, saying so on /diagnostics, and publishes nothing.
TEST_F(CameraCaptureTest, HalfResolutionRefusesARigOfTheFullSize) {
  CameraModel full = rigCamera();
  full.name = "cam1";
  full.frame_id = "cam1_optical_frame";
  full.width = 640;
  full.height = 480;
  RigDescription rig;
  rig.cameras.push_back(full);
  saveRigYaml(rig, root_ + "/rig_full.yaml");
  tabletop_common::test_support::DiagnosticsValues diag("cam1_capture");
  ros::NodeHandle nh;
  int images = 0;
  boost::function<void(const sensor_msgs::ImageConstPtr&)> on_image = [&images](const sensor_msgs::ImageConstPtr&) {
    ++images;
  };
  ros::Subscriber sub = nh.subscribe<sensor_msgs::Image>("/tabletop/cam1/image_raw", 10, on_image);
  const std::string ns = "/tabletop/cam1_capture/";
  ros::param::set(ns + "device", "file:" + dir_ + "/img_%04d.png");
  ros::param::set(ns + "camera_name", std::string("cam1"));
  ros::param::set(ns + "rig_file", root_ + "/rig_full.yaml");
  ros::param::set(ns + "bayer", std::string("rggb"));
  ros::param::set(ns + "half_resolution", true);
  ASSERT_TRUE(tabletop_common::test_support::loadNodelet("/tabletop/cam1_capture", "tabletop_capture/CameraCapture"));
  ASSERT_TRUE(waitFor([&] { return diag.message().find("not started") != std::string::npos; }, 5.0))
      << diag.message();
  EXPECT_NE(diag.message().find("camera 'cam1' is calibrated for 640x480 but the nodelet publishes 320x240"),
            std::string::npos) << diag.message();
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(images, 0);
  EXPECT_EQ(sub.getNumPublishers(), 0u);
  tabletop_common::test_support::loader().clear();
}

// Without a rig: images (the Bayer files read as they are, bayer: none) but no camera_info,
// and a warning that says so.
TEST_F(CameraCaptureTest, WithoutARigNoCameraInfoIsPublished) {
  ros::NodeHandle nh;
  std::mutex m;
  std::vector<sensor_msgs::ImageConstPtr> images;
  std::vector<std::string> warnings;
  boost::function<void(const sensor_msgs::ImageConstPtr&)> on_image = [&](const sensor_msgs::ImageConstPtr& i) {
    std::lock_guard<std::mutex> l(m);
    images.push_back(i);
  };
  boost::function<void(const rosgraph_msgs::LogConstPtr&)> on_log = [&](const rosgraph_msgs::LogConstPtr& l) {
    if (l->level != rosgraph_msgs::Log::WARN || l->msg.find("camera capture cam2") == std::string::npos) return;
    std::lock_guard<std::mutex> g(m);
    warnings.push_back(l->msg);
  };
  ros::Subscriber sub = nh.subscribe<sensor_msgs::Image>("/tabletop/cam2/image_raw", 50, on_image);
  ros::Subscriber info_sub = nh.subscribe<sensor_msgs::CameraInfo>("/tabletop/cam2/camera_info", 10,
      boost::function<void(const sensor_msgs::CameraInfoConstPtr&)>([](const sensor_msgs::CameraInfoConstPtr&) {}));
  ros::Subscriber log_sub = nh.subscribe<rosgraph_msgs::Log>("/rosout", 100, on_log);
  const std::string ns = "/tabletop/cam2_capture/";
  ros::param::set(ns + "device", "file:" + dir_ + "/img_%04d.png");
  ros::param::set(ns + "camera_name", std::string("cam2"));
  ASSERT_TRUE(tabletop_common::test_support::loadNodelet("/tabletop/cam2_capture", "tabletop_capture/CameraCapture"));
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> l(m);
    return images.size() >= 5 && !warnings.empty();
  }, 10.0));
  {
    std::lock_guard<std::mutex> l(m);
    EXPECT_NE(warnings.front().find("no camera_info is published"), std::string::npos) << warnings.front();
    EXPECT_EQ(images.front()->width, 640u);
    EXPECT_EQ(images.front()->height, 480u);
    EXPECT_TRUE(images.front()->encoding == "bgr8" || images.front()->encoding == "mono8")
        << images.front()->encoding;
    EXPECT_EQ(images.front()->header.frame_id, "cam2_optical_frame");
  }
  EXPECT_EQ(info_sub.getNumPublishers(), 0u);
  tabletop_common::test_support::loader().clear();
}

// camera_info_file (camera_calibration's YAML) instead of a rig: its K and D with each image's
// stamp, frame <camera_name>_optical_frame.
TEST_F(CameraCaptureTest, CameraInfoFromACalibrationFile) {
  {
    std::ofstream f(root_ + "/cam3.yaml");
    f << "image_width: 640\nimage_height: 480\ncamera_name: cam3\n"
         "camera_matrix: {rows: 3, cols: 3, data: [600, 0, 320.5, 0, 601, 240.5, 0, 0, 1]}\n"
         "distortion_model: plumb_bob\n"
         "distortion_coefficients: {rows: 1, cols: 5, data: [-0.2, 0.05, 0, 0, 0]}\n";
  }
  ros::NodeHandle nh;
  std::mutex m;
  std::vector<sensor_msgs::ImageConstPtr> images;
  std::map<double, sensor_msgs::CameraInfoConstPtr> infos;
  boost::function<void(const sensor_msgs::ImageConstPtr&)> on_image = [&](const sensor_msgs::ImageConstPtr& i) {
    std::lock_guard<std::mutex> l(m);
    images.push_back(i);
  };
  boost::function<void(const sensor_msgs::CameraInfoConstPtr&)> on_info = [&](const sensor_msgs::CameraInfoConstPtr& i) {
    std::lock_guard<std::mutex> l(m);
    infos[i->header.stamp.toSec()] = i;
  };
  ros::Subscriber sub = nh.subscribe<sensor_msgs::Image>("/tabletop/cam3/image_raw", 50, on_image);
  ros::Subscriber info_sub = nh.subscribe<sensor_msgs::CameraInfo>("/tabletop/cam3/camera_info", 50, on_info);
  const std::string ns = "/tabletop/cam3_capture/";
  ros::param::set(ns + "device", "file:" + dir_ + "/img_%04d.png");
  ros::param::set(ns + "camera_name", std::string("cam3"));
  ros::param::set(ns + "camera_info_file", "file://" + root_ + "/cam3.yaml");
  ASSERT_TRUE(tabletop_common::test_support::loadNodelet("/tabletop/cam3_capture", "tabletop_capture/CameraCapture"));
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> l(m);
    return images.size() >= 5 && infos.count(images[4]->header.stamp.toSec());
  }, 10.0));
  {
    std::lock_guard<std::mutex> l(m);
    const sensor_msgs::CameraInfo& ci = *infos.at(images[4]->header.stamp.toSec());
    EXPECT_EQ(ci.header.frame_id, "cam3_optical_frame");
    EXPECT_EQ(images[4]->header.frame_id, "cam3_optical_frame");
    EXPECT_EQ(ci.width, 640u);
    EXPECT_EQ(ci.K[0], 600.0);
    EXPECT_EQ(ci.K[5], 240.5);
    EXPECT_EQ(ci.D[0], -0.2);
  }
  tabletop_common::test_support::loader().clear();
}

int main(int argc, char** argv) {
  return tabletop_common::test_support::runNodeletTests(argc, argv, "test_camera_capture", 4);
}
