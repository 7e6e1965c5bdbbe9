// Integration test of the CveBridge nodelet (hosted in this process): a RoomServer on loopback,
// the bridge feeding it synthetic hand volumes from psfs/hand_volumes, and a viewer client that
// decodes what the room relays. Checks: the bridge joins by itself (also when the server starts
// after it), every hand arrives with its id and placement, the decoded volume meshes to the
// same triangles as the original, the diagnostics count what was sent, and malformed volumes
// are rejected and counted while the good hands keep flowing. A second bridge joins a TLS room
// server over wss (tls, tls_ca_file: a throw-away self-signed certificate).
#include <gtest/gtest.h>

#include <map>
#include <mutex>

#include <boost/make_shared.hpp>
#include <ros/ros.h>

#include <tabletop_msgs/HandVolumes.h>

#include "ball_volume.h"
#include "cvephands_bridge/mesh/marching_cubes.h"
#include "cvephands_bridge/room/room_client.h"
#include "cvephands_bridge/room/room_server.h"
#include "cvephands_bridge/stream/hand_stream_codec.h"
#include "tabletop_common/ros/test_support.h"
#include "test_certificate.h"

namespace {

using tabletop_common::test_support::loadNodelet;
using tabletop_common::test_support::loader;
using tabletop_common::test_support::waitFor;

}  // namespace

TEST(CveBridge, StreamsHandsIntoTheRoom) {
  ros::NodeHandle nh;
  // The server is created first only to reserve a free port; the bridge starts before it
  // listens, so the reconnection path is exercised.
  cvephands::RoomServerOptions so;
  cvephands::RoomServer probe(so);
  probe.start();
  const uint16_t port = probe.port();
  probe.stop();
  ros::param::set("/tabletop/cve_bridge/server_port", int(port));
  ros::param::set("/tabletop/cve_bridge/room", std::string("test_room"));
  ros::param::set("/tabletop/cve_bridge/name", std::string("rig_a"));
  ros::param::set("/tabletop/cve_bridge/reconnect_interval", 0.2);

  std::mutex m;
  tabletop_common::test_support::DiagnosticsValues diag("cve bridge");
  ros::Publisher pub = nh.advertise<tabletop_msgs::HandVolumes>("/tabletop/psfs/hand_volumes", 5);
  ASSERT_TRUE(loadNodelet("/tabletop/cve_bridge", "cvephands_bridge/CveBridge"));
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; }, 10.0));
  ros::WallDuration(0.5).sleep();  // a few failed connection attempts

  so.port = port;
  cvephands::RoomServer server(so);
  server.start();
  // The viewer: decodes every hand message it receives.
  std::map<uint32_t, cvephands::HandFrame> received;
  std::map<uint32_t, int> count;
  std::vector<std::string> reasons;
  cvephands::HandStreamDecoder decoder;
  cvephands::RoomClientOptions co;
  co.port = port;
  co.join.room = "test_room";
  co.join.name = "viewer";
  co.join.role = cvephands::room::Role::kViewer;
  co.on_hands = [&](const cvephands::room::RelayHeader&, const uint8_t* data, size_t size) {
    std::lock_guard<std::mutex> l(m);
    cvephands::HandFrame f;
    std::string reason;
    if (decoder.decode(data, size, &f, &reason)) {
      ++count[f.target_id];
      received[f.target_id] = std::move(f);
    } else {
      reasons.push_back(reason);
    }
  };
  cvephands::RoomClient viewer(co);
  std::string error;
  ASSERT_TRUE(viewer.connect(&error)) << error;
  ASSERT_TRUE(waitFor([&] { return viewer.participants().size() == 2; }, 10.0))
      << "the bridge did not join";

  const Eigen::Vector3d o3(-0.30, -0.20, 0.0), o4(0.05, -0.20, 0.0);
  auto msg = boost::make_shared<tabletop_msgs::HandVolumes>();
  msg->header.frame_id = "world";
  msg->target_ids = {3, 4};
  msg->volumes = {cvephands_test::ballVolume(o3, 0.05), cvephands_test::ballVolume(o4, 0.04)};
  for (int i = 0; i < 10; ++i) {
    msg->header.stamp = ros::Time(100.0 + 0.04 * i);
    pub.publish(msg);
    ros::WallDuration(0.04).sleep();
  }
  ASSERT_TRUE(waitFor([&] { std::lock_guard<std::mutex> l(m); return count[3] >= 10 && count[4] >= 10; }, 10.0))
      << count[3] << " / " << count[4] << " messages";
  {
  std::lock_guard<std::mutex> l(m);
  EXPECT_TRUE(reasons.empty()) << reasons.front();
  cvephands::MarchingCubes mc;
  for (uint32_t id : {3u, 4u}) {
    const cvephands::HandFrame& f = received[id];
    const tabletop_msgs::VoxelVolume& v = msg->volumes[id == 3 ? 0 : 1];
    EXPECT_EQ(f.dims, Eigen::Vector3i(83, 83, 83));
    EXPECT_NEAR((f.origin - Eigen::Vector3d(v.origin.x, v.origin.y, v.origin.z)).norm(), 0.0, 1e-12);
    EXPECT_EQ(f.stamp_sec, 100u);
    // The above-iso mask is sent exactly: the receiver's mesh has the sender's triangles.
    cvephands::ProbabilityGridView g = f.view();
    cvephands::TriangleMesh decoded, original;
    mc.extract(g, &decoded);
    g.data = v.data.data();
    mc.extract(g, &original);
    EXPECT_EQ(decoded.triangles, original.triangles) << "hand " << id;
    ASSERT_EQ(decoded.vertices.size(), original.vertices.size());
    double worst = 0;
    for (size_t k = 0; k < decoded.vertices.size(); ++k)
      worst = std::max(worst, double((decoded.vertices[k] - original.vertices[k]).norm()));
    std::printf("[bridge] hand %u: %d messages, %zu triangles, worst vertex shift %.2f mm\n", id,
                count[id], decoded.numTriangles(), 1e3 * worst);
    EXPECT_LT(worst, 0.5 * g.voxel_size);
  }
  }
  EXPECT_TRUE(waitFor([&] {
    return diag.has("hand messages sent") && std::stoi(diag.get("hand messages sent")) >= 20;
  }, 5.0));
  // Bad input: a volume shorter than its dims, and ids / volumes of different counts. Both are
  // rejected and counted; the good hand of the first message still goes out.
  auto bad = boost::make_shared<tabletop_msgs::HandVolumes>(*msg);
  bad->header.stamp = ros::Time(101.0);
  bad->volumes[1].data.resize(10);
  pub.publish(bad);
  auto mismatched = boost::make_shared<tabletop_msgs::HandVolumes>(*msg);
  mismatched->target_ids = {3};
  pub.publish(mismatched);
  EXPECT_TRUE(waitFor([&] {
    std::lock_guard<std::mutex> l(m);
    return diag.get("volumes rejected") == "2" && count[3] >= 11;
  }, 5.0)) << "rejected: " << diag.get("volumes rejected");
  {
    std::lock_guard<std::mutex> l(m);
    EXPECT_EQ(count[4], 10);
    std::printf("[bridge] diagnostics: %s messages sent, mean %s bytes, encode %s ms\n",
                diag.get("hand messages sent").c_str(), diag.get("message size, mean (bytes)").c_str(),
                diag.get("encode per hand (ms)").c_str());
  }
  viewer.close();
  server.stop();
}

