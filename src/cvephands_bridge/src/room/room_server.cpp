#include "cvephands_bridge/room/room_server.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>
#include <unordered_map>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "cvephands_bridge/room/static_files.h"

namespace cvephands {
namespace {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;
using Bytes = std::shared_ptr<const std::string>;

constexpr size_t kReadChunk = 64 * 1024;
constexpr auto kHttpTimeout = std::chrono::seconds(10);
constexpr auto kHandshakeTimeout = std::chrono::seconds(5);
// After an error message: time for it and the close handshake to go out before the socket is
// cut (a stalled client never reads them).
constexpr auto kCloseGrace = std::chrono::seconds(2);
constexpr auto kShutdownGrace = std::chrono::milliseconds(500);
// A receiver counts as slow once its current write has waited this long (its socket buffer is
// full: the link or the reader cannot keep up). Only then is its queue held to queue_length;
// one that keeps up may take a burst (a sender's backlog after a network hiccup, or the
// server's own thread descheduled for a moment) of up to kBurstFactor * queue_length without
// drops, because a dropped delta frame costs the receiver the hand until the next key frame.
constexpr auto kSlowWrite = std::chrono::milliseconds(50);
constexpr size_t kBurstFactor = 4;
// Control messages are never dropped; this many waiting means the client is not reading.
constexpr size_t kMaxControlBacklog = 256;

Clock::duration toDuration(double seconds) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

websocket::close_code closeCodeFor(const std::string& reason) {
  if (reason == "too_large") return websocket::close_code::too_big;
  if (reason == "room_full" || reason == "server_full")
    return websocket::close_code::try_again_later;
  if (reason == "shutdown") return websocket::close_code::going_away;
  return websocket::close_code::policy_error;
}

bool sameToken(const std::string& expected, const std::string& given) {
  if (expected.size() != given.size()) return false;
  unsigned char diff = 0;  // no early exit: timing does not tell how much matched
  for (size_t i = 0; i < expected.size(); ++i) diff |= uint8_t(expected[i] ^ given[i]);
  return diff == 0;
}

class ServerCore;

// What stop() needs of every live connection.
class Connection {
 public:
  virtual ~Connection() = default;
  virtual void shutdown() = 0;  // any thread
};

enum class Admission { kOk, kFull, kStopping };

// One WebSocket participant. All its state lives on its strand (the socket's executor); other
// connections reach it only through deliver() and shutdown(), which post there.
class WsSession : public Connection, public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(ServerCore& server, beast::tcp_stream&& stream)
      : server_(server), ws_(std::move(stream)), timer_(ws_.get_executor()) {}
  ~WsSession() override;

  void run(http::request<http::string_body> upgrade);
  void shutdown() override;
  // Queue a message for this client (any thread).
  void deliver(Bytes message, bool binary);

  // Identity: set by ServerCore::join under its mutex, read there too (and on this strand).
  uint32_t id = 0;
  std::string room, name;
  room::Role role = room::Role::kRig;
  int seat = -1;
  uint32_t sequence = 0;  // binary messages received (relay header)
  std::atomic<uint64_t> messages_in{0}, bytes_in{0}, messages_out{0}, bytes_out{0}, dropped{0};
  std::atomic<size_t> queued{0};

 private:
  struct Outgoing {
    Bytes data;
    bool binary = false;
    bool close = false;  // the close frame (data unused)
    websocket::close_reason close_reason;
  };

  void onAccept(beast::error_code ec, bool full);
  void doRead();
  void onRead(beast::error_code ec);
  void handleText(std::string_view text);
  void handleBinary();
  void enqueue(Bytes message, bool binary);
  void writeNext();
  void onWrite(beast::error_code ec, size_t bytes);
  // Error message, close handshake, and the socket cut after `grace` whatever happens.
  void kick(const std::string& reason, const std::string& detail,
            Clock::duration grace = kCloseGrace, bool count = true);
  void hardKick(const std::string& reason);  // cut now (nothing can be written any more)
  void end();

