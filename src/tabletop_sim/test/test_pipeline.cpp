// Integration test of the capture stage: simulated rig + frame synchroniser in one nodelet
// manager (this process), checking frame rate, zero-copy delivery, the frames' content against
// the rig, a bag record/replay round trip, and the synchroniser's behaviour on bad input.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <map>
#include <mutex>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <tabletop_msgs/MultiViewFrame.h>

#include "tabletop_capture/ros/conversions.h"
#include "tabletop_capture/ros/published_frames.h"
#include "tabletop_common/ros/test_support.h"
#include "tabletop_capture/default_rig.h"

using namespace tabletop_capture;

namespace {

constexpr int kCameras = 8;
constexpr int kFrames = 100;  // 4 s at 25 fps
constexpr int kEmpty = 10;

uint64_t hashBytes(const std::vector<uint8_t>& v) {
  uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (uint8_t b : v) h = (h ^ b) * 1099511628211ull;
  return h;
}

struct FrameLog {
  std::mutex mutex;
  std::vector<tabletop_msgs::MultiViewFrame::ConstPtr> frames;
  std::vector<ros::WallTime> arrival;
  int not_zero_copy = 0;
  void add(const tabletop_msgs::MultiViewFrame::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!wasPublishedFrame(m.get())) ++not_zero_copy;
    frames.push_back(m);
    arrival.push_back(ros::WallTime::now());
  }
  size_t size() {
    std::lock_guard<std::mutex> lock(mutex);
    return frames.size();
  }
};

using tabletop_common::test_support::waitFor;

// A small rig of n cameras (w x h, no distortion) for a synchroniser test, with its static tf
// sent by `broadcaster`; `frame_prefix` gives its optical frames names of their own, so that the
// other tests' static tf cannot matter.
RigDescription testRig(int n, const std::string& frame_prefix, tf2_ros::StaticTransformBroadcaster* broadcaster,
                       int w = 32, int h = 24) {
  RigDescription rig = tabletop_capture::makeDefaultRig(tabletop_capture::DefaultRigOptions{n, w, h, false});
  std::vector<geometry_msgs::TransformStamped> tfs;
  for (auto& cam : rig.cameras) {
    cam.frame_id = frame_prefix + cam.frame_id;
    geometry_msgs::TransformStamped t;
    t.header.stamp = ros::Time::now();
    t.header.frame_id = "world";
    t.child_frame_id = cam.frame_id;
    t.transform = toTransform(cam.world_T_camera);
    tfs.push_back(t);
  }
  broadcaster->sendTransform(tfs);
  return rig;
}

// A w x h rgb8 image of one grey level.
sensor_msgs::ImagePtr greyImage(double stamp, const std::string& frame_id, uint8_t level, int w = 32,
                                int h = 24) {
  sensor_msgs::ImagePtr m(new sensor_msgs::Image);
  m->header.stamp = ros::Time(stamp);
  m->header.frame_id = frame_id;
  m->encoding = "rgb8";
  m->width = w;
  m->height = h;
  m->step = 3 * w;
  m->data.assign(size_t(m->step) * h, level);
  return m;
}

}  // namespace

class PipelineTest : public ::testing::Test {
 protected:
  static bool load(const std::string& name, const std::string& type) {
    return tabletop_common::test_support::loadNodelet(name, type);
  }

 public:
  // Unloads every nodelet before roscpp shuts down (avoids the ROS 1 teardown race).
  static void unloadAll() { tabletop_common::test_support::loader().clear(); }
};

