// Room protocol (DESIGN.md section 4, "Hand meshes and the CVE"): how rigs and browsers meet in
// a shared virtual meeting room. Each rig is one participant with a SEAT at a round table; the
// seat fixes where the rig's `world` frame (DESIGN.md section 3) lies in the common ROOM frame,
// so every user's hands appear at their own place around one table. The server relays hand
// messages between the participants of a room without looking inside them (they are the hand
// stream codec's messages, hand_stream_codec.h, magic "CVHS", or face pictures, face_video.h,
// magic "CVVF"; a client tells them apart by the first 4 bytes and ignores other magics).
//
// Transport: one WebSocket (RFC 6455) per participant, on path /ws of the room server (the same
// port also serves the browser client's static files over plain HTTP GET).
//   TEXT frames   = control messages, one JSON object each (UTF-8, RFC 8259).
//   BINARY frames = hand data: client -> server the opaque payload (a codec message);
//                   server -> client the 32-byte RELAY HEADER below + that payload unchanged.
// Every message a client sends, text or binary, is at most the server's max message size
// (default 1 MiB). Anything that breaks this page gets an "error" message and the connection is
// closed; other participants are never affected. The server pings every 15 s (WebSocket ping
// frames; browsers answer on their own) and drops a client it has heard nothing from for 15-30
// s. An upgrade request with an Origin header (i.e. from a browser) is refused with HTTP 403
// unless the page came from this server (Origin = http(s)://<Host>) or from an origin the
// server allows; on a loopback server the Host must also be a loopback name.
//
// Client -> server (text)
//   {"type":"join", "room":R, "name":N, "token":T, "role":"rig"|"viewer"}
//       Must be the first message, within 10 s (server option) of the handshake. R: 1..64 chars
//       of [A-Za-z0-9_.-]. N: display name, at most 64 bytes (optional; default
//       "participant <id>"). T: the shared token (optional when the server has none; compared
//       exactly). role (optional, default "rig"): a rig takes a seat and may send hands; a viewer
//       (e.g. a browser that only watches) takes no seat and must not send binary frames.
//       Unknown members are ignored (room for later versions).
//   {"type":"ping", "id":X}   (after the join) answered by a "pong" with the same id (X: a
//       number or a string, optional) and the server clock: for latency and clock offsets.
// Server -> client (text)
//   {"type":"welcome", "protocol":1, "room":R, "participant":ID, "name":N, "role":"rig",
//    "seat":K, "seat_pose":[16 numbers], "seats":S, "server_time_us":T}
//       The answer to a good join. ID: uint32 >= 1, unique for the server's lifetime (never
//       reused). K: 0..S-1, the lowest free seat (-1 for a viewer). seat_pose: room_T_world of
//       this participant (below); null for a viewer. S: seats per room.
//   {"type":"participants", "room":R, "list":[{"id":ID, "name":N, "role":"rig"|"viewer",
//    "seat":K, "seat_pose":[16]|null}, ...]}
//       The whole membership of the room, ordered by id, including the receiver. Sent to every
//       member after each join and leave (the joiner gets it right after its welcome).
//   {"type":"pong", "id":X, "server_time_us":T}
//   {"type":"error", "reason":CODE, "detail":"human-readable text"}
//       Always followed by the server closing the connection, with CODE as the close frame's
//       reason and the close code below. CODE (stable, for programs):
//         bad_token     token missing or wrong            (close code 1008 policy violation)
//         malformed     text frame is not a JSON object with a string "type"         (1008)
//         bad_join      join fields missing or invalid                               (1008)
//         not_joined    binary frame or ping before the join                         (1008)
//         already_joined  a second join                                              (1008)
//         unknown_type  a "type" the server does not know                            (1008)
//         viewer_cannot_send  binary frame from a viewer                             (1008)
//         too_large     message over the max message size                            (1009)
//         room_full     all seats of the room are taken                              (1013)
//         server_full   max clients reached                                          (1013)
//         evicted       closed before its join to admit a newer connection: the oldest of
//                       those waiting to join from its address, or from all      (1013)
//         join_timeout  no join within 10 s                                          (1008)
//         slow_client   the client stopped reading (its queue stayed full)   (no message: the
//                       socket is closed at once, as nothing can be written to it)
//         shutdown      the server is stopping                                (1001 going away)
//       A text frame that is not valid UTF-8 is refused by the WebSocket layer itself (close
//       code 1007, no error message).
//
// Relay header (server -> client binary frames), all fields little endian:
//   offset size
//    0      4   magic "CVRM" (0x43 0x56 0x52 0x4D)
//    4      1   version (1)
//    5      1   header size in bytes (32; a reader skips this many bytes to reach the payload,
//               so later versions may append fields)
//    6      2   reserved, 0
//    8      4   sender participant id (uint32)
//   12      4   sender seat (uint32, 0..S-1)
//   16      4   sequence: the server's count of binary messages received from this sender
//               (from 0, wraps at 2^32). A gap seen by a receiver = messages the server dropped
//               for that receiver (a slow reader; see below)
//   20      4   reserved, 0
//   24      8   server receive time: microseconds since the Unix epoch (server's system clock)
//   32      n   payload: the sender's bytes, unchanged
// In JavaScript: const v = new DataView(buf); v.getUint32(8, true) is the sender, etc.
//
// Delivery: messages of one sender arrive in order. Per receiver the server keeps a bounded
// queue; when a receiver falls behind (its connection cannot take the data) the OLDEST queued
// binary message is dropped (live data: the newest matters); control messages never are. So a
// receiver may miss hand messages (the sequence shows it) and must resync on the codec's next
// key frame. A receiver whose connection takes nothing for the stall timeout (5 s) while data
// is waiting is disconnected.
//
// Room frame and seats: origin at the centre of the round table ON THE TABLE TOP (z = 0 is the
// table surface, as `world`'s z = 0 is the desk), z up, x and y horizontal. Seat k of S sits at
// angle a_k = 2 pi k / S: the rig's `world` origin (the desk marker, middle of the workspace) is
// placed at radius r (default 0.9 m) from the centre, c_k = (r cos a_k, r sin a_k, 0), and
// `world` is turned so that its +y (from the user towards the screen) points at the table centre
// and its +z is the room's +z:
//   world x -> room (-sin a_k,  cos a_k, 0)     (the user's right)
//   world y -> room (-cos a_k, -sin a_k, 0)     (towards the centre)
//   world z -> room (0, 0, 1)
// seat_pose is that 4x4 rigid transform room_T_world (p_room = T * p_world, metres) as 16
// numbers in COLUMN-MAJOR order (m00 m10 m20 m30 m01 ...; the translation is elements 12..14),
// the order of WebGL and three.js Matrix4.fromArray. A renderer with y up (three.js) applies its
// own room -> y-up rotation on top. The table top's height above the floor is the client's
// choice for drawing (0.75 m is typical of a desk).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace cvephands {
namespace room {

constexpr int kProtocolVersion = 1;
constexpr const char* kWebSocketPath = "/ws";
constexpr size_t kMaxRoomLength = 64;
constexpr size_t kMaxNameLength = 64;
constexpr double kJoinTimeoutSeconds = 10.0;

// Relay header (layout above).
constexpr uint8_t kRelayMagic[4] = {'C', 'V', 'R', 'M'};
constexpr uint8_t kRelayVersion = 1;
constexpr size_t kRelayHeaderSize = 32;

struct RelayHeader {
  uint32_t sender = 0;
  uint32_t seat = 0;
  uint32_t sequence = 0;
  uint64_t server_time_us = 0;
};

void writeRelayHeader(const RelayHeader& h, uint8_t out[kRelayHeaderSize]);
// Checks magic, version and that the stated header size fits in `size`; on success
// *payload_offset is where the payload starts.
bool readRelayHeader(const uint8_t* data, size_t size, RelayHeader* h, size_t* payload_offset);

// Seats ---------------------------------------------------------------------------------------

// room_T_world, column-major (see above).
using SeatPose = std::array<double, 16>;

struct SeatLayout {
  int seats = 6;        // per room, >= 1
  double radius = 0.9;  // m, table centre to each rig's world origin
};

SeatPose seatPose(int seat, const SeatLayout& layout);
SeatPose identityPose();

// Control messages ----------------------------------------------------------------------------

enum class Role { kRig, kViewer };
const char* roleName(Role role);

struct JoinRequest {
  std::string room;
  std::string name;
  std::string token;
  Role role = Role::kRig;
};

struct ParticipantInfo {
  uint32_t id = 0;
  std::string name;
  Role role = Role::kRig;
  int seat = -1;                        // -1 for viewers
  SeatPose seat_pose = identityPose();  // identity for viewers (sent as null)
};

// What a client sent, as the server reads it.
struct ClientMessage {
  enum class Type { kJoin, kPing, kInvalid };
  Type type = Type::kInvalid;
  JoinRequest join;     // kJoin
  std::string ping_id;  // kPing: the "id" member as JSON text ("null" when absent)
  std::string reason;   // kInvalid: an error code of the table above
  std::string detail;   // kInvalid: what was wrong
};
ClientMessage parseClientMessage(std::string_view text);

// What the server sent, as a client reads it.
struct ServerMessage {
  enum class Type { kWelcome, kParticipants, kPong, kError, kUnknown };
  Type type = Type::kUnknown;
  std::string room;                           // welcome, participants
  ParticipantInfo self;                       // welcome
  int seats = 0;                              // welcome
  std::vector<ParticipantInfo> participants;  // participants
  uint64_t server_time_us = 0;                // welcome, pong
  std::string ping_id;                        // pong, as JSON text
  std::string reason, detail;                 // error; kUnknown: why it was not understood
};
ServerMessage parseServerMessage(std::string_view text);

std::string encodeJoin(const JoinRequest& join);
std::string encodePing(std::string_view id_json);  // id as JSON text, e.g. "7"
std::string encodeWelcome(const std::string& room, const ParticipantInfo& self, int seats,
                          uint64_t server_time_us);
std::string encodeParticipants(const std::string& room, const std::vector<ParticipantInfo>& list);
std::string encodePong(std::string_view id_json, uint64_t server_time_us);
std::string encodeError(std::string_view reason, std::string_view detail);

// Room names: 1..kMaxRoomLength characters of [A-Za-z0-9_.-].
bool validRoomName(std::string_view room);

// Microseconds since the Unix epoch (the relay header's and the control messages' clock).
uint64_t nowMicros();

}  // namespace room
}  // namespace cvephands