  ServerCore& server_;
  websocket::stream<beast::tcp_stream> ws_;
  net::steady_timer timer_;  // join timeout, then the close grace
  http::request<http::string_body> upgrade_;
  beast::flat_buffer in_;
  std::deque<Outgoing> queue_;  // waiting, not counting the one being written
  size_t queued_binary_ = 0;
  Outgoing in_flight_;
  bool writing_ = false;
  Clock::time_point write_started_;
  bool registered_ = false, joined_ = false, closing_ = false, dead_ = false;
};

// Plain HTTP: static files, and the upgrade to a WsSession on /ws.
class HttpSession : public Connection, public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(ServerCore& server, tcp::socket&& socket)
      : server_(server), strand_(socket.get_executor()), stream_(std::move(socket)) {}
  ~HttpSession() override;
  void run();
  void shutdown() override;

 private:
  void doRead();
  void onRead(beast::error_code ec);
  void respondError(const http::request<http::string_body>& req, http::status status);
  void respondFile(const http::request<http::string_body>& req);
  template <class Response>
  void send(Response&& response);
  void onWrite(beast::error_code ec, bool close);
  void closeSocket();

  ServerCore& server_;
  net::any_io_executor strand_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::shared_ptr<void> response_;  // alive until its write completes
  bool registered_ = false, upgraded_ = false;
};

class ServerCore {
 public:
  explicit ServerCore(const RoomServerOptions& options) : options_(options) {
    if (options_.queue_length < 1) throw std::invalid_argument("RoomServer: queue_length < 1");
    if (options_.max_message_size < 1)
      throw std::invalid_argument("RoomServer: max_message_size < 1");
    if (options_.seats.seats < 1) throw std::invalid_argument("RoomServer: seats < 1");
    if (options_.threads < 1) throw std::invalid_argument("RoomServer: threads < 1");
    if (!(options_.stall_timeout > 0) || !(options_.join_timeout > 0) || options_.idle_timeout < 0)
      throw std::invalid_argument("RoomServer: timeouts must be positive");
  }
  ~ServerCore() {
    stop();
    // Handlers still queued (only after a forced stop) die with the io_context; they may own
    // sessions whose destructors call unregisterConnection, so this must go first.
    acceptor_.reset();
    ioc_.reset();
  }

  void start();
  void stop();
  uint16_t port() const { return port_; }
  const RoomServerOptions& options() const { return options_; }
  const std::filesystem::path& root() const { return root_; }
  RoomServerStats stats() const;

  Admission registerConnection(Connection* c, std::weak_ptr<Connection> weak, bool websocket);
  void unregisterConnection(Connection* c, bool websocket);
  bool originAllowed(const http::request<http::string_body>& req) const;
  bool tokenOk(const std::string& given) const {
    return options_.token.empty() || sameToken(options_.token, given);
  }
  // Seats the session and sends the new participants list to the others; the session queues
  // *welcome and *list itself. False with an error reason when the room is full.
  bool join(const std::shared_ptr<WsSession>& s, const room::JoinRequest& request, Bytes* welcome,
            Bytes* list, std::string* reason, std::string* detail);
  void leave(WsSession* s);
  void relay(WsSession& sender, const beast::flat_buffer& payload);
  void countKick(const std::string& reason) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++kicked_[reason];
  }
  std::atomic<uint64_t> dropped{0}, http_requests{0}, connections{0};

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
  std::unordered_map<Connection*, std::weak_ptr<Connection>> connections_;
  size_t websockets_ = 0, https_ = 0;
  std::map<std::string, Room> rooms_;
  std::map<std::string, uint64_t> kicked_;
  uint32_t next_id_ = 1;
  std::condition_variable threads_done_;
  int threads_running_ = 0;

  std::unique_ptr<net::io_context> ioc_ = std::make_unique<net::io_context>();
  std::optional<tcp::acceptor> acceptor_;
  std::optional<net::executor_work_guard<net::io_context::executor_type>> work_;
  std::vector<std::thread> threads_;
};

// ---- WsSession --------------------------------------------------------------------------------

