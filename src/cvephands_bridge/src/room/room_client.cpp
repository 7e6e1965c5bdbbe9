#include "cvephands_bridge/room/room_client.h"

#include <atomic>
#include <chrono>
#include <deque>
#include <filesystem>
#include <future>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include <openssl/ssl.h>
#include <openssl/x509v3.h>

#include <boost/asio.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>

#include "openssl_errors.h"

namespace cvephands {
namespace {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;
using Payload = std::shared_ptr<const std::vector<uint8_t>>;
using PlainStream = beast::tcp_stream;
using TlsStream = beast::ssl_stream<beast::tcp_stream>;

constexpr auto kCloseTimeout = std::chrono::seconds(2);

std::chrono::steady_clock::duration toDuration(double seconds) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(seconds));
}

// The client side of TLS: TLS 1.2 or newer, the server's certificate verified against the
// system's CAs or those of ca_file. "" or the reason the CA file cannot be used.
std::string setUpTls(net::ssl::context& ctx, const std::string& ca_file) {
  SSL_CTX* native = ctx.native_handle();
  ERR_clear_error();
  if (SSL_CTX_set_min_proto_version(native, TLS1_2_VERSION) != 1)
    return "tls: cannot require TLS 1.2: " + room_tls::openSslErrors();
  ctx.set_verify_mode(net::ssl::verify_peer);
  if (ca_file.empty()) {
    if (SSL_CTX_set_default_verify_paths(native) != 1)
      return "tls: cannot load the system's CA certificates: " + room_tls::openSslErrors();
    return "";
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(ca_file, ec))
    return "tls: CA file " + ca_file + ": no such file";
  if (SSL_CTX_load_verify_locations(native, ca_file.c_str(), nullptr) != 1)
    return "tls: CA file " + ca_file + ": cannot load PEM certificates: " + room_tls::openSslErrors();
  return "";
}

}  // namespace

// What the API (any thread) and the connection share. The connection itself is Link<Stream>
// below, one code path for ws (PlainStream) and wss (TlsStream).
struct RoomClient::Impl {
  explicit Impl(const RoomClientOptions& o) : options(o) {
    if (options.send_queue_length < 1)
      throw std::invalid_argument("RoomClient: send_queue_length < 1");
    if (options.tls) {
      tls_context.emplace(net::ssl::context::tls_client);
      tls_error = setUpTls(*tls_context, options.tls_ca_file);  // connect() reports it
    }
  }
  virtual ~Impl() = default;
  static std::unique_ptr<Impl> make(const RoomClientOptions& o);

  // On the io thread.
  virtual void start() = 0;
  virtual void enqueue(Payload p) = 0;
  virtual void requestClose() = 0;  // from close()

  template <class Stream>
  struct Link;

  RoomClientOptions options;
  std::optional<net::ssl::context> tls_context;  // with options.tls
  std::string tls_error;                         // why tls_context is unusable
  net::io_context ioc;
  std::optional<net::executor_work_guard<net::io_context::executor_type>> work;
  std::promise<std::string> joined;  // "" or the reason connect() failed
  std::thread thread;
  std::promise<void> thread_done;

  // Any thread.
  std::atomic<bool> connected{false}, user_closed{false}, started{false};
  std::atomic<uint64_t> sent{0}, bytes_sent{0}, send_dropped{0}, received{0}, bytes_received{0};
  mutable std::mutex mutex;  // the three below
  room::ParticipantInfo self;
  std::vector<room::ParticipantInfo> participants;
  std::string close_reason;
};

// Everything in a Link runs on the client's one io thread. Handlers capture `this`: close()
// joins the thread before the object goes, and handlers still queued then are destroyed with
// the io_context without running.
template <class Stream>
struct RoomClient::Impl::Link final : RoomClient::Impl {
  static constexpr bool kTls = std::is_same_v<Stream, TlsStream>;

  explicit Link(const RoomClientOptions& o) : Impl(o), ws(makeStream()) {}

  Stream makeStream() {
    if constexpr (kTls) return Stream(ioc, *tls_context);
    else return Stream(ioc);
  }

  void requestClose() override {
    // Ended already (refused, kicked, lost): nothing is left to do, but Beast's handshake or
    // close timer may still be armed and would keep the thread (and close()) waiting for it.
    if (ended) return ioc.stop();
    close_requested = true;
    doClose();
  }