// The bridge's tls and tls_ca_file parameters: it joins a wss room and its hands arrive.
TEST(CveBridge, StreamsHandsOverTls) {
  ros::NodeHandle nh;
  const cvephands_test::TestCertificate cert;
  cvephands::RoomServerOptions so;
  so.tls_certificate_file = cert.cert.string();
  so.tls_private_key_file = cert.key.string();
  cvephands::RoomServer server(so);
  server.start();
  ros::param::set("/tabletop/cve_bridge_tls/server_port", int(server.port()));
  ros::param::set("/tabletop/cve_bridge_tls/room", std::string("tls_room"));
  ros::param::set("/tabletop/cve_bridge_tls/name", std::string("rig_tls"));
  ros::param::set("/tabletop/cve_bridge_tls/tls", true);
  ros::param::set("/tabletop/cve_bridge_tls/tls_ca_file", cert.cert.string());
  ros::param::set("/tabletop/cve_bridge_tls/reconnect_interval", 0.2);
  ros::param::set("/tabletop/cve_bridge_tls/face_video", false);
  ros::Publisher pub = nh.advertise<tabletop_msgs::HandVolumes>("/tabletop/psfs/hand_volumes", 5);
  ASSERT_TRUE(loadNodelet("/tabletop/cve_bridge_tls", "cvephands_bridge/CveBridge"));

  std::mutex m;
  int hands = 0;
  cvephands::RoomClientOptions co;
  co.port = server.port();
  co.tls = true;
  co.tls_ca_file = cert.cert.string();
  co.join.room = "tls_room";
  co.join.name = "viewer";
  co.join.role = cvephands::room::Role::kViewer;
  co.on_hands = [&](const cvephands::room::RelayHeader&, const uint8_t*, size_t) {
    std::lock_guard<std::mutex> l(m);
    ++hands;
  };
  cvephands::RoomClient viewer(co);
  std::string error;
  ASSERT_TRUE(viewer.connect(&error)) << error;
  ASSERT_TRUE(waitFor([&] { return viewer.participants().size() == 2; }, 10.0))
      << "the bridge did not join over wss";
  auto msg = boost::make_shared<tabletop_msgs::HandVolumes>();
  msg->header.frame_id = "world";
  msg->target_ids = {7};
  msg->volumes = {cvephands_test::ballVolume(Eigen::Vector3d(-0.1, -0.2, 0.0), 0.05)};
  // Published until they arrive: the subscription may still be connecting.
  const auto received = [&] {
    std::lock_guard<std::mutex> l(m);
    return hands;
  };
  for (int i = 0; i < 250 && received() < 5; ++i) {
    msg->header.stamp = ros::Time(200.0 + 0.04 * i);
    pub.publish(msg);
    ros::WallDuration(0.04).sleep();
  }
  EXPECT_GE(received(), 5);
  viewer.close();
  server.stop();
}

int main(int argc, char** argv) {
  return tabletop_common::test_support::runNodeletTests(argc, argv, "test_cve_bridge", 2);
}