WsSession::~WsSession() {
  if (registered_) server_.unregisterConnection(this, true);
}

void WsSession::run(http::request<http::string_body> upgrade) {
  upgrade_ = std::move(upgrade);
  const Admission admission = server_.registerConnection(this, weak_from_this(), true);
  if (admission == Admission::kStopping) {
    beast::get_lowest_layer(ws_).close();
    return;
  }
  registered_ = true;
  const RoomServerOptions& o = server_.options();
  beast::get_lowest_layer(ws_).expires_never();  // the websocket timeouts below take over
  websocket::stream_base::timeout t;
  t.handshake_timeout = kHandshakeTimeout;
  t.idle_timeout = o.idle_timeout > 0 ? toDuration(o.idle_timeout) : websocket::stream_base::none();
  t.keep_alive_pings = o.idle_timeout > 0;
  ws_.set_option(t);
  ws_.set_option(websocket::stream_base::decorator(
      [](websocket::response_type& res) { res.set(http::field::server, "cvephands-room"); }));
  ws_.read_message_max(0);   // enforced in onRead, so the client gets an error message first
  ws_.auto_fragment(false);  // one frame per message
  ws_.async_accept(upgrade_, [self = shared_from_this(), full = admission == Admission::kFull](
                                 beast::error_code ec) { self->onAccept(ec, full); });
}

void WsSession::onAccept(beast::error_code ec, bool full) {
  if (ec) return end();
  if (full) return kick("server_full", "the server has its maximum number of clients");
  timer_.expires_after(toDuration(server_.options().join_timeout));
  timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
    if (!ec && !self->joined_ && !self->closing_)
      self->kick("join_timeout", "no join message in time");
  });
  doRead();
}

void WsSession::doRead() {
  ws_.async_read_some(in_, kReadChunk, [self = shared_from_this()](beast::error_code ec, size_t) {
    self->onRead(ec);
  });
}

void WsSession::onRead(beast::error_code ec) {
  if (ec) return end();
  if (closing_) return;  // the close handshake reads on its own
  if (in_.size() > server_.options().max_message_size)
    return kick("too_large",
                "message over " + std::to_string(server_.options().max_message_size) + " bytes");
  if (!ws_.is_message_done()) return doRead();
  if (ws_.got_text()) {
    const auto data = in_.data();
    handleText(std::string_view(static_cast<const char*>(data.data()), data.size()));
  } else {
    handleBinary();
  }
  in_.consume(in_.size());
  if (closing_) return;
  // Next read through the back of the queue: a read completes in one handler, a write to each
  // receiver takes several, so reading on at once lets a burst from one sender outrun the
  // fan-out (and fill queues of receivers that are not slow at all).
  net::post(ws_.get_executor(), [self = shared_from_this()] { self->doRead(); });
}

void WsSession::handleText(std::string_view text) {
  const room::ClientMessage m = room::parseClientMessage(text);
  switch (m.type) {
    case room::ClientMessage::Type::kInvalid:
      return kick(m.reason, m.detail);
    case room::ClientMessage::Type::kPing:
      if (!joined_) return kick("not_joined", "ping before join");
      return enqueue(
          std::make_shared<const std::string>(room::encodePong(m.ping_id, room::nowMicros())),
          false);
    case room::ClientMessage::Type::kJoin: {
      if (joined_) return kick("already_joined", "a second join");
      if (!server_.tokenOk(m.join.token)) return kick("bad_token", "missing or wrong token");
      std::string reason, detail;
      Bytes welcome, list;
      if (!server_.join(shared_from_this(), m.join, &welcome, &list, &reason, &detail))
        return kick(reason, detail);
      joined_ = true;
      timer_.cancel();
      // Queued directly (this is our strand): they precede any hand message that other strands
      // post to us from now on.
      enqueue(std::move(welcome), false);
      enqueue(std::move(list), false);
      return;
    }
  }
}

void WsSession::handleBinary() {
  if (!joined_) return kick("not_joined", "binary message before join");
  if (role == room::Role::kViewer) return kick("viewer_cannot_send", "viewers only watch");
  server_.relay(*this, in_);
}

