// When to try again after failed connection attempts: exponential back-off from `initial` to
// `max` seconds, so that many rigs waiting for a restarting room server neither hammer it nor
// wait long once it is back. Deterministic (no jitter): a rig's attempts never depend on a
// random draw. The browser client does the same (web/src/room_connection.js, retryDelayMs).
#pragma once

#include <algorithm>
#include <stdexcept>

namespace cvephands {

class ReconnectBackoff {
 public:
  // Throws std::invalid_argument unless 0 < initial <= max.
  ReconnectBackoff(double initial, double max) : initial_(initial), max_(max) {
    if (!(initial > 0) || !(max >= initial))
      throw std::invalid_argument("ReconnectBackoff: need 0 < initial <= max");
  }
  // Seconds to wait after one more failure: initial, 2 initial, 4 initial, ... up to max.
  double failed() {
    const double d = next_;
    next_ = std::min(max_, next_ * 2.0);
    ++failures_;
    return d;
  }
  // Connected: the next failure waits `initial` again.
  void succeeded() {
    next_ = initial_;
    failures_ = 0;
  }
  int failures() const { return failures_; }

 private:
  double initial_, max_;
  double next_ = initial_;
  int failures_ = 0;
};

}  // namespace cvephands
