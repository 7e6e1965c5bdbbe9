// Integration test of the HandMesher nodelet (hosted in this process, like a nodelet manager):
// synthetic hand volumes in (a ball of known radius per hand id), meshes and markers out.
// Checks the mesh geometry against the ball, that ids carry through, that a hand which
// disappears gets its marker deleted, and that malformed volumes are rejected and counted
// without stopping the stream. The whole pipeline with the mesher runs in test_mpf_pipeline.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

#include <Eigen/Core>
#include <boost/make_shared.hpp>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include <tabletop_msgs/HandMeshes.h>
#include <tabletop_msgs/HandVolumes.h>

#include <dynamic_reconfigure/client.h>

#include "ball_volume.h"
#include "cvephands_bridge/HandMesherTuningConfig.h"
#include "tabletop_common/ros/test_support.h"

namespace {

using tabletop_common::test_support::loadNodelet;
using tabletop_common::test_support::loader;
using tabletop_common::test_support::waitFor;

constexpr int kN = 83;             // voxels per side, as the pipeline's hand volumes
constexpr double kVoxel = 0.30 / kN;
constexpr double kRadius = 0.05;   // m

tabletop_msgs::VoxelVolume ball(const Eigen::Vector3d& origin) {
  return cvephands_test::ballVolume(origin, kRadius, kN, 0.30);
}

}  // namespace