TEST_F(PipelineTest, SimRigSynchroniserRateZeroCopyAndBagRoundTrip) {
  ros::NodeHandle nh;
  ros::param::set("/tabletop/sim_rig/num_cameras", kCameras);
  ros::param::set("/tabletop/sim_rig/max_frames", kFrames);
  ros::param::set("/tabletop/sim_rig/empty_frames", kEmpty);
  ros::param::set("/tabletop/sim_rig/start_delay", 1.5);
  ros::param::set("/tabletop/frame_synchronizer/num_cameras", kCameras);

  // Live recording of the camera contract (what `rosbag record` would write).
  const std::string bag_path = "/tmp/tabletop_pipeline_test_" + std::to_string(getpid()) + ".bag";
  std::mutex bag_mutex;
  rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
  std::vector<ros::Subscriber> rec;
  for (int i = 0; i < kCameras; ++i) {
    const std::string base = "/tabletop/cam" + std::to_string(i);
    boost::function<void(const sensor_msgs::Image::ConstPtr&)> on_img =
        [&, base](const sensor_msgs::Image::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(bag_mutex);
          bag.write(base + "/image_raw", m->header.stamp, *m);
        };
    boost::function<void(const sensor_msgs::CameraInfo::ConstPtr&)> on_info =
        [&, base](const sensor_msgs::CameraInfo::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(bag_mutex);
          bag.write(base + "/camera_info", m->header.stamp, *m);
        };
    rec.push_back(nh.subscribe<sensor_msgs::Image>(base + "/image_raw", 50, on_img));
    rec.push_back(nh.subscribe<sensor_msgs::CameraInfo>(base + "/camera_info", 50, on_info));
  }
  boost::function<void(const tf2_msgs::TFMessage::ConstPtr&)> on_tf =
      [&](const tf2_msgs::TFMessage::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(bag_mutex);
        bag.write("/tf_static", ros::Time(1), *m);
      };
  rec.push_back(nh.subscribe<tf2_msgs::TFMessage>("/tf_static", 10, on_tf));

  FrameLog live;
  boost::function<void(const tabletop_msgs::MultiViewFrame::ConstPtr&)> on_frame =
      [&](const tabletop_msgs::MultiViewFrame::ConstPtr& m) { live.add(m); };
  ros::Subscriber frames_sub = nh.subscribe<tabletop_msgs::MultiViewFrame>(
      "/tabletop/frames", 200, on_frame);

  ASSERT_TRUE(load("/tabletop/frame_synchronizer", "tabletop_capture/FrameSynchronizer"));
  ASSERT_TRUE(load("/tabletop/sim_rig", "tabletop_sim/SimRig"));

  ASSERT_TRUE(waitFor([&] { return live.size() >= size_t(kFrames); }, 60.0))
      << "only " << live.size() << " of " << kFrames << " frame sets arrived";
  ros::WallDuration(0.5).sleep();
  for (auto& s : rec) s.shutdown();
  {
    std::lock_guard<std::mutex> lock(bag_mutex);
    bag.close();
  }

  std::lock_guard<std::mutex> lock(live.mutex);
  // Every rendered set arrives exactly once (in-process, exact stamps: nothing may be lost).
  EXPECT_EQ(live.frames.size(), size_t(kFrames));
  // Zero-copy: each received bundle is the very object the synchroniser published.
  EXPECT_EQ(live.not_zero_copy, 0);
  // Frame rate at the subscriber, reported only: tests never depend on the machine's speed
  // (bench_render and the demo measure it; a quarter of a slow machine gets ~17 fps here).
  const double span = (live.arrival.back() - live.arrival.front()).toSec();
  const double fps = (live.frames.size() - 1) / span;
  std::printf("[pipeline] %zu frame sets in %.2f s: %.1f fps (target 25)\n", live.frames.size(),
              span, fps);

  // Content: 8 rgb8 320x240 views, poses and intrinsics of the default rig, stamps increasing.
  const RigDescription rig = tabletop_capture::makeDefaultRig();
  for (size_t f = 0; f < live.frames.size(); ++f) {
    const auto& m = *live.frames[f];
    ASSERT_EQ(m.images.size(), size_t(kCameras));
    ASSERT_EQ(m.camera_poses.size(), size_t(kCameras));
    if (f > 0) {
      EXPECT_GT(m.header.stamp, live.frames[f - 1]->header.stamp);
    }
    for (int i = 0; i < kCameras; ++i) {
      EXPECT_EQ(m.images[i].encoding, "rgb8");
      EXPECT_EQ(m.images[i].width, 320u);
      EXPECT_EQ(m.images[i].height, 240u);
      EXPECT_EQ(m.images[i].header.stamp, m.header.stamp);
      Eigen::Isometry3d pose;
      ASSERT_TRUE(fromTransform(m.camera_poses[i], &pose));
      EXPECT_LT((pose.matrix() - rig.cameras[i].world_T_camera.matrix()).cwiseAbs().maxCoeff(),
                1e-9);
      EXPECT_DOUBLE_EQ(m.camera_infos[i].K[0], rig.cameras[i].fx);
    }
  }

  // Replay the recorded bag into a second synchroniser (namespace /replay) and compare.
  std::map<ros::Time, std::vector<uint64_t>> live_hashes;
  for (const auto& m : live.frames) {
    auto& h = live_hashes[m->header.stamp];
    for (const auto& im : m->images) h.push_back(hashBytes(im.data));
  }
  ros::param::set("/replay/frame_synchronizer/num_cameras", kCameras);
  FrameLog replay;
  boost::function<void(const tabletop_msgs::MultiViewFrame::ConstPtr&)> on_replay =
      [&](const tabletop_msgs::MultiViewFrame::ConstPtr& m) { replay.add(m); };
  ros::Subscriber replay_sub =
      nh.subscribe<tabletop_msgs::MultiViewFrame>("/replay/frames", 200, on_replay);
  ASSERT_TRUE(load("/replay/frame_synchronizer", "tabletop_capture/FrameSynchronizer"));

  rosbag::Bag in(bag_path, rosbag::bagmode::Read);
  rosbag::View view(in);
  std::map<std::string, ros::Publisher> pubs;
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (c->topic == "/tf_static") continue;  // the live static tf is still latched
    const std::string topic = "/replay" + c->topic.substr(std::string("/tabletop").size());
    if (pubs.count(c->topic)) continue;
    if (c->datatype == "sensor_msgs/Image")
      pubs[c->topic] = nh.advertise<sensor_msgs::Image>(topic, 50);
    else
      pubs[c->topic] = nh.advertise<sensor_msgs::CameraInfo>(topic, 50);
  }
  ASSERT_TRUE(waitFor(
      [&] {
        for (auto& p : pubs)
          if (p.second.getNumSubscribers() == 0) return false;
        return true;
      },
      10.0));
  // Like `rosbag play`, but camera_info first: a bag whose first image precedes its camera's
  // first camera_info loses that set, which this test is not about.
  for (const rosbag::MessageInstance& mi : view) {
    auto info = mi.instantiate<sensor_msgs::CameraInfo>();
    if (info && pubs.count(mi.getTopic())) pubs[mi.getTopic()].publish(info);
  }
  ros::WallDuration(0.3).sleep();
  size_t bag_images = 0;
  for (const rosbag::MessageInstance& mi : view) {
    auto it = pubs.find(mi.getTopic());
    if (it == pubs.end()) continue;
    if (auto img = mi.instantiate<sensor_msgs::Image>()) {
      it->second.publish(img);
      ++bag_images;
      if (bag_images % kCameras == 0) ros::WallDuration(0.01).sleep();  // like a real stream
    } else if (auto info = mi.instantiate<sensor_msgs::CameraInfo>()) {
      it->second.publish(info);
    }
  }
  EXPECT_EQ(bag_images, size_t(kFrames * kCameras)) << "the bag lost images while recording";
  ASSERT_TRUE(waitFor([&] { return replay.size() >= size_t(kFrames); }, 20.0))
      << "only " << replay.size() << " frame sets came back from the bag";
  std::lock_guard<std::mutex> lock2(replay.mutex);
  EXPECT_EQ(replay.frames.size(), size_t(kFrames));
  size_t identical = 0;
  for (const auto& m : replay.frames) {
    std::vector<uint64_t> h;
    for (const auto& im : m->images) h.push_back(hashBytes(im.data));
    auto it = live_hashes.find(m->header.stamp);
    if (it != live_hashes.end() && it->second == h) ++identical;
  }
  EXPECT_EQ(identical, size_t(kFrames)) << "replayed sets must equal the live ones bit for bit";
  std::remove(bag_path.c_str());
}

