// RoomServer and ServerCore's life: option checks, the TLS context, listen and accept loop,
// stop, admission.
#include "cvephands_bridge/room/room_server.h"

#include <openssl/bio.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>

#include <chrono>
#include <stdexcept>

#include "openssl_errors.h"
#include "room_server_internal.h"

namespace cvephands {
namespace room_server_internal {
namespace {

using room_tls::openSslErrors;

bool sameToken(const std::string& expected, const std::string& given) {
  if (expected.size() != given.size()) return false;
  unsigned char diff = 0;  // no early exit: timing does not tell how much matched
  for (size_t i = 0; i < expected.size(); ++i) diff |= uint8_t(expected[i] ^ given[i]);
  return diff == 0;
}

// The server side of TLS: TLS 1.2 or newer, the certificate chain and its key from PEM files.
// Throws std::runtime_error naming the file and OpenSSL's reason.
void loadTlsContext(net::ssl::context& ctx, const std::string& certificate, const std::string& key) {
  SSL_CTX* native = ctx.native_handle();
  ERR_clear_error();
  ctx.set_options(net::ssl::context::default_workarounds | net::ssl::context::single_dh_use);
  if (SSL_CTX_set_min_proto_version(native, TLS1_2_VERSION) != 1)
    throw std::runtime_error("RoomServer: cannot require TLS 1.2: " + openSslErrors());
  const auto check = [](const std::string& what, const std::string& file) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
      throw std::runtime_error("RoomServer: TLS " + what + " file " + file +
                               (std::filesystem::exists(file, ec) ? ": not a regular file" : ": no such file"));
  };
  check("certificate", certificate);
  check("private key", key);
  if (SSL_CTX_use_certificate_chain_file(native, certificate.c_str()) != 1)
    throw std::runtime_error("RoomServer: TLS certificate file " + certificate +
                             ": cannot load a PEM certificate: " + openSslErrors());
  // Read apart from its use, so that a key that loads but belongs to another certificate is
  // told as such; an encrypted key fails (no passphrase) instead of asking on the terminal.
  EVP_PKEY* pkey = nullptr;
  if (BIO* bio = BIO_new_file(key.c_str(), "r")) {
    pkey = PEM_read_bio_PrivateKey(bio, nullptr, [](char*, int, int, void*) { return 0; }, nullptr);
    BIO_free(bio);
  }
  if (!pkey)
    throw std::runtime_error("RoomServer: TLS private key file " + key +
                             ": cannot load an unencrypted PEM private key: " + openSslErrors());
  const bool used = X509_check_private_key(SSL_CTX_get0_certificate(native), pkey) == 1 &&
                    SSL_CTX_use_PrivateKey(native, pkey) == 1;
  EVP_PKEY_free(pkey);
  if (!used)
    throw std::runtime_error("RoomServer: TLS private key file " + key +
                             " does not match the certificate in " + certificate + ": " +
                             openSslErrors());
}

}  // namespace

ServerCore::ServerCore(const RoomServerOptions& options) : options_(options) {
  if (options_.queue_length < 1) throw std::invalid_argument("RoomServer: queue_length < 1");
  if (options_.max_message_size < 1)
    throw std::invalid_argument("RoomServer: max_message_size < 1");
  if (options_.seats.seats < 1) throw std::invalid_argument("RoomServer: seats < 1");
  if (options_.threads < 1) throw std::invalid_argument("RoomServer: threads < 1");
  if (options_.max_pending < 1 || options_.max_pending_per_address < 1 || options_.max_http_connections < 1)
    throw std::invalid_argument(
        "RoomServer: max_pending, max_pending_per_address and max_http_connections must be >= 1");
  if (!(options_.max_sender_messages_per_s >= 0) || !(options_.max_sender_bytes_per_s >= 0))
    throw std::invalid_argument("RoomServer: sender rate limits must be >= 0 (0: none)");
  // The byte bucket holds one second's worth: a larger message could never pass.
  if (options_.max_sender_bytes_per_s > 0 &&
      options_.max_sender_bytes_per_s < static_cast<double>(options_.max_message_size))
    throw std::invalid_argument("RoomServer: max_sender_bytes_per_s must be 0 or >= max_message_size");
  if (!(options_.stall_timeout > 0) || !(options_.join_timeout > 0) || options_.idle_timeout < 0)
    throw std::invalid_argument("RoomServer: timeouts must be positive");
  if (options_.tls_certificate_file.empty() != options_.tls_private_key_file.empty())
    throw std::invalid_argument(
        "RoomServer: TLS needs both tls_certificate_file and tls_private_key_file (or neither)");
}

ServerCore::~ServerCore() {
  stop();
  // Handlers still queued (only after a forced stop) die with the io_context; they may own
  // sessions whose destructors call unregisterConnection, so this must go first.
  acceptor_.reset();
  ioc_.reset();
}

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
  if (!options_.tls_certificate_file.empty()) {
    tls_.emplace(net::ssl::context::tls_server);
    try {
      loadTlsContext(*tls_, options_.tls_certificate_file, options_.tls_private_key_file);
    } catch (...) {
      tls_.reset();
      throw;
    }
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
          startHttpSession(*this, std::move(socket));
        } else if (ec == net::error::no_descriptors || ec == net::error::no_buffer_space ||
                   ec == net::error::no_memory) {
          // Out of file descriptors (a flood): accepting again at once would spin; the waiting
          // connections' evictions and timeouts free some meanwhile.
          auto wait = std::make_shared<net::steady_timer>(acceptor_->get_executor(), std::chrono::milliseconds(100));
          wait->async_wait([this, wait](beast::error_code) { doAccept(); });
          return;
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
    for (const auto& c : connections_) live.push_back(c.second.weak);
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
                                         bool websocket, const std::string& address) {
  std::shared_ptr<Connection> victim;  // evicted outside the lock
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) return Admission::kStopping;
    Registered& r = connections_[c];
    r.weak = std::move(weak);
    r.order = next_order_++;
    r.websocket = websocket;
    r.address = address;
    // Every connection starts as plain HTTP (the WebSocket upgrade is an HTTP request), so both
    // kinds have limits for the waiting ones: HTTP connections (not upgraded) and WebSockets
    // not joined. A full address, or else a full pool, gives up its oldest waiting connection
    // (a linear search: the pools are small and this is rare).
    const int pool = websocket ? 1 : 0;
    const auto by = pending_by_address_[pool].find(address);
    const bool address_full =
        by != pending_by_address_[pool].end() && by->second >= options_.max_pending_per_address;
    const size_t limit = websocket ? options_.max_pending : options_.max_http_connections;
    if (address_full || pending_[pool] >= limit) {
      Registered* oldest = nullptr;
      for (auto& e : connections_)
        if (e.second.pending && e.second.websocket == websocket &&
            (!address_full || e.second.address == address) && (!oldest || e.second.order < oldest->order))
          oldest = &e.second;
      if (oldest) {
        unpendLocked(*oldest);
        victim = oldest->weak.lock();
        ++kicked_[websocket ? "evicted" : "evicted_http"];  // counted when decided
      }
    }
    r.pending = true;
    ++pending_by_address_[pool][address];
    ++pending_[pool];
  }
  if (victim) victim->evict();
  return Admission::kOk;
}

