// Room client (room_protocol.h): joins a room of a RoomServer, sends this rig's hand messages
// and hands the other participants' ones to a callback. The hand bridge nodelet feeds the room
// through it, and the tests use it; it speaks WebSocket (ws://, or wss:// with `tls`), so the
// server may be in the same process, on the same machine or across the network.
//
// Sending never blocks the caller (the nodelet's callback thread): payloads go into a bounded
// queue written by the client's own thread, and when the link cannot keep up the OLDEST waiting
// payload is dropped (live data; counted in stats()). Callbacks run on the client's thread, one
// at a time, in arrival order; they must return quickly and must not call close().
//
// One object is one connection: after it closes (server gone, kicked, close()) make a new one to
// reconnect.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cvephands_bridge/room/room_protocol.h"

namespace cvephands {

struct RoomClientOptions {
  std::string host = "127.0.0.1";
  uint16_t port = 0;
  std::string path = room::kWebSocketPath;
  // wss:// instead of ws://: TLS 1.2 or newer, and the server's certificate must be valid for
  // `host` (its name, or its address) and issued by a CA of tls_ca_file (PEM; a self-signed
  // certificate is its own CA), or of the system's store (/etc/ssl/certs) when that is empty.
  // A failed check fails connect() with "tls: certificate verify failed: <why>".
  bool tls = false;
  std::string tls_ca_file;
  room::JoinRequest join;         // room, display name, token, role
  size_t send_queue_length = 16;  // payloads waiting to be written before the oldest is dropped
  size_t max_message_size = (size_t(1) << 20) + room::kRelayHeaderSize;  // bytes received
  double connect_timeout = 5.0;  // s: TCP connect (+ TLS) + WebSocket handshake + welcome
  // s without any data from the server (which pings every 15 s: half its own idle_timeout)
  // before the connection counts as lost; 0: never.
  double idle_timeout = 40.0;

  // Another participant's hand message: the relay header and the payload as its sender sent it
  // (valid during the call only).
  std::function<void(const room::RelayHeader&, const uint8_t* payload, size_t size)> on_hands;
  // The room's membership changed (the whole list, this client included).
  std::function<void(const std::vector<room::ParticipantInfo>&)> on_participants;
  // The connection ended; reason is the server's error ("bad_token: missing or wrong token"),
  // the WebSocket close reason, or the network error. Called once, not after close().
  std::function<void(const std::string& reason)> on_closed;
};

struct RoomClientStats {
  uint64_t sent = 0, bytes_sent = 0;          // payloads written to the socket
  uint64_t send_dropped = 0;                  // payloads dropped from the full send queue
  uint64_t received = 0, bytes_received = 0;  // hand messages received (payload bytes)
};

class RoomClient {
 public:
  explicit RoomClient(const RoomClientOptions& options);
  ~RoomClient();  // close()
  RoomClient(const RoomClient&) = delete;
  RoomClient& operator=(const RoomClient&) = delete;

  // Connects, joins and waits for the welcome (at most connect_timeout). False with the reason
  // in *error when refused or unreachable. Once per object.
  bool connect(std::string* error = nullptr);
  // Queues one hand message (copied / moved); false when not connected.
  bool send(const uint8_t* data, size_t size);
  bool send(std::vector<uint8_t>&& payload);
  // Closes cleanly (close handshake, at most ~2 s) and joins the client's thread. Idempotent.
  void close();

  bool connected() const;
  room::ParticipantInfo self() const;  // id, seat and seat pose from the welcome
  std::vector<room::ParticipantInfo> participants() const;
  std::string closeReason() const;  // empty while connected
  RoomClientStats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cvephands