// Bad input on a 2-camera synchroniser: no crash, nothing wrong published, and a good set still
// goes through afterwards; a dropped camera shows up in the diagnostics.
TEST_F(PipelineTest, SynchroniserSurvivesBadInput) {
  ros::NodeHandle nh;
  ros::param::set("/bad/frame_synchronizer/num_cameras", 2);
  ros::param::set("/bad/frame_synchronizer/timeout", 0.1);
  FrameLog out;
  boost::function<void(const tabletop_msgs::MultiViewFrame::ConstPtr&)> on_frame =
      [&](const tabletop_msgs::MultiViewFrame::ConstPtr& m) { out.add(m); };
  ros::Subscriber sub = nh.subscribe<tabletop_msgs::MultiViewFrame>("/bad/frames", 50, on_frame);
  std::mutex diag_mutex;
  std::string last_diag;
  boost::function<void(const diagnostic_msgs::DiagnosticArray::ConstPtr&)> on_diag =
      [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        for (const auto& s : m->status) {
          if (s.name.find("bad/frame_synchronizer") == std::string::npos) continue;
          std::string text = s.message;
          for (const auto& kv : s.values) text += "|" + kv.key + "=" + kv.value;
          std::lock_guard<std::mutex> lock(diag_mutex);
          last_diag = text;
        }
      };
  ros::Subscriber dsub = nh.subscribe<diagnostic_msgs::DiagnosticArray>("/diagnostics", 50, on_diag);
  ASSERT_TRUE(load("/bad/frame_synchronizer", "tabletop_capture/FrameSynchronizer"));

  // This test must not depend on another test's static tf: publish the two cameras' poses.
  tf2_ros::StaticTransformBroadcaster static_tf;
  const RigDescription rig = testRig(2, "", &static_tf);
  ros::Publisher img_pub[2], info_pub[2];
  for (int i = 0; i < 2; ++i) {
    img_pub[i] = nh.advertise<sensor_msgs::Image>("/bad/cam" + std::to_string(i) + "/image_raw", 50);
    info_pub[i] =
        nh.advertise<sensor_msgs::CameraInfo>("/bad/cam" + std::to_string(i) + "/camera_info", 5, true);
  }
  ASSERT_TRUE(waitFor([&] {
    return img_pub[0].getNumSubscribers() && img_pub[1].getNumSubscribers() &&
           info_pub[0].getNumSubscribers() && info_pub[1].getNumSubscribers();
  }, 10.0));
  auto image = [&](int cam, double stamp, const std::string& enc, int w, int h) {
    sensor_msgs::ImagePtr m(new sensor_msgs::Image);
    m->header.stamp = ros::Time(stamp);
    m->header.frame_id = rig.cameras[cam].frame_id;
    m->encoding = enc;
    m->width = w;
    m->height = h;
    const int bpp = (enc == "rgb8" || enc == "bgr8") ? 3 : 1;
    m->step = w * bpp;
    m->data.assign(size_t(m->step) * h, 100);
    img_pub[cam].publish(m);
  };
  // 1. Images before any camera_info: dropped with an error.
  image(0, 10.00, "rgb8", 32, 24);
  image(1, 10.00, "rgb8", 32, 24);
  ros::WallDuration(0.3).sleep();
  EXPECT_EQ(out.size(), 0u);
  // camera_info: a NaN focal length on cam1 is rejected, then a valid one.
  sensor_msgs::CameraInfo bad = toCameraInfo(rig.cameras[1]);
  bad.K[0] = std::nan("");
  info_pub[1].publish(bad);
  info_pub[0].publish(toCameraInfo(rig.cameras[0]));
  ros::WallDuration(0.3).sleep();
  image(0, 11.00, "rgb8", 32, 24);
  image(1, 11.00, "rgb8", 32, 24);
  ros::WallDuration(0.3).sleep();
  EXPECT_EQ(out.size(), 0u) << "a camera with NaN calibration must not produce sets";
  info_pub[1].publish(toCameraInfo(rig.cameras[1]));
  ros::WallDuration(0.3).sleep();
  // 2. Unknown encoding, size mismatch, truncated data: dropped, never published.
  image(0, 12.00, "rgb8", 32, 24);
  image(1, 12.00, "yuv422_weird", 32, 24);
  image(0, 12.04, "rgb8", 32, 24);
  image(1, 12.04, "rgb8", 64, 48);
  ros::WallDuration(0.3).sleep();
  EXPECT_EQ(out.size(), 0u);
  // 3. Good sets, Bayer and bgr8 included, come through as rgb8.
  image(0, 13.00, "bayer_rggb8", 32, 24);
  image(1, 13.00, "bgr8", 32, 24);
  image(0, 13.04, "mono8", 32, 24);
  image(1, 13.04, "rgb8", 32, 24);
  ASSERT_TRUE(waitFor([&] { return out.size() >= 2; }, 5.0));
  // 4. A dropped camera: cam1 stops; cam0's sets time out and are counted against cam1.
  for (int k = 0; k < 5; ++k) image(0, 14.0 + 0.04 * k, "rgb8", 32, 24);
  ros::WallDuration(0.6).sleep();
  image(0, 15.00, "rgb8", 32, 24);
  image(1, 15.00, "rgb8", 32, 24);
  ASSERT_TRUE(waitFor([&] { return out.size() >= 3; }, 5.0));
  // 5. A late image (older than the last published set) is dropped.
  image(1, 14.5, "rgb8", 32, 24);
  ros::WallDuration(1.5).sleep();
  {
    std::lock_guard<std::mutex> lock(out.mutex);
    ASSERT_EQ(out.frames.size(), 3u);
    EXPECT_DOUBLE_EQ(out.frames[0]->header.stamp.toSec(), 13.00);
    EXPECT_DOUBLE_EQ(out.frames[1]->header.stamp.toSec(), 13.04);
    EXPECT_DOUBLE_EQ(out.frames[2]->header.stamp.toSec(), 15.00);
    for (const auto& f : out.frames)
      for (const auto& im : f->images) {
        EXPECT_EQ(im.encoding, "rgb8");
        EXPECT_EQ(im.data.size(), 32u * 24u * 3u);
      }
    // bgr8 100,100,100 and mono8 100 are grey: rgb8 must be 100 everywhere.
    EXPECT_EQ(out.frames[1]->images[0].data[0], 100);
  }
  std::lock_guard<std::mutex> lock(diag_mutex);
  std::printf("[pipeline] bad-input diagnostics: %s\n", last_diag.c_str());
  // cam1: 8 images, 4 rejected (before camera_info, NaN camera_info, bad encoding, bad size);
  // the 8 sets without it (11.00, 12.00, 12.04, 14.00..14.16) dropped; one late image.
  EXPECT_NE(last_diag.find("cam0=12 received, 1 rejected, 0 sets missed"), std::string::npos)
      << last_diag;
  EXPECT_NE(last_diag.find("cam1=8 received, 4 rejected, 8 sets missed"), std::string::npos)
      << last_diag;
  EXPECT_NE(last_diag.find("sets incomplete (dropped)=8|"), std::string::npos) << last_diag;
  EXPECT_NE(last_diag.find("late images (dropped)=1|"), std::string::npos) << last_diag;
  EXPECT_NE(last_diag.find("sets published=3|"), std::string::npos) << last_diag;
}

