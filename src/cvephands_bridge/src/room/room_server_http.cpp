// HttpSession: HTTP requests (the browser client's static files) and the upgrade to /ws, on a
// plain or a TLS stream (HttpSession<PlainStream>, HttpSession<TlsStream>: with TLS the session
// starts with the handshake, registered as a waiting connection like any other).
#include <memory>
#include <optional>
#include <string_view>
#include <tuple>
#include <type_traits>

#include "cvephands_bridge/room/static_files.h"
#include "room_server_internal.h"

namespace cvephands {
namespace room_server_internal {
namespace {

constexpr auto kHttpTimeout = std::chrono::seconds(10);

// Static files, and the upgrade to a WsSession on /ws.
template <class Stream>
class HttpSession : public Connection, public std::enable_shared_from_this<HttpSession<Stream>> {
 public:
  static constexpr bool kTls = std::is_same_v<Stream, TlsStream>;

  HttpSession(ServerCore& server, Stream&& stream)
      : server_(server), strand_(stream.get_executor()), stream_(std::move(stream)) {}
  ~HttpSession() override;
  void run();
  void shutdown() override;
  void evict() override;

 private:
  void onHandshake(beast::error_code ec);
  void doRead();
  void onRead(beast::error_code ec);
  void respondError(const http::request<http::string_body>& req, http::status status);
  void respondFile(const http::request<http::string_body>& req);
  template <class Response>
  void send(Response&& response);
  void onWrite(beast::error_code ec, bool close);
  void finish();       // after a last response: TLS close_notify, then closeSocket
  void closeSocket();  // cut now

  ServerCore& server_;
  net::any_io_executor strand_;
  Stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::shared_ptr<void> response_;  // alive until its write completes
  bool registered_ = false, upgraded_ = false;
  bool closed_ = false;  // by closeSocket (evicted, stopping, done): its errors are no failures
};

template <class Stream>
HttpSession<Stream>::~HttpSession() {
  if (registered_) server_.unregisterConnection(this);
}

template <class Stream>
void HttpSession<Stream>::run() {
  if (server_.registerConnection(this, this->weak_from_this(), false,
                                 remoteAddress(beast::get_lowest_layer(stream_).socket())) !=
      Admission::kOk) {
    beast::error_code ignored;
    beast::get_lowest_layer(stream_).socket().close(ignored);
    return;
  }
  registered_ = true;
  net::dispatch(strand_, [self = this->shared_from_this()] {
    if constexpr (kTls) {
      // Waiting like any connection that has not sent its request: evictable, and timed out.
      beast::get_lowest_layer(self->stream_).expires_after(kHandshakeTimeout);
      self->stream_.async_handshake(net::ssl::stream_base::server,
                                    [self](beast::error_code ec) { self->onHandshake(ec); });
    } else {
      self->doRead();
    }
  });
}

// A plain http or ws client, one that does not trust the certificate, or a port scan: counted
// and closed (not if the server closed it: evicted or stopping).
template <class Stream>
void HttpSession<Stream>::onHandshake(beast::error_code ec) {
  if (!ec) return doRead();
  if (!closed_) server_.countKick(ec == beast::error::timeout ? "tls_handshake_timeout" : "tls_handshake");
  closeSocket();
}

template <class Stream>
void HttpSession<Stream>::shutdown() {
  net::post(strand_, [self = this->shared_from_this()] {
    if (!self->upgraded_) self->closeSocket();
  });
}

// The oldest waiting HTTP connection goes when the pool or its address is full: a client
// that connects and never sends a request (or trickles one) cannot keep others out.
template <class Stream>
void HttpSession<Stream>::evict() {
  net::post(strand_, [self = this->shared_from_this()] {
    if (!self->upgraded_) self->closeSocket();  // counted by registerConnection
  });
}

template <class Stream>
void HttpSession<Stream>::closeSocket() {
  closed_ = true;
  beast::error_code ignored;
  beast::get_lowest_layer(stream_).socket().shutdown(tcp::socket::shutdown_both, ignored);
  beast::get_lowest_layer(stream_).close();
}

template <class Stream>
void HttpSession<Stream>::finish() {
  if constexpr (kTls) {
    // close_notify, so that the client can tell the end of the response from a cut.
    beast::get_lowest_layer(stream_).expires_after(kHttpTimeout);
    stream_.async_shutdown([self = this->shared_from_this()](beast::error_code) { self->closeSocket(); });
  } else {
    closeSocket();
  }
}

template <class Stream>
void HttpSession<Stream>::doRead() {
  parser_.emplace();
  parser_->header_limit(8 * 1024);
  parser_->body_limit(4 * 1024);  // GET has no body; a WebSocket upgrade neither
  beast::get_lowest_layer(stream_).expires_after(kHttpTimeout);
  http::async_read(stream_, buffer_, *parser_,
                   [self = this->shared_from_this()](beast::error_code ec, size_t) { self->onRead(ec); });
}

template <class Stream>
void HttpSession<Stream>::onRead(beast::error_code ec) {
  if (ec) return closeSocket();  // includes end_of_stream and the timeout
  http::request<http::string_body> req = parser_->release();
  const std::string_view target(req.target().data(), req.target().size());
  const std::string_view path = target.substr(0, target.find('?'));
  if (websocket::is_upgrade(req)) {
    if (path != room::kWebSocketPath) return respondError(req, http::status::not_found);
    if (!server_.originAllowed(req)) return respondError(req, http::status::forbidden);
    upgraded_ = true;
    startWsSession(server_, std::move(stream_), std::move(req));
    return;
  }
  ++server_.http_requests;
  if (req.method() != http::verb::get && req.method() != http::verb::head)
    return respondError(req, http::status::method_not_allowed);
  if (path == room::kWebSocketPath) return respondError(req, http::status::upgrade_required);
  if (server_.root().empty()) return respondError(req, http::status::not_found);
  respondFile(req);
}

template <class Stream>
void HttpSession<Stream>::respondError(const http::request<http::string_body>& req, http::status status) {
  http::response<http::string_body> res(status, req.version());
  res.set(http::field::server, "cvephands-room");
  res.set(http::field::content_type, "text/plain; charset=utf-8");
  res.keep_alive(req.keep_alive());
  if (req.method() != http::verb::head)
    res.body() = std::string(http::obsolete_reason(status)) + "\n";
  res.prepare_payload();
  send(std::move(res));
}

template <class Stream>
void HttpSession<Stream>::respondFile(const http::request<http::string_body>& req) {
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

template <class Stream>
template <class Response>
void HttpSession<Stream>::send(Response&& response) {
  auto res = std::make_shared<std::decay_t<Response>>(std::move(response));
  response_ = res;
  beast::get_lowest_layer(stream_).expires_after(kHttpTimeout);
  http::async_write(stream_, *res,
                    [self = this->shared_from_this(), close = res->need_eof()](
                        beast::error_code ec, size_t) { self->onWrite(ec, close); });
}

template <class Stream>
void HttpSession<Stream>::onWrite(beast::error_code ec, bool close) {
  response_.reset();
  if (ec) return closeSocket();
  if (close) return finish();
  doRead();
}

}  // namespace

void startHttpSession(ServerCore& server, tcp::socket&& socket) {
  if (net::ssl::context* tls = server.tlsContext())
    std::make_shared<HttpSession<TlsStream>>(server, TlsStream(std::move(socket), *tls))->run();
  else
    std::make_shared<HttpSession<PlainStream>>(server, PlainStream(std::move(socket)))->run();
}

}  // namespace room_server_internal
}  // namespace cvephands
