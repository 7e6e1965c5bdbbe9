// Integration test of the pSfS nodelet: simulated rig -> frame synchroniser -> psfs in one
// nodelet manager (this process). Checks that the background is learned from the empty frames
// and saved, that every later frame set gives body and skin volumes on the contract grid whose
// body volume matches the rig's occupancy oracle, that hand ROIs on hands/targets give hand
// sub-volumes with the targets' ids, that diagnostics report the stages, and that a bundle that
// breaks the contract is rejected and counted without stopping the nodelet.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <map>
#include <mutex>
#include <set>

#include <nodelet/loader.h>
#include <ros/ros.h>

#include <tabletop_msgs/HandVolumes.h>
#include <std_srvs/Trigger.h>
#include <tabletop_msgs/MultiViewFrame.h>
#include <tabletop_msgs/TrackedTargets.h>
#include <tabletop_msgs/VoxelVolume.h>

#include <dynamic_reconfigure/client.h>

#include "psfs_reconstruction/PsfsTuningConfig.h"
#include "psfs_reconstruction/reconstructor_config.h"
#include "psfs_reconstruction/ros/volume_msgs.h"
#include "tabletop_common/ros/test_support.h"
#include "tabletop_sim/simulated_rig.h"

namespace {

namespace sim = tabletop_sim;

constexpr int kFrames = 70;
constexpr int kEmpty = 25;

using tabletop_common::test_support::loadNodelet;
using tabletop_common::test_support::loader;
using tabletop_common::test_support::waitFor;

}  // namespace

