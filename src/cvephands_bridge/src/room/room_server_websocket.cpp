// WsSession: one WebSocket participant (handshake, join, reads, its bounded send queue, kicks),
// on a plain or a TLS stream (WsSessionOn<PlainStream>, WsSessionOn<TlsStream>).
#include <algorithm>
#include <chrono>

#include "room_server_internal.h"

namespace cvephands {
namespace room_server_internal {
namespace {

constexpr size_t kReadChunk = 64 * 1024;
// A receiver counts as slow once its current write has waited this long (its socket buffer is
// full: the link or the reader cannot keep up). Only then is its queue held to queue_length;
// one that keeps up may take a burst (a sender's backlog after a network hiccup, or the
// server's own thread descheduled for a moment) of up to kBurstFactor * queue_length without
// drops, because a dropped delta frame costs the receiver the hand until the next key frame.
constexpr auto kSlowWrite = std::chrono::milliseconds(50);
constexpr size_t kBurstFactor = 4;
// Control messages are never dropped; this many waiting means the client is not reading.
constexpr size_t kMaxControlBacklog = 256;
constexpr const char* kEvictedDetail = "too many connections wait to join: the oldest one is closed";

Clock::duration toDuration(double seconds) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

websocket::close_code closeCodeFor(const std::string& reason) {
  if (reason == "too_large") return websocket::close_code::too_big;
  if (reason == "room_full" || reason == "server_full" || reason == "evicted")
    return websocket::close_code::try_again_later;
  if (reason == "shutdown") return websocket::close_code::going_away;
  return websocket::close_code::policy_error;
}

template <class Stream>
class WsSessionOn final : public WsSession {
 public:
  WsSessionOn(ServerCore& server, Stream&& stream);
  ~WsSessionOn() override;

  void run(http::request<http::string_body> upgrade);
  void shutdown() override;
  void evict() override;
  void deliver(Bytes message, bool binary) override;

 private:
  struct Outgoing {
    Bytes data;
    bool binary = false;
    bool close = false;  // the close frame (data unused)
    websocket::close_reason close_reason;
  };