// Degraded sets on a 3-camera synchroniser (max_missing_cameras 2, clamped to 1; absent_after 2):
// a camera that never sends, or stops, costs its slot, not the set. Its slot holds an empty image
// with its calibration; with two cameras silent, sets are dropped.
TEST_F(PipelineTest, SynchroniserPublishesSetsWithoutASilentCamera) {
  ros::NodeHandle nh;
  ros::param::set("/degraded/frame_synchronizer/num_cameras", 3);
  // A timeout far above any delivery delay on a slow or busy machine: here the sets that wait
  // for a silent camera leave when the next phase's newer stamps (1 s later) arrive.
  ros::param::set("/degraded/frame_synchronizer/timeout", 0.5);
  ros::param::set("/degraded/frame_synchronizer/absent_after", 2);
  FrameLog out;
  boost::function<void(const tabletop_msgs::MultiViewFrame::ConstPtr&)> on_frame =
      [&](const tabletop_msgs::MultiViewFrame::ConstPtr& m) { out.add(m); };
  ros::Subscriber sub = nh.subscribe<tabletop_msgs::MultiViewFrame>("/degraded/frames", 50, on_frame);
  ASSERT_TRUE(load("/degraded/frame_synchronizer", "tabletop_capture/FrameSynchronizer"));

  tf2_ros::StaticTransformBroadcaster static_tf;
  const RigDescription rig = testRig(3, "degraded_", &static_tf);
  ros::Publisher img_pub[3], info_pub[3];
  for (int i = 0; i < 3; ++i) {
    img_pub[i] = nh.advertise<sensor_msgs::Image>("/degraded/cam" + std::to_string(i) + "/image_raw", 50);
    info_pub[i] = nh.advertise<sensor_msgs::CameraInfo>(
        "/degraded/cam" + std::to_string(i) + "/camera_info", 5, true);
    info_pub[i].publish(toCameraInfo(rig.cameras[i]));
  }
  ASSERT_TRUE(waitFor([&] {
    for (int i = 0; i < 3; ++i)
      if (!img_pub[i].getNumSubscribers() || !info_pub[i].getNumSubscribers()) return false;
    return true;
  }, 10.0));
  ros::WallDuration(0.3).sleep();  // camera_info and tf in
  auto set = [&](double stamp, std::initializer_list<int> cams) {
    for (int c : cams) img_pub[c].publish(greyImage(stamp, rig.cameras[c].frame_id, 10 + c));
    ros::WallDuration(0.04).sleep();
  };
  // 1. cam2 has never sent an image (but its camera_info and tf are known): sets without it.
  for (int k = 0; k < 5; ++k) set(20.0 + 0.04 * k, {0, 1});
  // 2. All three.
  for (int k = 0; k < 3; ++k) set(21.0 + 0.04 * k, {0, 1, 2});
  // 3. cam1 stops.
  for (int k = 0; k < 5; ++k) set(22.0 + 0.04 * k, {0, 2});
  // 4. cam1 and cam2 silent: one view is not enough (max_missing 1): dropped.
  for (int k = 0; k < 3; ++k) set(23.0 + 0.04 * k, {0});
  // 5. All three again.
  set(24.0, {0, 1, 2});
  ASSERT_TRUE(waitFor([&] { return out.size() >= 14; }, 5.0)) << out.size() << " sets";
  ros::WallDuration(0.5).sleep();
  std::lock_guard<std::mutex> lock(out.mutex);
  ASSERT_EQ(out.frames.size(), 14u);
  // The camera that must be missing from a set, and the one that may be: the first set after
  // a camera comes back may still leave without it (the synchroniser learns that it is back
  // from that very image, which arrives after the others').
  auto mustMiss = [](double t) { return t < 20.5 ? 2 : (t > 21.5 && t < 22.5) ? 1 : -1; };
  auto mayMiss = [](double t) { return std::abs(t - 21.0) < 1e-6 ? 2 : std::abs(t - 24.0) < 1e-6 ? 2 : -1; };
  for (size_t k = 0; k < out.frames.size(); ++k) {
    const auto& f = *out.frames[k];
    const double t = f.header.stamp.toSec();
    ASSERT_EQ(f.images.size(), 3u);
    for (int c = 0; c < 3; ++c) {
      const auto& im = f.images[c];
      EXPECT_EQ(f.camera_names[c], "cam" + std::to_string(c));
      EXPECT_EQ(f.camera_infos[c].header.frame_id, rig.cameras[c].frame_id);
      EXPECT_DOUBLE_EQ(f.camera_infos[c].K[0], rig.cameras[c].fx) << "set " << t << " cam" << c;
      EXPECT_NEAR(f.camera_poses[c].translation.x, rig.cameras[c].world_T_camera.translation().x(), 1e-9);
      if (im.width == 0) {
        EXPECT_TRUE(c == mustMiss(t) || c == mayMiss(t)) << "set " << t << " lacks cam" << c;
        EXPECT_EQ(im.height, 0u);
        EXPECT_TRUE(im.data.empty());
        EXPECT_EQ(im.header.stamp, f.header.stamp);
      } else {
        EXPECT_NE(c, mustMiss(t)) << "set " << t << " has cam" << c;
        EXPECT_EQ(im.width, 32u);
        ASSERT_EQ(im.data.size(), 96u * 24u);
        EXPECT_EQ(im.data[0], 10 + c);
      }
    }
  }
  EXPECT_DOUBLE_EQ(out.frames.back()->header.stamp.toSec(), 24.0);
}