TEST(HandMesher, MeshesHandVolumesAndDeletesLostHands) {
  ros::NodeHandle nh;
  std::mutex m;
  std::vector<tabletop_msgs::HandMeshes::ConstPtr> meshes;
  std::vector<visualization_msgs::MarkerArray::ConstPtr> markers;
  boost::function<void(const tabletop_msgs::HandMeshes::ConstPtr&)> on_meshes =
      [&](const tabletop_msgs::HandMeshes::ConstPtr& x) {
        std::lock_guard<std::mutex> l(m);
        meshes.push_back(x);
      };
  boost::function<void(const visualization_msgs::MarkerArray::ConstPtr&)> on_markers =
      [&](const visualization_msgs::MarkerArray::ConstPtr& x) {
        std::lock_guard<std::mutex> l(m);
        markers.push_back(x);
      };
  auto s1 = nh.subscribe<tabletop_msgs::HandMeshes>("/tabletop/cve/hand_mesh_data", 10, on_meshes);
  auto s2 = nh.subscribe<visualization_msgs::MarkerArray>("/tabletop/cve/hand_meshes", 10, on_markers);
  tabletop_common::test_support::DiagnosticsValues diag("hand meshing");
  ros::Publisher pub = nh.advertise<tabletop_msgs::HandVolumes>("/tabletop/psfs/hand_volumes", 5);
  ASSERT_TRUE(loadNodelet("/tabletop/hand_mesher", "cvephands_bridge/HandMesher"));
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && s1.getNumPublishers() > 0 &&
                                   s2.getNumPublishers() > 0; }, 10.0));

  // Frame 1: hands 3 and 4.
  const Eigen::Vector3d o3(-0.30, -0.20, 0.0), o4(0.05, -0.20, 0.0);
  auto two = boost::make_shared<tabletop_msgs::HandVolumes>();
  two->header.stamp = ros::Time(100.0);
  two->header.frame_id = "world";
  two->target_ids = {3, 4};
  two->volumes = {ball(o3), ball(o4)};
  // Hand 4's cube also holds a 2 cm blob in a corner, 0.18 m from the hand (the face or the
  // other hand in a real cube): hundreds of triangles, not a speck, but beyond keep_radius
  // (hand_mesher.yaml, 0.08 m), so its mesh is the ball alone.
  for (int z = 5; z < 11; ++z)
    for (int y = 5; y < 11; ++y)
      for (int x = 5; x < 11; ++x) two->volumes[1].data[x + kN * (y + size_t(kN) * z)] = 255;
  pub.publish(two);
  ASSERT_TRUE(waitFor([&] { std::lock_guard<std::mutex> l(m); return meshes.size() >= 1 && markers.size() >= 1; }, 10.0));
  {
    std::lock_guard<std::mutex> l(m);
    const auto& hm = *meshes[0];
    EXPECT_EQ(hm.header.stamp, ros::Time(100.0));
    EXPECT_EQ(hm.header.frame_id, "world");
    ASSERT_EQ(hm.meshes.size(), 2u);
    for (int i = 0; i < 2; ++i) {
      const auto& mesh = hm.meshes[i];
      EXPECT_EQ(mesh.target_id, uint32_t(i == 0 ? 3 : 4));
      const Eigen::Vector3d c = (i == 0 ? o3 : o4) + Eigen::Vector3d::Constant(0.15);
      ASSERT_GT(mesh.triangles.size(), 3000u);  // a 5 cm ball at 3.6 mm: ~ 4 pi r^2 / (v^2 / 2)
      ASSERT_EQ(mesh.normals.size(), mesh.vertices.size());
      double worst = 0.0, worst_normal = 1.0;
      for (size_t k = 0; k < mesh.vertices.size(); ++k) {
        const Eigen::Vector3d p(mesh.vertices[k].x, mesh.vertices[k].y, mesh.vertices[k].z);
        const Eigen::Vector3d n(mesh.normals[k].x, mesh.normals[k].y, mesh.normals[k].z);
        worst = std::max(worst, std::abs((p - c).norm() - kRadius));
        worst_normal = std::min(worst_normal, n.dot((p - c).normalized()));
      }
      for (uint32_t t : mesh.triangles) ASSERT_LT(t, mesh.vertices.size());
      std::printf("[mesher] hand %u: %zu vertices, %zu triangles, worst |r - R| %.2f mm, "
                  "worst normal cos %.3f\n", mesh.target_id, mesh.vertices.size(),
                  mesh.triangles.size() / 3, 1e3 * worst, worst_normal);
      // Linear interpolation of a linear ramp: exact up to float rounding and the ramp's
      // curvature (a fraction of a voxel).
      EXPECT_LT(worst, 0.25 * kVoxel);
      EXPECT_GT(worst_normal, 0.95);
    }
    const auto& ma = *markers[0];
    ASSERT_EQ(ma.markers.size(), 2u);
    for (const auto& mk : ma.markers) {
      EXPECT_EQ(mk.type, visualization_msgs::Marker::TRIANGLE_LIST);
      EXPECT_EQ(mk.action, visualization_msgs::Marker::ADD);
      EXPECT_EQ(mk.points.size(), hm.meshes[mk.id == 3 ? 0 : 1].triangles.size());
      EXPECT_EQ(mk.header.frame_id, "world");
    }
  }

  // Frame 2: hand 4 is gone -> its marker is deleted, hand 3 is updated.
  auto one = boost::make_shared<tabletop_msgs::HandVolumes>();
  one->header.stamp = ros::Time(100.04);
  one->target_ids = {3};
  one->volumes = {ball(o3)};
  pub.publish(one);
  ASSERT_TRUE(waitFor([&] { std::lock_guard<std::mutex> l(m); return meshes.size() >= 2 && markers.size() >= 2; }, 10.0));
  {
    std::lock_guard<std::mutex> l(m);
    ASSERT_EQ(meshes[1]->meshes.size(), 1u);
    bool deleted4 = false, added3 = false;
    for (const auto& mk : markers[1]->markers) {
      deleted4 |= mk.id == 4 && mk.action == visualization_msgs::Marker::DELETE;
      added3 |= mk.id == 3 && mk.action == visualization_msgs::Marker::ADD;
    }
    EXPECT_TRUE(deleted4);
    EXPECT_TRUE(added3);
  }

  // Malformed: data shorter than the dims, and ids/volumes of different counts. Hand 3 of the
  // first message is still meshed; the second message is dropped whole.
  auto bad = boost::make_shared<tabletop_msgs::HandVolumes>();
  bad->header.stamp = ros::Time(100.08);
  bad->target_ids = {3, 4};
  bad->volumes = {ball(o3), ball(o4)};
  bad->volumes[1].data.resize(10);
  pub.publish(bad);
  auto mismatched = boost::make_shared<tabletop_msgs::HandVolumes>();
  mismatched->header.stamp = ros::Time(100.12);
  mismatched->target_ids = {3};
  pub.publish(mismatched);
  ASSERT_TRUE(waitFor([&] { std::lock_guard<std::mutex> l(m); return meshes.size() >= 3; }, 10.0));
  {
    std::lock_guard<std::mutex> l(m);
    ASSERT_EQ(meshes[2]->meshes.size(), 1u);
    EXPECT_EQ(meshes[2]->meshes[0].target_id, 3u);
  }
  EXPECT_TRUE(waitFor([&] { return diag.get("volumes rejected") == "2"; }, 5.0));
  std::lock_guard<std::mutex> l(m);
  std::printf("[mesher] diagnostics: %s ms per hand, %s triangles per hand\n",
              diag.get("meshing per hand (ms)").c_str(), diag.get("triangles per hand").c_str());
  EXPECT_EQ(diag.get("meshes"), "4");
}