  std::shared_ptr<WsSessionOn> shared() {
    return std::static_pointer_cast<WsSessionOn>(shared_from_this());
  }
  void onAccept(beast::error_code ec);
  // Takes a message of `bytes` from the sender's rate; false (counted as a drop) if over it.
  bool withinRate(size_t bytes);
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
  websocket::stream<Stream> ws_;
  net::steady_timer timer_;  // join timeout, then the close grace
  http::request<http::string_body> upgrade_;
  beast::flat_buffer in_;
  std::deque<Outgoing> queue_;  // waiting, not counting the one being written
  size_t queued_binary_ = 0;
  Outgoing in_flight_;
  bool writing_ = false;
  Clock::time_point write_started_;
  bool registered_ = false, joined_ = false, closing_ = false, dead_ = false;
  bool accepted_ = false, evicted_ = false;  // WebSocket handshake done; evicted during it
  SenderRateLimit rate_;
};

}  // namespace

template <class Stream>
WsSessionOn<Stream>::WsSessionOn(ServerCore& server, Stream&& stream)
    : server_(server), ws_(std::move(stream)), timer_(ws_.get_executor()),
      rate_(server.options().max_sender_messages_per_s, server.options().max_sender_bytes_per_s) {}

template <class Stream>
WsSessionOn<Stream>::~WsSessionOn() {
  if (registered_) server_.unregisterConnection(this);
}

template <class Stream>
void WsSessionOn<Stream>::run(http::request<http::string_body> upgrade) {
  upgrade_ = std::move(upgrade);
  if (server_.registerConnection(this, weak_from_this(), true,
                                 remoteAddress(beast::get_lowest_layer(ws_).socket())) == Admission::kStopping) {
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
  ws_.async_accept(upgrade_, [self = shared()](beast::error_code ec) { self->onAccept(ec); });
}

template <class Stream>
void WsSessionOn<Stream>::onAccept(beast::error_code ec) {
  if (ec) return end();
  accepted_ = true;
  if (evicted_) return kick("evicted", kEvictedDetail, kCloseGrace, /*count=*/false);
  timer_.expires_after(toDuration(server_.options().join_timeout));
  timer_.async_wait([self = shared()](beast::error_code ec) {
    if (!ec && !self->joined_ && !self->closing_)
      self->kick("join_timeout", "no join message in time");
  });
  doRead();
}

template <class Stream>
void WsSessionOn<Stream>::doRead() {
  ws_.async_read_some(in_, kReadChunk, [self = shared()](beast::error_code ec, size_t) {
    self->onRead(ec);
  });
}

template <class Stream>
void WsSessionOn<Stream>::onRead(beast::error_code ec) {
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
  net::post(ws_.get_executor(), [self = shared()] { self->doRead(); });
}

template <class Stream>
void WsSessionOn<Stream>::handleText(std::string_view text) {
  // Control messages count against the sender's message rate too (a ping flood would keep
  // the server encoding pongs); over it, they are dropped like hand messages.
  if (joined_ && !withinRate(text.size())) return;
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

template <class Stream>
void WsSessionOn<Stream>::handleBinary() {
  if (!joined_) return kick("not_joined", "binary message before join");
  if (role == room::Role::kViewer) return kick("viewer_cannot_send", "viewers only watch");
  if (!withinRate(in_.size())) return;
  server_.relay(*this, in_);
}

template <class Stream>
bool WsSessionOn<Stream>::withinRate(size_t bytes) {
  if (rate_.admit(bytes, Clock::now())) return true;
  ++rate_dropped;
  ++server_.rate_dropped;
  return false;
}

template <class Stream>
void WsSessionOn<Stream>::deliver(Bytes message, bool binary) {
  net::post(ws_.get_executor(), [self = shared(), m = std::move(message),
                                 binary]() mutable { self->enqueue(std::move(m), binary); });
}

template <class Stream>
void WsSessionOn<Stream>::enqueue(Bytes message, bool binary) {
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

template <class Stream>
void WsSessionOn<Stream>::writeNext() {
  if (queue_.empty() || dead_) return;
  in_flight_ = std::move(queue_.front());
  queue_.pop_front();
  queued = queue_.size();
  if (in_flight_.binary) --queued_binary_;
  writing_ = true;
  write_started_ = Clock::now();
  if (in_flight_.close) {
    ws_.async_close(in_flight_.close_reason,
                    [self = shared()](beast::error_code) { self->end(); });
    return;
  }
  ws_.binary(in_flight_.binary);
  ws_.async_write(net::buffer(*in_flight_.data),
                  [self = shared()](beast::error_code ec, size_t bytes) {
                    self->onWrite(ec, bytes);
                  });
}

template <class Stream>
void WsSessionOn<Stream>::onWrite(beast::error_code ec, size_t bytes) {
  writing_ = false;
  in_flight_.data.reset();
  if (ec) return end();
  ++messages_out;
  bytes_out += bytes;
  writeNext();
}

template <class Stream>
void WsSessionOn<Stream>::kick(const std::string& reason, const std::string& detail, Clock::duration grace,
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
  timer_.async_wait([self = shared()](beast::error_code ec) {
    if (!ec) self->end();
  });
}

template <class Stream>
void WsSessionOn<Stream>::hardKick(const std::string& reason) {
  if (dead_) return;
  server_.countKick(reason);
  end();
}

template <class Stream>
void WsSessionOn<Stream>::shutdown() {
  net::post(ws_.get_executor(), [self = shared()] {
    if (self->dead_) return;
    if (!self->closing_)
      return self->kick("shutdown", "the server is stopping", kShutdownGrace, false);
    self->timer_.expires_after(kShutdownGrace);  // already closing: do not wait the full grace
    self->timer_.async_wait([self](beast::error_code ec) {
      if (!ec) self->end();
    });
  });
}

template <class Stream>
void WsSessionOn<Stream>::evict() {
  net::post(ws_.get_executor(), [self = shared()] {
    if (self->joined_ || self->closing_) return;
    if (!self->accepted_) {
      self->evicted_ = true;  // still in the handshake: onAccept closes it
      return;
    }
    self->kick("evicted", kEvictedDetail, kCloseGrace, /*count=*/false);
  });
}

template <class Stream>
void WsSessionOn<Stream>::end() {
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

void startWsSession(ServerCore& server, PlainStream&& stream, http::request<http::string_body> upgrade) {
  std::make_shared<WsSessionOn<PlainStream>>(server, std::move(stream))->run(std::move(upgrade));
}

void startWsSession(ServerCore& server, TlsStream&& stream, http::request<http::string_body> upgrade) {
  std::make_shared<WsSessionOn<TlsStream>>(server, std::move(stream))->run(std::move(upgrade));
}

}  // namespace room_server_internal
}  // namespace cvephands
