// Room protocol pieces without sockets: the relay header's bytes, the seat poses, the strictness
// of the control-message parser, server-message round trips, and the static-file mapping's
// refusal of everything outside the client directory.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cvephands_bridge/room/reconnect_backoff.h"
#include "cvephands_bridge/room/room_protocol.h"
#include "cvephands_bridge/room/static_files.h"

namespace cvephands {
namespace {

using room::ClientMessage;
using room::ServerMessage;

TEST(RoomProtocol, RelayHeaderBytes) {
  room::RelayHeader h;
  h.sender = 0x01020304;
  h.seat = 5;
  h.sequence = 0xA0B0C0D0;
  h.server_time_us = 0x1122334455667788ull;
  uint8_t b[room::kRelayHeaderSize + 3];
  room::writeRelayHeader(h, b);
  b[32] = 7, b[33] = 8, b[34] = 9;
  EXPECT_EQ(std::string(reinterpret_cast<char*>(b), 4), "CVRM");
  EXPECT_EQ(b[4], 1);
  EXPECT_EQ(b[5], 32);
  EXPECT_EQ(b[6] | b[7] | b[20] | b[21] | b[22] | b[23], 0);
  EXPECT_EQ(b[8], 0x04);  // little endian
  EXPECT_EQ(b[11], 0x01);
  EXPECT_EQ(b[16], 0xD0);
  EXPECT_EQ(b[24], 0x88);
  EXPECT_EQ(b[31], 0x11);
  room::RelayHeader r;
  size_t offset = 0;
  ASSERT_TRUE(room::readRelayHeader(b, sizeof(b), &r, &offset));
  EXPECT_EQ(offset, 32u);
  EXPECT_EQ(r.sender, h.sender);
  EXPECT_EQ(r.seat, h.seat);
  EXPECT_EQ(r.sequence, h.sequence);
  EXPECT_EQ(r.server_time_us, h.server_time_us);
  EXPECT_FALSE(room::readRelayHeader(b, 31, &r, &offset));
  b[0] = 'X';
  EXPECT_FALSE(room::readRelayHeader(b, sizeof(b), &r, &offset));
}

// p_room = T p_world with T column-major.
std::array<double, 3> apply(const room::SeatPose& t, double x, double y, double z) {
  return {t[0] * x + t[4] * y + t[8] * z + t[12], t[1] * x + t[5] * y + t[9] * z + t[13],
          t[2] * x + t[6] * y + t[10] * z + t[14]};
}

TEST(RoomProtocol, SeatsFaceTheTableCentre) {
  room::SeatLayout layout;  // 6 seats, 0.9 m
  for (int k = 0; k < layout.seats; ++k) {
    const room::SeatPose t = room::seatPose(k, layout);
    EXPECT_EQ(t[3], 0.0);
    EXPECT_EQ(t[7], 0.0);
    EXPECT_EQ(t[11], 0.0);
    EXPECT_EQ(t[15], 1.0);
    // Rotation: orthonormal columns, determinant +1 (right-handed stays right-handed).
    const double* x = &t[0];
    const double* y = &t[4];
    const double* z = &t[8];
    for (const double* c : {x, y, z})
      EXPECT_NEAR(c[0] * c[0] + c[1] * c[1] + c[2] * c[2], 1.0, 1e-12);
    EXPECT_NEAR(x[0] * y[0] + x[1] * y[1] + x[2] * y[2], 0.0, 1e-12);
    const double det = x[0] * (y[1] * z[2] - y[2] * z[1]) - y[0] * (x[1] * z[2] - x[2] * z[1]) +
                       z[0] * (x[1] * y[2] - x[2] * y[1]);
    EXPECT_NEAR(det, 1.0, 1e-12);
    // The desk marker sits on the circle at angle 2 pi k / 6, on the table top.
    const double a = 2 * M_PI * k / layout.seats;
    const auto origin = apply(t, 0, 0, 0);
    EXPECT_NEAR(origin[0], 0.9 * std::cos(a), 1e-12);
    EXPECT_NEAR(origin[1], 0.9 * std::sin(a), 1e-12);
    EXPECT_NEAR(origin[2], 0.0, 1e-12);
    // 0.9 m towards the screen (+y) is the table centre; up stays up.
    const auto centre = apply(t, 0, 0.9, 0);
    EXPECT_NEAR(std::hypot(centre[0], centre[1]), 0.0, 1e-12);
    EXPECT_NEAR(apply(t, 0, 0, 0.3)[2], 0.3, 1e-12);
    // The user's right (+x) runs counter-clockwise around the table, seen from above.
    const auto right = apply(t, 0.1, 0, 0);
    EXPECT_GT(origin[0] * right[1] - origin[1] * right[0], 0.0);
  }
}

TEST(RoomProtocol, JoinParsing) {
  ClientMessage m = room::parseClientMessage(R"({"type":"join","room":"r1"})");
  ASSERT_EQ(m.type, ClientMessage::Type::kJoin);
  EXPECT_EQ(m.join.room, "r1");
  EXPECT_EQ(m.join.role, room::Role::kRig);
  EXPECT_TRUE(m.join.name.empty());
  EXPECT_TRUE(m.join.token.empty());

  m = room::parseClientMessage(
      " {\"type\":\"join\", \"room\":\"lab-2.a_b\", \"name\":\"Ana \\\"\\u00e9\\ud83d\\ude00\","
      "\"token\":\"t\",\"role\":\"viewer\",\"future\":[1,{}]} \n");
  ASSERT_EQ(m.type, ClientMessage::Type::kJoin) << m.detail;
  EXPECT_EQ(m.join.name, "Ana \"\xC3\xA9\xF0\x9F\x98\x80");
  EXPECT_EQ(m.join.token, "t");
  EXPECT_EQ(m.join.role, room::Role::kViewer);

  // Round trip through the client's encoder.
  m = room::parseClientMessage(room::encodeJoin(m.join));
  ASSERT_EQ(m.type, ClientMessage::Type::kJoin);
  EXPECT_EQ(m.join.name, "Ana \"\xC3\xA9\xF0\x9F\x98\x80");

  for (const char* bad :
       {R"({"type":"join"})", R"({"type":"join","room":""})", R"({"type":"join","room":"a/b"})",
        R"({"type":"join","room":"r","role":"god"})", R"({"type":"join","room":"r","token":5})",
        R"({"type":"join","room":7})"}) {
    m = room::parseClientMessage(bad);
    EXPECT_EQ(m.type, ClientMessage::Type::kInvalid) << bad;
    EXPECT_EQ(m.reason, "bad_join") << bad;
  }
  m = room::parseClientMessage("{\"type\":\"join\",\"room\":\"r\",\"name\":\"" +
                               std::string(65, 'n') + "\"}");
  EXPECT_EQ(m.reason, "bad_join");
  m = room::parseClientMessage("{\"type\":\"join\",\"room\":\"" + std::string(65, 'r') + "\"}");
  EXPECT_EQ(m.reason, "bad_join");
}

TEST(RoomProtocol, StrictJson) {
  std::string deep;
  for (int i = 0; i < 17; ++i) deep += "[";
  deep = "{\"type\":\"ping\",\"x\":" + deep + std::string(17, ']') + "}";
  for (const std::string& bad : std::vector<std::string>{"",
                                                         "   ",
                                                         "null",
                                                         "[]",
                                                         "\"join\"",
                                                         "{",
                                                         "{\"type\":\"join\",}",
                                                         "{'type':'join'}",
                                                         "{\"type\":\"join\" /* c */}",
                                                         "{\"type\":1}",
                                                         "{\"kind\":\"join\"}",
                                                         "{\"type\":\"ping\",\"id\":NaN}",
                                                         "{\"type\":\"ping\",\"id\":01}",
                                                         "{\"type\":\"ping\",\"id\":1.}",
                                                         "{\"type\":\"ping\",\"id\":-}",
                                                         "{\"type\":\"ping\",\"id\":1e999}",
                                                         "{\"type\":\"ping\",\"id\":\"\\ud800\"}",
                                                         "{\"type\":\"ping\",\"id\":\"\\udc00x\"}",
                                                         "{\"type\":\"ping\",\"id\":\"\\x\"}",
                                                         "{\"type\":\"ping\",\"id\":\"a\tb\"}",
                                                         "{\"type\":\"ping\",\"type\":\"join\"}",
                                                         "{\"type\":\"ping\"} x",
                                                         "{\"type\":\"ping\",\"id\":tru}",
                                                         "{\"type\":\"ping\",\"id\":[1 2]}",
                                                         deep}) {
    const ClientMessage m = room::parseClientMessage(bad);
    EXPECT_EQ(m.type, ClientMessage::Type::kInvalid) << bad;
    EXPECT_EQ(m.reason, "malformed") << bad;
    EXPECT_FALSE(m.detail.empty());
  }
  EXPECT_EQ(room::parseClientMessage(R"({"type":"hello"})").reason, "unknown_type");
  ClientMessage ping = room::parseClientMessage(R"({"type":"ping","id":-1.5e3})");
  ASSERT_EQ(ping.type, ClientMessage::Type::kPing);
  EXPECT_EQ(ping.ping_id, "-1500");
  ping = room::parseClientMessage(R"({"type":"ping","id":"a\"b"})");
  EXPECT_EQ(ping.ping_id, R"("a\"b")");
  EXPECT_EQ(room::parseClientMessage(R"({"type":"ping"})").ping_id, "null");
}

TEST(RoomProtocol, ServerMessagesRoundTrip) {
  room::SeatLayout layout;
  room::ParticipantInfo rig;
  rig.id = 7;
  rig.name = "rig \"seven\"\n";
  rig.seat = 2;
  rig.seat_pose = room::seatPose(2, layout);
  room::ParticipantInfo viewer;
  viewer.id = 9;
  viewer.name = "browser";
  viewer.role = room::Role::kViewer;

  ServerMessage m =
      room::parseServerMessage(room::encodeWelcome("r1", rig, 6, 1700000000123456ull));
  ASSERT_EQ(m.type, ServerMessage::Type::kWelcome) << m.detail;
  EXPECT_EQ(m.room, "r1");
  EXPECT_EQ(m.self.id, 7u);
  EXPECT_EQ(m.self.name, rig.name);
  EXPECT_EQ(m.self.seat, 2);
  EXPECT_EQ(m.seats, 6);
  EXPECT_EQ(m.server_time_us, 1700000000123456ull);
  EXPECT_EQ(m.self.seat_pose, rig.seat_pose);  // shortest round-trip numbers: exact

  m = room::parseServerMessage(room::encodeParticipants("r1", {rig, viewer}));
  ASSERT_EQ(m.type, ServerMessage::Type::kParticipants) << m.detail;
  ASSERT_EQ(m.participants.size(), 2u);
  EXPECT_EQ(m.participants[1].role, room::Role::kViewer);
  EXPECT_EQ(m.participants[1].seat, -1);
  EXPECT_EQ(m.participants[1].seat_pose, room::identityPose());
  EXPECT_NE(room::encodeParticipants("r1", {viewer}).find("\"seat_pose\":null"), std::string::npos);

  m = room::parseServerMessage(room::encodeError("bad_token", "missing or wrong token"));
  ASSERT_EQ(m.type, ServerMessage::Type::kError);
  EXPECT_EQ(m.reason, "bad_token");
  EXPECT_EQ(m.detail, "missing or wrong token");

  m = room::parseServerMessage(room::encodePong("\"x\"", 42));
  ASSERT_EQ(m.type, ServerMessage::Type::kPong);
  EXPECT_EQ(m.ping_id, "\"x\"");
  EXPECT_EQ(m.server_time_us, 42u);

  EXPECT_EQ(room::parseServerMessage(R"({"type":"news"})").type, ServerMessage::Type::kUnknown);
  EXPECT_EQ(room::parseServerMessage("{").type, ServerMessage::Type::kUnknown);
}

class StaticFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    namespace fs = std::filesystem;
    dir_ = fs::temp_directory_path() / ("room_static_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "js");
    std::ofstream(dir_ / "index.html") << "<html>room</html>";
    std::ofstream(dir_ / "js" / "app.js") << "1;";
    std::ofstream(dir_ / "js" / "index.html") << "js index";
    std::ofstream(dir_ / ".secret") << "no";
    std::ofstream(dir_ / "mod.WASM") << "w";
    fs::create_symlink("/etc/passwd", dir_ / "passwd");
    fs::create_symlink("index.html", dir_ / "home.html");  // inside: fine
    root_ = fs::canonical(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  int status(const std::string& target) { return resolveStaticFile(root_, target).status; }

  std::filesystem::path dir_, root_;
};

TEST_F(StaticFilesTest, ServesOnlyRegularFilesUnderTheRoot) {
  StaticFileLookup f = resolveStaticFile(root_, "/");
  ASSERT_EQ(f.status, 200);
  EXPECT_EQ(f.path, root_ / "index.html");
  EXPECT_STREQ(f.content_type, "text/html; charset=utf-8");
  f = resolveStaticFile(root_, "/js/app.js?v=3#x");
  ASSERT_EQ(f.status, 200);
  EXPECT_STREQ(f.content_type, "text/javascript; charset=utf-8");
  EXPECT_EQ(resolveStaticFile(root_, "/js/").path, root_ / "js" / "index.html");
  EXPECT_EQ(resolveStaticFile(root_, "//js//app.js").status, 200);
  EXPECT_EQ(resolveStaticFile(root_, "/%6As/app.js").status, 200);
  EXPECT_EQ(resolveStaticFile(root_, "/home.html").status, 200);
  EXPECT_STREQ(resolveStaticFile(root_, "/mod.WASM").content_type, "application/wasm");

  for (const char* t :
       {"/../etc/passwd", "/js/../../etc/passwd", "/%2e%2e/etc/passwd", "/%2E%2E%2Fetc%2Fpasswd",
        "/js/%2e%2e/%2e%2e/etc/passwd", "/./index.html", "/.%2e/x", "/..\\etc\\passwd",
        "/index.html%00.png", "/%zz", "/%2", "etc/passwd", "", "*"})
    EXPECT_EQ(status(t), 400) << t;
  for (const char* t : {"/passwd", "/.secret", "/js", "/missing.html", "/%2fetc%2fpasswd",
                        "//etc/passwd", "/index.html/"})
    EXPECT_EQ(status(t), 404) << t;
}

TEST(StaticFiles, ContentTypes) {
  EXPECT_STREQ(contentTypeFor("a.css"), "text/css; charset=utf-8");
  EXPECT_STREQ(contentTypeFor("a.json"), "application/json");
  EXPECT_STREQ(contentTypeFor("a.png"), "image/png");
  EXPECT_STREQ(contentTypeFor("a.mjs"), "text/javascript; charset=utf-8");
  EXPECT_STREQ(contentTypeFor("a.bin"), "application/octet-stream");
  EXPECT_STREQ(contentTypeFor("Makefile"), "application/octet-stream");
}

}  // namespace
}  // namespace cvephands

// The rigs' reconnect back-off (the browser client's retryDelayMs has the same sequence).
namespace cvephands {
namespace {
TEST(ReconnectBackoff, DoublesUpToTheMaximumAndStartsOverAfterASuccess) {
  ReconnectBackoff b(2.0, 30.0);
  EXPECT_EQ(b.failed(), 2.0);
  EXPECT_EQ(b.failed(), 4.0);
  EXPECT_EQ(b.failed(), 8.0);
  EXPECT_EQ(b.failed(), 16.0);
  EXPECT_EQ(b.failed(), 30.0);
  EXPECT_EQ(b.failed(), 30.0);
  EXPECT_EQ(b.failures(), 6);
  b.succeeded();
  EXPECT_EQ(b.failures(), 0);
  EXPECT_EQ(b.failed(), 2.0);
  EXPECT_THROW(ReconnectBackoff(0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(ReconnectBackoff(2.0, 1.0), std::invalid_argument);
}
}  // namespace
}  // namespace cvephands
