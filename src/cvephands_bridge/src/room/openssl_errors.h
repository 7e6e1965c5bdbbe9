// OpenSSL's error queue as text, for the room server's and client's TLS messages.
#pragma once

#include <openssl/err.h>

#include <string>

namespace cvephands {
namespace room_tls {

// The reasons OpenSSL queued for the last failure on this thread ("; "-joined), emptying the
// queue; call ERR_clear_error() before the call that may fail.
inline std::string openSslErrors() {
  std::string text;
  while (const unsigned long e = ERR_get_error()) {
    char buffer[256];
    ERR_error_string_n(e, buffer, sizeof buffer);
    text += (text.empty() ? "" : "; ") + std::string(buffer);
  }
  return text.empty() ? "unknown OpenSSL error" : text;
}

}  // namespace room_tls
}  // namespace cvephands