  void start() override {
    if constexpr (kTls) {
      if (!tls_error.empty()) return end(tls_error);
      // The name (or address) the certificate must be for, and the name the server is told
      // (SNI: names only, never addresses).
      SSL* ssl = ws.next_layer().native_handle();
      X509_VERIFY_PARAM* param = SSL_get0_param(ssl);
      X509_VERIFY_PARAM_set_hostflags(param, X509_CHECK_FLAG_NO_PARTIAL_WILDCARDS);
      beast::error_code not_address;
      net::ip::make_address(options.host, not_address);
      ERR_clear_error();
      const bool ok = not_address ? X509_VERIFY_PARAM_set1_host(param, options.host.c_str(), 0) == 1 &&
                                        SSL_set_tlsext_host_name(ssl, options.host.c_str()) == 1
                                  : X509_VERIFY_PARAM_set1_ip_asc(param, options.host.c_str()) == 1;
      if (!ok) return end("tls: cannot verify the host " + options.host + ": " + room_tls::openSslErrors());
    }
    resolver.async_resolve(
        options.host, std::to_string(options.port),
        [this](beast::error_code ec, tcp::resolver::results_type results) {
          if (ec) return end("resolve: " + ec.message());
          beast::get_lowest_layer(ws).expires_after(toDuration(options.connect_timeout));
          beast::get_lowest_layer(ws).async_connect(
              results, [this](beast::error_code ec, const tcp::endpoint&) { onConnect(ec); });
        });
  }

  void onConnect(beast::error_code ec) {
    if (ec) return end("connect: " + ec.message());
    beast::error_code ignored;
    beast::get_lowest_layer(ws).socket().set_option(tcp::no_delay(true), ignored);
    if constexpr (kTls) {
      // Within connect_timeout still (the expiry of the TCP connect).
      ws.next_layer().async_handshake(net::ssl::stream_base::client, [this](beast::error_code ec) {
        if (ec) return end("tls: " + tlsFailure(ec));
        handshake();
      });
    } else {
      handshake();
    }
  }

  // Why the TLS handshake failed: the certificate check's own reason when that was it.
  std::string tlsFailure(beast::error_code ec) {
    if constexpr (kTls) {
      const long result = SSL_get_verify_result(ws.next_layer().native_handle());
      if (result != X509_V_OK)
        return "certificate verify failed: " + std::string(X509_verify_cert_error_string(result)) +
               (options.tls_ca_file.empty() ? " (trusted: the system's CAs)"
                                            : " (trusted: CA file " + options.tls_ca_file + ")");
    }
    return ec == beast::error::timeout ? std::string("handshake timed out") : ec.message();
  }

  // The WebSocket handshake, then the join.
  void handshake() {
    beast::get_lowest_layer(ws).expires_never();  // the websocket timeouts take over
    websocket::stream_base::timeout t;
    t.handshake_timeout = toDuration(options.connect_timeout);
    // Idleness is watched by armIdle(), not by Beast: Beast 1.74 counts its idle timeout only
    // with keep-alive pings of its own, and pings from both ends sometimes stall the close
    // handshake until its timeout. The server pings; pongs are automatic.
    t.idle_timeout = websocket::stream_base::none();
    t.keep_alive_pings = false;
    ws.set_option(t);
    ws.control_callback([this](websocket::frame_type, beast::string_view) { heard(); });
    ws.read_message_max(options.max_message_size);
    ws.auto_fragment(false);
    ws.async_handshake(options.host + ":" + std::to_string(options.port), options.path,
                       [this](beast::error_code ec) {
                         if (ec) return end("handshake: " + ec.message());
                         handshaken = true;
                         if (close_requested) return doClose();
                         heard();
                         armIdle();
                         join_text = room::encodeJoin(options.join);
                         ws.text(true);
                         ws.async_write(net::buffer(join_text),
                                        [this](beast::error_code ec, size_t) {
                                          if (ec) return end("join: " + ec.message());
                                          doRead();
                                        });
                       });
  }

  void doRead() {
    ws.async_read(in, [this](beast::error_code ec, size_t) { onRead(ec); });
  }

  void heard() { last_heard = std::chrono::steady_clock::now(); }

