// Private to the room server files: the connection classes, ServerCore and what they share.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <unordered_map>
#include <vector>

#include <boost/asio.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>

#include "cvephands_bridge/room/room_server.h"

namespace cvephands {
namespace room_server_internal {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;
using Bytes = std::shared_ptr<const std::string>;
// The two streams a connection runs on; the sessions are templates on them.
using PlainStream = beast::tcp_stream;
using TlsStream = beast::ssl_stream<beast::tcp_stream>;

// After an error message: time for it and the close handshake to go out before the socket is
// cut (a stalled client never reads them).
constexpr auto kCloseGrace = std::chrono::seconds(2);
constexpr auto kShutdownGrace = std::chrono::milliseconds(500);
// For the TLS handshake, and then for the WebSocket one: a real client takes milliseconds.
constexpr auto kHandshakeTimeout = std::chrono::seconds(5);

class ServerCore;

// What stop() needs of every live connection.
class Connection {
 public:
  virtual ~Connection() = default;
  virtual void shutdown() = 0;  // any thread
  // Closed to make room for a newer connection while it waits (HTTP not upgraded, WebSocket
  // not joined; any thread).
  virtual void evict() {}
};

enum class Admission { kOk, kStopping };

// The peer's IP address as text ("?" if the socket no longer knows it): the per-address limit.
inline std::string remoteAddress(const tcp::socket& socket) {
  beast::error_code ec;
  const auto remote = socket.remote_endpoint(ec);
  return ec ? std::string("?") : remote.address().to_string();
}

// Per-sender token buckets (RoomServerOptions::max_sender_*), on the sender's strand.
class SenderRateLimit {
 public:
  SenderRateLimit(double messages_per_s, double bytes_per_s)
      : message_rate_(messages_per_s), byte_rate_(bytes_per_s),
        messages_(messages_per_s), bytes_(bytes_per_s) {}
  // True if a message of `size` bytes may pass at `now` (and takes it from the buckets).
  bool admit(size_t size, Clock::time_point now) {
    const double dt = started_ ? std::chrono::duration<double>(now - last_).count() : 0.0;
    started_ = true;
    last_ = now;
    if (message_rate_ > 0) messages_ = std::min(message_rate_, messages_ + dt * message_rate_);
    if (byte_rate_ > 0) bytes_ = std::min(byte_rate_, bytes_ + dt * byte_rate_);
    const bool ok = (message_rate_ <= 0 || messages_ >= 1.0) &&
                    (byte_rate_ <= 0 || bytes_ >= static_cast<double>(size));
    if (ok) messages_ -= 1.0, bytes_ -= static_cast<double>(size);
    return ok;
  }

 private:
  double message_rate_, byte_rate_;
  double messages_, bytes_;  // tokens: start full (one second's worth)
  bool started_ = false;
  Clock::time_point last_;
};

// One WebSocket participant as the rooms see it (ServerCore::join, leave, relay, stats). The
// session is WsSessionOn<Stream> (room_server_websocket.cpp): all its state lives on its strand
// (the socket's executor); other connections reach it only through deliver() and shutdown(),
// which post there.
class WsSession : public Connection, public std::enable_shared_from_this<WsSession> {
 public:
  // Queue a message for this client (any thread).
  virtual void deliver(Bytes message, bool binary) = 0;

  // Identity: set by ServerCore::join under its mutex, read there too (and on this strand).
  uint32_t id = 0;
  std::string room, name;
  room::Role role = room::Role::kRig;
  int seat = -1;
  uint32_t sequence = 0;  // binary messages received (relay header)
  std::atomic<uint64_t> messages_in{0}, bytes_in{0}, messages_out{0}, bytes_out{0}, dropped{0},
      rate_dropped{0};
  std::atomic<size_t> queued{0};
};

// The WebSocket session of an upgrade request that the HTTP session read on `stream` (its TLS
// handshake, if any, done): registers as waiting to join, answers the upgrade, then reads.
void startWsSession(ServerCore& server, PlainStream&& stream, http::request<http::string_body> upgrade);
void startWsSession(ServerCore& server, TlsStream&& stream, http::request<http::string_body> upgrade);

// HTTP on a freshly accepted socket (room_server_http.cpp), after the TLS handshake when the
// server has a certificate: static files, and the upgrade to a WsSession on /ws.
void startHttpSession(ServerCore& server, tcp::socket&& socket);

class ServerCore {
 public:
  explicit ServerCore(const RoomServerOptions& options);  // throws on bad options
  ~ServerCore();