// Images come through image_transport: cam0 on its default topic (raw), cam1 remapped to a
// topic in another namespace (a camera driver that publishes elsewhere). A transport whose
// plugin is not installed stops the stage with a clear reason instead of a crash.
TEST_F(PipelineTest, SynchroniserTakesImagesThroughImageTransport) {
  ros::NodeHandle nh;
  ros::param::set("/it/frame_synchronizer/num_cameras", 2);
  ros::param::set("/it/frame_synchronizer/image_transport", "raw");
  FrameLog out;
  boost::function<void(const tabletop_msgs::MultiViewFrame::ConstPtr&)> on_frame =
      [&](const tabletop_msgs::MultiViewFrame::ConstPtr& m) { out.add(m); };
  ros::Subscriber sub = nh.subscribe<tabletop_msgs::MultiViewFrame>("/it/frames", 50, on_frame);
  nodelet::M_string remap{{"/it/cam1/image_raw", "/elsewhere/camera/image"}};
  ASSERT_TRUE(tabletop_common::test_support::loadNodelet("/it/frame_synchronizer",
                                                         "tabletop_capture/FrameSynchronizer", remap));
  tf2_ros::StaticTransformBroadcaster static_tf;
  const RigDescription rig = testRig(2, "it_", &static_tf);
  ros::Publisher img_pub[2] = {nh.advertise<sensor_msgs::Image>("/it/cam0/image_raw", 10),
                               nh.advertise<sensor_msgs::Image>("/elsewhere/camera/image", 10)};
  ros::Publisher info_pub[2];
  for (int i = 0; i < 2; ++i) {
    info_pub[i] = nh.advertise<sensor_msgs::CameraInfo>("/it/cam" + std::to_string(i) + "/camera_info", 5, true);
    info_pub[i].publish(toCameraInfo(rig.cameras[i]));
  }
  ASSERT_TRUE(waitFor([&] { return img_pub[0].getNumSubscribers() && img_pub[1].getNumSubscribers(); }, 10.0))
      << "the synchroniser did not subscribe to the raw and the remapped topic";
  ros::WallDuration(0.3).sleep();
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 2; ++c) img_pub[c].publish(greyImage(30.0 + 0.04 * k, rig.cameras[c].frame_id, 50 + c));
    ros::WallDuration(0.04).sleep();
  }
  ASSERT_TRUE(waitFor([&] { return out.size() >= 3; }, 5.0)) << out.size() << " sets";
  {
    std::lock_guard<std::mutex> lock(out.mutex);
    for (const auto& f : out.frames) {
      ASSERT_EQ(f->images.size(), 2u);
      EXPECT_EQ(f->images[0].data.at(0), 50);
      EXPECT_EQ(f->images[1].data.at(0), 51);  // from the remapped topic
    }
  }

  // A transport without a plugin: not started, said on /diagnostics, nothing crashed.
  ros::param::set("/it_missing/frame_synchronizer/num_cameras", 2);
  ros::param::set("/it_missing/frame_synchronizer/image_transport", "no_such_transport");
  tabletop_common::test_support::DiagnosticsValues diag("it_missing/frame_synchronizer");
  ASSERT_TRUE(load("/it_missing/frame_synchronizer", "tabletop_capture/FrameSynchronizer"));
  ASSERT_TRUE(waitFor([&] { return diag.message().find("not started") != std::string::npos; }, 5.0))
      << diag.message();
  EXPECT_NE(diag.message().find("image_transport 'no_such_transport' is not available"), std::string::npos)
      << diag.message();
}