void WsSession::deliver(Bytes message, bool binary) {
  net::post(ws_.get_executor(), [self = shared_from_this(), m = std::move(message),
                                 binary]() mutable { self->enqueue(std::move(m), binary); });
}

void WsSession::enqueue(Bytes message, bool binary) {
  if (closing_) return;  // after a kick only its error and close go out
  if (binary) {
    const size_t limit = server_.options().queue_length;
    const bool slow = writing_ && Clock::now() - write_started_ > kSlowWrite;
    if (queued_binary_ >= limit && (slow || queued_binary_ >= limit * kBurstFactor)) {
      // Live data: the newest hands matter, so the oldest waiting one goes.
      const auto oldest =
          std::find_if(queue_.begin(), queue_.end(), [](const Outgoing& o) { return o.binary; });
      queue_.erase(oldest);
      --queued_binary_;
      ++dropped;
      ++server_.dropped;
      if (writing_ && Clock::now() - write_started_ > toDuration(server_.options().stall_timeout))
        return hardKick("slow_client");
    }
    ++queued_binary_;
  } else if (queue_.size() >= server_.options().queue_length + kMaxControlBacklog) {
    return hardKick("slow_client");
  }
  Outgoing o;
  o.data = std::move(message);
  o.binary = binary;
  queue_.push_back(std::move(o));
  queued = queue_.size();
  if (!writing_) writeNext();
}

void WsSession::writeNext() {
  if (queue_.empty() || dead_) return;
  in_flight_ = std::move(queue_.front());
  queue_.pop_front();
  queued = queue_.size();
  if (in_flight_.binary) --queued_binary_;
  writing_ = true;
  write_started_ = Clock::now();
  if (in_flight_.close) {
    ws_.async_close(in_flight_.close_reason,
                    [self = shared_from_this()](beast::error_code) { self->end(); });
    return;
  }
  ws_.binary(in_flight_.binary);
  ws_.async_write(net::buffer(*in_flight_.data),
                  [self = shared_from_this()](beast::error_code ec, size_t bytes) {
                    self->onWrite(ec, bytes);
                  });
}

void WsSession::onWrite(beast::error_code ec, size_t bytes) {
  writing_ = false;
  in_flight_.data.reset();
  if (ec) return end();
  ++messages_out;
  bytes_out += bytes;
  writeNext();
}

void WsSession::kick(const std::string& reason, const std::string& detail, Clock::duration grace,
                     bool count) {
  if (closing_) return;
  closing_ = true;
  if (count) server_.countKick(reason);
  // Hand data still waiting would only delay the error.
  queue_.erase(
      std::remove_if(queue_.begin(), queue_.end(), [](const Outgoing& o) { return o.binary; }),
      queue_.end());
  queued_binary_ = 0;
  Outgoing error;
  error.data = std::make_shared<const std::string>(room::encodeError(reason, detail));
  queue_.push_back(std::move(error));
  Outgoing close;
  close.close = true;
  close.close_reason = websocket::close_reason(closeCodeFor(reason), reason);
  queue_.push_back(std::move(close));
  queued = queue_.size();
  if (!writing_) writeNext();
  timer_.expires_after(grace);
  timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
    if (!ec) self->end();
  });
}

void WsSession::hardKick(const std::string& reason) {
  if (dead_) return;
  server_.countKick(reason);
  end();
}

void WsSession::shutdown() {
  net::post(ws_.get_executor(), [self = shared_from_this()] {
    if (self->dead_) return;
    if (!self->closing_)
      return self->kick("shutdown", "the server is stopping", kShutdownGrace, false);
    self->timer_.expires_after(kShutdownGrace);  // already closing: do not wait the full grace
    self->timer_.async_wait([self](beast::error_code ec) {
      if (!ec) self->end();
    });
  });
}