  // A server that vanished without closing (network gone) is noticed here: nothing, not even
  // its pings or pongs, for idle_timeout. The server pings only a client it has not heard from,
  // so a rig that only sends (alone in its room) would hear nothing at all: after a quarter of
  // the timeout in silence the client asks for a pong itself (checked every eighth: the pong
  // has at least half the timeout to come back).
  void armIdle() {
    if (!(options.idle_timeout > 0)) return;
    idle_timer.expires_after(toDuration(options.idle_timeout / 8));
    idle_timer.async_wait([this](beast::error_code ec) {
      if (ec || ended || closing) return;
      const auto quiet = std::chrono::steady_clock::now() - last_heard;
      if (quiet > toDuration(options.idle_timeout))
        return end("idle_timeout: nothing from the server for " +
                   std::to_string(options.idle_timeout) + " s");
      if (quiet > toDuration(options.idle_timeout / 4) && connected && !ping_due) {
        ping_due = true;
        if (!writing) writeNext();
      }
      armIdle();
    });
  }

  void onRead(beast::error_code ec) {
    if (ec) {
      std::string reason = ec.message();
      if (ec == websocket::error::closed && !ws.reason().reason.empty())
        reason = std::string(ws.reason().reason.c_str());
      return end(reason);
    }
    heard();
    const auto data = in.data();
    const auto* bytes = static_cast<const uint8_t*>(data.data());
    if (ws.got_text()) {
      onText(room::parseServerMessage(
          std::string_view(reinterpret_cast<const char*>(bytes), data.size())));
    } else {
      room::RelayHeader h;
      size_t offset;
      if (room::readRelayHeader(bytes, data.size(), &h, &offset)) {
        ++received;
        bytes_received += data.size() - offset;
        if (options.on_hands) options.on_hands(h, bytes + offset, data.size() - offset);
      }
    }
    in.consume(in.size());
    doRead();
  }

  void onText(const room::ServerMessage& m) {
    switch (m.type) {
      case room::ServerMessage::Type::kWelcome: {
        {
          std::lock_guard<std::mutex> lock(mutex);
          self = m.self;
        }
        connected = true;
        settle("");
        break;
      }
      case room::ServerMessage::Type::kParticipants: {
        std::lock_guard<std::mutex> lock(mutex);
        participants = m.participants;
      }
        if (options.on_participants) options.on_participants(m.participants);
        break;
      case room::ServerMessage::Type::kError:
        server_error = m.reason + ": " + m.detail;  // the close follows
        break;
      default:
        break;  // pong, or a later protocol's message
    }
  }

  void enqueue(Payload p) override {
    if (ended || close_requested) return;
    if (queue.size() >= options.send_queue_length) {
      queue.pop_front();  // live data: the newest hands matter
      ++send_dropped;
    }
    queue.push_back(std::move(p));
    if (!writing) writeNext();
  }

  void writeNext() {
    if (ended) return;
    if (close_requested) return doClose();
    if (ping_due) {  // a keep-alive ping goes before the next hand message
      ping_due = false;
      ping_text = room::encodePing(std::to_string(++pings));
      writing = true;
      ws.text(true);
      ws.async_write(net::buffer(ping_text), [this](beast::error_code ec, size_t) {
        writing = false;
        if (ec) return end("write: " + ec.message());
        writeNext();
      });
      return;
    }
    if (queue.empty()) return;
    in_flight = std::move(queue.front());
    queue.pop_front();
    writing = true;
    ws.binary(true);
    ws.async_write(net::buffer(*in_flight), [this](beast::error_code ec, size_t n) {
      writing = false;
      in_flight.reset();
      if (ec) return end("write: " + ec.message());
      ++sent;
      bytes_sent += n;
      writeNext();
    });
  }

  // On the io thread, after close() asked for it.
  void doClose() {
    if (ended || closing) return;
    queue.clear();
    if (!handshaken) return end("closed");  // still connecting: cut
    if (writing) return;                    // writeNext comes back here
    closing = true;
    websocket::stream_base::timeout t;
    t.handshake_timeout = kCloseTimeout;  // also bounds the close handshake
    t.idle_timeout = websocket::stream_base::none();
    t.keep_alive_pings = false;
    ws.set_option(t);
    ws.async_close(websocket::close_code::normal, [this](beast::error_code) { end("closed"); });
  }