// Live tuning (dynamic_reconfigure): iso 0.85 moves the surface of the ball's ramp (0.25 per
// voxel, 0.6 on the sphere) one voxel inwards: (0.85 - 0.6) / 0.25 = 1 voxel.
TEST(HandMesher, IsoIsTunedLive) {
  ros::NodeHandle nh;
  std::mutex m;
  std::vector<tabletop_msgs::HandMeshes::ConstPtr> meshes;
  boost::function<void(const tabletop_msgs::HandMeshes::ConstPtr&)> on_meshes =
      [&](const tabletop_msgs::HandMeshes::ConstPtr& x) {
        std::lock_guard<std::mutex> l(m);
        meshes.push_back(x);
      };
  auto sub = nh.subscribe<tabletop_msgs::HandMeshes>("/tabletop/cve/hand_mesh_data", 10, on_meshes);
  ros::Publisher pub = nh.advertise<tabletop_msgs::HandVolumes>("/tabletop/psfs/hand_volumes", 5);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && sub.getNumPublishers() > 0; }, 10.0));
  dynamic_reconfigure::Client<cvephands_bridge::HandMesherTuningConfig> client("/tabletop/hand_mesher");
  cvephands_bridge::HandMesherTuningConfig now;
  ASSERT_TRUE(client.getCurrentConfiguration(now, ros::Duration(5.0)));
  EXPECT_DOUBLE_EQ(now.iso, 0.6);  // the server starts from the file, not from the .cfg
  now.iso = 0.85;
  ASSERT_TRUE(client.setConfiguration(now));
  const Eigen::Vector3d o(-0.30, -0.20, 0.0);
  auto v = boost::make_shared<tabletop_msgs::HandVolumes>();
  v->header.stamp = ros::Time(200.0);
  v->target_ids = {7};
  v->volumes = {ball(o)};
  pub.publish(v);
  ASSERT_TRUE(waitFor([&] { std::lock_guard<std::mutex> l(m); return !meshes.empty(); }, 10.0));
  std::lock_guard<std::mutex> l(m);
  ASSERT_EQ(meshes[0]->meshes.size(), 1u);
  const auto& mesh = meshes[0]->meshes[0];
  const Eigen::Vector3d c = o + Eigen::Vector3d::Constant(0.15);
  // The byte level floor(255 * 0.85) + 0.5 = 216.5 lies at (216.5 / 255 - 0.6) / 0.25 voxel.
  const double expected = kRadius - kVoxel * (216.5 / 255.0 - 0.6) / 0.25;
  double worst = 0.0;
  for (const auto& p : mesh.vertices)
    worst = std::max(worst, std::abs((Eigen::Vector3d(p.x, p.y, p.z) - c).norm() - expected));
  std::printf("[mesher] iso 0.85: %zu vertices, worst |r - %.2f mm| %.2f mm\n", mesh.vertices.size(),
              1e3 * expected, 1e3 * worst);
  EXPECT_LT(worst, 0.25 * kVoxel);
}

// One parameter style: a private parameter that is no key of config/hand_mesher.yaml (a typo)
// stops the stage with its name, instead of silently keeping the default.
TEST(HandMesher, UnknownParameterStopsTheStage) {
  ros::param::set("/typo/hand_mesher/isolevel", 0.5);
  tabletop_common::test_support::DiagnosticsValues diag("typo/hand_mesher: hand meshing");
  ASSERT_TRUE(loadNodelet("/typo/hand_mesher", "cvephands_bridge/HandMesher"));
  ASSERT_TRUE(waitFor([&] { return diag.message().find("not started") != std::string::npos; }, 10.0))
      << diag.message();
  EXPECT_NE(diag.message().find("~isolevel: unknown parameter"), std::string::npos) << diag.message();
}

int main(int argc, char** argv) {
  return tabletop_common::test_support::runNodeletTests(argc, argv, "test_hand_mesher", 2);
}