void WsSession::end() {
  if (dead_) return;
  dead_ = closing_ = true;
  timer_.cancel();
  auto& socket = beast::get_lowest_layer(ws_).socket();
  beast::error_code ignored;
  socket.shutdown(tcp::socket::shutdown_both, ignored);
  beast::get_lowest_layer(ws_).close();  // pending operations complete with an error
  queue_.clear();
  queued = 0;
  if (joined_) server_.leave(this);
}

// ---- HttpSession ------------------------------------------------------------------------------

HttpSession::~HttpSession() {
  if (registered_) server_.unregisterConnection(this, false);
}

void HttpSession::run() {
  if (server_.registerConnection(this, weak_from_this(), false) != Admission::kOk) {
    beast::error_code ignored;
    stream_.socket().close(ignored);
    return;
  }
  registered_ = true;
  net::dispatch(strand_, [self = shared_from_this()] { self->doRead(); });
}

void HttpSession::shutdown() {
  net::post(strand_, [self = shared_from_this()] {
    if (!self->upgraded_) self->closeSocket();
  });
}

void HttpSession::closeSocket() {
  beast::error_code ignored;
  stream_.socket().shutdown(tcp::socket::shutdown_both, ignored);
  stream_.close();
}

void HttpSession::doRead() {
  parser_.emplace();
  parser_->header_limit(8 * 1024);
  parser_->body_limit(4 * 1024);  // GET has no body; a WebSocket upgrade neither
  stream_.expires_after(kHttpTimeout);
  http::async_read(stream_, buffer_, *parser_,
                   [self = shared_from_this()](beast::error_code ec, size_t) { self->onRead(ec); });
}

void HttpSession::onRead(beast::error_code ec) {
  if (ec) return closeSocket();  // includes end_of_stream and the timeout
  http::request<http::string_body> req = parser_->release();
  const std::string_view target(req.target().data(), req.target().size());
  const std::string_view path = target.substr(0, target.find('?'));
  if (websocket::is_upgrade(req)) {
    if (path != room::kWebSocketPath) return respondError(req, http::status::not_found);
    if (!server_.originAllowed(req)) return respondError(req, http::status::forbidden);
    upgraded_ = true;
    std::make_shared<WsSession>(server_, std::move(stream_))->run(std::move(req));
    return;
  }
  ++server_.http_requests;
  if (req.method() != http::verb::get && req.method() != http::verb::head)
    return respondError(req, http::status::method_not_allowed);
  if (path == room::kWebSocketPath) return respondError(req, http::status::upgrade_required);
  if (server_.root().empty()) return respondError(req, http::status::not_found);
  respondFile(req);
}

void HttpSession::respondError(const http::request<http::string_body>& req, http::status status) {
  http::response<http::string_body> res(status, req.version());
  res.set(http::field::server, "cvephands-room");
  res.set(http::field::content_type, "text/plain; charset=utf-8");
  res.keep_alive(req.keep_alive());
  if (req.method() != http::verb::head)
    res.body() = std::string(http::obsolete_reason(status)) + "\n";
  res.prepare_payload();
  send(std::move(res));
}

void HttpSession::respondFile(const http::request<http::string_body>& req) {
  const std::string_view target(req.target().data(), req.target().size());
  const StaticFileLookup file = resolveStaticFile(server_.root(), target);
  if (file.status != 200) return respondError(req, http::status(file.status));
  beast::error_code ec;
  http::file_body::value_type body;
  body.open(file.path.c_str(), beast::file_mode::scan, ec);
  if (ec) return respondError(req, http::status::not_found);
  const auto setHeaders = [&](auto& res) {
    res.set(http::field::server, "cvephands-room");
    res.set(http::field::content_type, file.content_type);
    res.set(http::field::cache_control, "no-cache");
    res.set("X-Content-Type-Options", "nosniff");
    res.keep_alive(req.keep_alive());
  };
  if (req.method() == http::verb::head) {
    http::response<http::empty_body> res(http::status::ok, req.version());
    setHeaders(res);
    res.content_length(body.size());
    return send(std::move(res));
  }
  const auto size = body.size();
  http::response<http::file_body> res(std::piecewise_construct, std::make_tuple(std::move(body)),
                                      std::make_tuple(http::status::ok, req.version()));
  setHeaders(res);
  res.content_length(size);
  send(std::move(res));
}