  void end(const std::string& why) {
    if (ended) return;
    ended = true;
    connected = false;
    resolver.cancel();
    idle_timer.cancel();
    beast::error_code ignored;
    beast::get_lowest_layer(ws).socket().shutdown(tcp::socket::shutdown_both, ignored);
    beast::get_lowest_layer(ws).close();
    queue.clear();
    const std::string reason = server_error.empty() ? why : server_error;
    {
      std::lock_guard<std::mutex> lock(mutex);
      close_reason = reason;
    }
    if (!settle(reason) && !user_closed && options.on_closed) options.on_closed(reason);
  }

  // Answers connect() once; true if this call did.
  bool settle(const std::string& result) {
    if (settled) return false;
    settled = true;
    joined.set_value(result);
    return true;
  }

  tcp::resolver resolver{ioc};
  net::steady_timer idle_timer{ioc};
  std::chrono::steady_clock::time_point last_heard;
  websocket::stream<Stream> ws;
  beast::flat_buffer in;
  std::string join_text;
  std::deque<Payload> queue;
  Payload in_flight;
  bool writing = false, handshaken = false, closing = false, ended = false, settled = false;
  bool ping_due = false;  // a keep-alive ping waits for the writer (armIdle)
  std::string ping_text;  // the one being written
  uint64_t pings = 0;
  bool close_requested = false;
  std::string server_error;
};

std::unique_ptr<RoomClient::Impl> RoomClient::Impl::make(const RoomClientOptions& o) {
  if (o.tls) return std::make_unique<Link<TlsStream>>(o);
  return std::make_unique<Link<PlainStream>>(o);
}

RoomClient::RoomClient(const RoomClientOptions& options) : impl_(Impl::make(options)) {}

RoomClient::~RoomClient() { close(); }

bool RoomClient::connect(std::string* error) {
  Impl& d = *impl_;
  if (d.started.exchange(true)) throw std::logic_error("RoomClient::connect: once per object");
  std::future<std::string> joined = d.joined.get_future();
  d.work.emplace(d.ioc.get_executor());
  d.thread = std::thread([&d] {
    d.ioc.run();
    d.thread_done.set_value();
  });
  net::post(d.ioc, [&d] { d.start(); });
  std::string result = "connect: timed out";
  if (joined.wait_for(toDuration(d.options.connect_timeout) + std::chrono::milliseconds(500)) ==
      std::future_status::ready)
    result = joined.get();
  if (result.empty()) return true;
  if (error) *error = result;
  close();
  return false;
}

bool RoomClient::send(std::vector<uint8_t>&& payload) {
  Impl& d = *impl_;
  if (!d.connected) return false;
  auto p = std::make_shared<const std::vector<uint8_t>>(std::move(payload));
  net::post(d.ioc, [&d, p = std::move(p)]() mutable { d.enqueue(std::move(p)); });
  return true;
}

bool RoomClient::send(const uint8_t* data, size_t size) {
  return send(std::vector<uint8_t>(data, data + size));
}

void RoomClient::close() {
  Impl& d = *impl_;
  if (!d.thread.joinable()) return;
  if (std::this_thread::get_id() == d.thread.get_id())
    throw std::logic_error("RoomClient::close from its own callback");
  d.user_closed = true;
  net::post(d.ioc, [&d] { d.requestClose(); });
  d.work.reset();
  if (d.thread_done.get_future().wait_for(kCloseTimeout + std::chrono::seconds(1)) !=
      std::future_status::ready)
    d.ioc.stop();  // something is stuck; its handlers die with the io_context
  d.thread.join();
  d.connected = false;
}

bool RoomClient::connected() const { return impl_->connected; }

room::ParticipantInfo RoomClient::self() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->self;
}

std::vector<room::ParticipantInfo> RoomClient::participants() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->participants;
}

std::string RoomClient::closeReason() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->close_reason;
}

RoomClientStats RoomClient::stats() const {
  RoomClientStats s;
  s.sent = impl_->sent;
  s.bytes_sent = impl_->bytes_sent;
  s.send_dropped = impl_->send_dropped;
  s.received = impl_->received;
  s.bytes_received = impl_->bytes_received;
  return s;
}

}  // namespace cvephands