// The rig publisher turns the committed rig YAML into latched camera_info and static tf.
TEST_F(PipelineTest, RigPublisherPublishesCameraInfoAndTf) {
  ros::NodeHandle nh;
  ros::param::set("/rigpub/rig_publisher/rig_file", std::string(TABLETOP_SIM_CONFIG_DIR "/sim_rig.yaml"));
  std::mutex m;
  sensor_msgs::CameraInfo::ConstPtr info;
  boost::function<void(const sensor_msgs::CameraInfo::ConstPtr&)> on_info =
      [&](const sensor_msgs::CameraInfo::ConstPtr& msg) {
        std::lock_guard<std::mutex> lock(m);
        info = msg;
      };
  ros::Subscriber sub = nh.subscribe<sensor_msgs::CameraInfo>("/rigpub/cam5/camera_info", 1, on_info);
  std::vector<geometry_msgs::TransformStamped> tfs;
  boost::function<void(const tf2_msgs::TFMessage::ConstPtr&)> on_tf =
      [&](const tf2_msgs::TFMessage::ConstPtr& msg) {
        std::lock_guard<std::mutex> lock(m);
        for (const auto& t : msg->transforms) tfs.push_back(t);
      };
  ros::Subscriber tf_sub = nh.subscribe<tf2_msgs::TFMessage>("/tf_static", 10, on_tf);
  ASSERT_TRUE(load("/rigpub/rig_publisher", "tabletop_capture/RigPublisher"));
  ASSERT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> lock(m);
    return info != nullptr;
  }, 10.0)) << "no latched camera_info from the rig publisher";
  ros::WallDuration(0.5).sleep();
  const RigDescription rig = tabletop_capture::makeDefaultRig();
  std::lock_guard<std::mutex> lock(m);
  CameraModel cam;
  std::string why;
  ASSERT_TRUE(fromCameraInfo(*info, &cam, &why)) << why;
  EXPECT_EQ(info->header.frame_id, "cam5_optical_frame");
  EXPECT_NEAR(cam.fx, rig.cameras[5].fx, 1e-9);
  EXPECT_NEAR(cam.cy, rig.cameras[5].cy, 1e-9);
  EXPECT_NEAR(cam.distortion[0], rig.cameras[5].distortion[0], 1e-12);
  bool found = false;
  for (const auto& t : tfs) {
    if (t.child_frame_id != "cam5_optical_frame" || t.header.frame_id != "world") continue;
    Eigen::Isometry3d pose;
    ASSERT_TRUE(fromTransform(t.transform, &pose));
    EXPECT_LT((pose.matrix() - rig.cameras[5].world_T_camera.matrix()).cwiseAbs().maxCoeff(), 1e-9);
    found = true;
  }
  EXPECT_TRUE(found) << "no static tf world -> cam5_optical_frame";
}

int main(int argc, char** argv) {
  return tabletop_common::test_support::runNodeletTests(argc, argv, "test_pipeline", 4, [] { PipelineTest::unloadAll(); });
}