template <class Response>
void HttpSession::send(Response&& response) {
  auto res = std::make_shared<std::decay_t<Response>>(std::move(response));
  response_ = res;
  stream_.expires_after(kHttpTimeout);
  http::async_write(stream_, *res,
                    [self = shared_from_this(), close = res->need_eof()](
                        beast::error_code ec, size_t) { self->onWrite(ec, close); });
}

void HttpSession::onWrite(beast::error_code ec, bool close) {
  response_.reset();
  if (ec || close) return closeSocket();
  doRead();
}

// ---- ServerCore -------------------------------------------------------------------------------

void ServerCore::start() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (running_ || stopping_) throw std::logic_error("RoomServer::start: call once");
  }
  if (!options_.static_root.empty()) {
    std::error_code ec;
    root_ = std::filesystem::canonical(options_.static_root, ec);
    if (ec || !std::filesystem::is_directory(root_))
      throw std::runtime_error("RoomServer: static_root is not a directory: " +
                               options_.static_root);
  }
  try {
    const tcp::endpoint endpoint(net::ip::make_address(options_.bind_address), options_.port);
    acceptor_.emplace(net::make_strand(*ioc_));
    acceptor_->open(endpoint.protocol());
    acceptor_->set_option(net::socket_base::reuse_address(true));
    acceptor_->bind(endpoint);
    acceptor_->listen(net::socket_base::max_listen_connections);
    port_ = acceptor_->local_endpoint().port();
    loopback_bind_ = endpoint.address().is_loopback();
  } catch (const boost::system::system_error& e) {
    acceptor_.reset();
    throw std::runtime_error("RoomServer: cannot listen on " + options_.bind_address + ":" +
                             std::to_string(options_.port) + ": " + e.what());
  }
  work_.emplace(ioc_->get_executor());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    running_ = true;
    threads_running_ = options_.threads;
  }
  net::post(acceptor_->get_executor(), [this] { doAccept(); });
  for (int i = 0; i < options_.threads; ++i)
    threads_.emplace_back([this] {
      ioc_->run();
      std::lock_guard<std::mutex> lock(mutex_);
      --threads_running_;
      threads_done_.notify_all();
    });
}

void ServerCore::doAccept() {
  acceptor_->async_accept(
      net::make_strand(*ioc_), [this](beast::error_code ec, tcp::socket socket) {
        if (ec == net::error::operation_aborted || !acceptor_->is_open()) return;
        if (!ec) {
          ++connections;
          beast::error_code ignored;
          socket.set_option(tcp::no_delay(true), ignored);  // small hand messages: no Nagle delay
          std::make_shared<HttpSession>(*this, std::move(socket))->run();
        }
        doAccept();
      });
}

void ServerCore::stop() {
  std::vector<std::weak_ptr<Connection>> live;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!running_) return;
    stopping_ = true;  // connections accepted from now on close at once
    for (const auto& c : connections_) live.push_back(c.second);
  }
  net::post(acceptor_->get_executor(), [this] {
    beast::error_code ignored;
    acceptor_->close(ignored);
  });
  for (const auto& weak : live)
    if (const auto c = weak.lock()) c->shutdown();
  live.clear();
  work_.reset();
  {
    std::unique_lock<std::mutex> lock(mutex_);
    // Sessions cut themselves after kShutdownGrace; beyond that something is stuck.
    if (!threads_done_.wait_for(lock, kShutdownGrace + std::chrono::seconds(1),
                                [this] { return threads_running_ == 0; }))
      ioc_->stop();
  }
  for (std::thread& t : threads_) t.join();
  threads_.clear();
  std::vector<std::shared_ptr<WsSession>> members;  // released outside the lock
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& r : rooms_)
      for (auto& m : r.second.members) members.push_back(std::move(m));
    rooms_.clear();
    running_ = false;
  }
}