TEST(PsfsPipeline, SimRigToVolumes) {
  ros::NodeHandle nh;
  const std::string bg_dir = "/tmp/psfs_pipeline_bg_" + std::to_string(getpid());
  ros::param::set("/tabletop/sim_rig/max_frames", kFrames);
  ros::param::set("/tabletop/sim_rig/empty_frames", kEmpty);
  ros::param::set("/tabletop/sim_rig/script", std::string("wave"));
  ros::param::set("/tabletop/sim_rig/start_delay", 1.5);
  ros::param::set("/tabletop/frame_synchronizer/num_cameras", 8);
  ros::param::set("/tabletop/psfs/config_file", std::string(PSFS_RECONSTRUCTION_CONFIG_DIR "/psfs.yaml"));
  ros::param::set("/tabletop/psfs/background_save_dir", bg_dir);
  // Every frame set is waited for: this test checks what comes out, not whether a busy test
  // machine keeps up with 25 fps (bench_fusion and the demo measure that).
  ros::param::set("/tabletop/psfs/queue_size", 100);
  // And the rig never outruns pSfS (lockstep on psfs/processed): no stage drops a set, even
  // with a quarter of a slow machine's CPU.
  ros::param::set("/tabletop/sim_rig/lockstep", 2);
  ros::param::set("/tabletop/sim_rig/lockstep_timeout", 30.0);

  std::mutex m;
  std::vector<ros::Time> frame_stamps;  // in publication order = sim frame index
  std::map<ros::Time, tabletop_msgs::VoxelVolume::ConstPtr> bodies, skins;
  std::map<ros::Time, tabletop_msgs::HandVolumes::ConstPtr> hands;
  std::map<ros::Time, tabletop_msgs::TrackedTargets::ConstPtr> truths;
  boost::function<void(const tabletop_msgs::MultiViewFrame::ConstPtr&)> on_frame =
      [&](const tabletop_msgs::MultiViewFrame::ConstPtr& f) {
        std::lock_guard<std::mutex> l(m);
        frame_stamps.push_back(f->header.stamp);
      };
  boost::function<void(const tabletop_msgs::VoxelVolume::ConstPtr&)> on_body =
      [&](const tabletop_msgs::VoxelVolume::ConstPtr& v) {
        std::lock_guard<std::mutex> l(m);
        bodies[v->header.stamp] = v;
      };
  boost::function<void(const tabletop_msgs::VoxelVolume::ConstPtr&)> on_skin =
      [&](const tabletop_msgs::VoxelVolume::ConstPtr& v) {
        std::lock_guard<std::mutex> l(m);
        skins[v->header.stamp] = v;
      };
  boost::function<void(const tabletop_msgs::HandVolumes::ConstPtr&)> on_hands =
      [&](const tabletop_msgs::HandVolumes::ConstPtr& v) {
        std::lock_guard<std::mutex> l(m);
        hands[v->header.stamp] = v;
      };
  // Stands in for the hand tracker: the true hands become the ROIs of the hand sub-volumes.
  ros::Publisher roi_pub = nh.advertise<tabletop_msgs::TrackedTargets>("/tabletop/hands/targets", 10);
  boost::function<void(const tabletop_msgs::TrackedTargets::ConstPtr&)> on_truth =
      [&](const tabletop_msgs::TrackedTargets::ConstPtr& t) {
        {
          std::lock_guard<std::mutex> l(m);
          truths[t->header.stamp] = t;
        }
        roi_pub.publish(t);
      };
  auto s1 = nh.subscribe<tabletop_msgs::MultiViewFrame>("/tabletop/frames", 200, on_frame);
  auto s2 = nh.subscribe<tabletop_msgs::VoxelVolume>("/tabletop/psfs/body_volume", 200, on_body);
  auto s3 = nh.subscribe<tabletop_msgs::VoxelVolume>("/tabletop/psfs/skin_volume", 200, on_skin);
  auto s4 = nh.subscribe<tabletop_msgs::HandVolumes>("/tabletop/psfs/hand_volumes", 200, on_hands);
  auto s5 = nh.subscribe<tabletop_msgs::TrackedTargets>("/tabletop/ground_truth/targets", 200, on_truth);
  tabletop_common::test_support::DiagnosticsValues diag("psfs reconstruction");

  ASSERT_TRUE(loadNodelet("/tabletop/psfs", "psfs_reconstruction/Psfs"));
  ASSERT_TRUE(loadNodelet("/tabletop/frame_synchronizer", "tabletop_capture/FrameSynchronizer"));
  ASSERT_TRUE(loadNodelet("/tabletop/sim_rig", "tabletop_sim/SimRig"));

  ASSERT_TRUE(waitFor([&] { std::lock_guard<std::mutex> l(m); return frame_stamps.size() >= size_t(kFrames); }, 280.0));
  // The queued sets, then a diagnostics round.
  waitFor([&] { std::lock_guard<std::mutex> l(m); return int(skins.size()) >= kFrames - kEmpty; }, 30.0);
  ros::WallDuration(2.5).sleep();

  std::unique_lock<std::mutex> lock(m);
  ASSERT_EQ(frame_stamps.size(), size_t(kFrames));
  // No volume during learning; every later set reconstructed (a few spared: the synchroniser
  // may still drop an incomplete set when the test machine is very busy).
  for (int i = 0; i < kEmpty; ++i) EXPECT_EQ(bodies.count(frame_stamps[i]), 0u) << "frame " << i;
  const int expected = kFrames - kEmpty;
  std::printf("[psfs] %zu body and %zu skin volumes, %zu hand volume sets for %d frame sets "
              "after learning\n", bodies.size(), skins.size(), hands.size(), expected);
  EXPECT_GE(int(bodies.size()), expected - 3);
  EXPECT_EQ(bodies.size(), skins.size());

  // Contract grid and agreement with the oracle.
  sim::SimOptions so;
  so.script = "wave";
  so.empty_frames = kEmpty;
  sim::SimulatedRig rig(so);
  double iou_sum = 0;
  int scored = 0;
  for (int i = kEmpty; i < kFrames; i += 9) {
    auto it = bodies.find(frame_stamps[i]);
    if (it == bodies.end()) continue;
    const auto& v = *it->second;
    EXPECT_EQ(v.header.frame_id, "world");
    EXPECT_EQ(v.size_x, 64u);
    EXPECT_EQ(v.size_y, 64u);
    EXPECT_EQ(v.size_z, 48u);
    EXPECT_NEAR(v.origin.x, -0.5, 1e-9);
    EXPECT_NEAR(v.origin.z, 0.0, 1e-9);
    psfs::ProbabilityVolume vol;
    std::string why;
    ASSERT_TRUE(psfs::fromVoxelVolumeMsg(v, &vol, &why)) << why;
    std::vector<uint8_t> person;
    rig.oracle(i).sampleGrid(vol.grid.origin, vol.grid.voxel_size, vol.grid.dims, &person, nullptr);
    size_t both = 0, either = 0;
    for (size_t k = 0; k < person.size(); ++k) {
      const bool a = vol.data[k] > psfs::thresholdByte(0.75), b = person[k] != 0;
      both += a && b;
      either += a || b;
    }
    const double iou = either ? double(both) / either : 1.0;
    std::printf("[psfs] frame %d: body IoU %.3f vs the oracle\n", i, iou);
    iou_sum += iou;
    ++scored;
  }
  ASSERT_GT(scored, 2);
  // test_reconstructor measures 0.69-0.72 for the same pipeline on the same script.
  EXPECT_GE(iou_sum / scored, 0.63);

  // Hand sub-volumes carry the ids of the ROIs (here: the true hands).
  ASSERT_FALSE(hands.empty());
  size_t checked = 0;
  for (const auto& h : hands) {
    auto t = truths.find(h.first);
    if (t == truths.end()) continue;
    std::set<uint32_t> hand_ids;
    for (const auto& target : t->second->targets)
      if (target.active && target.type == tabletop_msgs::TrackedTarget::HAND) hand_ids.insert(target.id);
    ASSERT_EQ(h.second->volumes.size(), h.second->target_ids.size());
    for (size_t k = 0; k < h.second->volumes.size(); ++k) {
      EXPECT_EQ(hand_ids.count(h.second->target_ids[k]), 1u);
      EXPECT_EQ(h.second->volumes[k].size_x, 83u);
    }
    ++checked;
  }
  EXPECT_GT(checked, 0u);

  // Diagnostics and the saved background.
  ASSERT_TRUE(diag.has("frame sets reconstructed"));
  EXPECT_GE(std::stoi(diag.get("frame sets reconstructed")), expected - 3);
  EXPECT_GT(std::stod(diag.get("body fusion (ms)")), 0.0);
  std::printf("[psfs] diagnostics: classify %s ms, body %s ms, skin %s ms, hands %s ms, total %s ms\n",
              diag.get("classify (ms)").c_str(), diag.get("body fusion (ms)").c_str(),
              diag.get("skin fusion (ms)").c_str(), diag.get("hand volumes (ms)").c_str(),
              diag.get("total (ms)").c_str());
  for (int c = 0; c < 8; ++c)
    EXPECT_TRUE(std::filesystem::exists(bg_dir + "/cam" + std::to_string(c) + ".bgm")) << c;
  std::filesystem::remove_all(bg_dir);

  // A bundle that breaks the contract (mono8 image) is rejected, counted, and survived.
  ASSERT_EQ(diag.get("frame sets rejected"), "0");
  lock.unlock();
  ros::Publisher bad = nh.advertise<tabletop_msgs::MultiViewFrame>("/tabletop/frames", 1);
  auto f = boost::make_shared<tabletop_msgs::MultiViewFrame>();
  f->header.stamp = ros::Time::now();
  f->camera_names = {"cam0"};
  f->images.resize(1);
  f->images[0].encoding = "mono8";
  f->camera_infos.resize(1);
  f->camera_poses.resize(1);
  waitFor([&] { return bad.getNumSubscribers() > 0; }, 5.0);
  bad.publish(f);
  EXPECT_TRUE(waitFor([&] { return diag.get("frame sets rejected") == "1"; }, 5.0));
  {
    std::lock_guard<std::mutex> l2(m);
    EXPECT_NE(diag.message().find("encoding 'mono8'"), std::string::npos) << diag.message();
  }

  // ~relearn_background: answered, and the stage reports that it learns again from scratch.
  const std::string service = "/tabletop/psfs/relearn_background";
  ASSERT_TRUE(ros::service::waitForService(service, 5000));
  std_srvs::Trigger relearn;
  ASSERT_TRUE(ros::service::call(service, relearn));
  EXPECT_TRUE(relearn.response.success);
  EXPECT_NE(relearn.response.message.find("next 25 frame sets"), std::string::npos)
      << relearn.response.message;
  EXPECT_TRUE(waitFor([&] { return diag.message().find("learning the background (0/25)") !=
                                   std::string::npos; }, 5.0)) << diag.message();

  // Live tuning: the server starts from the file's thresholds (not the .cfg's), takes a new one
  // and shows it on the parameter server under the alias of fusion/skin/threshold.
  dynamic_reconfigure::Client<psfs_reconstruction::PsfsTuningConfig> tuning("/tabletop/psfs");
  psfs_reconstruction::PsfsTuningConfig live;
  ASSERT_TRUE(tuning.getCurrentConfiguration(live, ros::Duration(5.0)));
  const psfs::ReconstructorConfig file = psfs::loadReconstructorConfig(PSFS_RECONSTRUCTION_CONFIG_DIR "/psfs.yaml");
  EXPECT_DOUBLE_EQ(live.body_threshold, file.params.body.threshold);
  EXPECT_DOUBLE_EQ(live.skin_threshold, file.params.skin.threshold);
  EXPECT_DOUBLE_EQ(live.hand_threshold, file.params.hand.threshold);
  live.skin_threshold = 0.8;
  ASSERT_TRUE(tuning.setConfiguration(live));
  double on_server = 0.0;
  EXPECT_TRUE(ros::param::get("/tabletop/psfs/skin_threshold", on_server));
  EXPECT_DOUBLE_EQ(on_server, 0.8);
}

int main(int argc, char** argv) {
  return tabletop_common::test_support::runNodeletTests(argc, argv, "test_psfs_pipeline", 4);
}
