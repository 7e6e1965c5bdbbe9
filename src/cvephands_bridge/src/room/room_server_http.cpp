// HttpSession: plain HTTP requests (the browser client's static files) and the upgrade to /ws.
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

// Plain HTTP: static files, and the upgrade to a WsSession on /ws.
class HttpSession : public Connection, public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(ServerCore& server, tcp::socket&& socket)
      : server_(server), strand_(socket.get_executor()), stream_(std::move(socket)) {}
  ~HttpSession() override;
  void run();
  void shutdown() override;
  void evict() override;

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

HttpSession::~HttpSession() {
  if (registered_) server_.unregisterConnection(this);
}

void HttpSession::run() {
  if (server_.registerConnection(this, weak_from_this(), false, remoteAddress(stream_.socket())) !=
      Admission::kOk) {
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

// The oldest waiting HTTP connection goes when the pool or its address is full: a client
// that connects and never sends a request (or trickles one) cannot keep others out.
void HttpSession::evict() {
  net::post(strand_, [self = shared_from_this()] {
    if (!self->upgraded_) self->closeSocket();  // counted by registerConnection
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

}  // namespace

void startHttpSession(ServerCore& server, tcp::socket&& socket) {
  std::make_shared<HttpSession>(server, std::move(socket))->run();
}

}  // namespace room_server_internal
}  // namespace cvephands