bool ServerCore::originAllowed(const http::request<http::string_body>& req) const {
  const beast::string_view origin = req[http::field::origin];
  if (origin.empty()) return true;  // not a browser: the token is the guard
  const beast::string_view host = req[http::field::host];
  if (loopback_bind_) {
    // The host part of Host, without the port ("[::1]:80", "localhost:80", "127.0.0.1").
    const beast::string_view name =
        host.substr(0, host.size() && host[0] == '[' ? host.find(']') + 1 : host.rfind(':'));
    const bool loopback_name =
        beast::iequals(name, "localhost") || name == "[::1]" || name.substr(0, 4) == "127.";
    if (!loopback_name) return false;
  }
  for (const std::string& allowed : options_.allowed_origins)
    if (allowed == "*" || beast::iequals(allowed, origin)) return true;
  // Same origin: the page came from this server, so Origin is scheme://<Host header>.
  for (const beast::string_view scheme : {"http://", "https://"})
    if (origin.substr(0, scheme.size()) == scheme)
      return beast::iequals(origin.substr(scheme.size()), host);
  return false;
}

Admission ServerCore::registerConnection(Connection* c, std::weak_ptr<Connection> weak,
                                         bool websocket) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (stopping_) return Admission::kStopping;
  size_t& count = websocket ? websockets_ : https_;
  const size_t limit = websocket ? options_.max_clients : options_.max_http_connections;
  connections_[c] = std::move(weak);
  ++count;
  return count > limit ? Admission::kFull : Admission::kOk;
}

void ServerCore::unregisterConnection(Connection* c, bool websocket) {
  std::lock_guard<std::mutex> lock(mutex_);
  connections_.erase(c);
  --(websocket ? websockets_ : https_);
}

Bytes ServerCore::participantsMessage(const std::string& name, const Room& r) const {
  std::vector<room::ParticipantInfo> list;
  for (const auto& m : r.members) {
    room::ParticipantInfo p;
    p.id = m->id;
    p.name = m->name;
    p.role = m->role;
    p.seat = m->seat;
    if (m->seat >= 0) p.seat_pose = room::seatPose(m->seat, options_.seats);
    list.push_back(std::move(p));
  }
  return std::make_shared<const std::string>(room::encodeParticipants(name, list));
}

bool ServerCore::join(const std::shared_ptr<WsSession>& s, const room::JoinRequest& request,
                      Bytes* welcome, Bytes* list, std::string* reason, std::string* detail) {
  room::ParticipantInfo self;
  std::vector<std::shared_ptr<WsSession>> others;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    Room& r = rooms_[request.room];
    if (r.seat_taken.empty()) r.seat_taken.assign(options_.seats.seats, false);
    int seat = -1;
    if (request.role == room::Role::kRig) {
      const auto free = std::find(r.seat_taken.begin(), r.seat_taken.end(), false);
      if (free == r.seat_taken.end()) {
        if (r.members.empty()) rooms_.erase(request.room);
        *reason = "room_full";
        *detail = "all " + std::to_string(options_.seats.seats) + " seats of the room are taken";
        return false;
      }
      seat = int(free - r.seat_taken.begin());
      *free = true;
    }
    s->id = next_id_++;
    s->room = request.room;
    s->name = request.name.empty() ? "participant " + std::to_string(s->id) : request.name;
    s->role = request.role;
    s->seat = seat;
    r.members.push_back(s);  // ids only grow: stays sorted
    r.snapshot = std::make_shared<const std::vector<std::shared_ptr<WsSession>>>(r.members);
    self.id = s->id;
    self.name = s->name;
    self.role = s->role;
    self.seat = seat;
    if (seat >= 0) self.seat_pose = room::seatPose(seat, options_.seats);
    *list = participantsMessage(request.room, r);
    for (const auto& m : r.members)
      if (m != s) others.push_back(m);
  }
  *welcome = std::make_shared<const std::string>(
      room::encodeWelcome(request.room, self, options_.seats.seats, room::nowMicros()));
  for (const auto& m : others) m->deliver(*list, false);
  return true;
}

