// Room server (DESIGN.md section 4, "Hand meshes and the CVE"): a WebSocket relay that puts the
// hands of several rigs into shared meeting rooms, and the web server of the browser client.
// The protocol is room_protocol.h; rigs usually feed it through RoomClient (room_client.h), from
// the same machine or across the network.
//
// Live hand data must never wait for the slowest participant, so every connection has its own
// bounded outgoing queue and its own asynchronous writes: when a receiver falls behind, the
// OLDEST hand message queued for it is dropped (counted), control messages never are, and a
// receiver whose current write has made no progress for stall_timeout is disconnected. Anything
// that breaks the protocol (malformed JSON, binary before the join, an oversized message, a
// wrong token) gets an error message and closes that connection only.
//
// Exposure: binds 127.0.0.1 unless told otherwise. On another address anyone who reaches the
// port can join a room unless a token is set, and without TLS the token and the hands travel in
// clear text: give it a certificate (tls_certificate_file, tls_private_key_file) and it serves
// https and wss instead (TLS 1.2 or newer, OpenSSL) on the same port. Browsers let any web page open a
// WebSocket to 127.0.0.1, so upgrades from a browser (they carry an Origin header) are accepted
// only from the server's own pages or allowed_origins, and on a loopback bind only with a
// loopback Host header (a DNS-rebinding page names its own host there).
//
// Implementation: Boost.Beast on Boost.Asio (Debian's Boost, header-only) and asio::ssl, one
// io_context with `threads` threads, one strand per connection; the sessions are templates on
// the stream (TCP, or TLS over TCP), one code path for both. Hidden behind this header so users
// do not compile Beast.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cvephands_bridge/room/room_protocol.h"

namespace cvephands {

struct RoomServerOptions {
  std::string bind_address = "127.0.0.1";  // IPv4 or IPv6 literal; "0.0.0.0" for all
  uint16_t port = 0;                       // 0: ephemeral; RoomServer::port() tells which
  std::string token;                       // empty: no token required
  // Origins ("http://host:port", exact, case-insensitive) whose pages may connect besides the
  // server's own; "*" allows any. Clients without an Origin header (RoomClient) are not
  // affected.
  std::vector<std::string> allowed_origins;
  std::string static_root;                    // browser client directory; empty: no HTTP files
  // TLS: a PEM certificate (the server's first, then any intermediates) and its PEM private key
  // (not encrypted). Both set: the port speaks only https and wss, and start() throws when
  // either cannot be loaded or they do not match; both empty: plain http and ws.
  std::string tls_certificate_file, tls_private_key_file;
  size_t max_message_size = size_t(1) << 20;  // bytes, any message a client sends
  // Hand messages queued per SLOW receiver (its current write has waited > 50 ms) before the
  // oldest is dropped. A receiver that keeps up may queue 4x as many during a burst.
  size_t queue_length = 16;
  double stall_timeout = 5.0;        // s: a receiver whose write is stuck this long is closed
  size_t max_clients = 64;           // joined participants (rigs and viewers), all rooms
  // WebSocket connections that have not joined yet have their own limits, so that idle or
  // slow handshakes cannot take the seats of participants: at most max_pending_per_address
  // from one IP address and max_pending in all. One more, and the OLDEST pending connection
  // (of that address, or of all) is closed with "evicted": a real client joins within
  // milliseconds of its handshake, so the idle ones go first, and a rig behind the same
  // address (NAT) as a flood still gets in.
  size_t max_pending = 64;
  size_t max_pending_per_address = 8;
  // Plain HTTP connections (the browser's file requests, and every WebSocket before its
  // upgrade; with TLS from the accept on, so the TLS handshake counts too): one more, and the
  // oldest goes, of its address (max_pending_per_address) or of all.
  size_t max_http_connections = 32;
  // Per sender: messages per second (hands and control messages) and bytes per second, each a
  // token bucket holding one second's worth (so a burst of up to a second's allowance passes;
  // the byte rate must be 0 or at least max_message_size). Messages beyond either are dropped
  // at the server (not relayed or answered) and counted in ParticipantStats::rate_dropped.
  // 0 = no limit. The defaults pass the densest codec (raw, ~12.5 MB/s for two hands at 25 fps)
  // and stop a sender from flooding a room.
  double max_sender_messages_per_s = 200.0;
  double max_sender_bytes_per_s = 16e6;
  double join_timeout = room::kJoinTimeoutSeconds;  // s from the handshake to the join
  // A client silent for half to all of this (s) is closed: the server pings it at half this
  // period and browsers and RoomClient answer on their own. 0: never (and no pings).
  double idle_timeout = 30.0;
  room::SeatLayout seats;
  int threads = 1;  // io_context threads (a rig sends ~1 Mbit/s of hands: one is plenty)
};

struct ParticipantStats {
  uint32_t id = 0;
  std::string room, name;
  room::Role role = room::Role::kRig;
  int seat = -1;
  uint64_t messages_in = 0, bytes_in = 0;    // hand messages received from it
  uint64_t messages_out = 0, bytes_out = 0;  // messages written to it (all kinds)
  uint64_t dropped = 0;                      // hand messages dropped for it (slow reader)
  uint64_t rate_dropped = 0;                 // its own hand messages dropped (over its rate)
  size_t queued = 0;                         // messages waiting for it now
};

struct RoomStats {
  std::string name;
  size_t rigs = 0, viewers = 0;
  // Sums over the room's participants, present and past (a room lives while it has members).
  uint64_t messages_in = 0, bytes_in = 0, messages_out = 0, bytes_out = 0, dropped = 0;
};

struct RoomServerStats {
  std::vector<RoomStats> rooms;                // by name
  std::vector<ParticipantStats> participants;  // joined ones, by id
  uint64_t connections = 0;                    // TCP connections accepted
  uint64_t http_requests = 0;                  // plain HTTP requests answered (files and errors)
  uint64_t dropped = 0;                        // hand messages dropped, all receivers ever
  uint64_t rate_dropped = 0;                   // hand messages dropped over senders' rates
  size_t pending = 0;                          // WebSocket connections not joined yet (now)
  // Connections the server closed, by error reason (room_protocol.h), e.g. "slow_client";
  // "evicted_http": HTTP connections closed for newer ones (no error message: plain HTTP);
  // with TLS, "tls_handshake": handshakes that failed (a plain http or ws client, a client
  // that does not trust the certificate, a connection closed before its handshake) and
  // "tls_handshake_timeout": handshakes that took longer than 5 s.
  std::map<std::string, uint64_t> kicked;
};

class RoomServer {
 public:
  explicit RoomServer(const RoomServerOptions& options = RoomServerOptions());
  ~RoomServer();  // stop()
  RoomServer(const RoomServer&) = delete;
  RoomServer& operator=(const RoomServer&) = delete;

  // Binds, listens and starts the threads. Throws std::runtime_error when the address cannot
  // be bound, static_root is not a directory or the TLS certificate or key cannot be loaded
  // (naming the file and OpenSSL's reason), std::invalid_argument for bad options. Once.
  void start();
  // Closes the listener, tells every client "shutdown" (close code 1001), gives them a moment
  // to close cleanly, then cuts what is left and joins the threads. Returns within ~1.5 s.
  void stop();

  uint16_t port() const;  // the bound port, valid after start()
  bool tls() const;       // https and wss (a certificate was given)
  const RoomServerOptions& options() const;
  RoomServerStats stats() const;  // thread-safe, for diagnostics

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cvephands