void ServerCore::unpendLocked(Registered& r) {
  if (!r.pending) return;
  r.pending = false;
  const int pool = r.websocket ? 1 : 0;
  --pending_[pool];
  const auto it = pending_by_address_[pool].find(r.address);
  if (it != pending_by_address_[pool].end() && --it->second == 0) pending_by_address_[pool].erase(it);
}

void ServerCore::unregisterConnection(Connection* c) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = connections_.find(c);
  if (it == connections_.end()) return;
  unpendLocked(it->second);
  if (it->second.joined) --joined_;
  connections_.erase(it);
}

bool ServerCore::tokenOk(const std::string& given) const {
  return options_.token.empty() || sameToken(options_.token, given);
}

}  // namespace room_server_internal

// ---- RoomServer -------------------------------------------------------------------------------

struct RoomServer::Impl : room_server_internal::ServerCore {
  using room_server_internal::ServerCore::ServerCore;
};

RoomServer::RoomServer(const RoomServerOptions& options) : impl_(std::make_unique<Impl>(options)) {}
RoomServer::~RoomServer() = default;
void RoomServer::start() { impl_->start(); }
void RoomServer::stop() { impl_->stop(); }
uint16_t RoomServer::port() const { return impl_->port(); }
bool RoomServer::tls() const { return !impl_->options().tls_certificate_file.empty(); }
const RoomServerOptions& RoomServer::options() const { return impl_->options(); }
RoomServerStats RoomServer::stats() const { return impl_->stats(); }

}  // namespace cvephands