void ServerCore::leave(WsSession* s) {
  Bytes list;
  std::vector<std::shared_ptr<WsSession>> rest;
  std::shared_ptr<WsSession> keep;  // released outside the lock
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = rooms_.find(s->room);
    if (it == rooms_.end()) return;
    Room& r = it->second;
    const auto m = std::find_if(r.members.begin(), r.members.end(),
                                [s](const std::shared_ptr<WsSession>& p) { return p.get() == s; });
    if (m == r.members.end()) return;
    keep = std::move(*m);
    r.members.erase(m);
    if (s->seat >= 0) r.seat_taken[s->seat] = false;
    r.departed.add(*s);
    if (r.members.empty()) {
      rooms_.erase(it);
    } else {
      r.snapshot = std::make_shared<const std::vector<std::shared_ptr<WsSession>>>(r.members);
      list = participantsMessage(s->room, r);
      rest = r.members;
    }
  }
  for (const auto& m : rest) m->deliver(list, false);
}

void ServerCore::relay(WsSession& sender, const beast::flat_buffer& payload) {
  const size_t n = payload.size();
  auto message = std::make_shared<std::string>(room::kRelayHeaderSize + n, '\0');
  room::RelayHeader h;
  h.sender = sender.id;
  h.seat = uint32_t(sender.seat);
  h.sequence = sender.sequence++;
  h.server_time_us = room::nowMicros();
  room::writeRelayHeader(h, reinterpret_cast<uint8_t*>(&(*message)[0]));
  net::buffer_copy(net::buffer(&(*message)[room::kRelayHeaderSize], n), payload.data());
  ++sender.messages_in;
  sender.bytes_in += n;
  std::shared_ptr<const std::vector<std::shared_ptr<WsSession>>> members;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = rooms_.find(sender.room);
    if (it == rooms_.end()) return;
    members = it->second.snapshot;
  }
  const Bytes shared = std::move(message);
  for (const auto& m : *members)
    if (m.get() != &sender) m->deliver(shared, true);
}

RoomServerStats ServerCore::stats() const {
  RoomServerStats st;
  st.connections = connections;
  st.http_requests = http_requests;
  st.dropped = dropped;
  std::lock_guard<std::mutex> lock(mutex_);
  st.kicked = kicked_;
  for (const auto& [name, r] : rooms_) {
    RoomStats rs;
    rs.name = name;
    Totals t = r.departed;
    for (const auto& m : r.members) {
      (m->role == room::Role::kViewer ? rs.viewers : rs.rigs)++;
      t.add(*m);
      ParticipantStats p;
      p.id = m->id;
      p.room = name;
      p.name = m->name;
      p.role = m->role;
      p.seat = m->seat;
      p.messages_in = m->messages_in;
      p.bytes_in = m->bytes_in;
      p.messages_out = m->messages_out;
      p.bytes_out = m->bytes_out;
      p.dropped = m->dropped;
      p.queued = m->queued;
      st.participants.push_back(std::move(p));
    }
    rs.messages_in = t.messages_in, rs.bytes_in = t.bytes_in, rs.messages_out = t.messages_out;
    rs.bytes_out = t.bytes_out, rs.dropped = t.dropped;
    st.rooms.push_back(std::move(rs));
  }
  std::sort(st.participants.begin(), st.participants.end(),
            [](const ParticipantStats& a, const ParticipantStats& b) { return a.id < b.id; });
  return st;
}

}  // namespace

// ---- RoomServer -------------------------------------------------------------------------------

struct RoomServer::Impl : ServerCore {
  using ServerCore::ServerCore;
};

RoomServer::RoomServer(const RoomServerOptions& options) : impl_(std::make_unique<Impl>(options)) {}
RoomServer::~RoomServer() = default;
void RoomServer::start() { impl_->start(); }
void RoomServer::stop() { impl_->stop(); }
uint16_t RoomServer::port() const { return impl_->port(); }
const RoomServerOptions& RoomServer::options() const { return impl_->options(); }
RoomServerStats RoomServer::stats() const { return impl_->stats(); }

}  // namespace cvephands