  void start();
  void stop();
  uint16_t port() const { return port_; }
  const RoomServerOptions& options() const { return options_; }
  const std::filesystem::path& root() const { return root_; }
  // The server's TLS context (certificate and key loaded by start()); null without TLS.
  net::ssl::context* tlsContext() { return tls_ ? &*tls_ : nullptr; }
  RoomServerStats stats() const;

  // A connection registers as waiting (HTTP: not upgraded; WebSocket: not joined) from
  // `address`; in a full pool or address the oldest waiting one of its kind is evicted.
  Admission registerConnection(Connection* c, std::weak_ptr<Connection> weak, bool websocket,
                               const std::string& address);
  void unregisterConnection(Connection* c);
  bool originAllowed(const http::request<http::string_body>& req) const;
  bool tokenOk(const std::string& given) const;
  // Seats the session and sends the new participants list to the others; the session queues
  // *welcome and *list itself. False with an error reason when the room is full.
  bool join(const std::shared_ptr<WsSession>& s, const room::JoinRequest& request, Bytes* welcome,
            Bytes* list, std::string* reason, std::string* detail);
  void leave(WsSession* s);
  void relay(WsSession& sender, const beast::flat_buffer& payload);
  void countKick(const std::string& reason);
  std::atomic<uint64_t> dropped{0}, rate_dropped{0}, http_requests{0}, connections{0};

 private:
  struct Totals {
    uint64_t messages_in = 0, bytes_in = 0, messages_out = 0, bytes_out = 0, dropped = 0;
    void add(const WsSession& s) {
      messages_in += s.messages_in, bytes_in += s.bytes_in, messages_out += s.messages_out;
      bytes_out += s.bytes_out, dropped += s.dropped;
    }
  };
  struct Room {
    std::vector<std::shared_ptr<WsSession>> members;  // by id
    // Copy-on-write view for relays: taking it costs one lock and one refcount.
    std::shared_ptr<const std::vector<std::shared_ptr<WsSession>>> snapshot;
    std::vector<bool> seat_taken;
    Totals departed;
  };

  void doAccept();
  Bytes participantsMessage(const std::string& name, const Room& r) const;  // under mutex_

  RoomServerOptions options_;
  std::filesystem::path root_;
  uint16_t port_ = 0;
  bool loopback_bind_ = true;

  mutable std::mutex mutex_;  // everything below
  bool running_ = false, stopping_ = false;
  struct Registered {
    std::weak_ptr<Connection> weak;
    bool websocket = false;
    bool pending = false;  // HTTP not upgraded / WebSocket not joined, and not being evicted
    bool joined = false;
    std::string address;
    uint64_t order = 0;    // admission order: the oldest pending is evicted first
  };
  std::unordered_map<Connection*, Registered> connections_;
  size_t joined_ = 0;
  size_t pending_[2] = {0, 0};  // waiting connections: [0] HTTP (not upgraded), [1] WebSocket (not joined)
  std::map<std::string, size_t> pending_by_address_[2];
  uint64_t next_order_ = 0;
  void unpendLocked(Registered& r);  // under mutex_
  std::map<std::string, Room> rooms_;
  std::map<std::string, uint64_t> kicked_;
  uint32_t next_id_ = 1;
  std::condition_variable threads_done_;
  int threads_running_ = 0;

  std::optional<net::ssl::context> tls_;  // set before the threads start, then only read
  std::unique_ptr<net::io_context> ioc_ = std::make_unique<net::io_context>();
  std::optional<tcp::acceptor> acceptor_;
  std::optional<net::executor_work_guard<net::io_context::executor_type>> work_;
  std::vector<std::thread> threads_;
};

}  // namespace room_server_internal
}  // namespace cvephands
